//! The plots of the report and their CSV data: the FRFs of the forced objectives and ζ(X) of
//! level 1.

use super::write;
use crate::DesignError;
use crate::dem::DemVerification;
use crate::fidelity::{amplitude_grid, curve_at, simulated_damping_curve, time_evaluation};
use crate::search::Candidate;
use crate::space::Space;
use crate::study::ObjectiveSpec;
use pdamp_plot::{Axis, LinePlot, Series, line_plot};
use pdamp_structure::free::TimeHistory;
use std::fmt::Write as _;
use std::path::Path;

/// Forced objectives: the steady-state FRF at the output point (D Eq. 3.44) of the bare
/// structure and of the three best verified designs around every objective mode
/// (`frf.csv`: `mode,frequency_hz,bare_m,design_1_m,…`), and in `frf.png` also the coupled-DEM
/// sweeps of the first packing of every verified design (its `frf.csv` × the force). Returns
/// whether the plot was written.
pub(super) fn frf_plots(
    space: &Space,
    verified: &[&Candidate],
    dem: &[DemVerification],
    out: &Path,
) -> Result<bool, DesignError> {
    let st = space.study;
    let (ObjectiveSpec::MinFrfPeak { modes, band, .. }
    | ObjectiveSpec::MaxResonanceDamping { modes, band, .. }) = &st.file.objective
    else {
        return Ok(false);
    };
    let force = st.load.as_ref().map_or(0.0, |l| l.force_n);
    let top: Vec<&&Candidate> = verified.iter().take(3).collect();
    let mut csv = String::from("mode,frequency_hz,bare_m");
    for i in 0..top.len() {
        let _ = write!(csv, ",design_{}_m", i + 1);
    }
    csv.push('\n');
    let mut plot = LinePlot::new(
        Axis::linear("frequency f (Hz)"),
        Axis::log("amplitude at the output point x (m)"),
    );
    for &m in modes {
        let k = m - 1;
        let fk = st.structure.modes[k].frequency_hz;
        // the bed's mass lowers the resonance: the band reaches further down than up
        let (lo, hi) = (fk * (1.0 - 2.0 * band).max(0.05), fk * (1.0 + band));
        let freqs: Vec<f64> = (0..400)
            .map(|i| lo + (hi - lo) * i as f64 / 399.0)
            .collect();
        let mut columns = vec![crate::fidelity::steady_frf_at_output(
            st,
            &st.structure,
            &[],
            k,
            &freqs,
        )?];
        for c in &top {
            let dm = space.coupled_dampers(&c.design)?;
            columns.push(crate::fidelity::steady_frf_at_output(
                st,
                space.structure(c.design.choice),
                &dm,
                k,
                &freqs,
            )?);
        }
        for (i, f) in freqs.iter().enumerate() {
            let _ = write!(csv, "{m},{f:e}");
            for col in &columns {
                let _ = write!(csv, ",{:e}", col[i]);
            }
            csv.push('\n');
        }
        for (j, col) in columns.into_iter().enumerate() {
            let label = if j == 0 {
                format!("mode {m}, bare structure")
            } else {
                format!("mode {m}, design {j} (formulas)")
            };
            plot.series.push(Series::new(label, freqs.clone(), col));
        }
        for d in dem {
            let path = out
                .join(&d.dir)
                .join("packing_1")
                .join(format!("mode_{m}"))
                .join("out")
                .join("frf.csv");
            if let Ok(text) = std::fs::read_to_string(&path) {
                let (fs, xs): (Vec<f64>, Vec<f64>) = text
                    .lines()
                    .skip(1)
                    .filter_map(|l| {
                        let mut it = l.split(',');
                        let f = it.next()?.parse::<f64>().ok()?;
                        let h = it.next()?.parse::<f64>().ok()?;
                        Some((f, h * force))
                    })
                    .unzip();
                if !fs.is_empty() {
                    plot.series.push(Series::new(
                        format!("mode {m}, design {}, coupled DEM sweep (packing 1)", d.rank),
                        fs,
                        xs,
                    ));
                }
            }
        }
    }
    write(out, "frf.csv", &csv)?;
    match line_plot(out.join("frf"), &plot) {
        Ok(_) => Ok(true),
        Err(e) => {
            eprintln!("note: no frf.png: {e}");
            Ok(false)
        }
    }
}

/// ζ(X) of the three best verified designs from level 1 (`damping_curve.csv` for the best,
/// `damping.png` for all three): over the objective's amplitude range (max_damping) or from
/// the release amplitude down to half the best stroke (min_stroke). Returns the plot (level 3
/// adds its curves) and the plots written.
pub(super) fn level1_damping_curves(
    space: &Space,
    verified: &[&Candidate],
    out: &Path,
) -> Result<(LinePlot, Vec<&'static str>), DesignError> {
    let st = space.study;
    let f = &st.file;
    let best = verified[0];
    let (curve_modes, lo, hi) = match &f.objective {
        ObjectiveSpec::MinStroke { .. } => {
            let out_phi = st
                .structure
                .point(&st.free.output_point)
                .map_err(DesignError::from)?;
            let init_phi = st
                .structure
                .point(&st.free.initial_point)
                .map_err(DesignError::from)?;
            let k = st.free.mode;
            let x0 = (st.free.initial_displacement_m * out_phi[k] / init_phi[k]).abs();
            let x1 = best
                .time
                .as_ref()
                .and_then(|t| t.stroke_m)
                .unwrap_or(x0 / 10.0);
            (vec![k + 1], (0.5 * x1).max(x0 * 1e-3), x0)
        }
        ObjectiveSpec::MaxDamping {
            modes,
            amplitude_min_m,
            amplitude_max_m,
            ..
        } => (modes.clone(), *amplitude_min_m, *amplitude_max_m),
        ObjectiveSpec::MinFrfPeak { .. } | ObjectiveSpec::MaxResonanceDamping { .. } => {
            (Vec::new(), 0.0, 0.0)
        }
    };
    let mut curve_csv =
        String::from("mode,amplitude_m,damping_ratio_time_simulation,damping_ratio_bare\n");
    let mut plot = LinePlot::new(
        Axis::log("amplitude at the output point X (m)"),
        Axis::linear("damping ratio ζ (-)"),
    );
    for &m in &curve_modes {
        let grid = amplitude_grid(lo, hi, 16);
        for (label, c) in verified.iter().take(3).enumerate() {
            let dm = space.coupled_dampers(&c.design)?;
            let curve =
                simulated_damping_curve(st, space.structure(c.design.choice), &dm, m - 1, lo, hi)?;
            let ys: Vec<f64> = grid.iter().map(|&x| curve_at(&curve, x)).collect();
            if label == 0 {
                let zb = st.structure.modes[m - 1].damping_ratio;
                for (x, y) in grid.iter().zip(&ys) {
                    let _ = writeln!(curve_csv, "{m},{x:e},{y:e},{zb:e}");
                }
            }
            plot.series.push(Series::new(
                format!("mode {m}, design {}", label + 1),
                grid.clone(),
                ys,
            ));
        }
    }
    let mut plots = Vec::new();
    if !curve_modes.is_empty() {
        write(out, "damping_curve.csv", &curve_csv)?;
        match line_plot(out.join("damping"), &plot) {
            Ok(_) => plots.push("damping.png"),
            Err(e) => eprintln!("note: no damping.png: {e}"),
        }
    }
    Ok((plot, plots))
}

/// min_stroke: `decay.png`, the decays of the three best verified designs against the bare
/// structure's `bare`. Returns whether the plot was written.
pub(super) fn decay_plot(
    space: &Space,
    verified: &[&Candidate],
    bare: &TimeHistory,
    out: &Path,
) -> Result<bool, DesignError> {
    let st = space.study;
    let mut p = LinePlot::new(
        Axis::linear("time t (s)"),
        Axis::linear("displacement at the output point x (mm)"),
    );
    let mm = |v: &[f64]| v.iter().map(|x| x * 1e3).collect::<Vec<f64>>();
    p.series.push(Series::new(
        "bare structure",
        bare.time_s.clone(),
        mm(&bare.displacement_m),
    ));
    for (i, c) in verified.iter().take(3).enumerate() {
        let dm = space.coupled_dampers(&c.design)?;
        if let (_, Some(h)) = time_evaluation(st, space.structure(c.design.choice), &dm)? {
            p.series.push(Series::new(
                format!("design {}", i + 1),
                h.time_s.clone(),
                mm(&h.displacement_m),
            ));
        }
    }
    match line_plot(out.join("decay"), &p) {
        Ok(_) => Ok(true),
        Err(e) => {
            eprintln!("note: no decay.png: {e}");
            Ok(false)
        }
    }
}
