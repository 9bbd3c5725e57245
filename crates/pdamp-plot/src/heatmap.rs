//! Colour maps of values on a 2-D grid (e.g. effective loss factor over
//! frequency and amplitude).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{Axis, cell_edges};
use crate::color::{ColorScale, Rgb};
use crate::legend::{
    LegendEntry, Occupancy, Placement, Swatch, draw_legend_box, legend_size, place_legend,
};
use crate::render::{
    AxisLayout, COLORBAR_WIDTH, ColorBar, Figure, Frame, PxRect, TICK_PT, chart_rect,
    clip_polyline, de, draw_axes, draw_colorbar, draw_frame, draw_polyline, font, rgb, segments,
    titled, write_figure, y_label_width,
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
    /// Text written on the map at the end of the line's visible part (e.g. `"X = 1 mm"` on
    /// a line of constant displacement amplitude); empty for none.
    pub annotation: String,
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
            annotation: String::new(),
        }
    }
}

/// Font size of overlay annotations, pt.
const ANNOTATION_PT: f64 = 0.85 * TICK_PT;

/// Box of the annotation `text` next to `end` (pixels relative to `area`), kept inside
/// `plot`.
fn annotation_rect<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: PxRect,
    end: (f64, f64),
    text: &str,
) -> Result<PxRect, PlotError> {
    let (tw, th) = area
        .estimate_text_size(text, &font(ANNOTATION_PT))
        .map_err(de)?;
    let (tw, th) = (tw as f64, th as f64);
    let x = (end.0 - tw - 6.0).clamp(plot.x0 + 3.0, (plot.x1 - tw - 3.0).max(plot.x0 + 3.0));
    let y = (end.1 + 4.0).clamp(plot.y0 + 3.0, (plot.y1 - th - 3.0).max(plot.y0 + 3.0));
    Ok(PxRect {
        x0: x.round(),
        y0: y.round(),
        x1: (x + tw).round(),
        y1: (y + th).round(),
    })
}

/// Writes `text` in the box `r` on a translucent white ground.
fn draw_annotation<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    r: PxRect,
    text: &str,
) -> Result<(), PlotError> {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let (x0, y0, x1, y1) = (r.x0 as i32, r.y0 as i32, r.x1 as i32, r.y1 as i32);
    area.draw(&Rectangle::new(
        [(x0 - 2, y0 - 1), (x1 + 2, y1 + 1)],
        WHITE.mix(0.7).filled(),
    ))
    .map_err(de)?;
    area.draw(&Text::new(
        text.to_string(),
        (x0, y0),
        font(ANNOTATION_PT)
            .color(&RGBColor(40, 40, 40))
            .pos(Pos::new(HPos::Left, VPos::Top)),
    ))
    .map_err(de)
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

        let rect = chart_rect(&area, &chart);
        let (xr, yr) = ((xl.lo, xl.hi), (yl.lo, yl.hi));
        let mut entries = Vec::new();
        let mut occ = Occupancy::default();
        let mut annotations = Vec::new();
        for (i, p) in self.overlays.iter().enumerate() {
            let color = p.color.unwrap_or(OVERLAY_COLORS[i % OVERLAY_COLORS.len()]);
            let runs = segments(&p.x, &p.y, xs, ys);
            draw_polyline(&mut chart, &runs, (&xl, &yl), color, p.width_px, p.dashed)?;
            occ.lines.extend(
                runs.iter()
                    .map(|r| r.iter().map(|t| rect.map(xr, yr, *t)).collect::<Vec<_>>()),
            );
            if !p.label.is_empty() {
                entries.push(LegendEntry {
                    label: p.label.clone(),
                    swatch: Swatch::Line {
                        color,
                        width: p.width_px.max(1),
                        dashed: p.dashed,
                    },
                });
            }
            let end = runs
                .iter()
                .flat_map(|r| clip_polyline(r, xr, yr))
                .filter_map(|piece| piece.last().copied())
                .next_back();
            if let (false, Some(end)) = (p.annotation.is_empty(), end) {
                let r = annotation_rect(&area, rect, rect.map(xr, yr, end), &p.annotation)?;
                // The legend keeps off the annotation too.
                occ.lines.push(vec![
                    (r.x0, r.y0),
                    (r.x1, r.y0),
                    (r.x1, r.y1),
                    (r.x0, r.y1),
                    (r.x0, r.y0),
                ]);
                annotations.push((r, p.annotation.as_str()));
            }
        }
        for (r, text) in annotations {
            draw_annotation(&area, r, text)?;
        }
        if !entries.is_empty() {
            let size = legend_size(&area, &entries)?;
            let pos = match self.legend_position {
                LegendPosition::Outside => LegendPosition::Auto,
                p => p,
            };
            if let Placement::Inside(r) = place_legend(pos, rect, size, &occ, false) {
                draw_legend_box(&area, r, &entries)?;
            }
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
