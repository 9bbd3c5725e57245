//! Plots (PNG and SVG) of effective-field maps, decay curves and FRFs.
//!
//! Every plotting function takes a path *stem* and writes both `<stem>.png`
//! and `<stem>.svg` (each atomically: written to a temporary file in the
//! same directory and renamed into place; missing parent directories are
//! created).
//!
//! Rendering is pure Rust ([`plotters`] without system font libraries): text
//! uses the DejaVu Sans font embedded in the binary (Bitstream Vera licence,
//! see `assets/DejaVuSans-LICENSE.txt`). SVG files reference the generic
//! `sans-serif` family.
//!
//! - [`heat_map`]: values on an `nx × ny` grid, e.g. the effective loss
//!   factor over frequency and amplitude, with colour bar, saturation at
//!   `vmax`, grey NaN cells and optional overlaid boundary curves.
//! - [`line_plot`]: named `(x, y)` series with legend (decay curves, energy
//!   time series, FRF magnitudes).
//! - [`frf_plot`] / [`frf_plot_with`]: magnitude (log) and phase (deg)
//!   two-panel FRF plot.
//! - [`scatter_field`]: points coloured by a scalar with colour bar, equal
//!   aspect and optional velocity arrows.

#![forbid(unsafe_code)]
mod axis;
mod color;
mod heatmap;
mod legend;
mod line;
mod marker;
mod raster;
mod render;
mod scatter;

use std::path::PathBuf;

pub use axis::{
    Axis, LOG_DECADES_ONLY_FROM, Scale, Ticks, cell_edges, format_decade, format_number,
    linear_ticks, log_ticks, midpoint, ticks,
};
pub use color::{ColorMap, ColorScale, MISSING_COLOR, PALETTE, Rgb, palette_color};
pub use heatmap::{HeatMap, Polyline, heat_map};
pub use line::{FrfPlot, FrfSeries, LinePlot, Series, XSpan, frf_plot, frf_plot_with, line_plot};
pub use marker::Marker;
pub use scatter::{Quiver, QuiverKey, ScatterField, scatter_field, typical_spacing};

/// Where the legend is placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LegendPosition {
    /// Off the data: the first corner (upper right, upper left, lower right, lower left) or
    /// side (top, bottom, right, left) of the plotting area under which no line passes and no
    /// marker lies, else the first such place moved inwards by 8 % of the plot; when every
    /// one is occupied, outside the plotting area on the right (line and FRF plots) or where
    /// it hides the least (maps, whose right margin holds the colour bar).
    #[default]
    Auto,
    /// Outside the plotting area, on the right (maps: as `Auto`).
    Outside,
    /// Top right corner.
    UpperRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom left corner.
    LowerLeft,
    /// Bottom right corner.
    LowerRight,
}

/// Paths of the files written by a plotting function.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotFiles {
    /// The raster image, `<stem>.png`.
    pub png: PathBuf,
    /// The vector image, `<stem>.svg`.
    pub svg: PathBuf,
}

/// Errors of the plotting functions.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Inconsistent or undrawable input (lengths, limits, grids).
    #[error("invalid plot input: {0}")]
    InvalidInput(String),
    /// The drawing backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// Creating, writing or renaming an output file failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The embedded font could not be registered.
    #[error("embedded font could not be loaded")]
    Font,
}
