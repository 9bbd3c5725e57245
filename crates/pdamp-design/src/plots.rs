//! Plots of damper results: effective-field maps [D Fig. 3.6, 8.3], phase-resolved velocity
//! fields [D Fig. 3.5c, 8.2], particle trajectories [D Fig. 3.5b], and the bed force and
//! container displacement of a point over time and as hysteresis loops [D Sect. 3.2.2]. PNG
//! and SVG each.

use crate::DesignError;
use crate::damper::PointResult;
use crate::fields::FieldGrid;
use crate::motion::MotionRecorder;
use pdamp_plot::{
    Axis, ColorScale, HeatMap, LinePlot, Polyline, Quiver, QuiverKey, Rgb, ScatterField, Series,
    XSpan,
};
use std::path::{Path, PathBuf};

/// [`pdamp_plot::heat_map`] with the stem in the error.
fn heat_map(stem: PathBuf, map: &HeatMap) -> Result<(), DesignError> {
    pdamp_plot::heat_map(&stem, map).map_err(DesignError::plot(&stem))?;
    Ok(())
}

/// [`pdamp_plot::line_plot`] with the stem in the error.
fn line_plot(stem: PathBuf, plot: &LinePlot) -> Result<(), DesignError> {
    pdamp_plot::line_plot(&stem, plot).map_err(DesignError::plot(&stem))?;
    Ok(())
}

/// [`pdamp_plot::scatter_field`] with the stem in the error.
fn scatter_field(stem: PathBuf, field: &ScatterField) -> Result<(), DesignError> {
    pdamp_plot::scatter_field(&stem, field).map_err(DesignError::plot(&stem))?;
    Ok(())
}

/// Maps of η̄ (colour saturating at 1, as in the dissertation), m̄_bed/m_bed, Ẽ and the split of
/// the dissipation over the grid: `effective_loss_factor`, `effective_mass_ratio`,
/// `dissipated_energy`, `dissipation_normal_over_tangential` [D Fig. 8.8],
/// `dissipation_wall_share` (.png/.svg).
pub fn field_maps(grid: &FieldGrid, points: &[PointResult], out: &Path) -> Result<(), DesignError> {
    field_maps_with(grid, points, out, None)
}

/// The grid's amplitude-axis value of the displacement amplitude `x_m` at `f_hz`.
fn axis_value(grid: &FieldGrid, f_hz: f64, x_m: f64) -> f64 {
    use pdamp_dem::math::STANDARD_GRAVITY_M_S2;
    use pdamp_scenario::schema::AmplitudeAxis;
    let w2 = (2.0 * std::f64::consts::PI * f_hz).powi(2);
    match grid.amplitude_axis {
        AmplitudeAxis::Displacement => x_m,
        AmplitudeAxis::Acceleration => x_m * w2,
        AmplitudeAxis::Intensity => x_m * w2 / STANDARD_GRAVITY_M_S2,
    }
}

/// Lines drawn over the η̄ map as in D's figures: A = g (Γ = 1, where the bed can lift off) and,
/// when the bed's clearance h is known, the bouncing optimum X_opt = h/π [D Eq. 6.11, 7.16, 8.2].
fn eta_overlays(grid: &FieldGrid, clearance_m: Option<f64>) -> Vec<pdamp_plot::Polyline> {
    use pdamp_dem::math::STANDARD_GRAVITY_M_S2;
    let fs = line_frequencies(grid);
    let line = |label: &str, x_of_f: &dyn Fn(f64) -> f64, dashed: bool| {
        let mut l = pdamp_plot::Polyline::new(
            label,
            fs.clone(),
            fs.iter().map(|&f| axis_value(grid, f, x_of_f(f))).collect(),
        );
        l.color = Some(pdamp_plot::Rgb(255, 255, 255));
        l.dashed = dashed;
        l
    };
    let mut v = vec![line(
        "A = g",
        &|f| STANDARD_GRAVITY_M_S2 / (2.0 * std::f64::consts::PI * f).powi(2),
        false,
    )];
    if let Some(h) = clearance_m.filter(|h| h.is_finite() && *h > 0.0) {
        v.push(line(
            &format!("X_opt = h/π, h = {:.2} mm", h * 1e3),
            &|_| h / std::f64::consts::PI,
            true,
        ));
    }
    v
}

/// Frequencies along the grid's frequency axis for drawing lines over a map (65, log or
/// linear as the axis).
fn line_frequencies(grid: &FieldGrid) -> Vec<f64> {
    let (f0, f1) = (
        grid.frequencies_hz[0],
        *grid
            .frequencies_hz
            .last()
            .unwrap_or(&grid.frequencies_hz[0]),
    );
    (0..=64)
        .map(|k| {
            let s = k as f64 / 64.0;
            if grid.frequency_log {
                f0 * (f1 / f0).powf(s)
            } else {
                f0 + (f1 - f0) * s
            }
        })
        .collect()
}

/// Lines of constant displacement amplitude X over a map whose amplitude axis is the
/// acceleration A = XΩ² or the intensity Γ = XΩ²/g [D Eq. 3.9–3.11], as in D's field
/// figures: the decades of X (every other one when more than four cross the map; 1-2-5
/// values when fewer than two do) that cross the map's range, each annotated "X = … mm".
/// None on a displacement axis (X is the axis itself).
fn constant_x_overlays(grid: &FieldGrid) -> Vec<Polyline> {
    use pdamp_scenario::schema::AmplitudeAxis;
    if grid.amplitude_axis == AmplitudeAxis::Displacement || grid.frequencies_hz.is_empty() {
        return Vec::new();
    }
    let fs = line_frequencies(grid);
    let (a_lo, a_hi) = grid
        .amplitude_values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    let (f_lo, f_hi) = (fs[0].min(fs[fs.len() - 1]), fs[0].max(fs[fs.len() - 1]));
    // Axis value per metre of X is increasing in f: X crosses the map for X in [x_lo, x_hi].
    let (x_lo, x_hi) = (
        a_lo / axis_value(grid, f_hi, 1.0),
        a_hi / axis_value(grid, f_lo, 1.0),
    );
    if !(x_lo > 0.0 && x_hi > x_lo && x_hi.is_finite()) {
        return Vec::new();
    }
    let inside = |x: f64| x > x_lo * (1.0 + 1e-9) && x < x_hi * (1.0 - 1e-9);
    let (k0, k1) = (x_lo.log10().floor() as i32, x_hi.log10().ceil() as i32);
    let mut xs: Vec<f64> = (k0..=k1)
        .map(|k| 10f64.powi(k))
        .filter(|x| inside(*x))
        .collect();
    if xs.len() > 4 {
        xs = xs.into_iter().step_by(2).collect();
    } else if xs.len() < 2 {
        xs = (k0..=k1)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
            .filter(|x| inside(*x))
            .collect();
        if xs.len() > 4 {
            xs = xs.into_iter().step_by(2).collect();
        }
    }
    xs.into_iter()
        .map(|x| {
            let mut l = Polyline::new(
                "",
                fs.clone(),
                fs.iter().map(|&f| axis_value(grid, f, x)).collect(),
            );
            l.color = Some(Rgb(225, 225, 225));
            l.width_px = 1;
            l.dashed = true;
            l.annotation = format!("X = {} mm", pdamp_plot::format_number(x * 1e3));
            l
        })
        .collect()
}

/// [`field_maps`] with the bed's clearance h along the excitation for the X_opt = h/π line
/// on the η̄ map (the A = g line is always drawn).
pub fn field_maps_with(
    grid: &FieldGrid,
    points: &[PointResult],
    out: &Path,
    clearance_m: Option<f64>,
) -> Result<(), DesignError> {
    let nx = grid.frequencies_hz.len();
    let ny = grid.amplitude_values.len();
    if nx < 2 || ny < 2 {
        return Ok(()); // a map needs a 2-D grid; fields.csv has the values
    }
    let pick = |f: &dyn Fn(&PointResult) -> f64| -> Vec<f64> {
        let mut v = vec![f64::NAN; nx * ny];
        for (k, p) in points.iter().enumerate() {
            let (i, j) = (k / ny, k % ny);
            v[j * nx + i] = f(p);
        }
        v
    };
    let x_axis = if grid.frequency_log {
        Axis::log("frequency f (Hz)")
    } else {
        Axis::linear("frequency f (Hz)")
    };
    let y_axis = if grid.amplitude_log {
        Axis::log(grid.amplitude_title())
    } else {
        Axis::linear(grid.amplitude_title())
    };
    let constant_x = constant_x_overlays(grid);
    let make = |values: Vec<f64>, color: ColorScale, title: &str, bar: &str| {
        let mut m = HeatMap::new(
            grid.frequencies_hz.clone(),
            grid.amplitude_values.clone(),
            values,
        );
        m.x_axis = x_axis.clone();
        m.y_axis = y_axis.clone();
        m.color = color;
        m.title = title.to_string();
        m.colorbar_title = bar.to_string();
        m.overlays = constant_x.clone();
        m
    };
    let eta = pick(&|p| p.effective_loss_factor);
    let mut eta_map = make(
        eta,
        ColorScale::linear(0.0, 1.0),
        "effective loss factor (values ≥ 1 saturate)",
        "η̄ (-)",
    );
    eta_map
        .overlays
        .splice(0..0, eta_overlays(grid, clearance_m));
    heat_map(out.join("effective_loss_factor"), &eta_map)?;
    let mass = pick(&|p| p.effective_mass_ratio);
    let mmax = mass
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(1.0_f64, f64::max);
    heat_map(
        out.join("effective_mass_ratio"),
        &make(
            mass,
            ColorScale::linear(0.0, mmax),
            "effective particle mass ratio",
            "m̄_bed / m_bed (-)",
        ),
    )?;
    let e = pick(&|p| p.dissipated_energy_per_cycle_j);
    let pos: Vec<f64> = e
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let color = if pos.len() >= 2 {
        let lo = pos.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = pos.iter().copied().fold(0.0, f64::max);
        if hi > lo {
            ColorScale::log(lo, hi)
        } else {
            ColorScale::linear(0.0, hi.max(1e-300))
        }
    } else {
        ColorScale::linear(0.0, 1.0)
    };
    let e: Vec<f64> = e
        .into_iter()
        .map(|v| if v > 0.0 { v } else { f64::NAN })
        .collect();
    // Ratio of normal to tangential dissipation [D Fig. 8.8], log scale 1/4 … 4.
    let ratio = pick(&|p| {
        let n = p.share_normal_pp + p.share_normal_pw;
        let t = p.share_tangential_pp + p.share_tangential_pw;
        if n > 0.0 && t > 0.0 { n / t } else { f64::NAN }
    });
    heat_map(
        out.join("dissipation_normal_over_tangential"),
        &make(
            ratio,
            ColorScale::log(0.25, 4.0),
            "dissipation in normal / tangential contacts",
            "E_diss,n / E_diss,t (-)",
        ),
    )?;
    let wall = pick(&|p| p.share_normal_pw + p.share_tangential_pw);
    heat_map(
        out.join("dissipation_wall_share"),
        &make(
            wall,
            ColorScale::linear(0.0, 1.0),
            "share of the dissipation in particle–wall contacts",
            "E_diss,pw / E_diss (-)",
        ),
    )?;
    heat_map(
        out.join("dissipated_energy"),
        &make(e, color, "dissipated energy per cycle", "Ẽ_diss (J)"),
    )?;
    Ok(())
}

/// `v` rounded to `digits` significant digits, as a tick label would show it.
fn significant(v: f64, digits: usize) -> String {
    let r: f64 = format!("{v:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(v);
    pdamp_plot::format_number(r)
}

/// Largest 1-2-5 × 10ⁿ value not above `v` (for reference arrows), `v` > 0.
fn nice_below(v: f64) -> f64 {
    let e = 10f64.powf(v.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * e)
        .find(|x| *x <= v * (1.0 + 1e-12))
        .unwrap_or(e)
}

/// How the field plane (coordinates along `rec.axes`) is drawn: a horizontal excitation
/// along the plot's x axis with up along y; a vertical excitation (gravity along it) upwards
/// along y, the perpendicular direction along x, so that the bed lies at the bottom as it does
/// in the container.
struct PlaneView {
    /// Draw (axis 1, s · axis 0) instead of (axis 0, axis 1).
    vertical: bool,
    /// +1 when the excitation points up, −1 when down.
    sign: f64,
}

impl PlaneView {
    fn of(rec: &MotionRecorder) -> Self {
        PlaneView {
            vertical: rec.excitation_up != 0.0,
            sign: if rec.excitation_up < 0.0 { -1.0 } else { 1.0 },
        }
    }

    /// Plot coordinates of the plane coordinates (a, b) (any unit).
    fn xy(&self, a: f64, b: f64) -> (f64, f64) {
        if self.vertical {
            (b, self.sign * a)
        } else {
            (a, b)
        }
    }

    fn titles(&self, rec: &MotionRecorder) -> (&'static str, &'static str) {
        if self.vertical {
            ("horizontal (mm)", "up, along the excitation (mm)")
        } else if rec.gravity_free {
            ("along excitation (mm)", "perpendicular (mm)")
        } else {
            ("along excitation (mm)", "up (mm)")
        }
    }
}

/// The container's outline in the field plane (container frame, mm) as a closed rectangle
/// (the walls' bounding box along the two plotted axes), if the walls are bounded.
fn container_outline_mm(rec: &MotionRecorder) -> Option<(Vec<f64>, Vec<f64>)> {
    let [[a0, a1], [b0, b1]] = rec.container_extent_m?;
    let view = PlaneView::of(rec);
    let corners = [(a0, b0), (a1, b0), (a1, b1), (a0, b1), (a0, b0)];
    Some(
        corners
            .iter()
            .map(|&(a, b)| view.xy(a * 1e3, b * 1e3))
            .unzip(),
    )
}

/// The velocity field of phase `k`: cell centres in the container frame (mm) coloured by the
/// phase-averaged |v|/V, arrows of the in-plane mean velocity scaled so that the fastest cell's
/// arrow is one cell long, a reference arrow stating the velocity it stands for, and the
/// container's outline. `None` for a phase without samples.
pub fn velocity_field_figure(rec: &MotionRecorder, k: usize) -> Option<ScatterField> {
    let f = rec.fields.get(k)?;
    let view = PlaneView::of(rec);
    let (mut x, mut y, mut val, mut u, mut v) = (vec![], vec![], vec![], vec![], vec![]);
    for c in 0..f.count.len() {
        let n = f.count[c];
        if n == 0 {
            continue;
        }
        let [cx, cy] = rec.cell_center(c);
        let (px, py) = view.xy(cx * 1e3, cy * 1e3);
        x.push(px);
        y.push(py);
        val.push(f.speed_sum[c] / n as f64);
        let (pu, pv) = view.xy(f.vel_sum[c][0] / n as f64, f.vel_sum[c][1] / n as f64);
        u.push(pu);
        v.push(pv);
    }
    if x.is_empty() {
        return None;
    }
    let mut s = ScatterField::new(x, y, val);
    s.title = format!(
        "velocity field at Ωt = {:.0}° (container frame)",
        f.phase_rad.to_degrees()
    );
    let (xt, yt) = view.titles(rec);
    s.x_axis = Axis::linear(xt);
    s.y_axis = Axis::linear(yt);
    s.color = ColorScale::linear(0.0, 2.0);
    s.colorbar_title = "|v| / V (-)".into();
    let mut q = Quiver::new(u, v);
    let vmax = q.max_magnitude();
    if vmax > 0.0 {
        q.scale = Some(rec.cell_m * 1e3 / vmax);
        let r = nice_below(vmax);
        q.key = Some(QuiverKey {
            magnitude: r,
            label: format!(
                "mean velocity v/V = {} ({} m/s)",
                pdamp_plot::format_number(r),
                significant(r * rec.velocity_amplitude_m_s, 3)
            ),
        });
    }
    s.arrows = Some(q);
    if let Some((ox, oy)) = container_outline_mm(rec) {
        let mut o = Polyline::new("container", ox, oy);
        o.color = Some(Rgb::BLACK);
        s.outlines.push(o);
    }
    s.marker_px = 6;
    Some(s)
}

/// One scatter plot per recorded phase ([`velocity_field_figure`]):
/// `velocity_field_phaseK.png/.svg`.
pub fn velocity_field_plots(rec: &MotionRecorder, out: &Path) -> Result<(), DesignError> {
    for k in 0..rec.fields.len() {
        if let Some(s) = velocity_field_figure(rec, k) {
            scatter_field(out.join(format!("velocity_field_phase{k}")), &s)?;
        }
    }
    Ok(())
}

/// Trajectories of the chosen particles in the container frame (excitation direction vs up),
/// with the container's outline.
pub fn trajectory_plot(rec: &MotionRecorder, out: &Path) -> Result<(), DesignError> {
    if rec.trajectories.is_empty() {
        return Ok(());
    }
    let view = PlaneView::of(rec);
    let (xt, yt) = view.titles(rec);
    let mut plot = LinePlot::new(Axis::linear(xt), Axis::linear(yt));
    plot.title = "particle trajectories (container frame)".into();
    for &i in &rec.trajectory_particles {
        let (mut a, mut b) = (vec![], vec![]);
        for row in rec.trajectories.iter().filter(|r| r[0] as usize == i) {
            let p = pdamp_dem::Vec3::new(row[2], row[3], row[4]);
            let (x, y) = view.xy(p.dot(&rec.axes[0]) * 1e3, p.dot(&rec.axes[1]) * 1e3);
            a.push(x);
            b.push(y);
        }
        plot.series.push(Series::new(format!("particle {i}"), a, b));
    }
    if let Some((ox, oy)) = container_outline_mm(rec) {
        // Last in the list: the particles keep their palette colours.
        plot.series
            .push(Series::new("container", ox, oy).with_color(Rgb::BLACK));
    }
    line_plot(out.join("trajectories"), &plot)?;
    Ok(())
}

/// Evaluated cycles drawn each in its own colour in the hysteresis plot (earlier evaluated
/// cycles are grey).
const HYSTERESIS_COLOURED_CYCLES: usize = 5;

/// The bed force on the container and the container displacement of a damper point
/// ([`MotionRecorder::force_displacement`]): `force_time.png/.svg`, both over time (force
/// left, displacement in mm on the right axis, the transient cycles shaded), and
/// `hysteresis.png/.svg`, the force against the displacement, one loop per cycle (transient
/// cycles faint, the last evaluated ones in colour), titled with the mean loop area
/// ∮(−f_p) dx per evaluated cycle and Ẽ_diss of the complex power method [D Sect. 3.2.2,
/// Eq. 3.13].
pub fn force_displacement_plots(
    rec: &MotionRecorder,
    transient_cycles: u32,
    point: &PointResult,
    out: &Path,
) -> Result<(), DesignError> {
    let rows = &rec.force_displacement;
    if rows.len() < 2 {
        return Ok(());
    }
    let col = |k: usize, scale: f64| -> Vec<f64> { rows.iter().map(|r| r[k] * scale).collect() };
    let heading = format!(
        "f = {} Hz, X = {} mm",
        pdamp_plot::format_number(point.frequency_hz),
        significant(point.amplitude_m * 1e3, 4)
    );

    let mut ft = LinePlot::new(
        Axis::linear("time t (s)"),
        Axis::linear("bed force on the container f_p (N)"),
    );
    ft.title = format!("bed force and container displacement, {heading}");
    ft.y2_axis = Some(Axis::linear("container displacement x (mm)"));
    let t_transient = transient_cycles as f64 / point.frequency_hz;
    if transient_cycles > 0 {
        ft.spans.push(XSpan::new(
            0.0,
            t_transient.min(rows[rows.len() - 1][0]),
            "transient cycles (not evaluated)",
        ));
    }
    ft.series.push(
        Series::new("bed force f_p", col(0, 1.0), col(4, 1.0))
            .with_color(Rgb(31, 119, 180))
            .with_width(1),
    );
    ft.series.push(
        Series::new("displacement x", col(0, 1.0), col(2, 1e3))
            .with_color(Rgb(255, 127, 14))
            .on_secondary_axis(),
    );
    ft.size_px = (1000, 520);
    line_plot(out.join("force_time"), &ft)?;

    let mut hy = LinePlot::new(
        Axis::linear("container displacement x (mm)"),
        Axis::linear("bed force on the container f_p (N)"),
    );
    let area = rec.loop_work_per_cycle_j(transient_cycles);
    hy.title = match area {
        Some(a) => format!(
            "hysteresis, {heading}: ∮(−f_p)dx = {} J/cycle, Ẽ_diss = {} J",
            significant(a, 4),
            significant(point.dissipated_energy_per_cycle_j, 4)
        ),
        None => format!("hysteresis, {heading}"),
    };
    let cycles: Vec<u32> = {
        let mut c: Vec<u32> = rows.iter().map(|r| r[1] as u32).collect();
        c.dedup();
        c
    };
    let evaluated: Vec<u32> = cycles
        .iter()
        .copied()
        .filter(|c| *c >= transient_cycles)
        .collect();
    let coloured = &evaluated[evaluated.len().saturating_sub(HYSTERESIS_COLOURED_CYCLES)..];
    let loop_of = |c: u32| -> (Vec<f64>, Vec<f64>) {
        rows.iter()
            .filter(|r| r[1] as u32 == c)
            .map(|r| (r[2] * 1e3, r[4]))
            .unzip()
    };
    let (mut transient_labelled, mut grey_labelled) = (false, false);
    for &c in &cycles {
        let (x, f) = loop_of(c);
        let s = if c < transient_cycles {
            let label = if transient_labelled {
                String::new()
            } else {
                transient_labelled = true;
                match transient_cycles {
                    1 => "transient cycle 0".to_string(),
                    n => format!("transient cycles 0–{}", n - 1),
                }
            };
            Series::new(label, x, f)
                .with_color(Rgb(205, 205, 205))
                .with_width(1)
        } else if coloured.contains(&c) {
            Series::new(format!("cycle {c}"), x, f).with_width(2)
        } else {
            let label = if grey_labelled {
                String::new()
            } else {
                grey_labelled = true;
                format!("cycles {}–{}", evaluated[0], coloured[0] - 1)
            };
            Series::new(label, x, f)
                .with_color(Rgb(140, 140, 140))
                .with_width(1)
        };
        hy.series.push(s);
    }
    // Palette colours for the coloured loops in order, whatever precedes them.
    for (k, s) in hy
        .series
        .iter_mut()
        .filter(|s| s.color.is_none())
        .enumerate()
    {
        s.color = Some(pdamp_plot::palette_color(k));
    }
    hy.size_px = (900, 620);
    line_plot(out.join("hysteresis"), &hy)?;
    Ok(())
}

/// One map of `values` (grid order, frequency-major, NaN grey) with a linear colour scale from
/// 0 to the largest finite value: e.g. the half-width of the 95 % confidence interval of η̄ over
/// an ensemble (`name`.png/.svg).
pub fn value_map(
    grid: &FieldGrid,
    values: &[f64],
    out: &Path,
    name: &str,
    title: &str,
    colorbar: &str,
) -> Result<(), DesignError> {
    let nx = grid.frequencies_hz.len();
    let ny = grid.amplitude_values.len();
    if nx < 2 || ny < 2 || values.len() != nx * ny {
        return Ok(());
    }
    let mut v = vec![f64::NAN; nx * ny];
    for (k, x) in values.iter().enumerate() {
        v[(k % ny) * nx + k / ny] = *x;
    }
    let hi = v
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0_f64, f64::max);
    let mut m = HeatMap::new(
        grid.frequencies_hz.clone(),
        grid.amplitude_values.clone(),
        v,
    );
    m.x_axis = if grid.frequency_log {
        Axis::log("frequency f (Hz)")
    } else {
        Axis::linear("frequency f (Hz)")
    };
    m.y_axis = if grid.amplitude_log {
        Axis::log(grid.amplitude_title())
    } else {
        Axis::linear(grid.amplitude_title())
    };
    m.color = ColorScale::linear(0.0, hi.max(1e-300));
    m.title = title.to_string();
    m.colorbar_title = colorbar.to_string();
    heat_map(out.join(name), &m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use pdamp_scenario::schema::AmplitudeAxis;

    /// A recorder on a 20 × 10 × 6 mm box (one particle, excitation along x, gravity −z) with
    /// 10 cells along the excitation: cells of 2 mm; phase 0 filled with a made-up field.
    /// A world with one fixed box of `half_extents_m` around the origin and one sphere
    /// (r = 1 mm) at `particle_m`.
    fn box_world(half_extents_m: pdamp_dem::Vec3, particle_m: pdamp_dem::Vec3) -> pdamp_dem::World {
        use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
        use pdamp_dem::walls::{BoxInside, Geometry};
        use pdamp_dem::{BodyState, Material, Motion, RigidBody, Vec3, World};
        let model = ContactModel {
            normal: NormalLaw::Linear {
                stiffness_n_m: 2e5,
                restitution: 0.5,
                clip_attractive: false,
            },
            friction: FrictionLaw::Frictionless,
            rolling: None,
            adhesion: None,
        };
        let mut w = World::new(vec![Material::new("steel", 7800.0, 2e9, 0.3)], model, 1e-6);
        w.add_body(
            RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
                "box",
                Geometry::BoxInside(BoxInside::new(Vec3::zeros(), half_extents_m)),
                0,
            ),
        );
        w.add_particle(particle_m, 1e-3, 0);
        w
    }

    fn recorder() -> MotionRecorder {
        use pdamp_dem::Vec3;
        let w = box_world(Vec3::new(10e-3, 5e-3, 3e-3), Vec3::new(0.0, 0.0, -2e-3));
        let damper = crate::Damper::from_world(w, 0, Vec3::x(), 0.1, 3, 1);
        let mut rec = MotionRecorder::new(&damper, 50.0, 0.25, 2, 10, vec![], 2e4);
        let f = &mut rec.fields[0];
        for c in 0..f.count.len() {
            let k = c as f64;
            f.count[c] = 2;
            f.speed_sum[c] = 0.2 * k;
            f.vel_sum[c] = [0.1 * k, -0.05 * k];
        }
        rec
    }

    /// The fastest cell's arrow is one cell (2 mm) long, the reference arrow stands for a
    /// 1-2-5 value not above the largest velocity and states it in m/s too, and the container
    /// outline is the box's inner extent along the plotted axes (x and up = z).
    #[test]
    fn velocity_field_arrows_one_cell_and_outline() {
        let rec = recorder();
        assert!((rec.cell_m - 2e-3).abs() < 1e-15);
        let fig = velocity_field_figure(&rec, 0).expect("phase 0 has samples");
        let q = fig.arrows.as_ref().unwrap();
        let longest = fig.arrow_scale(q) * q.max_magnitude();
        assert!((longest - 2.0).abs() < 1e-12, "longest arrow {longest} mm");
        let key = q.key.as_ref().unwrap();
        assert!(key.magnitude <= q.max_magnitude() && key.magnitude > 0.4 * q.max_magnitude());
        assert!(key.label.contains("m/s"), "{}", key.label);
        let o = &fig.outlines[0];
        let (xmin, xmax) =
            o.x.iter()
                .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(*v), a.1.max(*v)));
        let (ymin, ymax) =
            o.y.iter()
                .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(*v), a.1.max(*v)));
        assert!(
            (xmin + 10.0).abs() < 1e-9 && (xmax - 10.0).abs() < 1e-9,
            "{xmin} {xmax}"
        );
        assert!(
            (ymin + 3.0).abs() < 1e-9 && (ymax - 3.0).abs() < 1e-9,
            "{ymin} {ymax}"
        );
        assert_eq!((o.x[0], o.y[0]), (o.x[4], o.y[4]), "closed");
        assert_eq!(nice_below(0.83), 0.5);
        assert_eq!(nice_below(2.0), 2.0);
        assert_eq!(nice_below(0.0123), 0.01);
    }

    /// A vertical excitation (gravity along it) is drawn upwards: the y axis is the excitation
    /// ("up"), the x axis the horizontal direction, outline and arrows turned with it.
    #[test]
    fn vertical_excitation_is_drawn_upwards() {
        use pdamp_dem::Vec3;
        // 20 mm high (z), 8 mm wide (x), 6 mm deep (y)
        let mut w = box_world(Vec3::new(4e-3, 3e-3, 10e-3), Vec3::new(0.0, 0.0, -8e-3));
        w.gravity_m_s2 = Vec3::new(0.0, 0.0, -9.81);
        let damper = crate::Damper::from_world(w, 0, Vec3::z(), 0.1, 3, 1);
        let mut rec = MotionRecorder::new(&damper, 50.0, 0.25, 1, 10, vec![], 2e4);
        assert_eq!(rec.excitation_up, 1.0);
        rec.fields[0].count[0] = 1;
        rec.fields[0].speed_sum[0] = 1.0;
        rec.fields[0].vel_sum[0] = [1.0, 0.0]; // along the excitation: an upward arrow
        let fig = velocity_field_figure(&rec, 0).unwrap();
        assert_eq!(fig.x_axis.title, "horizontal (mm)");
        assert_eq!(fig.y_axis.title, "up, along the excitation (mm)");
        let q = fig.arrows.as_ref().unwrap();
        assert_eq!((q.u[0], q.v[0]), (0.0, 1.0));
        let o = &fig.outlines[0];
        let span = |v: &[f64]| {
            v.iter().fold(f64::MIN, |a, x| a.max(*x)) - v.iter().fold(f64::MAX, |a, x| a.min(*x))
        };
        assert!(
            (span(&o.y) - 20.0).abs() < 1e-9,
            "height along y: {:?}",
            o.y
        );
        assert!(span(&o.x) < 20.0 - 1e-9, "width along x: {:?}", o.x);
    }

    /// Lines of constant X on maps over Γ or A: decades of X crossing the map, each the curve
    /// XΩ²/g (XΩ²) and annotated in mm; none over X.
    #[test]
    fn constant_x_lines_on_intensity_and_acceleration_maps() {
        let mut grid = FieldGrid {
            frequencies_hz: vec![40.0, 1000.0],
            amplitude_axis: AmplitudeAxis::Intensity,
            amplitude_values: vec![1.0, 40.0],
            frequency_log: true,
            amplitude_log: true,
        };
        let lines = constant_x_overlays(&grid);
        // Γ from 1 to 40 over 40–1000 Hz: X from 2.5e-7 m to 6.2e-3 m → 1 µm … 1 mm.
        let labels: Vec<&str> = lines.iter().map(|l| l.annotation.as_str()).collect();
        assert!(labels.len() >= 2 && labels.len() <= 4, "{labels:?}");
        assert!(labels.contains(&"X = 0.01 mm") || labels.contains(&"X = 0.001 mm"));
        for l in &lines {
            let x_mm: f64 = l.annotation["X = ".len()..l.annotation.len() - 3]
                .parse()
                .unwrap();
            let f = l.x[20];
            let w = 2.0 * std::f64::consts::PI * f;
            assert!(
                (l.y[20] / (x_mm * 1e-3 * w * w / pdamp_scenario::schema::STANDARD_GRAVITY_M_S2)
                    - 1.0)
                    .abs()
                    < 1e-12
            );
            assert!(
                l.y.iter().any(|g| (1.0..=40.0).contains(g)),
                "crosses the map"
            );
            assert!(l.label.is_empty(), "no legend entry");
        }
        grid.amplitude_axis = AmplitudeAxis::Acceleration;
        grid.amplitude_values = vec![10.0, 30.0];
        let lines = constant_x_overlays(&grid);
        assert!(!lines.is_empty());
        for l in &lines {
            let x_mm: f64 = l.annotation["X = ".len()..l.annotation.len() - 3]
                .parse()
                .unwrap();
            let w = 2.0 * std::f64::consts::PI * l.x[0];
            assert!((l.y[0] / (x_mm * 1e-3 * w * w) - 1.0).abs() < 1e-12);
        }
        grid.amplitude_axis = AmplitudeAxis::Displacement;
        assert!(constant_x_overlays(&grid).is_empty());
    }

    /// The overlay lines in the units of each amplitude axis: A = g is Γ = 1, A = 9.81 m/s² and
    /// X = g/Ω²; X_opt = h/π is constant in X and grows as Ω² in Γ.
    #[test]
    fn eta_overlays_in_axis_units() {
        let mut grid = FieldGrid {
            frequencies_hz: vec![40.0, 1000.0],
            amplitude_axis: AmplitudeAxis::Intensity,
            amplitude_values: vec![1.0, 40.0],
            frequency_log: true,
            amplitude_log: true,
        };
        let h = 3e-3;
        let lines = eta_overlays(&grid, Some(h));
        assert_eq!(lines.len(), 2);
        assert!(lines[0].y.iter().all(|g| (g - 1.0).abs() < 1e-12));
        let f = lines[1].x[10];
        let w = 2.0 * std::f64::consts::PI * f;
        assert!((lines[1].y[10] - h / std::f64::consts::PI * w * w / 9.81).abs() < 1e-9);
        assert!((lines[1].x[0] - 40.0).abs() < 1e-12 && (lines[1].x[64] - 1000.0).abs() < 1e-9);
        grid.amplitude_axis = AmplitudeAxis::Displacement;
        let lines = eta_overlays(&grid, Some(h));
        assert!(
            lines[1]
                .y
                .iter()
                .all(|x| (x - h / std::f64::consts::PI).abs() < 1e-15)
        );
        assert!(
            (lines[0].y[0] - 9.81 / (2.0 * std::f64::consts::PI * 40.0f64).powi(2)).abs() < 1e-15
        );
        grid.amplitude_axis = AmplitudeAxis::Acceleration;
        assert!(eta_overlays(&grid, None).len() == 1);
        assert!(
            eta_overlays(&grid, None)[0]
                .y
                .iter()
                .all(|a| (a - 9.81).abs() < 1e-9)
        );
    }
}
