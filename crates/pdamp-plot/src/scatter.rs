//! Scatter fields: points coloured by a scalar, optionally with arrows
//! (e.g. phase-resolved particle velocities in the container frame).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{Axis, Scale};
use crate::color::{ColorScale, Rgb};
use crate::heatmap::Polyline;
use crate::render::{
    AxisLayout, COLORBAR_WIDTH, ColorBar, Figure, Frame, LEGEND_PT, auto_range, build_chart,
    chart_rect, de, draw_axes, draw_colorbar, draw_frame, draw_polyline, equalise, font, rgb,
    segments, titled, write_figure, y_label_width,
};
use crate::{PlotError, PlotFiles};

/// Arrows (quiver) attached to the points of a [`ScatterField`], drawn from
/// each point `(x, y)` to `(x + scale·u, y + scale·v)` (in data units).
#[derive(Debug, Clone, PartialEq)]
pub struct Quiver {
    /// Arrow x components (one per point; NaN skips the arrow).
    pub u: Vec<f64>,
    /// Arrow y components.
    pub v: Vec<f64>,
    /// Axis length per unit of `(u, v)`; `None` scales the longest arrow to the typical
    /// spacing of the points (the median distance to the nearest neighbour: one cell of a
    /// grid), or to 6 % of the larger axis span for a single point.
    pub scale: Option<f64>,
    /// Arrow colour.
    pub color: Rgb,
    /// Reference arrow drawn below the plot, with the value it stands for.
    pub key: Option<QuiverKey>,
}

/// The reference arrow of a [`Quiver`]: an arrow of length `magnitude` (in units of
/// `(u, v)`) drawn below the plotting area with `label` beside it, e.g. "|v|/V = 1
/// (0.25 m/s)".
#[derive(Debug, Clone, PartialEq)]
pub struct QuiverKey {
    /// Length of the reference arrow, in units of `(u, v)`.
    pub magnitude: f64,
    /// What the arrow stands for.
    pub label: String,
}

impl Quiver {
    /// Black, automatically scaled arrows.
    pub fn new(u: Vec<f64>, v: Vec<f64>) -> Self {
        Self {
            u,
            v,
            scale: None,
            color: Rgb::BLACK,
            key: None,
        }
    }

    /// Largest finite arrow magnitude `|(u, v)|` (0 when there is none).
    pub fn max_magnitude(&self) -> f64 {
        self.u
            .iter()
            .zip(&self.v)
            .map(|(u, v)| u.hypot(*v))
            .filter(|m| m.is_finite())
            .fold(0.0, f64::max)
    }
}

/// Typical spacing of the points `(x[i], y[i])`: the median distance to the nearest other
/// point (distinct positions only; at most 2 000 points are examined), `None` for fewer than
/// two distinct points.
pub fn typical_spacing(x: &[f64], y: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect();
    let step = pts.len().div_ceil(2000).max(1);
    let mut nn: Vec<f64> = pts
        .iter()
        .step_by(step)
        .filter_map(|p| {
            pts.iter()
                .map(|q| (p.0 - q.0).hypot(p.1 - q.1))
                .filter(|d| *d > 0.0)
                .min_by(f64::total_cmp)
        })
        .collect();
    if nn.is_empty() {
        return None;
    }
    nn.sort_by(f64::total_cmp);
    Some(nn[nn.len() / 2])
}

/// Points `(x, y)` coloured by `value`, with colour bar.
#[derive(Debug, Clone, PartialEq)]
pub struct ScatterField {
    /// Figure title (empty for none).
    pub title: String,
    /// x axis.
    pub x_axis: Axis,
    /// y axis.
    pub y_axis: Axis,
    /// Point x coordinates.
    pub x: Vec<f64>,
    /// Point y coordinates.
    pub y: Vec<f64>,
    /// Scalar per point, mapped through `color` (NaN: grey).
    pub value: Vec<f64>,
    /// Value → colour mapping.
    pub color: ColorScale,
    /// Title of the colour bar.
    pub colorbar_title: String,
    /// Optional arrows.
    pub arrows: Option<Quiver>,
    /// Lines drawn over the points (e.g. the container's outline); they count for the
    /// automatic axis limits. Their labels are not shown.
    pub outlines: Vec<Polyline>,
    /// Same length per pixel on both axes (in display space); automatic
    /// limits are widened to achieve it, fixed limits are kept as the minimum
    /// visible range.
    pub equal_aspect: bool,
    /// Marker radius in pixels.
    pub marker_px: u32,
    /// Image size in pixels (width, height).
    pub size_px: (u32, u32),
}

impl ScatterField {
    /// Field with linear untitled axes, equal aspect, and a linear viridis
    /// colour scale spanning the finite values.
    pub fn new(x: Vec<f64>, y: Vec<f64>, value: Vec<f64>) -> Self {
        let color = ColorScale::from_data(&value, false);
        Self {
            title: String::new(),
            x_axis: Axis::default(),
            y_axis: Axis::default(),
            x,
            y,
            value,
            color,
            colorbar_title: String::new(),
            arrows: None,
            outlines: Vec::new(),
            equal_aspect: true,
            marker_px: 4,
            size_px: (820, 680),
        }
    }
}

/// Writes the scatter field to `<stem>.png` and `<stem>.svg`.
pub fn scatter_field(stem: impl AsRef<Path>, field: &ScatterField) -> Result<PlotFiles, PlotError> {
    write_figure(stem.as_ref(), field)
}

impl ScatterField {
    /// Axis length per unit of the arrows' `(u, v)` (see [`Quiver::scale`]).
    pub fn arrow_scale(&self, q: &Quiver) -> f64 {
        if let Some(s) = q.scale {
            return s;
        }
        let vmax = q.max_magnitude();
        if vmax <= 0.0 {
            return 0.0;
        }
        let span = |a: &[f64]| {
            let (lo, hi) = crate::color::finite_range(a, false).unwrap_or((0.0, 1.0));
            hi - lo
        };
        let l = typical_spacing(&self.x, &self.y).unwrap_or_else(|| {
            let l = span(&self.x).max(span(&self.y));
            0.06 * if l > 0.0 { l } else { 1.0 }
        });
        l / vmax
    }
}

/// Draws an arrow from `pa` to `pb` (pixels of `area`) with a head of up to 8 px.
fn draw_arrow<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    pa: (i32, i32),
    pb: (i32, i32),
    style: ShapeStyle,
) -> Result<(), PlotError> {
    let (dx, dy) = ((pb.0 - pa.0) as f64, (pb.1 - pa.1) as f64);
    let len = dx.hypot(dy);
    if len < 1.0 {
        return Ok(());
    }
    let head = (0.3 * len).clamp(3.0, 8.0);
    let (ux, uy) = (dx / len, dy / len);
    let wing = |sgn: f64| {
        (
            pb.0 - (head * (ux * 0.94 - sgn * uy * 0.34)).round() as i32,
            pb.1 - (head * (uy * 0.94 + sgn * ux * 0.34)).round() as i32,
        )
    };
    area.draw(&PathElement::new(vec![pa, pb], style))
        .map_err(de)?;
    area.draw(&PathElement::new(vec![wing(1.0), pb, wing(-1.0)], style))
        .map_err(de)
}

/// Extra bottom margin for the reference arrow of a quiver, px.
const KEY_HEIGHT_PX: u32 = 30;

fn q_color(q: &Option<Quiver>) -> Rgb {
    q.as_ref().map_or(Rgb::BLACK, |q| q.color)
}

impl Figure for ScatterField {
    fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    fn validate(&self) -> Result<(), PlotError> {
        let n = self.x.len();
        if self.y.len() != n || self.value.len() != n {
            return Err(PlotError::InvalidInput(format!(
                "scatter field has {} x, {} y and {} values",
                n,
                self.y.len(),
                self.value.len()
            )));
        }
        if let Some(q) = &self.arrows {
            if q.u.len() != n || q.v.len() != n {
                return Err(PlotError::InvalidInput(format!(
                    "quiver has {} u and {} v components for {n} points",
                    q.u.len(),
                    q.v.len()
                )));
            }
            match q.scale {
                Some(s) if !(s.is_finite() && s >= 0.0) => {
                    return Err(PlotError::InvalidInput(format!("invalid arrow scale {s}")));
                }
                _ => {}
            }
        }
        for (i, o) in self.outlines.iter().enumerate() {
            if o.x.len() != o.y.len() {
                return Err(PlotError::InvalidInput(format!(
                    "outline {i} has {} x and {} y values",
                    o.x.len(),
                    o.y.len()
                )));
            }
        }
        self.x_axis.validate("x")?;
        self.y_axis.validate("y")?;
        self.color.validate()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (xs, ys) = (self.x_axis.scale, self.y_axis.scale);
        let area = titled(root, &self.title)?;
        let mut frame = Frame {
            right: COLORBAR_WIDTH,
            ..Frame::DEFAULT
        };
        // Data extent including arrow tips.
        let scale = self.arrows.as_ref().map(|q| (q, self.arrow_scale(q)));
        let mut xv = self.x.clone();
        let mut yv = self.y.clone();
        if let Some((q, s)) = scale {
            xv.extend(self.x.iter().zip(&q.u).map(|(x, u)| x + s * u));
            yv.extend(self.y.iter().zip(&q.v).map(|(y, v)| y + s * v));
        }
        for o in &self.outlines {
            xv.extend(o.x.iter().copied());
            yv.extend(o.y.iter().copied());
        }
        let key = scale.and_then(|(q, s)| {
            q.key
                .as_ref()
                .filter(|k| xs == Scale::Linear && k.magnitude.is_finite() && k.magnitude > 0.0)
                .map(|k| (k, s))
        });
        if key.is_some() {
            frame.bottom += KEY_HEIGHT_PX;
        }
        let (x0, x1) = auto_range(self.x_axis.limits, xs, xv.into_iter(), 0.04);
        let (y0, y1) = auto_range(self.y_axis.limits, ys, yv.into_iter(), 0.04);
        let layouts = |frame: &Frame| {
            if self.equal_aspect {
                let px = frame.plot_size(area.dim_in_pixel());
                let ((a, b), (c, d)) = equalise(
                    (xs.forward(x0), xs.forward(x1)),
                    (ys.forward(y0), ys.forward(y1)),
                    px,
                );
                (
                    AxisLayout::from_display(xs, a, b),
                    AxisLayout::from_display(ys, c, d),
                )
            } else {
                (AxisLayout::new(xs, x0, x1), AxisLayout::new(ys, y0, y1))
            }
        };
        // The y label width depends on the tick labels, which depend on the
        // (equal-aspect) range, which depends on the label width: iterate once.
        let (_, yl) = layouts(&frame);
        frame.y_label = y_label_width(&area, &yl, &self.y_axis.title)?;
        let (xl, yl) = layouts(&frame);
        let mut chart = build_chart(&area, frame, &xl, &yl)?;
        draw_axes(
            &mut chart,
            &xl,
            &yl,
            &self.x_axis.title,
            &self.y_axis.title,
            false,
        )?;

        let inside = |p: (f64, f64)| p.0 >= xl.lo && p.0 <= xl.hi && p.1 >= yl.lo && p.1 <= yl.hi;
        let r = self.marker_px.max(1);
        let pts = (0..self.x.len()).filter_map(|i| {
            let (x, y) = (self.x[i], self.y[i]);
            if !(xs.accepts(x) && ys.accepts(y)) {
                return None;
            }
            let p = (xl.t(x), yl.t(y));
            inside(p).then(|| Circle::new(p, r, rgb(self.color.color(self.value[i])).filled()))
        });
        chart.draw_series(pts).map_err(de)?;

        if let Some((q, s)) = scale {
            let plot = chart.plotting_area();
            let style = rgb(q.color).stroke_width(1);
            let base = root.get_base_pixel();
            let shift = |p: (i32, i32)| (p.0 - base.0, p.1 - base.1);
            for i in 0..self.x.len() {
                let (x, y) = (self.x[i], self.y[i]);
                let (xe, ye) = (x + s * q.u[i], y + s * q.v[i]);
                if !(xs.accepts(x) && ys.accepts(y) && xs.accepts(xe) && ys.accepts(ye)) {
                    continue;
                }
                let a = (xl.t(x), yl.t(y));
                let b = (xl.t(xe), yl.t(ye));
                if !inside(a) || !inside(b) {
                    continue;
                }
                let pa = shift(plot.map_coordinate(&a));
                let pb = shift(plot.map_coordinate(&b));
                draw_arrow(root, pa, pb, style)?;
            }
        }
        for (i, o) in self.outlines.iter().enumerate() {
            let color = o.color.unwrap_or(if i == 0 {
                Rgb::BLACK
            } else {
                crate::palette_color(i)
            });
            let runs = segments(&o.x, &o.y, xs, ys);
            draw_polyline(&mut chart, &runs, (&xl, &yl), color, o.width_px, o.dashed)?;
        }
        if let Some((k, s)) = key {
            let rect = chart_rect(&area, &chart);
            let px_per_unit = rect.w() / (xl.hi - xl.lo);
            let len = (s * k.magnitude * px_per_unit).round() as i32;
            let y = area.dim_in_pixel().1 as i32 - (KEY_HEIGHT_PX as i32) / 2 - 4;
            let x1 = rect.x1.round() as i32;
            draw_arrow(
                &area,
                (x1 - len, y),
                (x1, y),
                rgb(q_color(&self.arrows)).stroke_width(1),
            )?;
            use plotters::style::text_anchor::{HPos, Pos, VPos};
            area.draw(&Text::new(
                k.label.clone(),
                (x1 - len - 8, y),
                font(LEGEND_PT).pos(Pos::new(HPos::Right, VPos::Center)),
            ))
            .map_err(de)?;
        }
        draw_frame(&area, &chart, &xl, &yl)?;

        let cb = ColorBar::for_values(&self.color, &self.colorbar_title, &self.value);
        let plot = chart.plotting_area().get_pixel_range();
        let base = root.get_base_pixel();
        let plot = (
            plot.0.start - base.0..plot.0.end - base.0,
            plot.1.start - base.1..plot.1.end - base.1,
        );
        draw_colorbar(root, plot, &cb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Automatic arrow scale: on a grid of 2 mm cells the longest arrow is one cell long
    /// (it was 6 % of the span, a quarter of a cell here).
    #[test]
    fn longest_arrow_is_one_cell() {
        let (mut x, mut y, mut u, mut v) = (vec![], vec![], vec![], vec![]);
        for i in 0..40 {
            for j in 0..10 {
                x.push(i as f64 * 2.0);
                y.push(j as f64 * 2.0);
                u.push(0.1 * i as f64);
                v.push(-0.05 * j as f64);
            }
        }
        let q = Quiver::new(u, v);
        let f = ScatterField::new(x.clone(), y.clone(), vec![0.0; x.len()]);
        assert_eq!(typical_spacing(&x, &y), Some(2.0));
        let longest = f.arrow_scale(&q) * q.max_magnitude();
        assert!((longest - 2.0).abs() < 1e-12, "{longest}");
        // A single point: 6 % of the (degenerate → 1) span.
        let one = ScatterField::new(vec![1.0], vec![1.0], vec![0.0]);
        let q1 = Quiver::new(vec![3.0], vec![4.0]);
        assert!((one.arrow_scale(&q1) * 5.0 - 0.06).abs() < 1e-12);
    }
}
