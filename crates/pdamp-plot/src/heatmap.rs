//! Colour maps of values on a 2-D grid (e.g. effective loss factor over
//! frequency and amplitude).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{Axis, cell_edges};
use crate::color::{ColorScale, Rgb};
use crate::render::{
    AxisLayout, COLORBAR_WIDTH, ColorBar, Figure, Frame, de, draw_axes, draw_colorbar, draw_frame,
    draw_legend, draw_polyline, rgb, segments, titled, write_figure, y_label_width,
};
use crate::{LegendPosition, PlotError, PlotFiles};

/// Default colours of overlay curves (readable on the perceptual maps).
const OVERLAY_COLORS: [Rgb; 5] = [
    Rgb(0, 0, 0),
    Rgb(228, 26, 28),
    Rgb(255, 255, 255),
    Rgb(231, 41, 138),
    Rgb(55, 126, 184),
];

/// A labelled curve drawn over a map, e.g. an analytic boundary between
/// motion modes. Non-finite points (and ≤ 0 on log axes) break the line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polyline {
    /// Legend label; empty for no legend entry.
    pub label: String,
    /// x coordinates (data units of the x axis).
    pub x: Vec<f64>,
    /// y coordinates (data units of the y axis).
    pub y: Vec<f64>,
    /// Line colour; `None` picks from a default cycle.
    pub color: Option<Rgb>,
    /// Line width in pixels.
    pub width_px: u32,
    /// Draw dashed instead of solid.
    pub dashed: bool,
}

impl Polyline {
    /// Solid 2-px line with the given label and points.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            color: None,
            width_px: 2,
            dashed: false,
        }
    }
}

/// A map of values on an `nx × ny` grid.
///
/// Each value is drawn as a rectangle spanning the midpoints between
/// neighbouring grid points (geometric midpoints on log axes). NaN values
/// are drawn grey; values above `color.vmax` saturate to the top colour.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatMap {
    /// Figure title (empty for none).
    pub title: String,
    /// x axis (title, scale, limits; `None` limits span all cells).
    pub x_axis: Axis,
    /// y axis.
    pub y_axis: Axis,
    /// Grid x values, strictly increasing (length `nx`).
    pub x: Vec<f64>,
    /// Grid y values, strictly increasing (length `ny`).
    pub y: Vec<f64>,
    /// Values, row-major with x fastest: `values[iy * nx + ix]`.
    pub values: Vec<f64>,
    /// Value → colour mapping (limits, log scale, colour map).
    pub color: ColorScale,
    /// Title of the colour bar.
    pub colorbar_title: String,
    /// Curves drawn over the map.
    pub overlays: Vec<Polyline>,
    /// Legend placement (legend shown if any overlay has a label).
    pub legend_position: LegendPosition,
    /// Image size in pixels (width, height).
    pub size_px: (u32, u32),
}

impl HeatMap {
    /// Map of `values[iy * x.len() + ix]` with linear, untitled axes and a
    /// linear viridis colour scale spanning the finite values.
    pub fn new(x: Vec<f64>, y: Vec<f64>, values: Vec<f64>) -> Self {
        let color = ColorScale::from_data(&values, false);
        Self {
            title: String::new(),
            x_axis: Axis::default(),
            y_axis: Axis::default(),
            x,
            y,
            values,
            color,
            colorbar_title: String::new(),
            overlays: Vec::new(),
            legend_position: LegendPosition::default(),
            size_px: (900, 620),
        }
    }

    /// Value at grid point `(ix, iy)`.
    pub fn value(&self, ix: usize, iy: usize) -> f64 {
        self.values[iy * self.x.len() + ix]
    }
}

/// Writes the map to `<stem>.png` and `<stem>.svg`.
pub fn heat_map(stem: impl AsRef<Path>, map: &HeatMap) -> Result<PlotFiles, PlotError> {
    write_figure(stem.as_ref(), map)
}

fn clamp_span(a: f64, b: f64, lo: f64, hi: f64) -> Option<(f64, f64)> {
    let (a, b) = (a.max(lo), b.min(hi));
    (a < b).then_some((a, b))
}

impl Figure for HeatMap {
    fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    fn validate(&self) -> Result<(), PlotError> {
        let (nx, ny) = (self.x.len(), self.y.len());
        if self.values.len() != nx * ny {
            return Err(PlotError::InvalidInput(format!(
                "heat map has {} values for a {nx}×{ny} grid",
                self.values.len()
            )));
        }
        cell_edges(&self.x, self.x_axis.scale)?;
        cell_edges(&self.y, self.y_axis.scale)?;
        self.x_axis.validate("x")?;
        self.y_axis.validate("y")?;
        self.color.validate()?;
        for (i, p) in self.overlays.iter().enumerate() {
            if p.x.len() != p.y.len() {
                return Err(PlotError::InvalidInput(format!(
                    "overlay {i} has {} x and {} y values",
                    p.x.len(),
                    p.y.len()
                )));
            }
        }
        Ok(())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (xs, ys) = (self.x_axis.scale, self.y_axis.scale);
        let xe = cell_edges(&self.x, xs)?;
        let ye = cell_edges(&self.y, ys)?;
        let (x_lo, x_hi) = self.x_axis.limits.unwrap_or((xe[0], xe[xe.len() - 1]));
        let (y_lo, y_hi) = self.y_axis.limits.unwrap_or((ye[0], ye[ye.len() - 1]));
        let xl = AxisLayout::new(xs, x_lo, x_hi);
        let yl = AxisLayout::new(ys, y_lo, y_hi);

        let area = titled(root, &self.title)?;
        let frame = Frame {
            right: COLORBAR_WIDTH,
            y_label: y_label_width(&area, &yl, &self.y_axis.title)?,
            ..Frame::DEFAULT
        };
        let mut chart = crate::render::build_chart(&area, frame, &xl, &yl)?;

        // Cells, in display space, clamped to the axis range.
        let xe_t: Vec<f64> = xe.iter().map(|v| xl.t(*v)).collect();
        let ye_t: Vec<f64> = ye.iter().map(|v| yl.t(*v)).collect();
        let nx = self.x.len();
        let mut cells = Vec::with_capacity(self.values.len());
        for (iy, yw) in ye_t.windows(2).enumerate() {
            let Some((y0, y1)) = clamp_span(yw[0], yw[1], yl.lo, yl.hi) else {
                continue;
            };
            for (ix, xw) in xe_t.windows(2).enumerate() {
                let Some((x0, x1)) = clamp_span(xw[0], xw[1], xl.lo, xl.hi) else {
                    continue;
                };
                let c = rgb(self.color.color(self.values[iy * nx + ix]));
                cells.push(Rectangle::new([(x0, y0), (x1, y1)], c.filled()));
            }
        }
        chart.draw_series(cells).map_err(de)?;
        draw_axes(
            &mut chart,
            &xl,
            &yl,
            &self.x_axis.title,
            &self.y_axis.title,
            false,
        )?;
        draw_frame(&area, &chart, &xl, &yl)?;

        let mut any_label = false;
        for (i, p) in self.overlays.iter().enumerate() {
            let color = p.color.unwrap_or(OVERLAY_COLORS[i % OVERLAY_COLORS.len()]);
            let runs = segments(&p.x, &p.y, xs, ys);
            any_label |= draw_polyline(
                &mut chart, &runs, &xl, &yl, color, p.width_px, p.dashed, &p.label,
            )?;
        }
        if any_label {
            draw_legend(&mut chart, self.legend_position)?;
        }

        let cb = ColorBar::for_values(&self.color, &self.colorbar_title, &self.values);
        let plot = chart.plotting_area().get_pixel_range();
        let base = root.get_base_pixel();
        let plot = (
            plot.0.start - base.0..plot.0.end - base.0,
            plot.1.start - base.1..plot.1.end - base.1,
        );
        draw_colorbar(root, plot, &cb)
    }
}
