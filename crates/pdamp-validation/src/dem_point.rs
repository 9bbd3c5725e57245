//! DEM points of the references' dampers (level II, `Full` tier): one example scenario driven
//! at (f, X) with an ensemble of independently dropped beds, as `pdamp run EXAMPLE
//! --frequency-hz f --amplitude-m X --packings K` does; the value is the ensemble mean of η̄
//! (D Eq. 3.18) with its 95 % confidence interval.

use crate::{ComputeError, Context, Measured};

/// One ensemble point: mean η̄ and m̄/m_bed with the 95 % confidence interval of η̄.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsemblePoint {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Displacement amplitude, m.
    pub amplitude_m: f64,
    /// Mean effective loss factor η̄ over the packings.
    pub loss_factor: f64,
    /// 95 % confidence interval of the mean η̄.
    pub loss_factor_ci95: (f64, f64),
    /// Mean m̄_bed/m_bed.
    pub mass_ratio: f64,
    /// Packings (drop-down beds).
    pub packings: usize,
    /// η̄ of every packing (a bistable bed shows here as two groups).
    pub members: Vec<f64>,
}

/// Runs the damper example `file` at `f_hz`, `x_m` with `packings` beds into a folder of
/// `ctx.work_dir`.
pub fn ensemble_point(
    ctx: &Context,
    file: &str,
    f_hz: f64,
    x_m: f64,
    packings: usize,
) -> Result<EnsemblePoint, ComputeError> {
    let path = ctx.example(file);
    let (mut sc, _) =
        pdamp_scenario::schema::Scenario::load_and_build(&path).map_err(ComputeError::new)?;
    let d = sc
        .damper
        .as_mut()
        .ok_or_else(|| ComputeError::new(format!("{file} has no [damper] section")))?;
    d.frequency_hz = Some(f_hz);
    d.amplitude_m = Some(x_m);
    d.acceleration_m_s2 = None;
    d.intensity = None;
    d.packings = packings;
    sc.validate().map_err(ComputeError::new)?;
    let out = ctx.work_dir.join(format!(
        "{}_{f_hz}hz_{:.1}mm",
        file.trim_end_matches(".toml"),
        x_m * 1e3
    ));
    let _ = std::fs::remove_dir_all(&out);
    let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    let s = pdamp_design::report::run_damper_scenario(&sc, &base, &out, |_, _| {})
        .map_err(ComputeError::new)?;
    let members = match &s.ensemble {
        Some(e) => e.members.iter().map(|m| m.effective_loss_factor).collect(),
        None => vec![s.effective_loss_factor],
    };
    let (eta, ci, mass) = match &s.ensemble {
        Some(e) => (
            e.effective_loss_factor.mean,
            (
                e.effective_loss_factor.ci95_low,
                e.effective_loss_factor.ci95_high,
            ),
            e.effective_mass_ratio.mean,
        ),
        None => (
            s.effective_loss_factor,
            (s.effective_loss_factor, s.effective_loss_factor),
            s.effective_mass_ratio,
        ),
    };
    Ok(EnsemblePoint {
        frequency_hz: f_hz,
        amplitude_m: x_m,
        loss_factor: eta,
        loss_factor_ci95: ci,
        mass_ratio: mass,
        packings,
        members,
    })
}

/// The largest ensemble-mean η̄ along an amplitude line at `f_hz` (each point `packings`
/// beds), as a [`Measured`] naming the line and the amplitude of the peak.
pub fn peak_along_amplitudes(
    ctx: &Context,
    file: &str,
    f_hz: f64,
    amplitudes_m: &[f64],
    packings: usize,
) -> Result<Measured, ComputeError> {
    let mut points = Vec::with_capacity(amplitudes_m.len());
    for &x in amplitudes_m {
        points.push(ensemble_point(ctx, file, f_hz, x, packings)?);
    }
    let best = points
        .iter()
        .max_by(|a, b| a.loss_factor.total_cmp(&b.loss_factor))
        .ok_or_else(|| ComputeError::new("no amplitude given"))?;
    let members: Vec<String> = best.members.iter().map(|m| format!("{m:.2}")).collect();
    let line: Vec<String> = points
        .iter()
        .map(|p| format!("{:.1} mm: {:.2}", p.amplitude_m * 1e3, p.loss_factor))
        .collect();
    Ok(Measured {
        value: best.loss_factor,
        ci95: Some(best.loss_factor_ci95),
        runs: packings,
        how: format!(
            "pdamp run examples/{file} --frequency-hz {f_hz} --amplitude-m X --packings {packings}: \
             η̄ (ensemble mean) {}; peak at {:.1} mm (packings {}), m̄/m_bed {:.2}",
            line.join(", "),
            best.amplitude_m * 1e3,
            members.join(", "),
            best.mass_ratio
        ),
    })
}
