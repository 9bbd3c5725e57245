//! The fidelity levels that evaluate a design, cheapest first.
//!
//! | level | name | what it computes | cost |
//! |---|---|---|---|
//! | 0 | `envelope` | the decay envelope / ζ(X) of the damped mode from the formulas' η̄ and m̄ at the current amplitude (D Eq. 3.33, 3.39, 3.51) | µs–ms |
//! | 1 | `formulas_time` | the modal time simulation with the formula dampers updated at the events of D Sect. 3.3.1 (`pdamp couple`, approach 3); ζ from the log decrement (D Eq. 3.40, 3.41) | ms–s |
//!
//! Level 0 is the slowly-varying-amplitude form of level 1: for one mode k with dampers i at
//! points with mode-shape values φ_i, the modal equation
//! $(1 + \sum\varphi_i^2\bar m_i)\ddot q + (2\zeta_k\omega_k + \sum\varphi_i^2\bar d_i)\dot q + \omega_k^2 q = 0$
//! gives $\bar\omega = \omega_k/\sqrt{1+\sum\varphi_i^2\bar m_i}$ (D Eq. 3.33) and
//! $\zeta = (2\zeta_k\omega_k + \sum\varphi_i^2\bar d_i)/(2\bar\omega(1 + \sum\varphi_i^2\bar m_i))$
//! with $\bar d_i = \tilde E_i/(\pi\bar\omega X_i^2)$ (D Eq. 3.39), which is D Eq. 3.51 for one
//! damper without structural damping. The amplitude then falls by $e^{-\pi\zeta/\sqrt{1-\zeta^2}}$
//! per half cycle, with η̄ and m̄ updated at every half cycle as the time simulation does at
//! every zero crossing.

use crate::DesignError;
use crate::study::{DesignStudy, ObjectiveSpec};
use pdamp_structure::free::{
    self, CoupledDamper, FreeVibrationSpec, TimeHistory, UpdateRule, damping_per_cycle, decay_peaks,
};
use pdamp_structure::modal::ModalStructure;
use std::f64::consts::PI;

/// Damping ratio and effective angular frequency of mode `k` with the dampers at modal
/// amplitude `q` (see the module docs; D Eq. 3.33, 3.39, 3.51).
pub fn modal_damping(
    structure: &ModalStructure,
    k: usize,
    dampers: &[CoupledDamper],
    shapes: &[f64],
    q: f64,
) -> (f64, f64) {
    let w0 = structure.modes[k].omega_rad_s();
    let mut masses = vec![0.0; dampers.len()];
    let mut omega = w0;
    for _ in 0..50 {
        for (i, d) in dampers.iter().enumerate() {
            masses[i] = d
                .model
                .evaluate((shapes[i] * q).abs(), omega)
                .effective_mass_kg;
        }
        let extra: f64 = shapes.iter().zip(&masses).map(|(p, m)| p * p * m).sum();
        let w = w0 / (1.0 + extra).sqrt();
        let done = (w - omega).abs() <= 1e-12 * w0;
        omega = w;
        if done {
            break;
        }
    }
    let mut modal_mass = 1.0;
    let mut c = 2.0 * structure.modes[k].damping_ratio * w0;
    for (i, d) in dampers.iter().enumerate() {
        let x = (shapes[i] * q).abs();
        let s = d.model.evaluate(x, omega);
        modal_mass += shapes[i] * shapes[i] * s.effective_mass_kg;
        c += shapes[i] * shapes[i] * s.viscous_damping_n_s_m(x, omega);
    }
    (c / (2.0 * omega * modal_mass), omega)
}

/// Half cycles between two updates of the dampers under an update rule: the time simulation
/// updates at every zero crossing or peak (1), at the positive or the negative peaks only (2),
/// or never (`None`: η̄ and m̄ of the initial amplitude throughout).
pub fn half_cycles_per_update(rule: UpdateRule) -> Option<u32> {
    match rule {
        UpdateRule::ZeroCrossing | UpdateRule::EveryPeak => Some(1),
        UpdateRule::NegativePeak | UpdateRule::PositivePeak => Some(2),
        UpdateRule::Never => None,
    }
}

/// The decay envelope of mode `k` released from a peak of modal amplitude `q0`: (time,
/// modal amplitude, ω̄) at every peak of |q| (every half cycle), with the dampers updated as
/// the time simulation updates them (see [`half_cycles_per_update`]), until `until_s` (or
/// until the amplitude falls below `floor_q`).
#[allow(clippy::too_many_arguments)]
pub fn envelope(
    structure: &ModalStructure,
    k: usize,
    dampers: &[CoupledDamper],
    shapes: &[f64],
    q0: f64,
    until_s: f64,
    floor_q: f64,
    rule: UpdateRule,
) -> Vec<(f64, f64, f64)> {
    let mut t = 0.0;
    let mut q = q0;
    let mut out = Vec::new();
    let frozen = modal_damping(structure, k, dampers, shapes, q0);
    let halves = half_cycles_per_update(rule).unwrap_or(1);
    let (mut z, mut w) = frozen;
    // at most 10⁶ half cycles (a lightly damped high mode over a long time)
    for i in 0..1_000_000u32 {
        if i % halves == 0 && half_cycles_per_update(rule).is_some() {
            (z, w) = modal_damping(structure, k, dampers, shapes, q);
        }
        out.push((t, q, w));
        if t >= until_s || q <= floor_q {
            break;
        }
        if z >= 1.0 {
            // over-damped: the amplitude does not come back
            out.push((t + PI / w, 0.0, w));
            break;
        }
        let r = (1.0 - z * z).sqrt();
        q *= (-PI * z / r).exp();
        t += PI / (w * r);
    }
    out
}

/// The largest |q| of the envelope's peaks in `[from_s, to_s]` (the time simulation's stroke
/// window); the amplitude at `from_s` if no peak falls inside.
pub fn envelope_max(env: &[(f64, f64, f64)], from_s: f64, to_s: f64) -> f64 {
    env.iter()
        .filter(|e| e.0 >= from_s && e.0 <= to_s)
        .map(|e| e.1)
        .reduce(f64::max)
        .unwrap_or_else(|| envelope_at(env, from_s))
}

/// Modal amplitude of the envelope at time `t` (log-linear between half cycles).
pub fn envelope_at(env: &[(f64, f64, f64)], t: f64) -> f64 {
    let Some(i) = env.iter().position(|e| e.0 > t) else {
        return env.last().map_or(0.0, |e| e.1);
    };
    if i == 0 {
        return env[0].1;
    }
    let (a, b) = (env[i - 1], env[i]);
    if a.1 <= 0.0 || b.1 <= 0.0 {
        return b.1;
    }
    let s = (t - a.0) / (b.0 - a.0);
    a.1 * (b.1 / a.1).powf(s)
}

/// Shape values of the dampers' points in mode `k`.
fn shapes(structure: &ModalStructure, k: usize, dampers: &[CoupledDamper]) -> Vec<f64> {
    dampers
        .iter()
        .map(|d| structure.point(&d.point).map(|s| s[k]).unwrap_or(0.0))
        .collect()
}

/// Initial modal amplitude of the free analysis (with D Eq. 5.19 if the scenario asks for it).
fn initial_modal_amplitude(
    structure: &ModalStructure,
    free: &FreeVibrationSpec,
    bed_mass_kg: f64,
) -> f64 {
    let k = free.mode;
    let init = structure
        .point(&free.initial_point)
        .map(|s| s[k])
        .unwrap_or(1.0);
    let scale = if free.scale_initial_by_bed_mass {
        free::bed_mass_scale(init, bed_mass_kg)
    } else {
        1.0
    };
    let w = structure.modes[k].omega_rad_s();
    scale * (free.initial_displacement_m.powi(2) + (free.initial_velocity_m_s / w).powi(2)).sqrt()
        / init.abs()
}

/// Log-spaced amplitudes of a max_damping objective.
pub fn amplitude_grid(min_m: f64, max_m: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| min_m * (max_m / min_m).powf(i as f64 / (n - 1).max(1) as f64))
        .collect()
}

/// Several equivalent dampers at one point acting as one (energies and effective masses add),
/// for the single-damper steady-state schemes of D Fig. 3.7 and Eq. 3.44.
#[derive(Debug)]
struct Combined<'a>(&'a [CoupledDamper]);

impl pdamp_structure::effective::EffectiveDamper for Combined<'_> {
    fn evaluate(
        &self,
        amplitude_m: f64,
        omega_rad_s: f64,
    ) -> pdamp_structure::effective::EffectiveState {
        let mut s = pdamp_structure::effective::EffectiveState {
            effective_mass_kg: 0.0,
            dissipated_energy_per_cycle_j: 0.0,
        };
        for d in self.0 {
            let e = d.model.evaluate(amplitude_m, omega_rad_s);
            s.effective_mass_kg += e.effective_mass_kg;
            s.dissipated_energy_per_cycle_j += e.dissipated_energy_per_cycle_j;
        }
        s
    }
    fn bed_mass_kg(&self) -> f64 {
        self.0.iter().map(|d| d.model.bed_mass_kg()).sum()
    }
}

/// Modal data of mode `k` for the steady-state schemes: the dampers' point (all dampers of a
/// design share it), the study's excitation point and force.
fn mode_coupling(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
) -> Result<pdamp_structure::forced::ModeCoupling, DesignError> {
    let load = study
        .load
        .as_ref()
        .ok_or_else(|| DesignError::Solver("min_frf_peak without a harmonic load".into()))?;
    let phi_pd = match dampers.first() {
        Some(d) => structure.point(&d.point).map_err(DesignError::from)?[k],
        None => 0.0,
    };
    Ok(pdamp_structure::forced::ModeCoupling {
        omega_rad_s: structure.modes[k].omega_rad_s(),
        damping_ratio: structure.modes[k].damping_ratio,
        phi_pd,
        phi_ex: structure
            .point(&load.excitation_point)
            .map_err(DesignError::from)?[k],
        force_amplitude_n: load.force_n,
    })
}

/// The bare structure's resonance peak of mode `k` at the output point (the scenario's
/// structure, the reference of min_frf_peak): $|\varphi_{out}\varphi_{ex}|F/(2\zeta_k\omega_k^2)$, m.
pub fn bare_peak_m(study: &DesignStudy, k: usize) -> Result<f64, DesignError> {
    let st = &study.structure;
    let load = study
        .load
        .as_ref()
        .ok_or_else(|| DesignError::Solver("min_frf_peak without a harmonic load".into()))?;
    let phi_out = st
        .point(&study.free.output_point)
        .map_err(DesignError::from)?[k];
    let phi_ex = st
        .point(&load.excitation_point)
        .map_err(DesignError::from)?[k];
    let m = &st.modes[k];
    Ok((phi_out * phi_ex * load.force_n).abs()
        / (2.0 * m.damping_ratio.max(1e-12) * m.omega_rad_s().powi(2)))
}

/// Resonance peak of mode `k` at the output point from the equilibrium of D Fig. 3.7
/// (level 0): $|\varphi_{out}|Q$ with $Q = R/(2m\zeta\bar\omega^2)$ (D Eq. 3.48), and the
/// equilibrium's ζ.
fn equilibrium_peak(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
) -> Result<(f64, f64), DesignError> {
    let c = mode_coupling(study, structure, dampers, k)?;
    let phi_out = structure
        .point(&study.free.output_point)
        .map_err(DesignError::from)?[k];
    let r = (c.phi_ex * c.force_amplitude_n).abs();
    if dampers.is_empty() || c.phi_pd == 0.0 {
        let q = r / (2.0 * c.damping_ratio.max(1e-12) * c.omega_rad_s.powi(2));
        return Ok(((phi_out * q).abs(), c.damping_ratio));
    }
    let e = pdamp_structure::forced::resonance_equilibrium(&c, &Combined(dampers), 400);
    let q = e.amplitude_m / c.phi_pd.abs();
    Ok(((phi_out * q).abs(), e.damping_ratio))
}

/// A resonance of the steady-state FRF (D Eq. 3.44, level 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfResonance {
    /// Peak amplitude at the output point, m.
    pub peak_m: f64,
    /// Peak of the modal coordinate Q_max.
    pub modal_peak: f64,
    /// Frequency of the peak, Hz.
    pub frequency_hz: f64,
}

/// Resonance peak of mode `k` from the steady-state FRF (D Eq. 3.44, level 1) over ±`band`
/// around the equilibrium frequency, `n` frequencies, then three zooms around the highest
/// point.
///
/// # Errors
/// Unknown points, a study without a harmonic load.
pub fn frf_resonance(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
    n: usize,
    band: f64,
) -> Result<FrfResonance, DesignError> {
    let c = mode_coupling(study, structure, dampers, k)?;
    let phi_out = structure
        .point(&study.free.output_point)
        .map_err(DesignError::from)?[k];
    let f0 = if dampers.is_empty() || c.phi_pd == 0.0 {
        structure.modes[k].frequency_hz
    } else {
        pdamp_structure::forced::resonance_equilibrium(&c, &Combined(dampers), 400).frequency_hz
    };
    let none: [CoupledDamper; 0] = [];
    let model = Combined(if c.phi_pd == 0.0 { &none } else { dampers });
    // the band, then three zooms around its highest point (a lightly damped peak is far
    // narrower than the band's spacing)
    let (mut lo, mut hi) = (f0 * (1.0 - band), f0 * (1.0 + band));
    let (mut q_max, mut f_max) = (0.0_f64, f0);
    for _ in 0..4 {
        let freqs: Vec<f64> = (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
            .collect();
        let pts = pdamp_structure::forced::steady_state_frf(&c, &model, &freqs);
        let (i_max, q) = pts
            .iter()
            .map(|p| p.modal_amplitude.abs())
            .enumerate()
            .fold((0, 0.0), |a, (i, p)| if p > a.1 { (i, p) } else { a });
        if q > q_max {
            (q_max, f_max) = (q, freqs[i_max]);
        }
        let df = (hi - lo) / (n - 1) as f64;
        (lo, hi) = (freqs[i_max] - 2.0 * df, freqs[i_max] + 2.0 * df);
    }
    Ok(FrfResonance {
        peak_m: (phi_out * q_max).abs(),
        modal_peak: q_max,
        frequency_hz: f_max,
    })
}

/// The steady-state FRF of mode `k` (D Eq. 3.44) at the output point under the study's force
/// with the formula `dampers` (none: the bare structure): |φ_out Q| at every frequency, m.
///
/// # Errors
/// Unknown points, a study without a harmonic load.
pub fn steady_frf_at_output(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
    frequencies_hz: &[f64],
) -> Result<Vec<f64>, DesignError> {
    let c = mode_coupling(study, structure, dampers, k)?;
    let phi_out = structure
        .point(&study.free.output_point)
        .map_err(DesignError::from)?[k];
    let none: [CoupledDamper; 0] = [];
    let model = Combined(if c.phi_pd == 0.0 { &none } else { dampers });
    Ok(
        pdamp_structure::forced::steady_state_frf(&c, &model, frequencies_hz)
            .iter()
            .map(|p| (phi_out * p.modal_amplitude).abs())
            .collect(),
    )
}

/// D Eq. 3.47 with m = ω_k²/Ω_R² (Eq. 3.33): ζ = R/(2 Q_max ω_k²), R = φ_ex F.
///
/// # Errors
/// Unknown excitation point, no harmonic load.
pub fn resonance_damping_ratio(
    study: &DesignStudy,
    structure: &ModalStructure,
    k: usize,
    modal_peak: f64,
) -> Result<f64, DesignError> {
    let load = study
        .load
        .as_ref()
        .ok_or_else(|| DesignError::Solver("a forced objective without a harmonic load".into()))?;
    let phi_ex = structure
        .point(&load.excitation_point)
        .map_err(DesignError::from)?[k];
    let wk = structure.modes[k].omega_rad_s();
    Ok((phi_ex * load.force_n).abs() / (2.0 * modal_peak.max(1e-300) * wk * wk))
}

/// Cost of a forced objective: the mean relative peak (min_frf_peak) or −(mean ζ)
/// (max_resonance_damping), from the sum of the relative peaks and the ζ per mode.
fn forced_cost(study: &DesignStudy, relative_peak_sum: f64, zetas: &[f64]) -> f64 {
    let n = zetas.len().max(1) as f64;
    match study.file.objective {
        ObjectiveSpec::MinFrfPeak { .. } => relative_peak_sum / n,
        _ => -zetas.iter().sum::<f64>() / n,
    }
}

/// What one evaluation found.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Evaluation {
    /// Objective value to minimise: the stroke (m) for min_stroke, −(mean ζ) for max_damping.
    pub cost: f64,
    /// min_stroke: the stroke at the evaluation time, m.
    pub stroke_m: Option<f64>,
    /// max_damping: mean ζ over the amplitude range per objective mode; min_frf_peak: ζ at the
    /// resonance equilibrium per mode (level 0).
    pub damping_ratio_per_mode: Vec<f64>,
    /// min_frf_peak: the resonance peak at the output point per objective mode, m.
    pub peak_amplitude_per_mode_m: Vec<f64>,
}

/// Level 0: the envelope model.
///
/// # Errors
/// Unknown points (validated before, so only for structures changed by a detuning).
pub fn envelope_evaluation(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
) -> Result<Evaluation, DesignError> {
    let bed: f64 = dampers.iter().map(|d| d.model.bed_mass_kg()).sum();
    let out_shape = structure
        .point(&study.free.output_point)
        .map_err(DesignError::from)?
        .to_vec();
    match &study.file.objective {
        ObjectiveSpec::MinStroke { evaluate_at_s } => {
            let k = study.free.mode;
            let sh = shapes(structure, k, dampers);
            let q0 = initial_modal_amplitude(structure, &study.free, bed);
            let env = envelope(
                structure,
                k,
                dampers,
                &sh,
                q0,
                *evaluate_at_s,
                0.0,
                study.free.update,
            );
            // the stroke: the largest |x| over the last 1.1 bare periods (the time
            // simulation's window)
            let period = 1.0 / structure.modes[k].frequency_hz;
            let q = envelope_max(&env, evaluate_at_s - 1.1 * period, *evaluate_at_s);
            let stroke = (out_shape[k] * q).abs();
            Ok(Evaluation {
                cost: stroke,
                stroke_m: Some(stroke),
                ..Default::default()
            })
        }
        ObjectiveSpec::MaxDamping {
            modes,
            amplitude_min_m,
            amplitude_max_m,
            amplitudes,
        } => {
            let grid = amplitude_grid(*amplitude_min_m, *amplitude_max_m, *amplitudes);
            let per_mode: Vec<f64> = modes
                .iter()
                .map(|&m| {
                    let k = m - 1;
                    let sh = shapes(structure, k, dampers);
                    grid.iter()
                        .map(|x| {
                            let q = x / out_shape[k].abs().max(1e-300);
                            modal_damping(structure, k, dampers, &sh, q).0
                        })
                        .sum::<f64>()
                        / grid.len() as f64
                })
                .collect();
            let mean = per_mode.iter().sum::<f64>() / per_mode.len() as f64;
            Ok(Evaluation {
                cost: -mean,
                stroke_m: None,
                damping_ratio_per_mode: per_mode,
                peak_amplitude_per_mode_m: Vec::new(),
            })
        }
        ObjectiveSpec::MinFrfPeak { modes, .. }
        | ObjectiveSpec::MaxResonanceDamping { modes, .. } => {
            let mut peaks = Vec::new();
            let mut zetas = Vec::new();
            let mut rel = 0.0;
            for &m in modes {
                let (p, z) = equilibrium_peak(study, structure, dampers, m - 1)?;
                rel += p / bare_peak_m(study, m - 1)?;
                peaks.push(p);
                zetas.push(z);
            }
            let cost = forced_cost(study, rel, &zetas);
            Ok(Evaluation {
                cost,
                stroke_m: None,
                damping_ratio_per_mode: zetas,
                peak_amplitude_per_mode_m: peaks,
            })
        }
    }
}

/// The structure reduced to its mode `k` alone (shapes of every point kept for that mode).
pub fn single_mode(structure: &ModalStructure, k: usize) -> ModalStructure {
    let mut s = structure.clone();
    s.modes = vec![structure.modes[k]];
    for p in &mut s.points {
        p.shape = vec![p.shape[k]];
    }
    s
}

/// The free decay that measures ζ(X) of mode `k` at the output point: the structure reduced
/// to mode `k` alone ([`single_mode`]), released 10 % above the top of the amplitude range,
/// run until the envelope of the design's dampers predicts 10 % below its bottom (at least 10,
/// at most 3000 periods). On mode k alone the decay is the damping of that mode as D measures
/// it per mode, without the energy the dampers pass to the other modes (which would otherwise
/// beat in the output point's peaks and spoil the log decrement). Level 1 runs it with the
/// formula dampers, level 3 ([`crate::dem`]) with the coupled DEM.
#[derive(Debug, Clone)]
pub struct DecayPlan {
    /// The structure reduced to the mode (its only mode, index 0).
    pub structure: ModalStructure,
    /// The free analysis (mode 0, from the output point).
    pub spec: FreeVibrationSpec,
    /// The mode's period, s.
    pub period_s: f64,
}

/// The [`DecayPlan`] of mode `k` (0-based) over `[amplitude_min_m, amplitude_max_m]`.
///
/// # Errors
/// The output point is a node of the mode, or it is missing.
pub fn damping_decay_plan(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
    amplitude_min_m: f64,
    amplitude_max_m: f64,
) -> Result<DecayPlan, DesignError> {
    let out = &study.free.output_point;
    let structure = single_mode(structure, k);
    let mode = k;
    let k = 0;
    let phi_out = structure.point(out).map_err(DesignError::from)?[k];
    if phi_out == 0.0 {
        return Err(DesignError::Solver(format!(
            "the output point '{out}' is a node of mode {}: no amplitude range there",
            mode + 1
        )));
    }
    let period = 1.0 / structure.modes[k].frequency_hz;
    let sh = shapes(&structure, k, dampers);
    let q0 = 1.1 * amplitude_max_m / phi_out.abs();
    let update = if study.free.update == UpdateRule::Never {
        UpdateRule::ZeroCrossing
    } else {
        study.free.update
    };
    let env = envelope(
        &structure,
        k,
        dampers,
        &sh,
        q0,
        3000.0 * period,
        0.9 * amplitude_min_m / phi_out.abs(),
        update,
    );
    let duration = env
        .last()
        .map_or(0.0, |e| e.0)
        .clamp(10.0 * period, 3000.0 * period);
    let spec = FreeVibrationSpec {
        duration_s: duration,
        time_step_s: period / 80.0,
        mode: k,
        initial_point: out.clone(),
        initial_displacement_m: 1.1 * amplitude_max_m * phi_out.signum(),
        initial_velocity_m_s: 0.0,
        scale_initial_by_bed_mass: false,
        output_point: out.clone(),
        update,
        sample_every: 1,
    };
    Ok(DecayPlan {
        structure,
        spec,
        period_s: period,
    })
}

/// ζ per cycle of a decay at the output point: (mean amplitude per cycle, ζ per cycle)
/// [D Eq. 3.40, 3.41], peaks closer than half a period merged.
///
/// # Errors
/// A history that is not uniformly sampled.
pub fn damping_curve_of(hist: &TimeHistory, period_s: f64) -> Result<Vec<(f64, f64)>, DesignError> {
    let peaks = decay_peaks(hist, 0.5 * period_s).map_err(DesignError::from)?;
    Ok(damping_per_cycle(&peaks)
        .iter()
        .map(|c| (c.mean_amplitude_m, c.damping_ratio))
        .collect())
}

/// ζ(X) of mode `k` at the output point from the [`DecayPlan`]'s decay simulated with the
/// formula dampers (level 1).
///
/// # Errors
/// Solver errors.
pub fn simulated_damping_curve(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
    amplitude_min_m: f64,
    amplitude_max_m: f64,
) -> Result<Vec<(f64, f64)>, DesignError> {
    let plan = damping_decay_plan(
        study,
        structure,
        dampers,
        k,
        amplitude_min_m,
        amplitude_max_m,
    )?;
    let hist = free::run_free_vibration(&plan.structure, dampers, &plan.spec)
        .map_err(DesignError::from)?;
    damping_curve_of(&hist, plan.period_s)
}

/// ζ at amplitude `x` from a per-cycle curve (log-linear in X between the cycles that bracket
/// it; the nearest cycle outside the simulated range).
pub fn curve_at(curve: &[(f64, f64)], x: f64) -> f64 {
    let mut pts: Vec<(f64, f64)> = curve.iter().copied().filter(|p| p.0 > 0.0).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    match pts.as_slice() {
        [] => 0.0,
        [p] => p.1,
        _ => {
            if x <= pts[0].0 {
                return pts[0].1;
            }
            if x >= pts[pts.len() - 1].0 {
                return pts[pts.len() - 1].1;
            }
            let i = pts.partition_point(|p| p.0 < x);
            let (a, b) = (pts[i - 1], pts[i]);
            let s = (x / a.0).ln() / (b.0 / a.0).ln();
            a.1 + (b.1 - a.1) * s
        }
    }
}

/// Level 1: the modal time simulation with the formula dampers. Returns the evaluation and,
/// for min_stroke, the decay at the output point (for the plots).
///
/// # Errors
/// Solver errors.
pub fn time_evaluation(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
) -> Result<(Evaluation, Option<TimeHistory>), DesignError> {
    time_evaluation_by_mode(study, structure, &|_| dampers)
}

/// [`time_evaluation`] with the dampers of each mode's evaluation from `dampers_of(k)` (k the
/// 0-based mode the decay, stroke or resonance belongs to): level 2 couples every mode to the
/// effective field computed at that mode's frequency.
///
/// # Errors
/// Solver errors.
pub fn time_evaluation_by_mode<'a>(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers_of: &dyn Fn(usize) -> &'a [CoupledDamper],
) -> Result<(Evaluation, Option<TimeHistory>), DesignError> {
    match &study.file.objective {
        ObjectiveSpec::MinStroke { evaluate_at_s } => {
            let mut fs = study.free.clone();
            fs.duration_s = *evaluate_at_s;
            let k = fs.mode;
            let hist = free::run_free_vibration(structure, dampers_of(k), &fs)
                .map_err(DesignError::from)?;
            let period = 1.0 / structure.modes[k].frequency_hz;
            // the layer study's window: one bare period + 10 % (the loaded structure is slower)
            let stroke = pdamp_structure::study::stroke_at(&hist, *evaluate_at_s, 1.1 * period);
            Ok((
                Evaluation {
                    cost: stroke,
                    stroke_m: Some(stroke),
                    ..Default::default()
                },
                Some(hist),
            ))
        }
        ObjectiveSpec::MaxDamping {
            modes,
            amplitude_min_m,
            amplitude_max_m,
            amplitudes,
        } => {
            let grid = amplitude_grid(*amplitude_min_m, *amplitude_max_m, *amplitudes);
            let mut per_mode = Vec::new();
            for &m in modes {
                let curve = simulated_damping_curve(
                    study,
                    structure,
                    dampers_of(m - 1),
                    m - 1,
                    *amplitude_min_m,
                    *amplitude_max_m,
                )?;
                per_mode.push(
                    grid.iter().map(|&x| curve_at(&curve, x)).sum::<f64>() / grid.len() as f64,
                );
            }
            let mean = per_mode.iter().sum::<f64>() / per_mode.len() as f64;
            Ok((
                Evaluation {
                    cost: -mean,
                    stroke_m: None,
                    damping_ratio_per_mode: per_mode,
                    peak_amplitude_per_mode_m: Vec::new(),
                },
                None,
            ))
        }
        ObjectiveSpec::MinFrfPeak {
            modes,
            frequencies,
            band,
        }
        | ObjectiveSpec::MaxResonanceDamping {
            modes,
            frequencies,
            band,
        } => {
            let mut peaks = Vec::new();
            let mut zetas = Vec::new();
            let mut rel = 0.0;
            for &m in modes {
                let k = m - 1;
                let r = frf_resonance(study, structure, dampers_of(k), k, *frequencies, *band)?;
                rel += r.peak_m / bare_peak_m(study, k)?;
                peaks.push(r.peak_m);
                zetas.push(resonance_damping_ratio(study, structure, k, r.modal_peak)?);
            }
            let cost = forced_cost(study, rel, &zetas);
            Ok((
                Evaluation {
                    cost,
                    stroke_m: None,
                    damping_ratio_per_mode: zetas,
                    peak_amplitude_per_mode_m: peaks,
                },
                None,
            ))
        }
    }
}
