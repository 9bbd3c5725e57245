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
    pdamp_plot::heat_map(
        out.join("effective_loss_factor"),
        &make(
            eta,
            ColorScale::linear(0.0, 1.0),
            "effective loss factor (values ≥ 1 saturate)",
            "η̄ (-)",
        ),
    )
    .map_err(err)?;
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
