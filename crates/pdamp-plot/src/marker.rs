//! Marker symbols drawn at data points (line plots) and in legend swatches.

use plotters::element::DynElement;
use plotters::prelude::*;

/// Marker symbol drawn at each data point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle.
    Triangle,
    /// Diagonal cross.
    Cross,
}

/// The plotters element of `marker` centred at `at` (pixels), `size` its radius in pixels.
pub(crate) fn marker_element<DB: DrawingBackend>(
    marker: Marker,
    at: (i32, i32),
    size: u32,
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    let s = size as i32;
    match marker {
        Marker::Circle => Circle::new(at, size, color.filled()).into_dyn(),
        Marker::Square => {
            Rectangle::new([(at.0 - s, at.1 - s), (at.0 + s, at.1 + s)], color.filled()).into_dyn()
        }
        Marker::Triangle => TriangleMarker::new(at, size + 1, color.filled()).into_dyn(),
        Marker::Cross => Cross::new(at, size, color.stroke_width(2)).into_dyn(),
    }
}
