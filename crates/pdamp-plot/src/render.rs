//! Shared rendering machinery: font, file output, axes, colour bar, legend.

use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontTransform, register_font};

use crate::axis::{Scale, Ticks, ticks};
use crate::color::{ColorScale, MISSING_COLOR, Rgb};
use crate::raster::RasterBackend;
use crate::{PlotError, PlotFiles};

/// A pixel rectangle `[x0, x1] × [y0, y1]` (y down) relative to the drawing area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PxRect {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl PxRect {
    pub fn w(&self) -> f64 {
        self.x1 - self.x0
    }

    pub fn h(&self) -> f64 {
        self.y1 - self.y0
    }

    pub fn contains(&self, p: (f64, f64)) -> bool {
        p.0 >= self.x0 && p.0 <= self.x1 && p.1 >= self.y0 && p.1 <= self.y1
    }

    pub fn grown(&self, d: f64) -> Self {
        Self {
            x0: self.x0 - d,
            y0: self.y0 - d,
            x1: self.x1 + d,
            y1: self.y1 + d,
        }
    }

    /// Maps display-space `(tx, ty)` of axes spanning `x`/`y` onto this rectangle.
    pub fn map(&self, x: (f64, f64), y: (f64, f64), t: (f64, f64)) -> (f64, f64) {
        let fx = if x.1 > x.0 {
            (t.0 - x.0) / (x.1 - x.0)
        } else {
            0.5
        };
        let fy = if y.1 > y.0 {
            (t.1 - y.0) / (y.1 - y.0)
        } else {
            0.5
        };
        (self.x0 + fx * self.w(), self.y1 - fy * self.h())
    }
}

/// Font family name under which the embedded font is registered.
pub(crate) const FONT: &str = "sans-serif";
static FONT_DATA: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

pub(crate) const TITLE_PT: f64 = 22.0;
pub(crate) const AXIS_TITLE_PT: f64 = 17.0;
pub(crate) const TICK_PT: f64 = 15.0;
pub(crate) const LEGEND_PT: f64 = 15.0;

/// Registers the embedded font once per process.
pub(crate) fn ensure_font() -> Result<(), PlotError> {
    static OK: OnceLock<bool> = OnceLock::new();
    let ok = *OK.get_or_init(|| {
        register_font(FONT, FontStyle::Normal, FONT_DATA).is_ok()
            && register_font(FONT, FontStyle::Bold, FONT_DATA).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// A figure that can be drawn on any plotters backend.
pub(crate) trait Figure {
    fn size_px(&self) -> (u32, u32);
    fn validate(&self) -> Result<(), PlotError>;
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>;
}

/// Converts a plotters drawing error.
pub(crate) fn de<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

pub(crate) fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

pub(crate) fn font(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&BLACK)
}

fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s: OsString = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Temporary sibling of `target`, keeping its extension (the PNG encoder
/// picks the format from it).
fn temp_sibling(target: &Path, ext: &str) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = target
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{name}.{}-{n}.tmp.{ext}", std::process::id()))
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> PlotError + '_ {
    move |source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `fig` to `<stem>.svg` and `<stem>.png`, atomically.
pub(crate) fn write_figure<F: Figure>(stem: &Path, fig: &F) -> Result<PlotFiles, PlotError> {
    fig.validate()?;
    ensure_font()?;
    let (w, h) = fig.size_px();
    if w < 100 || h < 100 || w > 16384 || h > 16384 {
        return Err(PlotError::InvalidInput(format!(
            "image size {w}×{h} px outside 100…16384"
        )));
    }
    if stem.file_name().is_none() {
        return Err(PlotError::InvalidInput(format!(
            "path stem {} has no file name",
            stem.display()
        )));
    }
    let png = with_suffix(stem, "png");
    let svg = with_suffix(stem, "svg");
    if let Some(dir) = png.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(io_err(dir))?;
    }

    // SVG: render into memory, then write + rename.
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        fig.draw(&root)?;
        root.present().map_err(de)?;
    }
    let tmp = temp_sibling(&svg, "svg");
    let res = fs::write(&tmp, text.as_bytes())
        .map_err(io_err(&tmp))
        .and_then(|()| fs::rename(&tmp, &svg).map_err(io_err(&svg)));
    if res.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    res?;

    // PNG: the bitmap backend encodes to the temporary path on present().
    let tmp = temp_sibling(&png, "png");
    let res = (|| {
        let backend = RasterBackend::new(BitMapBackend::new(&tmp, (w, h)), FONT_DATA)
            .ok_or(PlotError::Font)?;
        let root = backend.into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        fig.draw(&root)?;
        root.present().map_err(de)
    })();
    let res = res.and_then(|()| fs::rename(&tmp, &png).map_err(io_err(&png)));
    if res.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    res?;
    Ok(PlotFiles { png, svg })
}

/// Area below the figure title (or the whole area without a title).
pub(crate) fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    if title.is_empty() {
        Ok(root.clone().margin(8, 0, 0, 0))
    } else {
        root.titled(title, font(TITLE_PT)).map_err(de)
    }
}

/// Range, ticks and labels of an axis in display space (identity or log10).
pub(crate) struct AxisLayout {
    pub scale: Scale,
    pub lo: f64,
    pub hi: f64,
    pub ticks: Ticks,
}

/// Display-space coordinate with explicit tick (key) points.
pub(crate) struct Coord1 {
    lo: f64,
    hi: f64,
    major: Vec<f64>,
    minor: Vec<f64>,
}

impl Ranged for Coord1 {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let span = (limit.1 - limit.0) as f64;
        if self.hi == self.lo || !v.is_finite() {
            return (limit.0 + limit.1) / 2;
        }
        let f = (v - self.lo) / (self.hi - self.lo);
        // Keep far-off values representable; callers clip beforehand.
        let f = f.clamp(-100.0, 100.0);
        limit.0 + (span * f).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

pub(crate) type Coord2 = Cartesian2d<Coord1, Coord1>;

impl AxisLayout {
    /// Layout for the data-space range `[lo, hi]`.
    pub fn new(scale: Scale, lo: f64, hi: f64) -> Self {
        Self {
            scale,
            lo: scale.forward(lo),
            hi: scale.forward(hi),
            ticks: ticks(scale, lo, hi),
        }
    }

    /// Layout for an explicit display-space range.
    pub fn from_display(scale: Scale, lo_t: f64, hi_t: f64) -> Self {
        Self::new(scale, scale.inverse(lo_t), scale.inverse(hi_t))
    }

    pub fn t(&self, v: f64) -> f64 {
        self.scale.forward(v)
    }

    pub fn coord(&self) -> Coord1 {
        Coord1 {
            lo: self.lo,
            hi: self.hi,
            major: self.ticks.major.iter().map(|v| self.t(*v)).collect(),
            minor: self.ticks.minor.iter().map(|v| self.t(*v)).collect(),
        }
    }

    /// Label of the major tick nearest to display value `t`.
    pub fn label(&self, t: f64) -> String {
        self.ticks
            .major
            .iter()
            .zip(&self.ticks.labels)
            .min_by(|a, b| {
                (self.t(*a.0) - t)
                    .abs()
                    .total_cmp(&(self.t(*b.0) - t).abs())
            })
            .map(|(_, l)| l.clone())
            .unwrap_or_default()
    }
}

/// Automatic data range of an axis: fixed limits if given, otherwise the
/// drawable data range, padded by `pad` (fraction of the display span).
pub(crate) fn auto_range(
    limits: Option<(f64, f64)>,
    scale: Scale,
    values: impl Iterator<Item = f64>,
    pad: f64,
) -> (f64, f64) {
    if let Some(l) = limits {
        return l;
    }
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.filter(|v| scale.accepts(*v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return match scale {
            Scale::Linear => (0.0, 1.0),
            Scale::Log => (1.0, 10.0),
        };
    }
    let (lo_t, hi_t) = (scale.forward(lo), scale.forward(hi));
    let (lo_t, hi_t) = if lo_t == hi_t {
        let d = match scale {
            Scale::Log => 0.5,
            Scale::Linear if lo_t == 0.0 => 0.5,
            Scale::Linear => 0.1 * lo_t.abs(),
        };
        (lo_t - d, hi_t + d)
    } else {
        let d = pad * (hi_t - lo_t);
        (lo_t - d, hi_t + d)
    };
    (scale.inverse(lo_t), scale.inverse(hi_t))
}

/// Pixel geometry of a chart around its plotting area.
#[derive(Clone, Copy)]
pub(crate) struct Frame {
    pub top: u32,
    pub bottom: u32,
    pub left: u32,
    pub right: u32,
    pub x_label: u32,
    pub y_label: u32,
}

/// Widest tick label of `y` and the height of the (rotated) axis `title` (0 without one), px.
fn tick_and_title_px<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: &AxisLayout,
    title: &str,
) -> Result<(u32, u32), PlotError> {
    let mut w = 0;
    for l in &y.ticks.labels {
        w = w.max(area.estimate_text_size(l, &font(TICK_PT)).map_err(de)?.0);
    }
    let th = if title.is_empty() {
        0
    } else {
        area.estimate_text_size(title, &font(AXIS_TITLE_PT))
            .map_err(de)?
            .1
    };
    Ok((w, th))
}

/// Width of the y label area needed for the tick labels of `y` and the
/// axis title.
pub(crate) fn y_label_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: &AxisLayout,
    title: &str,
) -> Result<u32, PlotError> {
    let (w, th) = tick_and_title_px(area, y, title)?;
    let th = if title.is_empty() { 0 } else { th + 12 };
    Ok((w + 16 + th).clamp(30, 200))
}

impl Frame {
    pub const DEFAULT: Frame = Frame {
        top: 10,
        bottom: 8,
        left: 8,
        right: 25,
        x_label: 58,
        y_label: 84,
    };

    /// Plotting-area size inside an area of `dim` pixels.
    pub fn plot_size(&self, dim: (u32, u32)) -> (f64, f64) {
        let w = dim.0 as f64 - (self.left + self.right + self.y_label) as f64;
        let h = dim.1 as f64 - (self.top + self.bottom + self.x_label) as f64;
        (w.max(1.0), h.max(1.0))
    }
}

/// Expands the display-space ranges so that one unit spans the same number
/// of pixels on both axes.
pub(crate) fn equalise(
    x: (f64, f64),
    y: (f64, f64),
    plot_px: (f64, f64),
) -> ((f64, f64), (f64, f64)) {
    let ux = (x.1 - x.0) / plot_px.0;
    let uy = (y.1 - y.0) / plot_px.1;
    let u = ux.max(uy);
    let grow = |r: (f64, f64), px: f64| {
        let c = 0.5 * (r.0 + r.1);
        let half = 0.5 * u * px;
        (c - half, c + half)
    };
    (grow(x, plot_px.0), grow(y, plot_px.1))
}

pub(crate) fn build_chart<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    frame: Frame,
    x: &AxisLayout,
    y: &AxisLayout,
) -> Result<ChartContext<'a, DB, Coord2>, PlotError> {
    ChartBuilder::on(area)
        .margin_top(frame.top)
        .margin_bottom(frame.bottom)
        .margin_left(frame.left)
        .margin_right(frame.right)
        .x_label_area_size(frame.x_label)
        .y_label_area_size(frame.y_label)
        .build_cartesian_2d(x.coord(), y.coord())
        .map_err(de)
}

/// Draws axes, tick labels, axis titles and (optionally) grid lines.
pub(crate) fn draw_axes<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Coord2>,
    x: &AxisLayout,
    y: &AxisLayout,
    x_title: &str,
    y_title: &str,
    grid: bool,
) -> Result<(), PlotError> {
    let xf = |t: &f64| x.label(*t);
    let yf = |t: &f64| y.label(*t);
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(font(TICK_PT))
        .axis_desc_style(font(AXIS_TITLE_PT))
        .axis_style(BLACK.stroke_width(1))
        .bold_line_style(RGBColor(200, 200, 200).stroke_width(1))
        .light_line_style(RGBColor(236, 236, 236).stroke_width(1))
        .set_all_tick_mark_size(5);
    if !x_title.is_empty() {
        mesh.x_desc(x_title);
    }
    if !y_title.is_empty() {
        mesh.y_desc(y_title);
    }
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(de)
}

/// Draws a frame around the plotting area and outward minor tick marks on
/// the bottom and left axes (`area` is the area the chart was built on).
pub(crate) fn draw_frame<'a, DB: DrawingBackend + 'a>(
    area: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'a, DB, Coord2>,
    x: &AxisLayout,
    y: &AxisLayout,
) -> Result<(), PlotError> {
    let plot = chart.plotting_area();
    plot.draw(&Rectangle::new(
        [(x.lo, y.lo), (x.hi, y.hi)],
        BLACK.stroke_width(1),
    ))
    .map_err(de)?;
    let base = area.get_base_pixel();
    let px = |p: (f64, f64)| {
        let q = plot.map_coordinate(&p);
        (q.0 - base.0, q.1 - base.1)
    };
    let style = BLACK.stroke_width(1);
    for v in &x.ticks.minor {
        let (a, b) = px((x.t(*v), y.lo));
        area.draw(&PathElement::new(vec![(a, b), (a, b + 3)], style))
            .map_err(de)?;
    }
    for v in &y.ticks.minor {
        let (a, b) = px((x.lo, y.t(*v)));
        area.draw(&PathElement::new(vec![(a - 3, b), (a, b)], style))
            .map_err(de)?;
    }
    Ok(())
}

/// Splits `(x, y)` into runs of points drawable on the given scales, mapped
/// to display space; undrawable points (NaN, ≤ 0 on log axes) break lines.
pub(crate) fn segments(x: &[f64], y: &[f64], xs: Scale, ys: Scale) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    for (&a, &b) in x.iter().zip(y) {
        if xs.accepts(a) && ys.accepts(b) {
            cur.push((xs.forward(a), ys.forward(b)));
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Extra colour-bar decorations.
pub(crate) struct ColorBar<'a> {
    pub scale: &'a ColorScale,
    pub title: &'a str,
    pub extend_low: bool,
    pub extend_high: bool,
    pub missing: bool,
}

impl<'a> ColorBar<'a> {
    /// Colour bar whose decorations (saturation triangles, "no data" key)
    /// reflect `values`.
    pub fn for_values(scale: &'a ColorScale, title: &'a str, values: &[f64]) -> Self {
        Self {
            scale,
            title,
            extend_low: values.iter().any(|v| *v < scale.vmin),
            extend_high: values.iter().any(|v| *v > scale.vmax),
            missing: values.iter().any(|v| v.is_nan()),
        }
    }
}

/// Width in pixels reserved right of the plotting area for the colour bar.
pub(crate) const COLORBAR_WIDTH: u32 = 140;

/// Draws a vertical colour bar on `root` (absolute pixel coordinates) right
/// of the plotting area whose pixel ranges are `plot`.
pub(crate) fn draw_colorbar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: (std::ops::Range<i32>, std::ops::Range<i32>),
    cb: &ColorBar<'_>,
) -> Result<(), PlotError> {
    let bw = 18;
    let x0 = plot.0.end + 22;
    let x1 = x0 + bw;
    let extend = bw;
    let top = plot.1.start + if cb.extend_high { extend } else { 0 };
    let bottom = plot.1.end - 1 - if cb.extend_low { extend } else { 0 };
    let bottom = bottom.max(top + 10);
    let n = (bottom - top).max(1);
    // Colour strips, one per pixel row.
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        let c = rgb(cb.scale.map.at(t));
        let y = bottom - i;
        root.draw(&Rectangle::new([(x0, y - 1), (x1, y)], c.filled()))
            .map_err(de)?;
    }
    let outline = BLACK.stroke_width(1);
    if cb.extend_high {
        let c = rgb(cb.scale.map.top());
        let tri = vec![(x0, top), (x1, top), ((x0 + x1) / 2, top - extend)];
        root.draw(&Polygon::new(tri.clone(), c.filled()))
            .map_err(de)?;
        root.draw(&PathElement::new(vec![tri[0], tri[2], tri[1]], outline))
            .map_err(de)?;
    }
    if cb.extend_low {
        let c = rgb(cb.scale.map.bottom());
        let tri = vec![(x0, bottom), (x1, bottom), ((x0 + x1) / 2, bottom + extend)];
        root.draw(&Polygon::new(tri.clone(), c.filled()))
            .map_err(de)?;
        root.draw(&PathElement::new(vec![tri[0], tri[2], tri[1]], outline))
            .map_err(de)?;
    }
    root.draw(&Rectangle::new([(x0, top), (x1, bottom)], outline))
        .map_err(de)?;

    // Ticks and labels.
    let sc = if cb.scale.log {
        Scale::Log
    } else {
        Scale::Linear
    };
    let tk = ticks(sc, cb.scale.vmin, cb.scale.vmax);
    let (f0, f1) = (sc.forward(cb.scale.vmin), sc.forward(cb.scale.vmax));
    let ypix = |v: f64| bottom as f64 - (sc.forward(v) - f0) / (f1 - f0) * (bottom - top) as f64;
    let label_style = font(TICK_PT).pos(Pos::new(HPos::Left, VPos::Center));
    let mut max_w = 0u32;
    for (v, label) in tk.major.iter().zip(&tk.labels) {
        let y = ypix(*v).round() as i32;
        root.draw(&PathElement::new(vec![(x1, y), (x1 + 5, y)], outline))
            .map_err(de)?;
        root.draw(&Text::new(label.clone(), (x1 + 8, y), label_style.clone()))
            .map_err(de)?;
        let (w, _) = root.estimate_text_size(label, &font(TICK_PT)).map_err(de)?;
        max_w = max_w.max(w);
    }
    for v in &tk.minor {
        let y = ypix(*v).round() as i32;
        root.draw(&PathElement::new(vec![(x1, y), (x1 + 3, y)], outline))
            .map_err(de)?;
    }
    if cb.missing {
        let y = plot.1.end + 14;
        root.draw(&Rectangle::new(
            [(x0, y), (x1, y + bw)],
            rgb(MISSING_COLOR).filled(),
        ))
        .map_err(de)?;
        root.draw(&Rectangle::new([(x0, y), (x1, y + bw)], outline))
            .map_err(de)?;
        root.draw(&Text::new(
            "no data",
            (x1 + 8, y + bw / 2),
            label_style.clone(),
        ))
        .map_err(de)?;
    }
    if !cb.title.is_empty() {
        let (_, th) = root
            .estimate_text_size(cb.title, &font(AXIS_TITLE_PT))
            .map_err(de)?;
        let x = x1 + 18 + max_w as i32 + th as i32 / 2;
        let y = (plot.1.start + plot.1.end) / 2;
        let style = font(AXIS_TITLE_PT)
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Center));
        root.draw(&Text::new(cb.title.to_string(), (x, y), style))
            .map_err(de)?;
    }
    Ok(())
}

/// Clips a display-space polyline to the rectangle `[x0, x1] × [y0, y1]`
/// (Liang–Barsky per segment), returning the visible runs.
pub(crate) fn clip_polyline(
    pts: &[(f64, f64)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let inside = |p: (f64, f64)| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1;
    if pts.len() == 1 && inside(pts[0]) {
        return vec![pts.to_vec()];
    }
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let mut t0 = 0.0f64;
        let mut t1 = 1.0f64;
        let mut visible = true;
        for (p, q) in [
            (-dx, a.0 - x0),
            (dx, x1 - a.0),
            (-dy, a.1 - y0),
            (dy, y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    visible = false;
                    break;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if !visible || t0 > t1 {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            continue;
        }
        let pa = (a.0 + t0 * dx, a.1 + t0 * dy);
        let pb = (a.0 + t1 * dx, a.1 + t1 * dy);
        if cur.is_empty() {
            cur.push(pa);
        } else if t0 > 0.0 {
            out.push(std::mem::take(&mut cur));
            cur.push(pa);
        }
        cur.push(pb);
        if t1 < 1.0 {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Draws a display-space polyline (already split into drawable runs),
/// clipped to the axes.
pub(crate) fn draw_polyline<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Coord2>,
    runs: &[Vec<(f64, f64)>],
    (x, y): (&AxisLayout, &AxisLayout),
    color: Rgb,
    width_px: u32,
    dashed: bool,
) -> Result<(), PlotError> {
    let style = rgb(color).stroke_width(width_px.max(1));
    for run in runs {
        for piece in clip_polyline(run, (x.lo, x.hi), (y.lo, y.hi)) {
            if dashed {
                let dash = 8 + 2 * width_px;
                chart
                    .draw_series(DashedLineSeries::new(piece, dash, dash / 2 + 2, style))
                    .map_err(de)?;
            } else {
                chart
                    .draw_series(LineSeries::new(piece, style))
                    .map_err(de)?;
            }
        }
    }
    Ok(())
}

/// The plotting area of a chart built with `frame` on an area of `dim` pixels, relative to
/// the area (as [`build_chart`] lays it out).
pub(crate) fn plot_rect(dim: (u32, u32), frame: &Frame) -> PxRect {
    PxRect {
        x0: (frame.left + frame.y_label) as f64,
        y0: frame.top as f64,
        x1: dim.0 as f64 - frame.right as f64,
        y1: dim.1 as f64 - (frame.bottom + frame.x_label) as f64,
    }
}

/// The plotting area of a built chart, relative to `area`.
pub(crate) fn chart_rect<'a, DB: DrawingBackend + 'a>(
    area: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'a, DB, Coord2>,
) -> PxRect {
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let base = area.get_base_pixel();
    PxRect {
        x0: (xr.start - base.0) as f64,
        y0: (yr.start - base.1) as f64,
        x1: (xr.end - base.0) as f64,
        y1: (yr.end - base.1) as f64,
    }
}

/// Width of the right margin that a secondary y axis with ticks of `y` and `title` needs.
pub(crate) fn right_axis_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: &AxisLayout,
    title: &str,
) -> Result<u32, PlotError> {
    let (w, th) = tick_and_title_px(area, y, title)?;
    let th = if title.is_empty() { 0 } else { th + 14 };
    Ok((w + 14 + th + 8).clamp(30, 220))
}

/// Draws a secondary y axis `y2` on the right edge of the plotting area `plot` (relative to
/// `area`): ticks outward, labels and the title (rotated, reading upwards).
pub(crate) fn draw_right_axis<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: PxRect,
    y2: &AxisLayout,
    title: &str,
) -> Result<(), PlotError> {
    let x = plot.x1.round() as i32 - 1;
    let ypix = |v: f64| {
        let f = (y2.t(v) - y2.lo) / (y2.hi - y2.lo);
        (plot.y1 - f * plot.h()).round() as i32
    };
    let style = BLACK.stroke_width(1);
    let label_style = font(TICK_PT).pos(Pos::new(HPos::Left, VPos::Center));
    let mut max_w = 0;
    for (v, label) in y2.ticks.major.iter().zip(&y2.ticks.labels) {
        let y = ypix(*v);
        area.draw(&PathElement::new(vec![(x, y), (x + 5, y)], style))
            .map_err(de)?;
        area.draw(&Text::new(label.clone(), (x + 8, y), label_style.clone()))
            .map_err(de)?;
        max_w = max_w.max(
            area.estimate_text_size(label, &font(TICK_PT))
                .map_err(de)?
                .0,
        );
    }
    for v in &y2.ticks.minor {
        let y = ypix(*v);
        area.draw(&PathElement::new(vec![(x, y), (x + 3, y)], style))
            .map_err(de)?;
    }
    if !title.is_empty() {
        let (_, th) = area
            .estimate_text_size(title, &font(AXIS_TITLE_PT))
            .map_err(de)?;
        let tx = x + 14 + max_w as i32 + th as i32 / 2;
        let ty = ((plot.y0 + plot.y1) / 2.0).round() as i32;
        let style = font(AXIS_TITLE_PT)
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Center));
        area.draw(&Text::new(title.to_string(), (tx, ty), style))
            .map_err(de)?;
    }
    Ok(())
}

/// Margin added on each side of an automatically scaled linear axis, as a fraction of the
/// data range, so that no data point lies on the frame.
pub(crate) const AUTO_MARGIN: f64 = 0.04;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_splits_runs() {
        let pts = [(-1.0, 0.5), (0.5, 0.5), (2.0, 0.5), (2.0, 0.7), (0.5, 0.7)];
        let runs = clip_polyline(&pts, (0.0, 1.0), (0.0, 1.0));
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], vec![(0.0, 0.5), (0.5, 0.5), (1.0, 0.5)]);
        assert_eq!(runs[1], vec![(1.0, 0.7), (0.5, 0.7)]);
        assert!(clip_polyline(&[(2.0, 2.0), (3.0, 3.0)], (0.0, 1.0), (0.0, 1.0)).is_empty());
    }

    #[test]
    fn equal_aspect_expands_smaller_span() {
        let ((x0, x1), (y0, y1)) = equalise((0.0, 1.0), (0.0, 1.0), (200.0, 100.0));
        assert!(((x1 - x0) - 2.0).abs() < 1e-12 && ((y1 - y0) - 1.0).abs() < 1e-12);
        assert!((x0 + 0.5).abs() < 1e-12);
    }
}
