//! Runs of the coupling examples (`pdamp couple`, analytical dampers), their free decays and the
//! measures the references quote from them: ζ per cycle against the mean cycle amplitude, ζ over an amplitude
//! band, the amplitude at a time.

use crate::{ComputeError, Context};

/// One cycle of a decay (`damping.csv`): mean amplitude (m), damping ratio, time (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cycle {
    /// Mean amplitude of the cycle, m.
    pub amplitude_m: f64,
    /// Damping ratio of the cycle.
    pub damping_ratio: f64,
    /// Time of the cycle, s.
    pub time_s: f64,
}

/// Runs the coupling example `file` by `pdamp couple` into a fresh folder of `ctx.work_dir`;
/// returns its summary and the folder.
pub fn run_couple_example(
    ctx: &Context,
    file: &str,
) -> Result<(serde_json::Value, std::path::PathBuf), ComputeError> {
    let out = ctx.work_dir.join(file.trim_end_matches(".toml"));
    let _ = std::fs::remove_dir_all(&out);
    let options = pdamp_scenario::run::RunOptions::new(0.0, false);
    let summary =
        pdamp_structure::report::run_couple(&ctx.example(file), &out, options, &mut |_| {})
            .map_err(ComputeError::new)?;
    Ok((summary, out))
}

/// The cycles of the free decay of the coupling example `file` ([`run_couple_example`]).
pub fn free_decay(ctx: &Context, file: &str) -> Result<Vec<Cycle>, ComputeError> {
    let (_, out) = run_couple_example(ctx, file)?;
    let (header, rows) =
        pdamp_io::csv::read_csv_f64(out.join("damping.csv")).map_err(ComputeError::new)?;
    let col = |n: &str| {
        header
            .iter()
            .position(|h| h == n)
            .ok_or_else(|| ComputeError::new(format!("damping.csv has no column {n}")))
    };
    let (a, z, t) = (
        col("mean_amplitude_m")?,
        col("damping_ratio")?,
        col("time_s")?,
    );
    Ok(rows
        .iter()
        .map(|r| Cycle {
            amplitude_m: r[a],
            damping_ratio: r[z],
            time_s: r[t],
        })
        .collect())
}

/// Mean ζ of the cycles whose amplitude lies in `band` (m).
pub fn mean_damping_in(cycles: &[Cycle], band: std::ops::Range<f64>) -> Result<f64, ComputeError> {
    let z: Vec<f64> = cycles
        .iter()
        .filter(|c| band.contains(&c.amplitude_m))
        .map(|c| c.damping_ratio)
        .collect();
    if z.is_empty() {
        return Err(ComputeError::new(format!("no cycle between {band:?} m")));
    }
    Ok(z.iter().sum::<f64>() / z.len() as f64)
}

/// Largest ζ of the decay.
pub fn max_damping(cycles: &[Cycle]) -> f64 {
    cycles.iter().map(|c| c.damping_ratio).fold(0.0, f64::max)
}

/// The amplitude at time `t` (linear between the cycles around it), m.
pub fn amplitude_at(cycles: &[Cycle], t: f64) -> Result<f64, ComputeError> {
    let k = cycles
        .iter()
        .position(|c| c.time_s >= t)
        .filter(|&k| k > 0)
        .ok_or_else(|| ComputeError::new(format!("the decay does not span t = {t} s")))?;
    let (c0, c1) = (cycles[k - 1], cycles[k]);
    Ok(c0.amplitude_m
        + (c1.amplitude_m - c0.amplitude_m) * (t - c0.time_s) / (c1.time_s - c0.time_s))
}

/// ζ of the first cycle.
pub fn first_damping(cycles: &[Cycle]) -> Result<f64, ComputeError> {
    cycles
        .first()
        .map(|c| c.damping_ratio)
        .ok_or_else(|| ComputeError::new("the decay has no cycle"))
}

/// ζ at amplitude `x` (m), linear between the two cycles around it (the cycles' amplitudes
/// fall with time).
pub fn damping_at_amplitude(cycles: &[Cycle], x: f64) -> Result<f64, ComputeError> {
    let k = cycles
        .windows(2)
        .position(|w| (w[1].amplitude_m..=w[0].amplitude_m).contains(&x))
        .ok_or_else(|| ComputeError::new(format!("the decay does not pass {x} m")))?;
    let (c0, c1) = (cycles[k], cycles[k + 1]);
    let s = (x - c0.amplitude_m) / (c1.amplitude_m - c0.amplitude_m);
    Ok(c0.damping_ratio + s * (c1.damping_ratio - c0.damping_ratio))
}

/// Amplitude (m) of the cycle with the largest ζ.
pub fn amplitude_of_max_damping(cycles: &[Cycle]) -> Result<f64, ComputeError> {
    cycles
        .iter()
        .max_by(|a, b| a.damping_ratio.total_cmp(&b.damping_ratio))
        .map(|c| c.amplitude_m)
        .ok_or_else(|| ComputeError::new("the decay has no cycle"))
}

/// The time (s) at which ζ per cycle first falls below `z`, linear between the two cycles
/// around the crossing.
pub fn time_damping_falls_below(cycles: &[Cycle], z: f64) -> Result<f64, ComputeError> {
    let k = cycles
        .windows(2)
        .position(|w| w[0].damping_ratio >= z && w[1].damping_ratio < z)
        .ok_or_else(|| ComputeError::new(format!("ζ per cycle never falls below {z}")))?;
    let (c0, c1) = (cycles[k], cycles[k + 1]);
    let s = (z - c0.damping_ratio) / (c1.damping_ratio - c0.damping_ratio);
    Ok(c0.time_s + s * (c1.time_s - c0.time_s))
}
