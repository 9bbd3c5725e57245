//! Forced vibration [D Sect. 3.3.2]: slow sine sweeps (linear or logarithmic, up or down) in the
//! time domain, the FRF $H = X^*/F^*$ [D Eq. 3.42] by synchronous demodulation of the sweep,
//! the time-domain damping ratio from the resonance peak [D Eq. 3.43–3.47], a single-mode
//! rational-fraction-polynomial fit, and the steady-state iteration scheme for approaches 2/3
//! [D Fig. 3.7, Eq. 3.48–3.50] including a full steady-state FRF.

use crate::StructureError;
use crate::effective::EffectiveDamper;
use crate::free::{CoupledDamper, TimeHistory, UpdateRecord};
use crate::integrate::{Attachment, ModalIntegrator, generalized_force};
use crate::modal::ModalStructure;
use nalgebra::{DMatrix, DVector};
use pdamp_signal::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Frequency law of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SweepLaw {
    /// f(t) = f0 + (f1 − f0) t/T.
    #[default]
    Linear,
    /// f(t) = f0 (f1/f0)^(t/T).
    Logarithmic,
}

/// A sine sweep from `start_hz` to `end_hz` (down if end < start) in `duration_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// Start frequency, Hz.
    pub start_hz: f64,
    /// End frequency, Hz.
    pub end_hz: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Frequency law.
    #[serde(default)]
    pub law: SweepLaw,
}

impl Sweep {
    /// Instantaneous frequency, Hz.
    pub fn frequency_hz(&self, t: f64) -> f64 {
        let s = (t / self.duration_s).clamp(0.0, 1.0);
        match self.law {
            SweepLaw::Linear => self.start_hz + (self.end_hz - self.start_hz) * s,
            SweepLaw::Logarithmic => self.start_hz * (self.end_hz / self.start_hz).powf(s),
        }
    }

    /// Phase $\varphi(t) = 2\pi\int_0^t f\,dt$, rad.
    pub fn phase_rad(&self, t: f64) -> f64 {
        let (f0, f1, tt) = (self.start_hz, self.end_hz, self.duration_s);
        match self.law {
            SweepLaw::Linear => TAU * (f0 * t + 0.5 * (f1 - f0) * t * t / tt),
            SweepLaw::Logarithmic => {
                let r = (f1 / f0).ln();
                if r.abs() < 1e-14 {
                    TAU * f0 * t
                } else {
                    TAU * f0 * tt / r * ((r * t / tt).exp() - 1.0)
                }
            }
        }
    }

    /// Checks the parameters: frequencies and duration finite and > 0.
    ///
    /// # Errors
    /// A message naming the key and the fix.
    pub fn validate(&self) -> Result<(), StructureError> {
        for (key, v) in [
            ("start_hz", self.start_hz),
            ("end_hz", self.end_hz),
            ("duration_s", self.duration_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(StructureError::invalid(
                    "sweep",
                    format!("{key} = {v:e} must be a finite number > 0"),
                ));
            }
        }
        Ok(())
    }
}

impl SweepSpec {
    /// Checks the sweep, the force amplitude (finite) and the time step against the highest
    /// excitation frequency (at least 8 steps per excitation period).
    ///
    /// # Errors
    /// A message naming the key and the fix.
    pub fn validate(&self) -> Result<(), StructureError> {
        self.sweep.validate()?;
        if !self.force_amplitude_n.is_finite() {
            return Err(StructureError::invalid(
                "sweep",
                format!(
                    "force amplitude {:e} N must be finite",
                    self.force_amplitude_n
                ),
            ));
        }
        let f_max = self.sweep.start_hz.max(self.sweep.end_hz);
        if self.time_step_s.is_finite() && self.time_step_s * f_max > 0.125 {
            return Err(StructureError::invalid(
                "sweep",
                format!(
                    "time_step_s = {:e} s resolves the highest excitation frequency {f_max:e} \
                     Hz with {:.2} steps per period; use at most {:e} s (8 steps per period, \
                     better 20)",
                    self.time_step_s,
                    1.0 / (self.time_step_s * f_max),
                    0.125 / f_max
                ),
            ));
        }
        Ok(())
    }
}

/// Settings of a time-domain sweep run.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSpec {
    /// The sweep.
    pub sweep: Sweep,
    /// Force amplitude F: $f_{ex} = F\cos\varphi(t)$ [D Eq. 3.30], N.
    pub force_amplitude_n: f64,
    /// Excitation point.
    pub excitation_point: String,
    /// Output point.
    pub output_point: String,
    /// Time step, s.
    pub time_step_s: f64,
    /// Store every n-th step.
    pub sample_every: usize,
}

/// Runs a sweep on the structure with equivalent dampers updated at every peak of their point
/// (X = |x|, Ω = 2πf(t) of the excitation).
///
/// # Errors
/// Unknown points or invalid settings.
pub fn run_sweep(
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    spec: &SweepSpec,
) -> Result<TimeHistory, StructureError> {
    structure.validate()?;
    spec.validate()?;
    crate::integrate::validate_settings(
        structure,
        spec.time_step_s,
        spec.sweep.duration_s,
        spec.sample_every,
        false,
    )?;
    let ex = structure.point(&spec.excitation_point)?.to_vec();
    let out = structure.point(&spec.output_point)?.to_vec();
    let shapes: Vec<Vec<f64>> = dampers
        .iter()
        .map(|d| structure.point(&d.point).map(|s| s.to_vec()))
        .collect::<Result<_, _>>()?;
    let mut it = ModalIntegrator::new(structure, spec.time_step_s);
    let mut atts: Vec<Attachment> = shapes
        .iter()
        .map(|s| Attachment {
            shape: s.clone(),
            mass_kg: 0.0,
            damping_n_s_m: 0.0,
        })
        .collect();
    let mut hist = TimeHistory::default();
    let f = |t: f64| spec.force_amplitude_n * spec.sweep.phase_rad(t).cos();
    // Start with the dampers evaluated at a tiny amplitude.
    for (i, d) in dampers.iter().enumerate() {
        let w = TAU * spec.sweep.start_hz;
        let s = d.model.evaluate(1e-6, w);
        atts[i].mass_kg = s.effective_mass_kg;
        atts[i].damping_n_s_m = s.viscous_damping_n_s_m(1e-6, w);
    }
    it.set_attachments(&atts);
    it.make_consistent(&generalized_force(&ex, f(0.0)));
    let n_steps = (spec.sweep.duration_s / spec.time_step_s).round() as usize;
    let every = spec.sample_every.max(1);
    let push = |it: &ModalIntegrator, h: &mut TimeHistory| {
        h.time_s.push(it.time_s);
        h.displacement_m.push(it.displacement(&out));
        h.velocity_m_s.push(it.velocity(&out));
        h.force_n.push(f(it.time_s));
    };
    push(&it, &mut hist);
    let mut prev_v: Vec<f64> = shapes.iter().map(|s| it.velocity(s)).collect();
    for step in 1..=n_steps {
        let t1 = step as f64 * spec.time_step_s;
        it.step(&generalized_force(&ex, f(t1)));
        let mut changed = false;
        for (i, d) in dampers.iter().enumerate() {
            let v1 = it.velocity(&shapes[i]);
            if prev_v[i] * v1 < 0.0 {
                let x = it.displacement(&shapes[i]).abs();
                let w = TAU * spec.sweep.frequency_hz(t1);
                let s = d.model.evaluate(x, w);
                atts[i].mass_kg = s.effective_mass_kg;
                atts[i].damping_n_s_m = s.viscous_damping_n_s_m(x, w);
                changed = true;
                hist.updates.push(UpdateRecord {
                    time_s: t1,
                    damper: i,
                    amplitude_m: x,
                    frequency_hz: w / TAU,
                    effective_mass_kg: atts[i].mass_kg,
                    damping_n_s_m: atts[i].damping_n_s_m,
                });
            }
            prev_v[i] = v1;
        }
        if changed {
            it.set_attachments(&atts);
            it.make_consistent(&generalized_force(&ex, f(t1)));
        }
        it.check_health(structure, step == n_steps)?;
        if step % every == 0 {
            push(&it, &mut hist);
        }
    }
    Ok(hist)
}

/// One FRF point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrfPoint {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// H = X*/F* [D Eq. 3.42], m/N.
    pub h_m_per_n: Complex64,
}

/// FRF of a sweep by synchronous demodulation: over windows of `cycles` whole excitation
/// cycles (in phase φ), $\hat x = \frac{1}{\pi N}\int x\,e^{-i\varphi}\,d\varphi$ for response
/// and force, H = x̂/f̂ [D Eq. 3.42], at the window's mid frequency; windows overlap by half.
/// Valid for slow sweeps (the response quasi-stationary over a window).
pub fn sweep_frf(hist: &TimeHistory, sweep: &Sweep, cycles: usize) -> Vec<FrfPoint> {
    let n = hist.time_s.len();
    if n < 3 || cycles == 0 {
        return Vec::new();
    }
    let phase: Vec<f64> = hist.time_s.iter().map(|&t| sweep.phase_rad(t)).collect();
    let span = TAU * cycles as f64;
    let total = phase[n - 1] - phase[0];
    let mut out = Vec::new();
    let mut start = phase[0];
    let mut i0 = 0;
    while start + span <= phase[0] + total {
        while i0 < n && phase[i0] < start {
            i0 += 1;
        }
        let (mut xs, mut fs) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
        let mut i = i0.max(1);
        while i < n && phase[i] <= start + span {
            let (p0, p1) = (phase[i - 1].max(start), phase[i]);
            let dp = p1 - p0;
            if dp > 0.0 {
                let e0 = Complex64::from_polar(1.0, -phase[i - 1]);
                let e1 = Complex64::from_polar(1.0, -phase[i]);
                xs += (e0 * hist.displacement_m[i - 1] + e1 * hist.displacement_m[i]) * (0.5 * dp);
                fs += (e0 * hist.force_n[i - 1] + e1 * hist.force_n[i]) * (0.5 * dp);
            }
            i += 1;
        }
        if fs.norm() > 0.0 {
            // mid-phase time → frequency
            let mid = start + 0.5 * span;
            let k = phase.partition_point(|&p| p < mid).min(n - 1);
            out.push(FrfPoint {
                frequency_hz: sweep.frequency_hz(hist.time_s[k]),
                h_m_per_n: xs / fs,
            });
        }
        start += 0.5 * span;
    }
    out.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out
}

/// One segment of a sweep split for the frequency-domain approach [D Sect. 3.3.2].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SweepSegment {
    /// The segment's own sweep (same law and rate as the full sweep).
    pub sweep: Sweep,
    /// FRF points below this frequency (the segment's start-up transient) are dropped, Hz.
    pub keep_from_hz: f64,
    /// Upper end of the kept range, Hz.
    pub keep_to_hz: f64,
}

/// Splits a sweep into `n` segments of equal width in the law's coordinate (frequency for
/// linear, log-frequency for logarithmic sweeps) with the same sweep rate [D Sect. 3.3.2:
/// "the frequency range is divided up into multiple overlapping segments and calculated
/// simultaneously. The initial transient vibration parts of each simulation are cut off"].
/// Segment i runs over $[u_i - o, u_{i+1} + o/2]$ (o = `overlap` × width, clipped to the
/// sweep); its first o/2 are its start-up transient and are dropped, so neighbouring kept
/// ranges overlap by o/2, where [`peak_hold`] combines them.
pub fn segment_sweep(sweep: &Sweep, n: usize, overlap: f64) -> Vec<SweepSegment> {
    let n = n.max(1);
    let f_at = |u: f64| match sweep.law {
        SweepLaw::Linear => sweep.start_hz + (sweep.end_hz - sweep.start_hz) * u,
        SweepLaw::Logarithmic => sweep.start_hz * (sweep.end_hz / sweep.start_hz).powf(u),
    };
    let w = 1.0 / n as f64;
    let o = overlap.clamp(0.0, 1.0) * w;
    (0..n)
        .map(|i| {
            let (a, b) = (i as f64 * w, (i + 1) as f64 * w);
            let u0 = (a - o).max(0.0);
            let u1 = (b + 0.5 * o).min(1.0);
            let keep0 = if i == 0 { 0.0 } else { a - 0.5 * o };
            let (k0, k1) = (f_at(keep0), f_at(u1));
            SweepSegment {
                sweep: Sweep {
                    start_hz: f_at(u0),
                    end_hz: f_at(u1),
                    duration_s: sweep.duration_s * (u1 - u0),
                    law: sweep.law,
                },
                keep_from_hz: k0.min(k1),
                keep_to_hz: k0.max(k1),
            }
        })
        .collect()
}

/// Peak hold over segment FRFs (as the analyser's peak-hold averaging, D Sect. 8.2.1): a point
/// of one segment is kept unless another segment that covers its frequency has a larger
/// magnitude there (linear interpolation of |H|); the result is sorted by frequency.
pub fn peak_hold(segments: &[Vec<FrfPoint>]) -> Vec<FrfPoint> {
    let mag_at = |seg: &[FrfPoint], f: f64| -> Option<f64> {
        let (lo, hi) = (seg.first()?.frequency_hz, seg.last()?.frequency_hz);
        if f < lo || f > hi {
            return None;
        }
        let j = seg.partition_point(|p| p.frequency_hz < f);
        if j == 0 {
            return Some(seg[0].h_m_per_n.norm());
        }
        let (p0, p1) = (&seg[j - 1], &seg[j.min(seg.len() - 1)]);
        let df = p1.frequency_hz - p0.frequency_hz;
        let t = if df > 0.0 {
            (f - p0.frequency_hz) / df
        } else {
            0.0
        };
        Some(p0.h_m_per_n.norm() + t * (p1.h_m_per_n.norm() - p0.h_m_per_n.norm()))
    };
    let mut out = Vec::new();
    for (s, seg) in segments.iter().enumerate() {
        for p in seg {
            let m = p.h_m_per_n.norm();
            let beaten = segments
                .iter()
                .enumerate()
                .filter(|(t, _)| *t != s)
                .any(|(_, other)| mag_at(other, p.frequency_hz).is_some_and(|mo| mo > m));
            if !beaten {
                out.push(*p);
            }
        }
    }
    out.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out
}

/// Time-domain damping ratio from the resonance peak of a sweep [D Eq. 3.47].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeakDamping {
    /// Largest response amplitude, m.
    pub max_amplitude_m: f64,
    /// Resonance frequency Ω_R/2π at the time of the maximum, Hz.
    pub resonance_frequency_hz: f64,
    /// $\zeta = R/(2 m Q_{max}\Omega_R^2)$ [D Eq. 3.47].
    pub damping_ratio: f64,
}

/// Eq. 3.47 for mode k from a sweep history: the largest |x| at the output point gives
/// $Q_{max} = x_{max}/\phi_{out}$, $R = \phi_{ex}F$, and `modal_mass` m (1 for the bare
/// structure, $1 + \phi_{pd}^2\bar m_{bed}$ with a damper; `None` estimates it from the
/// resonance frequency as $m = \omega_k^2/\Omega_R^2$, Eq. 3.33).
pub fn peak_damping(
    hist: &TimeHistory,
    sweep: &Sweep,
    force_amplitude_n: f64,
    phi_ex: f64,
    phi_out: f64,
    omega_k: f64,
    modal_mass: Option<f64>,
) -> Option<PeakDamping> {
    let n = hist.displacement_m.len();
    let mut best: Option<(f64, f64)> = None;
    for i in 1..n.saturating_sub(1) {
        let (a, b, c) = (
            hist.displacement_m[i - 1].abs(),
            hist.displacement_m[i].abs(),
            hist.displacement_m[i + 1].abs(),
        );
        if b >= a && b >= c {
            // parabolic refinement of the peak value
            let den = a - 2.0 * b + c;
            let (v, dt) = if den < 0.0 {
                let p = 0.5 * (a - c) / den;
                (b - 0.25 * (a - c) * p, p)
            } else {
                (b, 0.0)
            };
            if best.is_none_or(|(bv, _)| v > bv) {
                let h = hist.time_s[1] - hist.time_s[0];
                best = Some((v, hist.time_s[i] + dt * h));
            }
        }
    }
    let (x_max, t) = best?;
    let w_r = TAU * sweep.frequency_hz(t);
    let m = modal_mass.unwrap_or(omega_k * omega_k / (w_r * w_r));
    let q = x_max / phi_out.abs();
    let r = phi_ex.abs() * force_amplitude_n;
    Some(PeakDamping {
        max_amplitude_m: x_max,
        resonance_frequency_hz: w_r / TAU,
        damping_ratio: r / (2.0 * m * q * w_r * w_r),
    })
}

/// Modal parameters from a single-mode fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModalFit {
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
}

/// Single-mode rational fraction polynomial fit [Richardson & Formenti 1982] of receptance
/// points: $H(\omega) \approx (b_0 + i\omega b_1)/(a_0 + i\omega a_1 - \omega^2)$, linear least
/// squares in (a0, a1, b0, b1); $\omega_n = \sqrt{a_0}$, $\zeta = a_1/(2\omega_n)$. Use points
/// around one resonance (e.g. |H| above half the peak).
pub fn rfp_single_mode(points: &[FrfPoint]) -> Option<ModalFit> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len();
    let mut a = DMatrix::<f64>::zeros(2 * n, 4);
    let mut b = DVector::<f64>::zeros(2 * n);
    // Scale ω to O(1) for conditioning.
    let w0 = TAU * points[n / 2].frequency_hz;
    for (i, p) in points.iter().enumerate() {
        let w = TAU * p.frequency_hz / w0;
        let h = p.h_m_per_n;
        // H a0 + iωH a1 − b0 − iω b1 = ω² H
        let c_a1 = Complex64::new(0.0, w) * h;
        let rows = [
            (h.re, c_a1.re, -1.0, 0.0, w * w * h.re),
            (h.im, c_a1.im, 0.0, -w, w * w * h.im),
        ];
        for (r, row) in rows.iter().enumerate() {
            a[(2 * i + r, 0)] = row.0;
            a[(2 * i + r, 1)] = row.1;
            a[(2 * i + r, 2)] = row.2;
            a[(2 * i + r, 3)] = row.3;
            b[2 * i + r] = row.4;
        }
    }
    let sol = pdamp_fem::dense::least_squares(&a, &b, 1e-14)?;
    if sol[0] <= 0.0 {
        return None;
    }
    let wn = sol[0].sqrt();
    Some(ModalFit {
        frequency_hz: wn * w0 / TAU,
        damping_ratio: sol[1] / (2.0 * wn),
    })
}

/// Result of the resonance iteration of D Fig. 3.7.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Equilibrium {
    /// Damping ratio ζ_k [D Eq. 3.49].
    pub damping_ratio: f64,
    /// Damper amplitude X [D Eq. 3.50], m.
    pub amplitude_m: f64,
    /// Effective eigenfrequency ω̄_k/2π [D Eq. 3.33], Hz.
    pub frequency_hz: f64,
    /// Effective particle mass, kg.
    pub effective_mass_kg: f64,
    /// Effective viscous damping d̄, N·s/m.
    pub damping_n_s_m: f64,
    /// Effective loss factor at the equilibrium.
    pub effective_loss_factor: f64,
    /// Iterations used.
    pub iterations: usize,
    /// Converged (|Δζ| ≤ 1e-9 relative).
    pub converged: bool,
}

/// Mode-k data for the steady-state schemes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeCoupling {
    /// ω_k, rad/s.
    pub omega_rad_s: f64,
    /// Structural modal damping ratio ζ_k (D_k = 2ζ_kω_k).
    pub damping_ratio: f64,
    /// φ_pd^(k).
    pub phi_pd: f64,
    /// φ_ex^(k).
    pub phi_ex: f64,
    /// Force amplitude F_ex, N.
    pub force_amplitude_n: f64,
}

/// Iteration scheme of D Fig. 3.7: start with Ẽ = 0, m̄ = 0; then repeatedly
/// Q = R/(2mζω̄²) (Eq. 3.48), X = φ_pd Q (Eq. 3.50), Ẽ and m̄ at (ω̄, X), ω̄ (Eq. 3.33),
/// d̄ (Eq. 3.39), ζ (Eq. 3.49), until ζ converges. D relaxes by averaging Ẽ of successive
/// iterates; that diverges when X changes by orders of magnitude between the first iterates
/// (the first X is set by the structural damping alone), so the mean of successive ζ is taken
/// instead (same fixed point).
pub fn resonance_equilibrium(
    mode: &ModeCoupling,
    model: &dyn EffectiveDamper,
    max_iterations: usize,
) -> Equilibrium {
    let ModeCoupling {
        omega_rad_s: wk,
        damping_ratio: zk,
        phi_pd,
        phi_ex,
        force_amplitude_n,
    } = *mode;
    let p2 = phi_pd * phi_pd;
    let r = phi_ex * force_amplitude_n;
    let mut mbar = 0.0;
    let mut zeta = zk;
    let mut w = wk;
    let mut x = 0.0;
    let mut d = 0.0;
    let mut eta = 0.0;
    let mut converged = false;
    let mut iterations = 0;
    for n in 0..max_iterations {
        iterations = n + 1;
        let m = 1.0 + p2 * mbar;
        let q = r / (2.0 * m * zeta * w * w);
        x = (phi_pd * q).abs();
        let s = model.evaluate(x, w);
        let e = s.dissipated_energy_per_cycle_j;
        mbar = s.effective_mass_kg;
        let m = 1.0 + p2 * mbar;
        w = wk / m.sqrt();
        d = e / (PI * w * x * x);
        let z_new = (2.0 * zk * wk + p2 * d) / (2.0 * m * w);
        let v = x * w;
        eta = e / (PI * model.bed_mass_kg() * v * v);
        let done = (z_new - zeta).abs() <= 1e-9 * z_new;
        zeta = if n == 0 { z_new } else { 0.5 * (zeta + z_new) };
        if done {
            converged = true;
            break;
        }
    }
    Equilibrium {
        damping_ratio: zeta,
        amplitude_m: x,
        frequency_hz: w / TAU,
        effective_mass_kg: mbar,
        damping_n_s_m: d,
        effective_loss_factor: eta,
        iterations,
        converged,
    }
}

/// One point of a steady-state FRF of approaches 2/3.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SteadyPoint {
    /// Excitation frequency, Hz.
    pub frequency_hz: f64,
    /// Modal amplitude |Q| [D Eq. 3.44].
    pub modal_amplitude: f64,
    /// Damper amplitude X = φ_pd Q, m.
    pub amplitude_m: f64,
    /// Phase lag ψ_k of q behind the force [D Eq. 3.43], rad.
    pub phase_rad: f64,
    /// m = 1 + φ²m̄ at the point.
    pub modal_mass: f64,
    /// Fixed point converged.
    pub converged: bool,
}

/// Steady-state response of mode k with an amplitude-dependent damper at each frequency of
/// `frequencies_hz` (solved successively, each starting from the previous solution, as in
/// D Sect. 5.2.2): fixed point of $Q = R/\sqrt{(\omega_k^2 - m\Omega^2)^2 + (d\Omega)^2}$
/// [D Eq. 3.44 with 3.31] with m̄(Ω, X), d̄ = Ẽ/(πΩX²), relaxed by averaging.
pub fn steady_state_frf(
    mode: &ModeCoupling,
    model: &dyn EffectiveDamper,
    frequencies_hz: &[f64],
) -> Vec<SteadyPoint> {
    let p2 = mode.phi_pd * mode.phi_pd;
    let r = mode.phi_ex * mode.force_amplitude_n;
    let wk = mode.omega_rad_s;
    let dk = 2.0 * mode.damping_ratio * wk;
    let mut q = r / (wk * wk);
    let mut out = Vec::with_capacity(frequencies_hz.len());
    for &f in frequencies_hz {
        let w = TAU * f;
        let mut converged = false;
        let mut m = 1.0;
        let mut d = dk;
        for _ in 0..400 {
            let x = (mode.phi_pd * q).abs().max(1e-15);
            let s = model.evaluate(x, w);
            m = 1.0 + p2 * s.effective_mass_kg;
            d = dk + p2 * s.viscous_damping_n_s_m(x, w);
            let q_new = r / ((wk * wk - m * w * w).powi(2) + (d * w).powi(2)).sqrt();
            let done = (q_new - q).abs() <= 1e-10 * q_new;
            q = 0.5 * (q + q_new);
            if done {
                converged = true;
                break;
            }
        }
        out.push(SteadyPoint {
            frequency_hz: f,
            modal_amplitude: q,
            amplitude_m: (mode.phi_pd * q).abs(),
            phase_rad: (d * w).atan2(wk * wk - m * w * w),
            modal_mass: m,
            converged,
        });
    }
    out
}

/// Eq. 3.47 on a steady-state FRF: $\zeta = R/(2 m Q_{max}\Omega_R^2)$ at the point of largest
/// Q, with m from that point. Returns (ζ, resonance frequency Hz, peak damper amplitude m).
pub fn steady_state_damping(
    mode: &ModeCoupling,
    points: &[SteadyPoint],
) -> Option<(f64, f64, f64)> {
    let p = points
        .iter()
        .max_by(|a, b| a.modal_amplitude.total_cmp(&b.modal_amplitude))?;
    let w = TAU * p.frequency_hz;
    let r = (mode.phi_ex * mode.force_amplitude_n).abs();
    Some((
        r / (2.0 * p.modal_mass * p.modal_amplitude * w * w),
        p.frequency_hz,
        p.amplitude_m,
    ))
}
