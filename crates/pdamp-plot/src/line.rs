//! Line plots (decay curves, energy time series) and two-panel FRF plots.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{Axis, Scale};
use crate::color::{Rgb, palette_color};
use crate::legend::{
    LegendEntry, Occupancy, Placement, Swatch, draw_legend_box, legend_size, outside_rect,
    outside_width, place_legend,
};
use crate::marker::{Marker, marker_element};
use crate::render::{
    AUTO_MARGIN, AxisLayout, Coord2, Figure, Frame, PxRect, auto_range, build_chart, chart_rect,
    de, draw_axes, draw_frame, draw_polyline, draw_right_axis, plot_rect, rgb, right_axis_width,
    segments, titled, write_figure, y_label_width,
};
use crate::{LegendPosition, PlotError, PlotFiles};

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
    /// Drawn against the secondary (right) y axis, [`LinePlot::y2_axis`].
    pub secondary: bool,
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
            secondary: false,
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

    /// Returns the series with the given line width in pixels.
    pub fn with_width(mut self, width_px: u32) -> Self {
        self.width_px = width_px;
        self
    }

    /// Returns the series drawn against the secondary (right) y axis.
    pub fn on_secondary_axis(mut self) -> Self {
        self.secondary = true;
        self
    }

    fn color_at(&self, i: usize) -> Rgb {
        self.color.unwrap_or(palette_color(i))
    }

    fn legend_entry(&self, i: usize) -> Option<LegendEntry> {
        if self.label.is_empty() || !(self.line || self.marker.is_some()) {
            return None;
        }
        let color = self.color_at(i);
        let swatch = match self.marker {
            Some(marker) => Swatch::Marker {
                marker,
                color,
                size: self.marker_px.max(1),
                line: self.line.then_some(self.width_px.max(1)),
            },
            None => Swatch::Line {
                color,
                width: self.width_px.max(1),
                dashed: self.dashed,
            },
        };
        Some(LegendEntry {
            label: self.label.clone(),
            swatch,
        })
    }
}

/// A shaded band over the x range `[from, to]` (full height), e.g. the transient cycles of
/// a time series.
#[derive(Debug, Clone, PartialEq)]
pub struct XSpan {
    /// Start, in x data units.
    pub from: f64,
    /// End, in x data units.
    pub to: f64,
    /// Fill colour.
    pub color: Rgb,
    /// Legend label; empty for no legend entry.
    pub label: String,
}

impl XSpan {
    /// A light grey band with the given label.
    pub fn new(from: f64, to: f64, label: impl Into<String>) -> Self {
        Self {
            from,
            to,
            color: Rgb(228, 228, 228),
            label: label.into(),
        }
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
    /// Secondary y axis on the right, for the series with [`Series::secondary`] (e.g. a
    /// displacement in mm beside a force in N).
    pub y2_axis: Option<Axis>,
    /// The data series.
    pub series: Vec<Series>,
    /// Shaded x ranges drawn behind the series.
    pub spans: Vec<XSpan>,
    /// Legend placement (legend shown if any series or span has a label); the default
    /// [`LegendPosition::Auto`] keeps it off the data.
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
            y2_axis: None,
            series: Vec::new(),
            spans: Vec::new(),
            legend_position: LegendPosition::default(),
            grid: true,
            size_px: (800, 520),
        }
    }

    /// Display layouts of the x, y and (if any) secondary y axis: fixed limits, or the data
    /// range with a margin of [`AUTO_MARGIN`] of the range on each side of a linear axis
    /// (3 % on a log y axis).
    pub(crate) fn layouts(&self) -> (AxisLayout, AxisLayout, Option<AxisLayout>) {
        let on = |sec: bool| self.series.iter().filter(move |s| s.secondary == sec);
        let xl = series_axis(&self.x_axis, self.series.iter(), |s| &s.x, AUTO_MARGIN, 0.0);
        let yl = series_axis(&self.y_axis, on(false), |s| &s.y, AUTO_MARGIN, 0.03);
        let y2l = self
            .y2_axis
            .as_ref()
            .map(|a| series_axis(a, on(true), |s| &s.y, AUTO_MARGIN, 0.03));
        (xl, yl, y2l)
    }
}

/// Writes the line plot to `<stem>.png` and `<stem>.svg`.
pub fn line_plot(stem: impl AsRef<Path>, plot: &LinePlot) -> Result<PlotFiles, PlotError> {
    write_figure(stem.as_ref(), plot)
}

/// Maps a secondary-axis display value onto the primary axis' display range.
fn to_primary(t2: f64, y2: &AxisLayout, y: &AxisLayout) -> f64 {
    y.lo + (t2 - y2.lo) / (y2.hi - y2.lo) * (y.hi - y.lo)
}

/// The drawable runs of series `s` in the display space of the x and primary y axes.
fn series_runs(
    s: &Series,
    xl: &AxisLayout,
    yl: &AxisLayout,
    y2l: Option<&AxisLayout>,
) -> Vec<Vec<(f64, f64)>> {
    match (s.secondary, y2l) {
        (true, Some(y2)) => segments(&s.x, &s.y, xl.scale, y2.scale)
            .into_iter()
            .map(|r| {
                r.into_iter()
                    .map(|(a, b)| (a, to_primary(b, y2, yl)))
                    .collect()
            })
            .collect(),
        _ => segments(&s.x, &s.y, xl.scale, yl.scale),
    }
}

/// Draws the series of a panel (without legend).
pub(crate) fn draw_series_list<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Coord2>,
    series: &[Series],
    xl: &AxisLayout,
    yl: &AxisLayout,
    y2l: Option<&AxisLayout>,
) -> Result<(), PlotError> {
    for (i, s) in series.iter().enumerate() {
        let color = s.color_at(i);
        let runs = series_runs(s, xl, yl, y2l);
        if s.line {
            draw_polyline(chart, &runs, (xl, yl), color, s.width_px, s.dashed)?;
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
            chart
                .draw_series(
                    pts.into_iter()
                        .map(|p| EmptyElement::at(p) + marker_element::<DB>(m, (0, 0), size, c)),
                )
                .map_err(de)?;
        }
    }
    Ok(())
}

impl Figure for LinePlot {
    fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    fn validate(&self) -> Result<(), PlotError> {
        self.x_axis.validate("x")?;
        self.y_axis.validate("y")?;
        if let Some(a) = &self.y2_axis {
            a.validate("secondary y")?;
        } else if let Some(i) = self.series.iter().position(|s| s.secondary) {
            return Err(PlotError::InvalidInput(format!(
                "series {i} ({:?}) is on the secondary y axis, but the plot has no y2_axis",
                self.series[i].label
            )));
        }
        for (i, s) in self.spans.iter().enumerate() {
            if !(s.from.is_finite() && s.to.is_finite()) {
                return Err(PlotError::InvalidInput(format!(
                    "span {i} ({:?}) has non-finite limits [{}, {}]",
                    s.label, s.from, s.to
                )));
            }
        }
        validate_series(&self.series)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let area = titled(root, &self.title)?;
        let (xl, yl, y2l) = self.layouts();
        let mut frame = Frame {
            y_label: y_label_width(&area, &yl, &self.y_axis.title)?,
            ..Frame::DEFAULT
        };
        let y2 = match (&self.y2_axis, &y2l) {
            (Some(a), Some(l)) => {
                frame.right = right_axis_width(&area, l, &a.title)?;
                Some((l, a.title.as_str()))
            }
            _ => None,
        };
        let panel = Panel {
            xl: &xl,
            yl: &yl,
            y2,
            plot: self,
            x_title: &self.x_axis.title,
        };
        let legend = panel.plan_legend(&area, &mut frame, true)?;
        panel.draw(&area, frame, legend)
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

/// Layout of an axis over the values `pick` of `series`: fixed limits, or the data range
/// padded by `linear_pad` (linear scale) or `log_pad` (log scale) of the display span.
fn series_axis<'s>(
    axis: &Axis,
    series: impl Iterator<Item = &'s Series>,
    pick: impl Fn(&'s Series) -> &'s Vec<f64>,
    linear_pad: f64,
    log_pad: f64,
) -> AxisLayout {
    let pad = if axis.scale == Scale::Log {
        log_pad
    } else {
        linear_pad
    };
    // Only points drawable on both axes count; approximating with the
    // single-axis criterion is enough for the range.
    let (lo, hi) = auto_range(
        axis.limits,
        axis.scale,
        series.flat_map(|s| pick(s).iter().copied()),
        pad,
    );
    AxisLayout::new(axis.scale, lo, hi)
}

/// One pair of axes with its series: layout, legend and drawing.
struct Panel<'p> {
    xl: &'p AxisLayout,
    yl: &'p AxisLayout,
    /// Secondary y axis and its title.
    y2: Option<(&'p AxisLayout, &'p str)>,
    plot: &'p LinePlot,
    x_title: &'p str,
}

/// A legend to draw: its entries, size and place.
struct LegendPlan {
    entries: Vec<LegendEntry>,
    size: (f64, f64),
    placement: Placement,
}

impl Panel<'_> {
    fn entries(&self) -> Vec<LegendEntry> {
        let mut v: Vec<LegendEntry> = self
            .plot
            .series
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.legend_entry(i))
            .collect();
        v.extend(
            self.plot
                .spans
                .iter()
                .filter(|s| !s.label.is_empty())
                .map(|s| LegendEntry {
                    label: s.label.clone(),
                    swatch: Swatch::Patch { color: s.color },
                }),
        );
        v
    }

    /// The drawn data in pixels of the plotting area `rect`.
    fn occupancy(&self, rect: PxRect) -> Occupancy {
        let (xr, yr) = ((self.xl.lo, self.xl.hi), (self.yl.lo, self.yl.hi));
        let mut occ = Occupancy::default();
        for s in &self.plot.series {
            let runs = series_runs(s, self.xl, self.yl, self.y2.map(|y| y.0));
            for run in runs {
                let px: Vec<(f64, f64)> = run.iter().map(|t| rect.map(xr, yr, *t)).collect();
                if s.marker.is_some() {
                    occ.points.extend(px.iter().copied());
                }
                if s.line {
                    occ.lines.push(px);
                }
            }
        }
        occ
    }

    /// Where the legend goes; widens `frame` for a legend outside the plotting area.
    fn plan_legend<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        frame: &mut Frame,
        allow_outside: bool,
    ) -> Result<Option<LegendPlan>, PlotError> {
        let entries = self.entries();
        if entries.is_empty() {
            return Ok(None);
        }
        let size = legend_size(area, &entries)?;
        let rect = plot_rect(area.dim_in_pixel(), frame);
        let placement = place_legend(
            self.plot.legend_position,
            rect,
            size,
            &self.occupancy(rect),
            allow_outside,
        );
        if placement == Placement::Outside {
            frame.right += outside_width(size);
        }
        Ok(Some(LegendPlan {
            entries,
            size,
            placement,
        }))
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        frame: Frame,
        legend: Option<LegendPlan>,
    ) -> Result<(), PlotError> {
        let (xl, yl) = (self.xl, self.yl);
        let mut chart = build_chart(area, frame, xl, yl)?;
        for s in &self.plot.spans {
            let (a, b) = (s.from.min(s.to), s.from.max(s.to));
            if !(xl.scale.accepts(a) || xl.scale.accepts(b)) {
                continue;
            }
            let ta = if xl.scale.accepts(a) { xl.t(a) } else { xl.lo };
            let (ta, tb) = (ta.max(xl.lo), xl.t(b).min(xl.hi));
            if ta < tb {
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(ta, yl.lo), (tb, yl.hi)],
                        rgb(s.color).filled(),
                    )))
                    .map_err(de)?;
            }
        }
        draw_axes(
            &mut chart,
            xl,
            yl,
            self.x_title,
            &self.plot.y_axis.title,
            self.plot.grid,
        )?;
        draw_series_list(&mut chart, &self.plot.series, xl, yl, self.y2.map(|y| y.0))?;
        draw_frame(area, &chart, xl, yl)?;
        let rect = chart_rect(area, &chart);
        if let Some((y2, title)) = self.y2 {
            draw_right_axis(area, rect, y2, title)?;
        }
        if let Some(l) = legend {
            let r = match l.placement {
                Placement::Inside(r) => r,
                Placement::Outside => {
                    let x0 = area.dim_in_pixel().0 as f64 - outside_width(l.size) as f64;
                    outside_rect(x0, rect.y0, l.size)
                }
            };
            draw_legend_box(area, r, &l.entries)?;
        }
        Ok(())
    }
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
            x_axis: self.frequency_axis.clone(),
            y_axis: Axis {
                title: self.magnitude_title.clone(),
                scale: Scale::Log,
                limits: self.magnitude_limits,
            },
            series: mk(|s| &s.magnitude),
            legend_position: self.legend_position,
            size_px: self.size_px,
            ..LinePlot::new(Axis::default(), Axis::default())
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
        let xl = series_axis(
            &self.frequency_axis,
            mag.series.iter(),
            |s| &s.x,
            AUTO_MARGIN,
            0.0,
        );
        let ml = series_axis(&mag.y_axis, mag.series.iter(), |s| &s.y, 0.0, 0.0);
        let (plo, phi) = auto_range(
            None,
            Scale::Linear,
            phase.series.iter().flat_map(|s| s.y.iter().copied()),
            0.05,
        );
        let pl = phase_layout(plo, phi);
        let mut frame = Frame {
            y_label: y_label_width(&area, &ml, &mag.y_axis.title)?.max(y_label_width(
                &area,
                &pl,
                &phase.y_axis.title,
            )?),
            ..Frame::DEFAULT
        };
        let mut top_frame = Frame {
            x_label: 30,
            ..frame
        };
        let top_panel = Panel {
            xl: &xl,
            yl: &ml,
            y2: None,
            plot: &mag,
            x_title: "",
        };
        let legend = top_panel.plan_legend(&top, &mut top_frame, true)?;
        // Both panels keep one plotting width (an outside legend widens both).
        frame.right = top_frame.right;
        top_panel.draw(&top, top_frame, legend)?;
        Panel {
            xl: &xl,
            yl: &pl,
            y2: None,
            plot: &phase,
            x_title: &self.frequency_axis.title,
        }
        .draw(&bottom, frame, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An in-memory SVG drawing area of `size` px for layout checks.
    fn with_area<R>(
        size: (u32, u32),
        f: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> R,
    ) -> R {
        crate::render::ensure_font().unwrap();
        let mut text = String::new();
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        f(&root)
    }

    /// Automatic linear limits lie strictly outside the data (no point on the frame); fixed
    /// limits are kept.
    #[test]
    fn linear_axes_have_a_margin() {
        let mut p = LinePlot::new(Axis::linear("x (m)"), Axis::linear("y (N)"));
        p.series
            .push(Series::new("a", vec![0.0, 1.0, 2.0], vec![-3.0, 5.0, 1.0]));
        let (xl, yl, y2) = p.layouts();
        assert!(y2.is_none());
        assert!(xl.lo < 0.0 && xl.hi > 2.0, "x [{}, {}]", xl.lo, xl.hi);
        assert!(yl.lo < -3.0 && yl.hi > 5.0, "y [{}, {}]", yl.lo, yl.hi);
        assert!((xl.hi - 2.0 - AUTO_MARGIN * 2.0).abs() < 1e-12);
        p.x_axis = p.x_axis.with_limits(0.0, 2.0);
        let (xl, _, _) = p.layouts();
        assert_eq!((xl.lo, xl.hi), (0.0, 2.0));
    }

    /// The plotting area predicted from the frame (used to place the legend before the
    /// chart exists) is the one the chart gets.
    #[test]
    fn predicted_plot_rect_matches_chart() {
        with_area((800, 520), |root| {
            let xl = AxisLayout::new(Scale::Linear, 0.0, 1.0);
            let yl = AxisLayout::new(Scale::Linear, 0.0, 1.0);
            let frame = Frame {
                right: 77,
                ..Frame::DEFAULT
            };
            let chart = build_chart(root, frame, &xl, &yl).unwrap();
            let got = chart_rect(root, &chart);
            let want = plot_rect(root.dim_in_pixel(), &frame);
            for (a, b) in [
                (got.x0, want.x0),
                (got.x1, want.x1),
                (got.y0, want.y0),
                (got.y1, want.y1),
            ] {
                assert!((a - b).abs() <= 1.0, "{got:?} vs {want:?}");
            }
        });
    }

    /// A trajectory through the upper right corner (the old fixed legend place): the legend
    /// box covers none of its points and no piece of its line; a plot full of data gets its
    /// legend outside the plotting area.
    #[test]
    fn legend_box_covers_no_data() {
        let n = 400;
        let x: Vec<f64> = (0..n).map(|k| k as f64 / n as f64).collect();
        let y: Vec<f64> = x.iter().map(|x| x * x).collect();
        let mut p = LinePlot::new(Axis::linear("x (m)"), Axis::linear("y (m)"));
        p.series.push(Series::new(
            "trajectory of particle 17",
            x.clone(),
            y.clone(),
        ));
        p.series
            .push(Series::new("samples", x.clone(), y.clone()).points_only(Marker::Circle));
        let (xl, yl, _) = p.layouts();
        with_area(p.size_px, |area| {
            let mut frame = Frame {
                y_label: y_label_width(area, &yl, &p.y_axis.title).unwrap(),
                ..Frame::DEFAULT
            };
            let panel = Panel {
                xl: &xl,
                yl: &yl,
                y2: None,
                plot: &p,
                x_title: "",
            };
            let plan = panel.plan_legend(area, &mut frame, true).unwrap().unwrap();
            let Placement::Inside(r) = plan.placement else {
                panic!("free corners exist")
            };
            let rect = plot_rect(area.dim_in_pixel(), &frame);
            for (a, b) in x.iter().zip(&y) {
                let q = rect.map((xl.lo, xl.hi), (yl.lo, yl.hi), (*a, *b));
                assert!(
                    !r.contains(q),
                    "point ({a}, {b}) at {q:?} under the legend {r:?}"
                );
            }
            assert_eq!(panel.occupancy(rect).cost(&r), 0.0);
            // The old default (upper right) would hide the curve's end.
            assert!(r.x0 < rect.x0 + 0.5 * rect.w() || r.y0 > rect.y0 + 0.5 * rect.h());

            // Noise over the whole area: no free corner or side, the legend goes outside.
            let mut full = p.clone();
            full.series[0].y = (0..n).map(|k| if k % 2 == 0 { 0.0 } else { 1.0 }).collect();
            full.series.truncate(1);
            let (fxl, fyl, _) = full.layouts();
            let mut frame = Frame::DEFAULT;
            let right = frame.right;
            let panel = Panel {
                xl: &fxl,
                yl: &fyl,
                y2: None,
                plot: &full,
                x_title: "",
            };
            let plan = panel.plan_legend(area, &mut frame, true).unwrap().unwrap();
            assert_eq!(plan.placement, Placement::Outside);
            assert!(frame.right > right + plan.size.0 as u32);
        });
    }

    /// Series on the secondary axis are mapped linearly onto the primary display range: the
    /// ends of the secondary range land on the ends of the primary one.
    #[test]
    fn secondary_axis_maps_onto_primary() {
        let mut p = LinePlot::new(Axis::linear("time (s)"), Axis::linear("force (N)"));
        p.y2_axis = Some(Axis::linear("displacement (mm)"));
        p.series
            .push(Series::new("f", vec![0.0, 1.0], vec![-100.0, 100.0]));
        p.series
            .push(Series::new("x", vec![0.0, 1.0], vec![-2.0, 2.0]).on_secondary_axis());
        let (xl, yl, y2) = p.layouts();
        let y2 = y2.unwrap();
        // Each axis fits its own series.
        assert!(yl.lo < -100.0 && yl.lo > -120.0 && y2.lo < -2.0 && y2.lo > -2.4);
        let runs = series_runs(&p.series[1], &xl, &yl, Some(&y2));
        let t = runs[0][0].1;
        let f = (t - yl.lo) / (yl.hi - yl.lo);
        let f2 = (-2.0 - y2.lo) / (y2.hi - y2.lo);
        assert!((f - f2).abs() < 1e-12);
        p.y2_axis = None;
        assert!(p.validate().is_err());
    }
}
