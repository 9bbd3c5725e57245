//! End-to-end tests: every plotting function writes a decodable PNG and a
//! well-formed-looking SVG.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use pdamp_plot::{
    Axis, ColorScale, FrfPlot, FrfSeries, HeatMap, LegendPosition, LinePlot, Marker, PlotError,
    Polyline, Quiver, QuiverKey, Rgb, ScatterField, Series, XSpan, frf_plot, frf_plot_with,
    heat_map, line_plot, scatter_field,
};

/// Fresh, unique directory under the system temp dir, removed on drop
/// unless `PDAMP_PLOT_KEEP` is set (to look at the plots).
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::env::var_os("PDAMP_PLOT_KEEP").is_none() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

fn temp_dir(name: &str) -> TempDir {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "pdamp-plot-test-{}-{}-{name}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// Checks the PNG signature and returns the IHDR (width, height).
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert!(b.len() > 33, "PNG too short");
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&b[12..16], b"IHDR");
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    (w, h)
}

fn svg_text(path: &Path) -> String {
    let s = std::fs::read_to_string(path).unwrap();
    assert!(
        s.trim_start().starts_with("<svg"),
        "SVG start: {}",
        &s[..s.len().min(80)]
    );
    assert!(s.trim_end().ends_with("</svg>"), "SVG end");
    s
}

/// The texts of an SVG's `<text>` elements, trimmed.
fn svg_labels(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

/// No temporary files are left behind.
fn only_outputs(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn logspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 10f64.powf(a + (b - a) * i as f64 / (n - 1) as f64))
        .collect()
}

#[test]
fn heat_map_writes_png_and_svg() {
    let dir = temp_dir("heat");
    let f = logspace(1.0, 3.0, 40); // 10 Hz … 1 kHz
    let a = logspace(-5.0, -2.0, 30); // 10 µm … 10 mm
    let mut v = Vec::new();
    for (iy, ai) in a.iter().enumerate() {
        for (ix, fi) in f.iter().enumerate() {
            // Effective loss factor-like ridge; some values exceed 1.
            let g = ai * (2.0 * std::f64::consts::PI * fi).powi(2) / 9.81;
            let val = 1.4 * (-(g.ln() - 1.0).powi(2) / 2.0).exp();
            v.push(if ix == 3 && iy == 4 { f64::NAN } else { val });
        }
    }
    let mut map = HeatMap::new(f.clone(), a, v);
    map.title = "Effective loss factor (values ≥ 1 saturate)".into();
    map.x_axis = Axis::log("frequency_hz (Hz)");
    map.y_axis = Axis::log("amplitude_m (m)");
    map.colorbar_title = "η̄ (-)".into();
    map.color = ColorScale::linear(0.0, 1.0);
    let boundary: Vec<f64> = f
        .iter()
        .map(|fi| 9.81 / (2.0 * std::f64::consts::PI * fi).powi(2))
        .collect();
    map.overlays
        .push(Polyline::new("Γ = 1", f.clone(), boundary.clone()));
    let mut dashed = Polyline::new(
        "Γ = 4",
        f.clone(),
        boundary.iter().map(|b| 4.0 * b).collect(),
    );
    dashed.dashed = true;
    map.overlays.push(dashed);
    map.legend_position = LegendPosition::LowerLeft;

    let out = heat_map(dir.join("eta_map"), &map).unwrap();
    assert_eq!(out.png, dir.join("eta_map.png"));
    assert_eq!(png_size(&out.png), map.size_px);
    let svg = svg_text(&out.svg);
    for t in [
        "frequency_hz (Hz)",
        "amplitude_m (m)",
        "Effective loss factor",
        "η̄ (-)",
        "≥ 1 saturate",
        "Γ = 1",
    ] {
        assert!(svg.contains(t), "SVG lacks {t:?}");
    }
    assert!(svg.contains("10⁻³"), "decade tick labels");
    assert_eq!(only_outputs(&dir), ["eta_map.png", "eta_map.svg"]);
}

#[test]
fn heat_map_linear_log_color_and_limits() {
    let dir = temp_dir("heat-lin");
    let x: Vec<f64> = (0..12).map(|i| i as f64 * 5.0).collect();
    let y: Vec<f64> = (0..8).map(|i| 1.0 + i as f64).collect();
    let v: Vec<f64> = (0..96).map(|i| 10f64.powf(i as f64 / 24.0 - 2.0)).collect();
    let mut map = HeatMap::new(x, y, v);
    map.x_axis = Axis::linear("acceleration_m_s2 (m/s²)").with_limits(4.0, 40.0);
    map.y_axis = Axis::linear("intensity (-)");
    map.color = ColorScale::log(1e-2, 1.0);
    map.colorbar_title = "energy (J)".into();
    let out = heat_map(dir.join("sub/dir/map"), &map).unwrap();
    assert_eq!(png_size(&out.png), map.size_px);
    let svg = svg_text(&out.svg);
    assert!(svg.contains("acceleration_m_s2 (m/s²)") && svg.contains("energy (J)"));
}

#[test]
fn heat_map_rejects_bad_input() {
    let dir = temp_dir("heat-bad");
    let map = HeatMap::new(vec![1.0, 2.0], vec![1.0], vec![0.0]);
    assert!(matches!(
        heat_map(dir.join("bad"), &map),
        Err(PlotError::InvalidInput(_))
    ));
    let mut map = HeatMap::new(vec![0.0, 2.0], vec![1.0], vec![0.0, 1.0]);
    map.x_axis = Axis::log("x");
    assert!(heat_map(dir.join("bad"), &map).is_err());
    assert!(only_outputs(&dir).is_empty());
}

#[test]
fn line_plot_writes_png_and_svg() {
    let dir = temp_dir("line");
    let t: Vec<f64> = (0..400).map(|i| i as f64 * 1e-3).collect();
    let decay = |zeta: f64| -> Vec<f64> {
        t.iter()
            .map(|ti| (-zeta * 2.0 * std::f64::consts::PI * 50.0 * ti).exp())
            .collect()
    };
    let mut p = LinePlot::new(Axis::linear("time_s (s)"), Axis::log("energy_j (J)"));
    p.title = "Free decay".into();
    p.series
        .push(Series::new("ζ = 0.01", t.clone(), decay(0.01)));
    p.series
        .push(Series::new("ζ = 0.05", t.clone(), decay(0.05)).with_marker(Marker::Circle));
    let tp: Vec<f64> = t.iter().step_by(40).copied().collect();
    let yp: Vec<f64> = tp
        .iter()
        .map(|ti| 0.8 * (-0.02 * 2.0 * std::f64::consts::PI * 50.0 * ti).exp())
        .collect();
    p.series
        .push(Series::new("DEM", tp.clone(), yp.clone()).points_only(Marker::Square));
    p.series.push(
        Series::new("tri", tp.clone(), yp.iter().map(|y| y * 0.5).collect())
            .points_only(Marker::Triangle),
    );
    p.series.push(
        Series::new("cross", tp, yp.iter().map(|y| y * 0.25).collect()).points_only(Marker::Cross),
    );
    // A series with NaN and non-positive values (skipped on the log axis).
    p.series.push(Series::new(
        "gappy",
        vec![0.0, 0.1, 0.2, 0.3],
        vec![0.5, f64::NAN, -1.0, 0.1],
    ));
    let out = line_plot(dir.join("decay"), &p).unwrap();
    assert_eq!(png_size(&out.png), p.size_px);
    let svg = svg_text(&out.svg);
    assert!(svg.contains("time_s (s)") && svg.contains("energy_j (J)") && svg.contains("ζ = 0.05"));

    let mut bad = p.clone();
    bad.series[0].y.pop();
    assert!(line_plot(dir.join("bad"), &bad).is_err());
}

#[test]
fn frf_plot_writes_two_panels() {
    let dir = temp_dir("frf");
    let f = logspace(0.5, 3.0, 300);
    let h = |fn_hz: f64, zeta: f64| -> Vec<(f64, f64)> {
        f.iter()
            .map(|fi| {
                let r = fi / fn_hz;
                let (re, im) = (1.0 - r * r, 2.0 * zeta * r);
                let d = re * re + im * im;
                (re / d, -im / d)
            })
            .collect()
    };
    let series = [
        FrfSeries::from_complex("empty", &h(100.0, 0.01)),
        FrfSeries::from_complex("with particles", &h(95.0, 0.08)),
    ];
    let out = frf_plot(dir.join("frf"), &f, &series).unwrap();
    assert_eq!(png_size(&out.png), (800, 720));
    let svg = svg_text(&out.svg);
    assert!(
        svg.contains("phase (deg)") && svg.contains("frequency (Hz)") && svg.contains("magnitude")
    );

    let mut p = FrfPlot::new(f.clone(), series.to_vec());
    p.title = "Receptance".into();
    p.frequency_axis = Axis::log("frequency_hz (Hz)");
    p.magnitude_title = "|H| (m/N)".into();
    let out = frf_plot_with(dir.join("frf_log"), &p).unwrap();
    let svg = svg_text(&out.svg);
    assert!(svg.contains("|H| (m/N)") && svg.contains("Receptance"));
    assert_eq!(png_size(&out.png), p.size_px);
}

#[test]
fn scatter_field_with_arrows() {
    let dir = temp_dir("scatter");
    let mut x = Vec::new();
    let mut y = Vec::new();
    let mut u = Vec::new();
    let mut w = Vec::new();
    for i in 0..20 {
        for j in 0..8 {
            let (px, py) = (i as f64 * 2e-3, j as f64 * 2e-3);
            x.push(px);
            y.push(py);
            u.push(-(py - 7e-3));
            w.push(px - 19e-3);
        }
    }
    let speed: Vec<f64> = u.iter().zip(&w).map(|(a, b)| a.hypot(*b) / 0.02).collect();
    let mut field = ScatterField::new(x, y, speed);
    field.title = "Phase 90°".into();
    field.x_axis = Axis::linear("x_m (m)");
    field.y_axis = Axis::linear("z_m (m)");
    field.colorbar_title = "|v|/V (-)".into();
    field.color = ColorScale::linear(0.0, 0.8);
    field.arrows = Some(Quiver::new(u, w));
    field.value[5] = f64::NAN;
    let out = scatter_field(dir.join("field"), &field).unwrap();
    assert_eq!(png_size(&out.png), field.size_px);
    let svg = svg_text(&out.svg);
    assert!(svg.contains("x_m (m)") && svg.contains("z_m (m)") && svg.contains("|v|/V (-)"));

    field.equal_aspect = false;
    field.arrows = None;
    scatter_field(dir.join("field_free"), &field).unwrap();
}

#[test]
fn rewriting_replaces_files_atomically() {
    let dir = temp_dir("rewrite");
    let mut p = LinePlot::new(Axis::linear("x (m)"), Axis::linear("y (m)"));
    p.series
        .push(Series::new("a", vec![0.0, 1.0], vec![0.0, 1.0]));
    let first = line_plot(dir.join("p"), &p).unwrap();
    p.size_px = (640, 400);
    p.y_axis.title = "displacement_m (m)".into();
    let second = line_plot(dir.join("p"), &p).unwrap();
    assert_eq!(first, second);
    assert_eq!(png_size(&second.png), (640, 400));
    assert!(svg_text(&second.svg).contains("displacement_m (m)"));
    assert_eq!(only_outputs(&dir), ["p.png", "p.svg"]);
    // Stems with dots keep their full name.
    let out = line_plot(dir.join("run.v2"), &p).unwrap();
    assert_eq!(out.svg, dir.join("run.v2.svg"));
}

/// A time series with a secondary (right) axis, a shaded span and a legend pushed outside by
/// data everywhere; the SVG has both axis titles, the span's legend entry and 1-2-5 labels on
/// a log axis over less than two decades.
#[test]
fn line_plot_secondary_axis_and_span() {
    let dir = temp_dir("twin");
    let t: Vec<f64> = (0..2000).map(|i| i as f64 * 1e-3).collect();
    let w = 2.0 * std::f64::consts::PI * 5.0;
    let mut p = LinePlot::new(Axis::linear("time (s)"), Axis::linear("bed force f_p (N)"));
    p.title = "force and displacement".into();
    p.y2_axis = Some(Axis::linear("container displacement x (mm)"));
    p.spans.push(XSpan::new(0.0, 0.6, "transient cycles"));
    p.series.push(Series::new(
        "bed force",
        t.clone(),
        t.iter().map(|t| 3.0 * (w * t + 0.4).sin()).collect(),
    ));
    p.series.push(
        Series::new(
            "displacement",
            t.clone(),
            t.iter().map(|t| 2.0 * (w * t).sin()).collect(),
        )
        .on_secondary_axis(),
    );
    let out = line_plot(dir.join("twin"), &p).unwrap();
    let svg = svg_text(&out.svg);
    for s in [
        "time (s)",
        "bed force f_p (N)",
        "container displacement x (mm)",
        "transient cycles",
        "displacement",
    ] {
        assert!(svg.contains(s), "SVG lacks {s:?}");
    }

    let mut q = LinePlot::new(Axis::log("frequency (Hz)"), Axis::linear("η̄ (-)"));
    q.series.push(Series::new(
        "η̄",
        vec![1.0, 3.0, 10.0, 30.0],
        vec![0.1, 0.4, 0.9, 0.3],
    ));
    q.legend_position = LegendPosition::Outside;
    let out = line_plot(dir.join("log125"), &q).unwrap();
    let labels = svg_labels(&svg_text(&out.svg));
    for l in ["1", "2", "5", "10", "20"] {
        assert!(
            labels.iter().any(|s| s == l),
            "no tick label {l}: {labels:?}"
        );
    }
}

/// Arrows with a reference key and the container's outline; the key's label is in the SVG.
#[test]
fn scatter_field_with_key_and_outline() {
    let dir = temp_dir("quiver-key");
    let (mut x, mut y, mut u, mut v) = (vec![], vec![], vec![], vec![]);
    for i in 0..24 {
        for j in 0..12 {
            x.push(1.0 + 2.0 * i as f64);
            y.push(1.0 + 2.0 * j as f64);
            u.push((j as f64 - 6.0) * 0.1);
            v.push(-(i as f64 - 12.0) * 0.05);
        }
    }
    let speed: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a.hypot(*b)).collect();
    let mut f = ScatterField::new(x, y, speed);
    f.x_axis = Axis::linear("along excitation (mm)");
    f.y_axis = Axis::linear("up (mm)");
    let mut q = Quiver::new(u, v);
    q.key = Some(QuiverKey {
        magnitude: 0.5,
        label: "|v|/V = 0.5 (0.12 m/s)".into(),
    });
    f.arrows = Some(q);
    let mut outline = Polyline::new(
        "container",
        vec![0.0, 48.0, 48.0, 0.0, 0.0],
        vec![0.0, 0.0, 24.0, 24.0, 0.0],
    );
    outline.color = Some(Rgb(0, 0, 0));
    f.outlines.push(outline);
    let out = scatter_field(dir.join("field"), &f).unwrap();
    let svg = svg_text(&out.svg);
    assert!(svg.contains("|v|/V = 0.5 (0.12 m/s)") && svg.contains("up (mm)"));
}

/// Map overlays with annotations (lines of constant X) are written on the map.
#[test]
fn heat_map_annotated_overlays() {
    let dir = temp_dir("heat-annot");
    let f = logspace(1.0, 3.0, 12);
    let g = logspace(0.0, 1.5, 9);
    let v: Vec<f64> = (0..f.len() * g.len())
        .map(|k| (k % 7) as f64 / 7.0)
        .collect();
    let mut map = HeatMap::new(f.clone(), g, v);
    map.x_axis = Axis::log("frequency f (Hz)");
    map.y_axis = Axis::log("intensity Γ (-)");
    let mut line = Polyline::new(
        "",
        f.clone(),
        f.iter()
            .map(|f| 1e-4 * (2.0 * std::f64::consts::PI * f).powi(2) / 9.81)
            .collect(),
    );
    line.annotation = "X = 0.1 mm".into();
    map.overlays.push(line);
    map.overlays
        .push(Polyline::new("A = g", f.clone(), vec![1.0; f.len()]));
    let out = heat_map(dir.join("map"), &map).unwrap();
    let svg = svg_text(&out.svg);
    assert!(svg.contains("X = 0.1 mm") && svg.contains("A = g"));
}
