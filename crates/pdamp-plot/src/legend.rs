//! Legends: the entries, their box, and where the box goes.
//!
//! With [`LegendPosition::Auto`] the box goes into the first corner of the plotting area
//! (upper right, upper left, lower right, lower left), else the first side (top, bottom,
//! right, left) that it leaves free of data — no line passes under it and no marker
//! lies under it —, else the first of these places moved inwards by 8 % of the plot (inside
//! a frame of data such as a container's outline), and, when all are occupied, outside the
//! plotting area on the right (line plots) or into the place that hides the least data
//! (maps, whose right margin holds the colour bar).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::color::Rgb;
use crate::marker::{Marker, marker_element};
use crate::render::{LEGEND_PT, PxRect, clip_polyline, de, font, rgb};
use crate::{LegendPosition, PlotError};

/// The symbol of a legend entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Swatch {
    /// A line segment.
    Line {
        color: Rgb,
        width: u32,
        dashed: bool,
    },
    /// A marker, on a line segment when `line` gives its width.
    Marker {
        marker: Marker,
        color: Rgb,
        size: u32,
        line: Option<u32>,
    },
    /// A filled square (shaded spans).
    Patch { color: Rgb },
}

/// One legend row.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LegendEntry {
    pub label: String,
    pub swatch: Swatch,
}

/// What is drawn in the plotting area, in pixels (see [`PxRect`]): polylines and markers.
#[derive(Debug, Default, Clone)]
pub(crate) struct Occupancy {
    pub lines: Vec<Vec<(f64, f64)>>,
    pub points: Vec<(f64, f64)>,
}

/// Weight of one marker under a legend box, in pixels of line length.
const POINT_COST: f64 = 10.0;

impl Occupancy {
    /// Data under `r`: the pixel length of the lines inside (each piece at least 1) plus
    /// [`POINT_COST`] per marker inside; 0 when `r` hides nothing.
    pub fn cost(&self, r: &PxRect) -> f64 {
        let mut c = 0.0;
        for l in &self.lines {
            if l.len() == 1 {
                if r.contains(l[0]) {
                    c += POINT_COST;
                }
                continue;
            }
            for piece in clip_polyline(l, (r.x0, r.x1), (r.y0, r.y1)) {
                c += 1.0
                    + piece
                        .windows(2)
                        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                        .sum::<f64>();
            }
        }
        c + POINT_COST * self.points.iter().filter(|p| r.contains(**p)).count() as f64
    }
}

/// Where a legend goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Placement {
    /// Inside the plotting area, at this rectangle.
    Inside(PxRect),
    /// Outside the plotting area (on its right).
    Outside,
}

/// Distance of the legend box from the edges of the plotting area, px.
const INSET_PX: f64 = 10.0;
/// Clearance kept between data and the legend box, px.
const CLEARANCE_PX: f64 = 3.0;
const PAD_PX: f64 = 8.0;
const SWATCH_PX: f64 = 28.0;
const GAP_PX: f64 = 8.0;

fn row_height() -> f64 {
    (LEGEND_PT * 1.45).round()
}

/// Size (w, h) of the legend box of `entries`, px.
pub(crate) fn legend_size<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<(f64, f64), PlotError> {
    let mut tw = 0u32;
    for e in entries {
        tw = tw.max(
            area.estimate_text_size(&e.label, &font(LEGEND_PT))
                .map_err(de)?
                .0,
        );
    }
    Ok((
        2.0 * PAD_PX + SWATCH_PX + GAP_PX + tw as f64,
        2.0 * PAD_PX + entries.len() as f64 * row_height(),
    ))
}

/// Chooses where a legend box of `size` goes in the plotting area `plot` with the data
/// `occ` (see the module documentation); a fixed `pos` is kept.
pub(crate) fn place_legend(
    pos: LegendPosition,
    plot: PxRect,
    size: (f64, f64),
    occ: &Occupancy,
    allow_outside: bool,
) -> Placement {
    let (w, h) = size;
    let at_inset = |fx: f64, fy: f64, ix: f64, iy: f64| {
        let x0 = plot.x0 + ix + fx * (plot.w() - 2.0 * ix - w);
        let y0 = plot.y0 + iy + fy * (plot.h() - 2.0 * iy - h);
        PxRect {
            x0,
            y0,
            x1: x0 + w,
            y1: y0 + h,
        }
    };
    let at = |fx: f64, fy: f64| at_inset(fx, fy, INSET_PX, INSET_PX);
    let fixed = match pos {
        LegendPosition::UpperRight => Some(at(1.0, 0.0)),
        LegendPosition::UpperLeft => Some(at(0.0, 0.0)),
        LegendPosition::LowerLeft => Some(at(0.0, 1.0)),
        LegendPosition::LowerRight => Some(at(1.0, 1.0)),
        LegendPosition::Outside => return Placement::Outside,
        LegendPosition::Auto => None,
    };
    if let Some(r) = fixed {
        return Placement::Inside(r);
    }
    // The corners and sides, then the same places moved inwards by 8 % of the plot (inside
    // a frame of data such as a container's outline drawn along the axis margins).
    let places = [
        (1.0, 0.0),
        (0.0, 0.0),
        (1.0, 1.0),
        (0.0, 1.0),
        (0.5, 0.0),
        (0.5, 1.0),
        (1.0, 0.5),
        (0.0, 0.5),
    ];
    let (ix, iy) = (INSET_PX + 0.08 * plot.w(), INSET_PX + 0.08 * plot.h());
    let candidates: Vec<PxRect> = places
        .iter()
        .map(|&(fx, fy)| at(fx, fy))
        .chain(places.iter().map(|&(fx, fy)| at_inset(fx, fy, ix, iy)))
        .collect();
    let fits = w + 2.0 * ix <= plot.w() && h + 2.0 * iy <= plot.h();
    let costs: Vec<f64> = candidates
        .iter()
        .map(|r| occ.cost(&r.grown(CLEARANCE_PX)))
        .collect();
    if fits && let Some(i) = costs.iter().position(|c| *c == 0.0) {
        return Placement::Inside(candidates[i]);
    }
    if allow_outside {
        return Placement::Outside;
    }
    let best = (0..candidates.len())
        .min_by(|a, b| costs[*a].total_cmp(&costs[*b]))
        .unwrap_or(0);
    Placement::Inside(candidates[best])
}

/// Extra right margin an outside legend of `size` needs, px.
pub(crate) fn outside_width(size: (f64, f64)) -> u32 {
    (size.0 + 2.0 * INSET_PX).ceil() as u32
}

/// Rectangle of an outside legend whose left edge is `x0` and top `y0`.
pub(crate) fn outside_rect(x0: f64, y0: f64, size: (f64, f64)) -> PxRect {
    PxRect {
        x0: x0 + INSET_PX,
        y0,
        x1: x0 + INSET_PX + size.0,
        y1: y0 + size.1,
    }
}

fn draw_swatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: Swatch,
    (x, y): (i32, i32),
) -> Result<(), PlotError> {
    let w = SWATCH_PX as i32;
    match s {
        Swatch::Line {
            color,
            width,
            dashed,
        } => {
            let style = rgb(color).stroke_width(width.max(1));
            if dashed {
                let dash = (w - 4) / 3;
                for k in 0..2 {
                    let a = x + k * (dash + dash / 2 + 2);
                    area.draw(&PathElement::new(vec![(a, y), (a + dash, y)], style))
                        .map_err(de)?;
                }
            } else {
                area.draw(&PathElement::new(vec![(x, y), (x + w, y)], style))
                    .map_err(de)?;
            }
        }
        Swatch::Marker {
            marker,
            color,
            size,
            line,
        } => {
            if let Some(lw) = line {
                area.draw(&PathElement::new(
                    vec![(x, y), (x + w, y)],
                    rgb(color).stroke_width(lw.max(1)),
                ))
                .map_err(de)?;
            }
            area.draw(&marker_element::<DB>(
                marker,
                (x + w / 2, y),
                size.max(1),
                rgb(color),
            ))
            .map_err(de)?;
        }
        Swatch::Patch { color } => {
            let h = (row_height() * 0.3).round() as i32;
            area.draw(&Rectangle::new(
                [(x + 2, y - h), (x + w - 2, y + h)],
                rgb(color).filled(),
            ))
            .map_err(de)?;
            area.draw(&Rectangle::new(
                [(x + 2, y - h), (x + w - 2, y + h)],
                RGBColor(160, 160, 160).stroke_width(1),
            ))
            .map_err(de)?;
        }
    }
    Ok(())
}

/// Draws the legend box of `entries` at `r` (pixels relative to `area`).
pub(crate) fn draw_legend_box<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    r: PxRect,
    entries: &[LegendEntry],
) -> Result<(), PlotError> {
    let (x0, y0) = (r.x0.round() as i32, r.y0.round() as i32);
    let (x1, y1) = (r.x1.round() as i32, r.y1.round() as i32);
    area.draw(&Rectangle::new(
        [(x0, y0), (x1, y1)],
        WHITE.mix(0.88).filled(),
    ))
    .map_err(de)?;
    area.draw(&Rectangle::new(
        [(x0, y0), (x1, y1)],
        RGBColor(120, 120, 120).stroke_width(1),
    ))
    .map_err(de)?;
    let style = font(LEGEND_PT).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, e) in entries.iter().enumerate() {
        let yc = (r.y0 + PAD_PX + (k as f64 + 0.5) * row_height()).round() as i32;
        let xs = (r.x0 + PAD_PX).round() as i32;
        draw_swatch(area, e.swatch, (xs, yc))?;
        area.draw(&Text::new(
            e.label.clone(),
            (xs + (SWATCH_PX + GAP_PX) as i32, yc),
            style.clone(),
        ))
        .map_err(de)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot() -> PxRect {
        PxRect {
            x0: 100.0,
            y0: 20.0,
            x1: 700.0,
            y1: 420.0,
        }
    }

    /// A line through the upper right corner: the legend goes to the next free corner, and
    /// covers no data point.
    #[test]
    fn auto_legend_avoids_the_data() {
        let p = plot();
        // Rising line from the lower left to the upper right corner.
        let line: Vec<(f64, f64)> = (0..=100)
            .map(|k| {
                let f = k as f64 / 100.0;
                (p.x0 + f * p.w(), p.y1 - f * p.h())
            })
            .collect();
        let occ = Occupancy {
            lines: vec![line.clone()],
            points: vec![],
        };
        let size = (150.0, 60.0);
        let Placement::Inside(r) = place_legend(LegendPosition::Auto, p, size, &occ, true) else {
            panic!("a free corner exists");
        };
        assert!(line.iter().all(|q| !r.contains(*q)), "{r:?}");
        assert_eq!(occ.cost(&r), 0.0);
        // The fixed upper right corner would hide the line.
        let Placement::Inside(ur) = place_legend(LegendPosition::UpperRight, p, size, &occ, true)
        else {
            panic!()
        };
        assert!(occ.cost(&ur) > 0.0);
    }

    /// Data everywhere: outside when allowed, else the least covered place.
    #[test]
    fn full_plot_puts_legend_outside() {
        let p = plot();
        let mut points = Vec::new();
        for i in 0..=30 {
            for j in 0..=20 {
                points.push((
                    p.x0 + p.w() * i as f64 / 30.0,
                    p.y0 + p.h() * j as f64 / 20.0,
                ));
            }
        }
        let occ = Occupancy {
            lines: vec![],
            points,
        };
        let size = (150.0, 60.0);
        assert_eq!(
            place_legend(LegendPosition::Auto, p, size, &occ, true),
            Placement::Outside
        );
        assert!(matches!(
            place_legend(LegendPosition::Auto, p, size, &occ, false),
            Placement::Inside(_)
        ));
    }
}
