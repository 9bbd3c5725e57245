//! Scatter fields: points coloured by a scalar, optionally with arrows
//! (e.g. phase-resolved particle velocities in the container frame).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::Axis;
use crate::color::{ColorScale, Rgb};
use crate::render::{
    AxisLayout, COLORBAR_WIDTH, ColorBar, Figure, Frame, auto_range, build_chart, de, draw_axes,
    draw_colorbar, draw_frame, equalise, rgb, titled, write_figure, y_label_width,
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
    /// Axis length per unit of `(u, v)`; `None` scales the longest arrow to
    /// 6 % of the larger axis span.
    pub scale: Option<f64>,
    /// Arrow colour.
    pub color: Rgb,
}

impl Quiver {
    /// Black, automatically scaled arrows.
    pub fn new(u: Vec<f64>, v: Vec<f64>) -> Self {
        Self {
            u,
            v,
            scale: None,
            color: Rgb::BLACK,
        }
    }
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
    fn arrow_scale(&self, q: &Quiver) -> f64 {
        if let Some(s) = q.scale {
            return s;
        }
        let vmax =
            q.u.iter()
                .zip(&q.v)
                .map(|(u, v)| u.hypot(*v))
                .filter(|m| m.is_finite())
                .fold(0.0, f64::max);
        let span = |a: &[f64]| {
            let (lo, hi) = crate::color::finite_range(a, false).unwrap_or((0.0, 1.0));
            hi - lo
        };
        let l = span(&self.x).max(span(&self.y));
        let l = if l > 0.0 { l } else { 1.0 };
        if vmax > 0.0 { 0.06 * l / vmax } else { 0.0 }
    }
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
            let mut paths = Vec::new();
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
                let base = root.get_base_pixel();
                let shift = |p: (i32, i32)| (p.0 - base.0, p.1 - base.1);
                let pa = shift(plot.map_coordinate(&a));
                let pb = shift(plot.map_coordinate(&b));
                let (dx, dy) = ((pb.0 - pa.0) as f64, (pb.1 - pa.1) as f64);
                let len = dx.hypot(dy);
                if len < 1.0 {
                    continue;
                }
                let head = (0.3 * len).clamp(3.0, 8.0);
                let (ux, uy) = (dx / len, dy / len);
                let wing = |sgn: f64| {
                    (
                        pb.0 - (head * (ux * 0.94 - sgn * uy * 0.34)).round() as i32,
                        pb.1 - (head * (uy * 0.94 + sgn * ux * 0.34)).round() as i32,
                    )
                };
                paths.push(PathElement::new(vec![pa, pb], style));
                paths.push(PathElement::new(vec![wing(1.0), pb, wing(-1.0)], style));
            }
            for p in paths {
                root.draw(&p).map_err(de)?;
            }
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
