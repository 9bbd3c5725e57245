//! Line plots (decay curves, energy time series) and two-panel FRF plots.

use std::path::Path;

use plotters::coord::Shift;
use plotters::element::DynElement;
use plotters::prelude::*;

use crate::axis::{Axis, Scale};
use crate::color::{Rgb, palette_color};
use crate::render::{
    AxisLayout, Coord2, Figure, Frame, auto_range, build_chart, de, draw_axes, draw_frame,
    draw_legend, draw_polyline, rgb, segments, titled, write_figure, y_label_width,
};
use crate::{LegendPosition, PlotError, PlotFiles};

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

/// One named `(x, y)` data series of a [`LinePlot`]. Points that cannot be
/// drawn (NaN, or ≤ 0 on a log axis) are skipped and break the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label; empty for no legend entry.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// y values (same length as `x`).
    pub y: Vec<f64>,
    /// Colour; `None` takes the next colour of [`crate::PALETTE`].
    pub color: Option<Rgb>,
    /// Connect the points with a line.
    pub line: bool,
    /// Dashed instead of solid line.
    pub dashed: bool,
    /// Line width in pixels.
    pub width_px: u32,
    /// Marker at each point, if any.
    pub marker: Option<Marker>,
    /// Marker size (radius) in pixels.
    pub marker_px: u32,
}

impl Series {
    /// Solid 2-px line without markers.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            color: None,
            line: true,
            dashed: false,
            width_px: 2,
            marker: None,
            marker_px: 4,
        }
    }

    /// Returns the series with markers (and the line kept).
    pub fn with_marker(mut self, marker: Marker) -> Self {
        self.marker = Some(marker);
        self
    }

    /// Returns the series drawn as markers only, without a line.
    pub fn points_only(mut self, marker: Marker) -> Self {
        self.marker = Some(marker);
        self.line = false;
        self
    }

    /// Returns the series with a fixed colour.
    pub fn with_color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }
}

/// Several series on one pair of axes, with legend.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Figure title (empty for none).
    pub title: String,
    /// x axis.
    pub x_axis: Axis,
    /// y axis.
    pub y_axis: Axis,
    /// The data series.
    pub series: Vec<Series>,
    /// Legend placement (legend shown if any series has a label).
    pub legend_position: LegendPosition,
    /// Draw grid lines.
    pub grid: bool,
    /// Image size in pixels (width, height).
    pub size_px: (u32, u32),
}

impl LinePlot {
    /// Empty plot with the given axes, grid on, 800 × 520 px.
    pub fn new(x_axis: Axis, y_axis: Axis) -> Self {
        Self {
            title: String::new(),
            x_axis,
            y_axis,
            series: Vec::new(),
            legend_position: LegendPosition::default(),
            grid: true,
            size_px: (800, 520),
        }
    }
}

/// Writes the line plot to `<stem>.png` and `<stem>.svg`.
pub fn line_plot(stem: impl AsRef<Path>, plot: &LinePlot) -> Result<PlotFiles, PlotError> {
    write_figure(stem.as_ref(), plot)
}

fn marker_element<DB: DrawingBackend>(
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

/// Draws the series of a panel; returns whether any legend entry was made.
pub(crate) fn draw_series_list<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Coord2>,
    series: &[Series],
    xl: &AxisLayout,
    yl: &AxisLayout,
) -> Result<bool, PlotError> {
    let mut any_label = false;
    for (i, s) in series.iter().enumerate() {
        let color = s.color.unwrap_or(palette_color(i));
        let runs = segments(&s.x, &s.y, xl.scale, yl.scale);
        let mut labelled = false;
        if s.line {
            labelled = draw_polyline(chart, &runs, xl, yl, color, s.width_px, s.dashed, "")?;
        }
        if let Some(m) = s.marker {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .flatten()
                .copied()
                .filter(|p| p.0 >= xl.lo && p.0 <= xl.hi && p.1 >= yl.lo && p.1 <= yl.hi)
                .collect();
            let size = s.marker_px.max(1);
            let c = rgb(color);
            let anno = chart
                .draw_series(
                    pts.into_iter()
                        .map(|p| EmptyElement::at(p) + marker_element::<DB>(m, (0, 0), size, c)),
                )
                .map_err(de)?;
            if !s.label.is_empty() {
                let line = s.line.then_some(s.width_px.max(1));
                anno.label(s.label.clone()).legend(move |(lx, ly)| {
                    let path = match line {
                        Some(_) => vec![(0, 0), (22, 0)],
                        None => vec![],
                    };
                    EmptyElement::at((lx, ly))
                        + PathElement::new(path, c.stroke_width(line.unwrap_or(1)))
                        + marker_element::<DB>(m, (11, 0), size, c)
                });
                labelled = true;
            }
        }
        if !labelled && !s.label.is_empty() && s.line {
            // Label the line through an empty series so the legend shows it.
            let w = s.width_px.max(1);
            let c = rgb(color);
            chart
                .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                .map_err(de)?
                .label(s.label.clone())
                .legend(move |(lx, ly)| {
                    PathElement::new(vec![(lx, ly), (lx + 22, ly)], c.stroke_width(w))
                });
            labelled = true;
        }
        any_label |= labelled;
    }
    Ok(any_label)
}

impl Figure for LinePlot {
    fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    fn validate(&self) -> Result<(), PlotError> {
        self.x_axis.validate("x")?;
        self.y_axis.validate("y")?;
        validate_series(&self.series)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let area = titled(root, &self.title)?;
        let xl = series_axis(&self.x_axis, &self.series, |s| &s.x, 0.0);
        let yl = series_axis(&self.y_axis, &self.series, |s| &s.y, 0.05);
        let frame = Frame {
            y_label: y_label_width(&area, &yl, &self.y_axis.title)?,
            ..Frame::DEFAULT
        };
        draw_panel(&area, frame, &xl, &yl, self, &self.x_axis.title)
    }
}

fn validate_series(series: &[Series]) -> Result<(), PlotError> {
    for (i, s) in series.iter().enumerate() {
        if s.x.len() != s.y.len() {
            return Err(PlotError::InvalidInput(format!(
                "series {i} ({:?}) has {} x and {} y values",
                s.label,
                s.x.len(),
                s.y.len()
            )));
        }
    }
    Ok(())
}

fn series_axis(
    axis: &Axis,
    series: &[Series],
    pick: impl Fn(&Series) -> &Vec<f64>,
    pad: f64,
) -> AxisLayout {
    let pad = if axis.scale == Scale::Log {
        0.6 * pad
    } else {
        pad
    };
    // Only points drawable on both axes count; approximating with the
    // single-axis criterion is enough for the range.
    let (lo, hi) = auto_range(
        axis.limits,
        axis.scale,
        series.iter().flat_map(|s| pick(s).iter().copied()),
        pad,
    );
    AxisLayout::new(axis.scale, lo, hi)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frame: Frame,
    xl: &AxisLayout,
    yl: &AxisLayout,
    plot: &LinePlot,
    x_title: &str,
) -> Result<(), PlotError> {
    let mut chart = build_chart(area, frame, xl, yl)?;
    draw_axes(&mut chart, xl, yl, x_title, &plot.y_axis.title, plot.grid)?;
    let any_label = draw_series_list(&mut chart, &plot.series, xl, yl)?;
    draw_frame(area, &chart, xl, yl)?;
    if any_label {
        draw_legend(&mut chart, plot.legend_position)?;
    }
    Ok(())
}

/// One FRF curve: magnitude and phase at the plot's frequencies.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfSeries {
    /// Legend label; empty for no legend entry.
    pub label: String,
    /// Magnitude |H| (drawn on a log axis; ≤ 0 and NaN points are skipped).
    pub magnitude: Vec<f64>,
    /// Phase in degrees.
    pub phase_deg: Vec<f64>,
    /// Colour; `None` takes the next palette colour.
    pub color: Option<Rgb>,
}

impl FrfSeries {
    /// Series from magnitude and phase (deg).
    pub fn new(label: impl Into<String>, magnitude: Vec<f64>, phase_deg: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            magnitude,
            phase_deg,
            color: None,
        }
    }

    /// Series from complex values given as `(re, im)` pairs.
    pub fn from_complex(label: impl Into<String>, h: &[(f64, f64)]) -> Self {
        Self::new(
            label,
            h.iter().map(|(re, im)| re.hypot(*im)).collect(),
            h.iter()
                .map(|(re, im)| im.atan2(*re).to_degrees())
                .collect(),
        )
    }
}

/// Two-panel frequency-response plot: magnitude (log y) over phase (deg).
#[derive(Debug, Clone, PartialEq)]
pub struct FrfPlot {
    /// Figure title (empty for none).
    pub title: String,
    /// Frequencies of all series, in Hz.
    pub frequencies_hz: Vec<f64>,
    /// The FRF curves.
    pub series: Vec<FrfSeries>,
    /// Frequency axis (shared by both panels); title defaults to
    /// `"frequency (Hz)"`.
    pub frequency_axis: Axis,
    /// Title of the magnitude axis, with units.
    pub magnitude_title: String,
    /// Fixed magnitude limits, if any.
    pub magnitude_limits: Option<(f64, f64)>,
    /// Legend placement in the magnitude panel.
    pub legend_position: LegendPosition,
    /// Image size in pixels (width, height).
    pub size_px: (u32, u32),
}

impl FrfPlot {
    /// FRF plot with a linear frequency axis and default titles.
    pub fn new(frequencies_hz: Vec<f64>, series: Vec<FrfSeries>) -> Self {
        Self {
            title: String::new(),
            frequencies_hz,
            series,
            frequency_axis: Axis::linear("frequency (Hz)"),
            magnitude_title: "magnitude".into(),
            magnitude_limits: None,
            legend_position: LegendPosition::default(),
            size_px: (800, 720),
        }
    }
}

/// Writes a magnitude/phase FRF plot with default options to
/// `<stem>.png` and `<stem>.svg`.
pub fn frf_plot(
    stem: impl AsRef<Path>,
    frequencies_hz: &[f64],
    series: &[FrfSeries],
) -> Result<PlotFiles, PlotError> {
    frf_plot_with(
        stem,
        &FrfPlot::new(frequencies_hz.to_vec(), series.to_vec()),
    )
}

/// Writes a configured FRF plot to `<stem>.png` and `<stem>.svg`.
pub fn frf_plot_with(stem: impl AsRef<Path>, plot: &FrfPlot) -> Result<PlotFiles, PlotError> {
    write_figure(stem.as_ref(), plot)
}

/// Phase ticks at multiples of 15°, 30°, 45°, 90° or 180°.
fn phase_layout(lo: f64, hi: f64) -> AxisLayout {
    let mut layout = AxisLayout::new(Scale::Linear, lo, hi);
    let step = [15.0, 30.0, 45.0, 90.0, 180.0, 360.0]
        .into_iter()
        .find(|s| (hi - lo) / s <= 8.0);
    if let Some(step) = step {
        let k0 = (lo / step).ceil() as i64;
        let k1 = (hi / step).floor() as i64;
        if k1 > k0 {
            layout.ticks.major = (k0..=k1).map(|k| k as f64 * step).collect();
            layout.ticks.labels = layout.ticks.major.iter().map(|v| format!("{v}")).collect();
            layout.ticks.minor.clear();
        }
    }
    layout
}

impl Figure for FrfPlot {
    fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    fn validate(&self) -> Result<(), PlotError> {
        self.frequency_axis.validate("frequency")?;
        let n = self.frequencies_hz.len();
        for (i, s) in self.series.iter().enumerate() {
            if s.magnitude.len() != n || s.phase_deg.len() != n {
                return Err(PlotError::InvalidInput(format!(
                    "FRF series {i} ({:?}) has {} magnitudes and {} phases for {n} frequencies",
                    s.label,
                    s.magnitude.len(),
                    s.phase_deg.len()
                )));
            }
        }
        match self.magnitude_limits {
            Some((lo, hi)) if !(Scale::Log.accepts(lo) && Scale::Log.accepts(hi) && lo < hi) => {
                Err(PlotError::InvalidInput(format!(
                    "magnitude limits [{lo}, {hi}] must satisfy 0 < min < max"
                )))
            }
            _ => Ok(()),
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let area = titled(root, &self.title)?;
        let (_, h) = area.dim_in_pixel();
        let (top, bottom) = area.split_vertically((h as f64 * 0.56) as u32);
        let f = &self.frequencies_hz;
        let mk = |pick: fn(&FrfSeries) -> &Vec<f64>| -> Vec<Series> {
            self.series
                .iter()
                .enumerate()
                .map(|(i, s)| Series {
                    color: Some(s.color.unwrap_or(palette_color(i))),
                    ..Series::new(s.label.clone(), f.clone(), pick(s).clone())
                })
                .collect()
        };
        let mag = LinePlot {
            title: String::new(),
            x_axis: self.frequency_axis.clone(),
            y_axis: Axis {
                title: self.magnitude_title.clone(),
                scale: Scale::Log,
                limits: self.magnitude_limits,
            },
            series: mk(|s| &s.magnitude),
            legend_position: self.legend_position,
            grid: true,
            size_px: self.size_px,
        };
        let phase = LinePlot {
            y_axis: Axis::linear("phase (deg)"),
            series: mk(|s| &s.phase_deg)
                .into_iter()
                .map(|s| Series {
                    label: String::new(),
                    ..s
                })
                .collect(),
            ..mag.clone()
        };
        let xl = series_axis(&self.frequency_axis, &mag.series, |s| &s.x, 0.0);
        let ml = series_axis(&mag.y_axis, &mag.series, |s| &s.y, 0.0);
        let (plo, phi) = auto_range(
            None,
            Scale::Linear,
            phase.series.iter().flat_map(|s| s.y.iter().copied()),
            0.05,
        );
        let pl = phase_layout(plo, phi);
        let frame = Frame {
            y_label: y_label_width(&area, &ml, &mag.y_axis.title)?.max(y_label_width(
                &area,
                &pl,
                &phase.y_axis.title,
            )?),
            ..Frame::DEFAULT
        };
        let top_frame = Frame {
            x_label: 30,
            ..frame
        };
        draw_panel(&top, top_frame, &xl, &ml, &mag, "")?;
        draw_panel(&bottom, frame, &xl, &pl, &phase, &self.frequency_axis.title)
    }
}
