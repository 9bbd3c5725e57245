//! Plots of damper results: effective-field maps [D Fig. 3.6, 8.3], phase-resolved velocity
//! fields [D Fig. 3.5c, 8.2] and particle trajectories [D Fig. 3.5b]. PNG and SVG each.

use crate::damper::PointResult;
use crate::fields::FieldGrid;
use crate::motion::MotionRecorder;
use pdamp_plot::{Axis, ColorScale, HeatMap, LinePlot, Quiver, ScatterField, Series};
use std::path::Path;

fn err(e: impl std::fmt::Display) -> String {
    format!("plot: {e}")
}

/// Maps of η̄ (colour saturating at 1, as in the dissertation), m̄_bed/m_bed, Ẽ and the split of
/// the dissipation over the grid: `effective_loss_factor`, `effective_mass_ratio`,
/// `dissipated_energy`, `dissipation_normal_over_tangential` [D Fig. 8.8],
/// `dissipation_wall_share` (.png/.svg).
pub fn field_maps(grid: &FieldGrid, points: &[PointResult], out: &Path) -> Result<(), String> {
    field_maps_with(grid, points, out, None)
}

/// The grid's amplitude-axis value of the displacement amplitude `x_m` at `f_hz`.
fn axis_value(grid: &FieldGrid, f_hz: f64, x_m: f64) -> f64 {
    use pdamp_io::scenario::{AmplitudeAxis, STANDARD_GRAVITY_M_S2};
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
    use pdamp_io::scenario::STANDARD_GRAVITY_M_S2;
    let (f0, f1) = (
        grid.frequencies_hz[0],
        *grid
            .frequencies_hz
            .last()
            .unwrap_or(&grid.frequencies_hz[0]),
    );
    let fs: Vec<f64> = (0..=64)
        .map(|k| {
            let s = k as f64 / 64.0;
            if grid.frequency_log {
                f0 * (f1 / f0).powf(s)
            } else {
                f0 + (f1 - f0) * s
            }
        })
        .collect();
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

/// [`field_maps`] with the bed's clearance h along the excitation for the X_opt = h/π line
/// on the η̄ map (the A = g line is always drawn).
pub fn field_maps_with(
    grid: &FieldGrid,
    points: &[PointResult],
    out: &Path,
    clearance_m: Option<f64>,
) -> Result<(), String> {
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
        m
    };
    let eta = pick(&|p| p.effective_loss_factor);
    let mut eta_map = make(
        eta,
        ColorScale::linear(0.0, 1.0),
        "effective loss factor (values ≥ 1 saturate)",
        "η̄ (-)",
    );
    eta_map.overlays = eta_overlays(grid, clearance_m);
    pdamp_plot::heat_map(out.join("effective_loss_factor"), &eta_map).map_err(err)?;
    let mass = pick(&|p| p.effective_mass_ratio);
    let mmax = mass
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(1.0_f64, f64::max);
    pdamp_plot::heat_map(
        out.join("effective_mass_ratio"),
        &make(
            mass,
            ColorScale::linear(0.0, mmax),
            "effective particle mass ratio",
            "m̄_bed / m_bed (-)",
        ),
    )
    .map_err(err)?;
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
    pdamp_plot::heat_map(
        out.join("dissipation_normal_over_tangential"),
        &make(
            ratio,
            ColorScale::log(0.25, 4.0),
            "dissipation in normal / tangential contacts",
            "E_diss,n / E_diss,t (-)",
        ),
    )
    .map_err(err)?;
    let wall = pick(&|p| p.share_normal_pw + p.share_tangential_pw);
    pdamp_plot::heat_map(
        out.join("dissipation_wall_share"),
        &make(
            wall,
            ColorScale::linear(0.0, 1.0),
            "share of the dissipation in particle–wall contacts",
            "E_diss,pw / E_diss (-)",
        ),
    )
    .map_err(err)?;
    pdamp_plot::heat_map(
        out.join("dissipated_energy"),
        &make(e, color, "dissipated energy per cycle", "Ẽ_diss (J)"),
    )
    .map_err(err)?;
    Ok(())
}

/// One scatter plot per recorded phase: cell centres in the container frame coloured by the
/// phase-averaged |v|/V, with arrows of the in-plane mean velocity.
pub fn velocity_field_plots(rec: &MotionRecorder, out: &Path) -> Result<(), String> {
    for (k, f) in rec.fields.iter().enumerate() {
        let (mut x, mut y, mut val, mut u, mut v) = (vec![], vec![], vec![], vec![], vec![]);
        for c in 0..f.count.len() {
            let n = f.count[c];
            if n == 0 {
                continue;
            }
            let [cx, cy] = rec.cell_center(c);
            x.push(cx * 1e3);
            y.push(cy * 1e3);
            val.push(f.speed_sum[c] / n as f64);
            u.push(f.vel_sum[c][0] / n as f64);
            v.push(f.vel_sum[c][1] / n as f64);
        }
        if x.is_empty() {
            continue;
        }
        let mut s = ScatterField::new(x, y, val);
        s.title = format!(
            "velocity field at Ωt = {:.0}° (container frame)",
            f.phase_rad.to_degrees()
        );
        s.x_axis = Axis::linear("along excitation (mm)");
        s.y_axis = Axis::linear("up (mm)");
        s.color = ColorScale::linear(0.0, 2.0);
        s.colorbar_title = "|v| / V (-)".into();
        s.arrows = Some(Quiver::new(u, v));
        s.marker_px = 6;
        pdamp_plot::scatter_field(out.join(format!("velocity_field_phase{k}")), &s).map_err(err)?;
    }
    Ok(())
}

/// Trajectories of the chosen particles in the container frame (excitation direction vs up).
pub fn trajectory_plot(rec: &MotionRecorder, out: &Path) -> Result<(), String> {
    if rec.trajectories.is_empty() {
        return Ok(());
    }
    let mut plot = LinePlot::new(
        Axis::linear("along excitation (mm)"),
        Axis::linear("up (mm)"),
    );
    plot.title = "particle trajectories (container frame)".into();
    for &i in &rec.trajectory_particles {
        let (mut a, mut b) = (vec![], vec![]);
        for row in rec.trajectories.iter().filter(|r| r[0] as usize == i) {
            let p = pdamp_dem::Vec3::new(row[2], row[3], row[4]);
            a.push(p.dot(&rec.axes[0]) * 1e3);
            b.push(p.dot(&rec.axes[1]) * 1e3);
        }
        plot.series.push(Series::new(format!("particle {i}"), a, b));
    }
    pdamp_plot::line_plot(out.join("trajectories"), &plot).map_err(err)?;
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
) -> Result<(), String> {
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
    pdamp_plot::heat_map(out.join(name), &m).map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use pdamp_io::scenario::AmplitudeAxis;

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
