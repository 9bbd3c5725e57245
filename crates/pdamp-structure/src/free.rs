//! Free vibration [D Sect. 3.3.1]: the structure starts from an initial condition, attached
//! equivalent dampers (approaches 2 and 3) are updated during the decay, and the damping ratio
//! per cycle follows from the logarithmic decrement [D Eq. 3.40, 3.41].
//!
//! Updates of m̄_bed and d̄ happen at events of the damper point's motion: at zero crossings
//! with $X = |\dot x_{pd}(t_0)|/\bar\omega$ (horizontal dampers, D Sect. 5.2.1) or at peaks
//! with $X = |x_{pd}|$ (negative peaks for vertical dampers, D Sect. 7.2.1). Because
//! $\bar\omega$ depends on $\bar m_{bed}$ [D Eq. 3.33] which depends on Ω and X, each update is
//! a fixed-point iteration with $\Omega = \bar\omega_k$ [D Sect. 3.3.1].

use crate::StructureError;
use crate::effective::EffectiveDamper;
use crate::integrate::{Attachment, ModalIntegrator};
use crate::modal::ModalStructure;
use nalgebra::DVector;
use pdamp_signal::decay::{PeakOptions, find_peaks};
use serde::{Deserialize, Serialize};

/// When attached equivalent dampers are updated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum UpdateRule {
    /// At every zero crossing of the damper point, X = |ẋ|/ω̄ (D Sect. 5.2.1).
    #[default]
    ZeroCrossing,
    /// At negative peaks, X = |x| (D Sect. 7.2.1).
    NegativePeak,
    /// At positive peaks, X = x.
    PositivePeak,
    /// At every peak, X = |x|.
    EveryPeak,
    /// Never (parameters from the initial amplitude only).
    Never,
}

/// Which peaks of a free decay the logarithmic decrement is taken between [D Eq. 3.40].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DecayPeaks {
    /// The maximum positive strokes (D Sect. 5.1.2, horizontal dampers).
    #[default]
    Positive,
    /// The negative strokes, X = |x| (D Sect. 7.2: a vertical damper released from a negative
    /// deflection, whose parameters are updated at the negative peaks; D's samples 58 → 46.5 →
    /// 34 mm, ζ 0.035 at 53 mm and 0.05 at 41 mm, are cycles between negative peaks).
    Negative,
}

/// An equivalent damper attached at a named structure point.
#[derive(Debug)]
pub struct CoupledDamper {
    /// Structure point (its mode-shape values give φ_pd).
    pub point: String,
    /// The damper model.
    pub model: Box<dyn EffectiveDamper>,
}

/// One update of a damper's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct UpdateRecord {
    /// Time of the update, s.
    pub time_s: f64,
    /// Index of the damper.
    pub damper: usize,
    /// Amplitude X used, m.
    pub amplitude_m: f64,
    /// Frequency Ω/2π used (effective eigenfrequency), Hz.
    pub frequency_hz: f64,
    /// Effective particle mass m̄_bed, kg.
    pub effective_mass_kg: f64,
    /// Effective viscous damping d̄, N·s/m.
    pub damping_n_s_m: f64,
}

/// Sampled response.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TimeHistory {
    /// Sample times, s (uniform).
    pub time_s: Vec<f64>,
    /// Displacement at the output point, m.
    pub displacement_m: Vec<f64>,
    /// Velocity at the output point, m/s.
    pub velocity_m_s: Vec<f64>,
    /// External force, N (zero for free vibration).
    pub force_n: Vec<f64>,
    /// Parameter updates.
    pub updates: Vec<UpdateRecord>,
}

/// Free-vibration run settings.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeVibrationSpec {
    /// Simulated time, s.
    pub duration_s: f64,
    /// Time step, s.
    pub time_step_s: f64,
    /// Mode (0-based) that carries the initial condition and defines ω̄.
    pub mode: usize,
    /// Point where the initial condition is given.
    pub initial_point: String,
    /// Initial displacement there, m (q_k,0 = x_0/φ^(k)).
    pub initial_displacement_m: f64,
    /// Initial velocity there, m/s.
    pub initial_velocity_m_s: f64,
    /// Scale the initial displacement and velocity by $1 + m_{bed}/M$ [D Eq. 5.19] (see
    /// [`bed_mass_scale`]).
    pub scale_initial_by_bed_mass: bool,
    /// Output point.
    pub output_point: String,
    /// Update rule for attached dampers.
    pub update: UpdateRule,
    /// Store every n-th step.
    pub sample_every: usize,
}

/// The factor $1 + m_{bed}/M$ of the initial amplitude [D Eq. 5.19]: the excitation that starts
/// the decay gives the same peak acceleration with and without particles. $M = 1/\varphi^2$ is
/// the modal mass of the mode at the initial point ($\varphi$ its mass-normalised shape there).
pub fn bed_mass_scale(shape_at_initial_point: f64, bed_mass_kg: f64) -> f64 {
    1.0 + bed_mass_kg * shape_at_initial_point * shape_at_initial_point
}

/// Effective eigenfrequency of mode k with attached effective masses [D Eq. 3.33], rad/s.
pub fn effective_omega(structure: &ModalStructure, mode: usize, masses: &[(Vec<f64>, f64)]) -> f64 {
    let w = structure.modes[mode].omega_rad_s();
    let extra: f64 = masses.iter().map(|(s, m)| s[mode] * s[mode] * m).sum();
    w / (1.0 + extra).sqrt()
}

/// What was measured at an update event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measure {
    /// A peak: X = |x|.
    Peak(f64),
    /// A zero crossing with this velocity: X = |ẋ|/ω̄.
    Velocity(f64),
}

/// Fixed-point update of damper `i` [D Sect. 3.3.1]: with Ω = ω̄_k (Eq. 3.33) and
/// X from the [`Measure`], m̄ = m̄(Ω, X) (Eq. 3.38) until
/// ω̄ settles; then d̄ = Ẽ/(πΩX²) (Eq. 3.39). Returns (X, Ω, m̄, d̄).
pub fn fixed_point_update(
    structure: &ModalStructure,
    mode: usize,
    dampers: &[CoupledDamper],
    shapes: &[Vec<f64>],
    attachments: &[Attachment],
    i: usize,
    measure: Measure,
) -> (f64, f64, f64, f64) {
    let mut masses: Vec<(Vec<f64>, f64)> = shapes
        .iter()
        .zip(attachments)
        .map(|(s, a)| (s.clone(), a.mass_kg))
        .collect();
    let mut omega = effective_omega(structure, mode, &masses);
    let mut x = 0.0;
    for _ in 0..50 {
        x = match measure {
            Measure::Peak(p) => p.abs(),
            Measure::Velocity(v) => v.abs() / omega.max(1e-300),
        };
        let m = dampers[i].model.evaluate(x, omega).effective_mass_kg;
        masses[i].1 = m;
        let w_new = effective_omega(structure, mode, &masses);
        let done = (w_new - omega).abs() <= 1e-12 * omega;
        omega = w_new;
        if done {
            break;
        }
    }
    let s = dampers[i].model.evaluate(x, omega);
    (
        x,
        omega,
        s.effective_mass_kg,
        s.viscous_damping_n_s_m(x, omega),
    )
}

/// The structure, the analysed mode, the integration settings and the initial condition of a
/// free vibration checked before it runs.
fn check_free_vibration(
    structure: &ModalStructure,
    spec: &FreeVibrationSpec,
) -> Result<(), StructureError> {
    structure.validate()?;
    if spec.mode >= structure.modes.len() {
        return Err(StructureError::rule(
            format!("mode {}", spec.mode + 1),
            format!("does not exist ({} modes)", structure.modes.len()),
        ));
    }
    crate::integrate::validate_settings(
        structure,
        spec.time_step_s,
        spec.duration_s,
        spec.sample_every,
        false,
    )?;
    if !(spec.initial_displacement_m.is_finite() && spec.initial_velocity_m_s.is_finite()) {
        return Err(StructureError::inconsistent(format!(
            "initial_displacement_m = {:e}, initial_velocity_m_s = {:e}: must be finite",
            spec.initial_displacement_m, spec.initial_velocity_m_s
        )));
    }
    Ok(())
}

/// Whether the damper's parameters are updated over a step from (x0, v0) to (x1, v1) under
/// `rule`, and with which measure: the velocity interpolated at a zero crossing, or the
/// larger amplitude at a peak.
fn update_event(rule: UpdateRule, (x0, v0): (f64, f64), (x1, v1): (f64, f64)) -> Option<Measure> {
    match rule {
        UpdateRule::Never => None,
        UpdateRule::ZeroCrossing => (x0 != 0.0 && x0.signum() != x1.signum()).then(|| {
            let t = x0 / (x0 - x1);
            Measure::Velocity(v0 + (v1 - v0) * t)
        }),
        rule => {
            let pos = v0 > 0.0 && v1 <= 0.0;
            let neg = v0 < 0.0 && v1 >= 0.0;
            let hit = match rule {
                UpdateRule::PositivePeak => pos,
                UpdateRule::NegativePeak => neg,
                _ => pos || neg,
            };
            hit.then(|| Measure::Peak(x1.abs().max(x0.abs())))
        }
    }
}

/// Runs a free vibration of `structure` with the equivalent `dampers` [D Sect. 3.3.1].
///
/// # Errors
/// Unknown points, invalid spec.
pub fn run_free_vibration(
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    spec: &FreeVibrationSpec,
) -> Result<TimeHistory, StructureError> {
    check_free_vibration(structure, spec)?;
    let init = structure.point(&spec.initial_point)?.to_vec();
    let out = structure.point(&spec.output_point)?.to_vec();
    let shapes: Vec<Vec<f64>> = dampers
        .iter()
        .map(|d| structure.point(&d.point).map(|s| s.to_vec()))
        .collect::<Result<_, _>>()?;
    let k = spec.mode;
    if init[k] == 0.0 {
        return Err(StructureError::inconsistent(format!(
            "point '{}' is a node of mode {}: cannot set the initial condition there",
            spec.initial_point,
            k + 1
        )));
    }
    let mut it = ModalIntegrator::new(structure, spec.time_step_s);
    let scale = if spec.scale_initial_by_bed_mass {
        bed_mass_scale(init[k], dampers.iter().map(|d| d.model.bed_mass_kg()).sum())
    } else {
        1.0
    };
    it.q[k] = scale * spec.initial_displacement_m / init[k];
    it.v[k] = scale * spec.initial_velocity_m_s / init[k];
    let mut atts: Vec<Attachment> = shapes
        .iter()
        .map(|s| Attachment {
            shape: s.clone(),
            mass_kg: 0.0,
            damping_n_s_m: 0.0,
        })
        .collect();
    let mut hist = TimeHistory::default();
    // Initial parameters from the initial amplitude.
    for i in 0..dampers.len() {
        let x0 = it.displacement(&shapes[i]).abs();
        let v0 = it.velocity(&shapes[i]);
        let (x, w, m, d) = if x0 > 0.0 {
            fixed_point_update(structure, k, dampers, &shapes, &atts, i, Measure::Peak(x0))
        } else {
            fixed_point_update(
                structure,
                k,
                dampers,
                &shapes,
                &atts,
                i,
                Measure::Velocity(v0),
            )
        };
        atts[i].mass_kg = m;
        atts[i].damping_n_s_m = d;
        hist.updates.push(UpdateRecord {
            time_s: 0.0,
            damper: i,
            amplitude_m: x,
            frequency_hz: w / std::f64::consts::TAU,
            effective_mass_kg: m,
            damping_n_s_m: d,
        });
    }
    let zero = DVector::zeros(structure.modes.len());
    it.set_attachments(&atts);
    it.make_consistent(&zero);
    let n_steps = (spec.duration_s / spec.time_step_s).round() as usize;
    let every = spec.sample_every.max(1);
    let push = |it: &ModalIntegrator, h: &mut TimeHistory| {
        h.time_s.push(it.time_s);
        h.displacement_m.push(it.displacement(&out));
        h.velocity_m_s.push(it.velocity(&out));
        h.force_n.push(0.0);
    };
    push(&it, &mut hist);
    let mut prev: Vec<(f64, f64)> = shapes
        .iter()
        .map(|s| (it.displacement(s), it.velocity(s)))
        .collect();
    for step in 1..=n_steps {
        it.step(&zero);
        let mut changed = false;
        for i in 0..dampers.len() {
            let (x1, v1) = (it.displacement(&shapes[i]), it.velocity(&shapes[i]));
            let (x0, v0) = prev[i];
            prev[i] = (x1, v1);
            let event = update_event(spec.update, (x0, v0), (x1, v1));
            if let Some(measure) = event {
                let (x, w, m, d) =
                    fixed_point_update(structure, k, dampers, &shapes, &atts, i, measure);
                atts[i].mass_kg = m;
                atts[i].damping_n_s_m = d;
                changed = true;
                hist.updates.push(UpdateRecord {
                    time_s: it.time_s,
                    damper: i,
                    amplitude_m: x,
                    frequency_hz: w / std::f64::consts::TAU,
                    effective_mass_kg: m,
                    damping_n_s_m: d,
                });
            }
        }
        if changed {
            it.set_attachments(&atts);
            it.make_consistent(&zero);
        }
        it.check_health(structure, step == n_steps)?;
        if step % every == 0 {
            push(&it, &mut hist);
        }
    }
    Ok(hist)
}

/// Damping of one vibration cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CycleDamping {
    /// Time of the cycle's middle, s.
    pub time_s: f64,
    /// Mean amplitude $X_{n+1/2} = (X_n + X_{n+1})/2$ [D Sect. 3.3.1], m.
    pub mean_amplitude_m: f64,
    /// ζ from the logarithmic decrement $\vartheta = \ln(X_n/X_{n+1})$ [D Eq. 3.40, 3.41].
    pub damping_ratio: f64,
    /// 1/(t_{n+1} − t_n), Hz.
    pub frequency_hz: f64,
}

/// Positive peaks of a uniformly sampled decay (parabolic refinement, pdamp-signal), with
/// peaks closer than `min_separation_s` merged; the release point of a decay started at rest
/// from a positive displacement is the first.
///
/// # Errors
/// Fewer than three samples; errors of the peak search.
pub fn decay_peaks(
    hist: &TimeHistory,
    min_separation_s: f64,
) -> Result<Vec<(f64, f64)>, StructureError> {
    signed_decay_peaks(hist, min_separation_s, DecayPeaks::Positive)
}

/// The peaks of `which` sign of a uniformly sampled decay as (time, |x|) (see [`decay_peaks`]):
/// negative peaks are the maxima of −x. A decay released at rest (zero first velocity) from
/// a displacement of that sign starts on a peak, which comes first.
///
/// # Errors
/// Fewer than three samples; errors of the peak search.
pub fn signed_decay_peaks(
    hist: &TimeHistory,
    min_separation_s: f64,
    which: DecayPeaks,
) -> Result<Vec<(f64, f64)>, StructureError> {
    if hist.time_s.len() < 3 {
        return Err(StructureError::numerical("too few samples"));
    }
    let dt = hist.time_s[1] - hist.time_s[0];
    let flipped: Vec<f64>;
    let samples = match which {
        DecayPeaks::Positive => &hist.displacement_m,
        DecayPeaks::Negative => {
            flipped = hist.displacement_m.iter().map(|x| -x).collect();
            &flipped
        }
    };
    let peaks = find_peaks(
        samples,
        hist.time_s[0],
        dt,
        &PeakOptions {
            min_separation_s,
            ..Default::default()
        },
    )?;
    // A decay released at rest from a stroke of this sign starts on a peak that the search
    // (which never takes end samples) would drop: it is the first X_n of D Eq. 3.40.
    let mut out = Vec::with_capacity(peaks.len() + 1);
    if hist.velocity_m_s.first() == Some(&0.0) && samples[0] > 0.0 {
        out.push((hist.time_s[0], samples[0]));
    }
    out.extend(peaks.iter().map(|p| (p.time_s, p.value)));
    Ok(out)
}

/// Damping ratio per cycle from successive peaks (positive values: the strokes of
/// [`signed_decay_peaks`]) [D Eq. 3.40, 3.41], evaluated at the
/// mean amplitude of the cycle.
pub fn damping_per_cycle(peaks: &[(f64, f64)]) -> Vec<CycleDamping> {
    peaks
        .windows(2)
        .filter(|w| w[0].1 > 0.0 && w[1].1 > 0.0)
        .map(|w| {
            let theta = (w[0].1 / w[1].1).ln();
            CycleDamping {
                time_s: 0.5 * (w[0].0 + w[1].0),
                mean_amplitude_m: 0.5 * (w[0].1 + w[1].1),
                damping_ratio: pdamp_signal::decay::damping_ratio_from_log_decrement(theta),
                frequency_hz: 1.0 / (w[1].0 - w[0].0),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear decay x = x0 e^{−ζωt} cos(ω_d t) released at rest (to first order in ζ) from
    /// −58 mm: the negative peaks start with the release point and give ζ per cycle exactly
    /// (D Eq. 3.40, 3.41); the positive peaks give the same ζ one half cycle later.
    #[test]
    fn decay_peaks_of_either_sign_start_at_the_release_and_give_zeta() {
        let (zeta, f, x0) = (0.04_f64, 5.0_f64, -0.058_f64);
        let w = std::f64::consts::TAU * f;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let dt = 1e-5;
        let n = (2.0 / dt) as usize;
        let mut hist = TimeHistory::default();
        for i in 0..n {
            let t = i as f64 * dt;
            let e = (-zeta * w * t).exp();
            // x and ẋ of the damped free response from (x0, 0)
            let x = x0 * e * ((wd * t).cos() + zeta * w / wd * (wd * t).sin());
            let v = -x0 * e * w * w / wd * (wd * t).sin();
            hist.time_s.push(t);
            hist.displacement_m.push(x);
            hist.velocity_m_s.push(v);
        }
        assert_eq!(hist.velocity_m_s[0], 0.0);
        let neg = signed_decay_peaks(&hist, 0.5 / f, DecayPeaks::Negative).unwrap();
        assert_eq!(neg[0], (0.0, 0.058));
        assert!((neg[1].0 - 1.0 / (f * (1.0 - zeta * zeta).sqrt())).abs() < 2e-4);
        let pos = signed_decay_peaks(&hist, 0.5 / f, DecayPeaks::Positive).unwrap();
        assert!(
            pos[0].0 > 0.09 && pos[0].0 < 0.11,
            "first positive peak half a period in"
        );
        for peaks in [neg, pos] {
            let cycles = damping_per_cycle(&peaks);
            assert!(cycles.len() >= 8);
            for c in cycles {
                assert!((c.damping_ratio / zeta - 1.0).abs() < 1e-3, "{c:?}");
            }
        }
    }
}
