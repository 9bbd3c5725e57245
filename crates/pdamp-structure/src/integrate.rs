//! Time integration of the reduced structure [D Eq. 3.21] with attached equivalent dampers
//! [D Eq. 3.29–3.31],
//! $$(E + \sum \bar m\,\phi\phi^T)\ddot q + (D + \sum \bar d\,\phi\phi^T)\dot q
//! \;+\; \Omega q = \Phi^T f,$$
//! by the Newmark average-acceleration rule (γ = 1/2, β = 1/4: unconditionally stable, no
//! numerical damping, period error ≈ (ωΔt)²/12).
//!
//! **Health.** The integrator keeps an energy ledger: the work of the generalized forces
//! (trapezoidal, $\sum \tfrac12(p_n + p_{n+1})^T(q_{n+1} - q_n)$) and the energy changed by
//! replacing the attachments. For the Newmark rule the identity
//! $E_{n+1} - E_n = \bar p^T\Delta q - \tfrac{\Delta t}{4}(\dot q_n + \dot q_{n+1})^T C
//! (\dot q_n + \dot q_{n+1})$ holds exactly, so the dissipation
//! $W + E_{jumps} - (E - E_0)$ must stay ≥ 0 up to round-off; for the explicit Verlet scheme of
//! the DEM coupling up to its bounded energy error. [`ModalIntegrator::check_health`] stops a
//! run on non-finite states or energy created beyond that tolerance with an
//! [`IntegrationError`] naming the time, the mode and the likely cause;
//! [`validate_settings`] checks the time step, duration and sampling before a run.

use crate::modal::ModalStructure;
use nalgebra::{DMatrix, DVector};

/// Most time steps of one run (1e9).
pub const MAX_STEPS: f64 = 1e9;

/// Most stored samples of one run (2e7: four series of 8 bytes, 640 MB).
pub const MAX_SAMPLES: f64 = 2e7;

/// Relative energy tolerance of the Newmark rule (round-off only).
pub const NEWMARK_ENERGY_TOLERANCE: f64 = 1e-6;

/// Relative energy tolerance of the explicit (Verlet) scheme, to which (ω_max Δt)² is added.
pub const EXPLICIT_ENERGY_TOLERANCE: f64 = 0.05;

/// The energy balance is evaluated every this many calls of
/// [`ModalIntegrator::check_health`] (finiteness at every call).
pub const ENERGY_CHECK_EVERY: usize = 16;

/// Errors of the modal integration: bad settings (before a run) and numerical failures.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrationError {
    /// An integrator setting is out of range.
    #[error("{key} = {value:e}: {reason}")]
    Settings {
        /// The setting's key (`time_step_s`, `duration_s`, `sample_every`).
        key: String,
        /// Its value.
        value: f64,
        /// What is wrong and the fix.
        reason: String,
    },
    /// The state became non-finite.
    #[error(
        "numerical failure at t = {time_s:e} s, mode {mode} ({frequency_hz:.6e} Hz): non-finite \
         {quantity}; likely cause: {cause}"
    )]
    NonFinite {
        /// Time, s.
        time_s: f64,
        /// The mode (1-based).
        mode: usize,
        /// Its frequency, Hz.
        frequency_hz: f64,
        /// `displacement`, `velocity`, `acceleration` or `energy`.
        quantity: &'static str,
        /// Likely cause from the evidence.
        cause: String,
    },
    /// Energy was created: the dissipation became negative beyond round-off.
    #[error(
        "numerical failure at t = {time_s:e} s, mode {mode} ({frequency_hz:.6e} Hz): the \
         structure's energy {energy_j:e} J exceeds the initial energy plus the work put in \
         ({budget_j:e} J) by {excess_j:e} J (negative dissipation); likely cause: {cause}"
    )]
    EnergyGrowth {
        /// Time, s.
        time_s: f64,
        /// The mode holding most energy (1-based).
        mode: usize,
        /// Its frequency, Hz.
        frequency_hz: f64,
        /// Modal energy now, J.
        energy_j: f64,
        /// Initial energy + work + attachment changes, J.
        budget_j: f64,
        /// Energy created beyond the tolerance, J.
        excess_j: f64,
        /// Likely cause from the evidence.
        cause: String,
    },
}

impl From<IntegrationError> for String {
    fn from(e: IntegrationError) -> Self {
        e.to_string()
    }
}

/// Checks the settings of a run of `structure` before it starts: time step and duration
/// finite and > 0, the time step not above the duration, at most [`MAX_STEPS`] steps and
/// [`MAX_SAMPLES`] stored samples, and for the explicit scheme of the DEM coupling
/// (`explicit`) the stability limit ω_max Δt < 2 (Δt < T_min/π).
///
/// # Errors
/// [`IntegrationError::Settings`] naming the setting and the fix.
pub fn validate_settings(
    structure: &ModalStructure,
    time_step_s: f64,
    duration_s: f64,
    sample_every: usize,
    explicit: bool,
) -> Result<(), IntegrationError> {
    let bad = |key: &str, value: f64, reason: String| IntegrationError::Settings {
        key: key.into(),
        value,
        reason,
    };
    if !(time_step_s.is_finite() && time_step_s > 0.0) {
        return Err(bad(
            "time_step_s",
            time_step_s,
            "the time step must be a finite number > 0".into(),
        ));
    }
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(bad(
            "duration_s",
            duration_s,
            "the duration must be a finite number > 0".into(),
        ));
    }
    if time_step_s > duration_s {
        return Err(bad(
            "time_step_s",
            time_step_s,
            format!("the time step is longer than the duration {duration_s:e} s"),
        ));
    }
    let steps = duration_s / time_step_s;
    if steps > MAX_STEPS {
        return Err(bad(
            "time_step_s",
            time_step_s,
            format!(
                "{steps:.3e} steps over {duration_s:e} s, more than the {MAX_STEPS:e} accepted; \
                 use a longer time step or a shorter duration"
            ),
        ));
    }
    if sample_every == 0 {
        return Err(bad(
            "sample_every",
            0.0,
            "store at least every n-th step with n ≥ 1".into(),
        ));
    }
    if steps / sample_every as f64 > MAX_SAMPLES {
        return Err(bad(
            "sample_every",
            sample_every as f64,
            format!(
                "{:.3e} samples would be stored, more than the {MAX_SAMPLES:e} accepted; use \
                 sample_every ≥ {}",
                steps / sample_every as f64,
                (steps / MAX_SAMPLES).ceil()
            ),
        ));
    }
    if explicit
        && let Some((k, w)) = highest_mode(structure)
        && w * time_step_s >= 2.0
    {
        return Err(bad(
            "time_step_s",
            time_step_s,
            format!(
                "the explicit coupling is unstable: ω_max Δt = {:.3} ≥ 2 for mode {} ({:.6e} \
                     Hz, period {:e} s); use a time step below T_min/π = {:e} s or keep fewer \
                     modes",
                w * time_step_s,
                k + 1,
                w / std::f64::consts::TAU,
                std::f64::consts::TAU / w,
                2.0 / w
            ),
        ));
    }
    Ok(())
}

/// Index and ω of the highest mode.
fn highest_mode(structure: &ModalStructure) -> Option<(usize, f64)> {
    structure
        .modes
        .iter()
        .enumerate()
        .map(|(k, m)| (k, m.omega_rad_s()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// An equivalent mass + viscous damper acting at a point in the point's direction
/// [D Eq. 3.29]: $f_{pd} = -(\bar m \ddot x_{pd} + \bar d \dot x_{pd})$.
#[derive(Debug, Clone, PartialEq)]
pub struct Attachment {
    /// Mode-shape values at the damper point.
    pub shape: Vec<f64>,
    /// Effective particle mass m̄_bed, kg.
    pub mass_kg: f64,
    /// Effective viscous damping d̄, N·s/m.
    pub damping_n_s_m: f64,
}

/// Newmark integrator of the modal equations.
#[derive(Debug, Clone)]
pub struct ModalIntegrator {
    /// Time step, s.
    pub dt_s: f64,
    /// Time, s.
    pub time_s: f64,
    /// Modal coordinates q.
    pub q: DVector<f64>,
    /// Modal velocities q̇.
    pub v: DVector<f64>,
    /// Modal accelerations q̈.
    pub a: DVector<f64>,
    base_c: DVector<f64>,
    base_k: DVector<f64>,
    m: DMatrix<f64>,
    c: DMatrix<f64>,
    s_inv: DMatrix<f64>,
    ledger: EnergyLedger,
    verlet_q_prev: Option<DVector<f64>>,
}

/// Energy bookkeeping of [`ModalIntegrator`] (see the module docs).
#[derive(Debug, Clone, Default)]
struct EnergyLedger {
    /// The ledger has its initial energy.
    started: bool,
    /// Energy at the start (first step), J.
    initial_j: f64,
    /// Work of the generalized forces since the start, J.
    work_j: f64,
    /// Sum of |work| per step (scale of the tolerance), J.
    work_abs_j: f64,
    /// Energy changed by replacing the attachments, J.
    jumps_j: f64,
    /// Largest energy seen, J.
    peak_j: f64,
    /// Generalized force of the last consistent state.
    p_last: Option<DVector<f64>>,
    /// Explicit (Verlet) steps were taken.
    explicit: bool,
    /// Calls of `check_health`.
    checks: usize,
    /// Largest |d̄| or negative m̄ of the attachments (evidence for the diagnosis).
    negative_attachment: Option<(f64, f64)>,
    /// The inverse of the Newmark matrix failed.
    singular: bool,
}

impl ModalIntegrator {
    /// Integrator at rest with the structure's modal damping and no attachments.
    pub fn new(structure: &ModalStructure, dt_s: f64) -> Self {
        let n = structure.modes.len();
        let base_c = DVector::from_iterator(
            n,
            structure
                .modes
                .iter()
                .map(|m| 2.0 * m.damping_ratio * m.omega_rad_s()),
        );
        let base_k =
            DVector::from_iterator(n, structure.modes.iter().map(|m| m.omega_rad_s().powi(2)));
        let mut s = Self {
            dt_s,
            time_s: 0.0,
            q: DVector::zeros(n),
            v: DVector::zeros(n),
            a: DVector::zeros(n),
            base_c,
            base_k,
            m: DMatrix::identity(n, n),
            c: DMatrix::zeros(n, n),
            s_inv: DMatrix::zeros(n, n),
            ledger: EnergyLedger::default(),
            verlet_q_prev: None,
        };
        s.set_attachments(&[]);
        s
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// True for a structure without modes.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Replaces the attached equivalent dampers (the state q, q̇ is kept; q̈ is made consistent
    /// with the new matrices under the generalized force `p`, if given).
    pub fn set_attachments(&mut self, attachments: &[Attachment]) {
        let n = self.len();
        let mut m = DMatrix::<f64>::identity(n, n);
        let mut c = DMatrix::<f64>::from_diagonal(&self.base_c);
        self.ledger.negative_attachment = None;
        for at in attachments {
            if at.mass_kg < 0.0 || at.damping_n_s_m < 0.0 || !at.mass_kg.is_finite() {
                self.ledger.negative_attachment = Some((at.mass_kg, at.damping_n_s_m));
            }
            let phi = DVector::from_column_slice(&at.shape);
            let outer = &phi * phi.transpose();
            m += &outer * at.mass_kg;
            c += &outer * at.damping_n_s_m;
        }
        let (g, b, h) = (0.5, 0.25, self.dt_s);
        let s = &m + &c * (g * h) + DMatrix::from_diagonal(&self.base_k) * (b * h * h);
        self.s_inv = match pdamp_fem::dense::inverse(&s) {
            Some(s) => {
                self.ledger.singular = false;
                s
            }
            None => {
                // Reported by `check_health` (the state becomes non-finite).
                self.ledger.singular = true;
                DMatrix::from_element(n, n, f64::NAN)
            }
        };
        if self.ledger.started {
            let before = self.energy_j();
            self.m = m;
            self.ledger.jumps_j += self.energy_j() - before;
        } else {
            self.m = m;
        }
        self.c = c;
    }

    /// Sets q̈ from the equation of motion under generalized force `p` (after initial conditions
    /// or a change of the attachments).
    pub fn make_consistent(&mut self, p: &DVector<f64>) {
        let rhs = p - &self.c * &self.v - self.base_k.component_mul(&self.q);
        self.a = pdamp_fem::dense::inverse(&self.m)
            .map(|mi| mi * rhs)
            .unwrap_or_else(|| DVector::from_element(self.len(), f64::NAN));
        self.ledger.p_last = Some(p.clone());
    }

    /// Starts the energy ledger at the current state (called by the first step).
    fn start_ledger(&mut self) {
        if !self.ledger.started {
            self.ledger.started = true;
            self.ledger.initial_j = self.energy_j();
            self.ledger.peak_j = self.ledger.initial_j.abs();
        }
    }

    /// Books the work of the generalized force over a step from `q_prev` to the current q.
    fn book_work(&mut self, q_prev: &DVector<f64>, p_next: &DVector<f64>) {
        let dq = &self.q - q_prev;
        let w = match &self.ledger.p_last {
            Some(p0) if p0.len() == p_next.len() => 0.5 * (p0 + p_next).dot(&dq),
            _ => p_next.dot(&dq),
        };
        self.ledger.work_j += w;
        self.ledger.work_abs_j += w.abs();
        self.ledger.p_last = Some(p_next.clone());
    }

    /// One Newmark step to `time + dt` with the generalized force `p_next` = Φᵀf at the end of
    /// the step.
    pub fn step(&mut self, p_next: &DVector<f64>) {
        self.start_ledger();
        let q_prev = self.q.clone();
        let (g, b, h) = (0.5, 0.25, self.dt_s);
        let v_pred = &self.v + &self.a * ((1.0 - g) * h);
        let q_pred = &self.q + &self.v * h + &self.a * ((0.5 - b) * h * h);
        let rhs = p_next - &self.c * &v_pred - self.base_k.component_mul(&q_pred);
        let a1 = &self.s_inv * rhs;
        self.v = v_pred + &a1 * (g * h);
        self.q = q_pred + &a1 * (b * h * h);
        self.a = a1;
        self.time_s += h;
        self.book_work(&q_prev, p_next);
    }

    /// First half of an explicit velocity-Verlet step (used for the DEM coupling, where the
    /// combined structure + particle system is then one symplectic explicit scheme, stable
    /// for $\omega_{max}\Delta t < 2$): $\dot q_{n+1/2} = \dot q_n + \tfrac{\Delta t}{2}\ddot q_n$,
    /// $q_{n+1} = q_n + \Delta t\,\dot q_{n+1/2}$.
    pub fn verlet_drift(&mut self) {
        self.start_ledger();
        self.ledger.explicit = true;
        self.verlet_q_prev = Some(self.q.clone());
        let h = self.dt_s;
        self.v += &self.a * (0.5 * h);
        self.q += &self.v * h;
        self.time_s += h;
    }

    /// Second half of the velocity-Verlet step with the generalized force at $t_{n+1}$:
    /// $\ddot q_{n+1} = M^{-1}(p - D\dot q_{n+1/2} - \Omega q_{n+1})$,
    /// $\dot q_{n+1} = \dot q_{n+1/2} + \tfrac{\Delta t}{2}\ddot q_{n+1}$ (damping explicit).
    pub fn verlet_kick(&mut self, p: &DVector<f64>) {
        if let Some(q_prev) = self.verlet_q_prev.take() {
            self.book_work(&q_prev, p);
        }
        self.make_consistent(p);
        self.v += &self.a * (0.5 * self.dt_s);
    }

    /// Work of the generalized forces since the first step, J.
    pub fn work_j(&self) -> f64 {
        self.ledger.work_j
    }

    /// Energy dissipated since the first step: initial energy + work + attachment changes −
    /// energy now, J (≥ 0 up to round-off in a healthy run).
    pub fn dissipated_j(&self) -> f64 {
        self.ledger.initial_j + self.ledger.work_j + self.ledger.jumps_j - self.energy_j()
    }

    /// Health check (call after steps; cheap): non-finite q, q̇, q̈ stop the run at once, and
    /// every [`ENERGY_CHECK_EVERY`] calls (and with `force_energy`) the energy balance: the
    /// energy may not exceed the initial energy plus the work put in and the attachment
    /// changes by more than the tolerance ([`NEWMARK_ENERGY_TOLERANCE`] of the energy scale
    /// for the Newmark rule, [`EXPLICIT_ENERGY_TOLERANCE`] + (ω_max Δt)² for the explicit
    /// scheme).
    ///
    /// # Errors
    /// [`IntegrationError::NonFinite`] or [`IntegrationError::EnergyGrowth`] with the time,
    /// the mode and the likely cause.
    pub fn check_health(
        &mut self,
        structure: &ModalStructure,
        force_energy: bool,
    ) -> Result<(), IntegrationError> {
        self.ledger.checks += 1;
        let freq = |k: usize| structure.modes.get(k).map_or(f64::NAN, |m| m.frequency_hz);
        for (quantity, x) in [
            ("displacement", &self.q),
            ("velocity", &self.v),
            ("acceleration", &self.a),
        ] {
            if let Some(k) = x.iter().position(|v| !v.is_finite()) {
                return Err(IntegrationError::NonFinite {
                    time_s: self.time_s,
                    mode: k + 1,
                    frequency_hz: freq(k),
                    quantity,
                    cause: self.likely_cause(structure),
                });
            }
        }
        if !(force_energy || self.ledger.checks.is_multiple_of(ENERGY_CHECK_EVERY))
            || !self.ledger.started
        {
            return Ok(());
        }
        let e = self.energy_j();
        let (k, _) = self.dominant_mode();
        if !e.is_finite() {
            return Err(IntegrationError::NonFinite {
                time_s: self.time_s,
                mode: k + 1,
                frequency_hz: freq(k),
                quantity: "energy",
                cause: self.likely_cause(structure),
            });
        }
        let l = &mut self.ledger;
        l.peak_j = l.peak_j.max(e.abs());
        let budget = l.initial_j + l.work_j + l.jumps_j;
        let rel = if l.explicit {
            let wmax = highest_mode(structure).map_or(0.0, |(_, w)| w);
            EXPLICIT_ENERGY_TOLERANCE + (wmax * self.dt_s).powi(2)
        } else {
            NEWMARK_ENERGY_TOLERANCE
        };
        let scale = l.peak_j + l.initial_j.abs() + l.work_abs_j + l.jumps_j.abs();
        let tol = rel * scale + 1e-300;
        if e - budget > tol {
            return Err(IntegrationError::EnergyGrowth {
                time_s: self.time_s,
                mode: k + 1,
                frequency_hz: freq(k),
                energy_j: e,
                budget_j: budget,
                excess_j: e - budget - tol,
                cause: self.likely_cause(structure),
            });
        }
        Ok(())
    }

    /// Mode with the largest modal energy ½(q̇_k² m_kk + ω_k² q_k²) and that energy.
    fn dominant_mode(&self) -> (usize, f64) {
        (0..self.len())
            .map(|k| {
                let e = 0.5
                    * (self.v[k] * self.v[k] * self.m[(k, k)]
                        + self.base_k[k] * self.q[k] * self.q[k]);
                (k, if e.is_finite() { e } else { f64::INFINITY })
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0))
    }

    /// The likely cause of a failure, chosen from the evidence: a singular Newmark matrix, a
    /// damper model with negative or non-finite mass/damping, the explicit stability limit
    /// (ω_max Δt vs 2), non-finite loads, or (Newmark, stable for any step) the loads.
    fn likely_cause(&self, structure: &ModalStructure) -> String {
        let wmax = highest_mode(structure);
        if self.ledger.singular {
            return "the matrix M + Δt/2 C + Δt²/4 Ω of the attached dampers is singular (an \
                    effective mass cancels the modal mass); check the damper model's mass"
                .into();
        }
        if let Some((m, d)) = self.ledger.negative_attachment {
            return format!(
                "an attached damper has a negative or non-finite effective mass or damping \
                 (m̄ = {m:e} kg, d̄ = {d:e} N·s/m): check the damper model (fields.csv values, \
                 formula inputs)"
            );
        }
        if let Some(p) = &self.ledger.p_last
            && p.iter().any(|x| !x.is_finite())
        {
            return "the generalized force became non-finite (excitation or damper load)".into();
        }
        match wmax {
            Some((k, w)) if self.ledger.explicit => {
                let r = w * self.dt_s;
                if r >= 1.0 {
                    format!(
                        "the time step {:e} s against the highest natural period {:e} s (mode {}, \
                         ω_max Δt = {r:.3}; the explicit coupling needs < 2): reduce the time step \
                         or keep fewer modes",
                        self.dt_s,
                        std::f64::consts::TAU / w,
                        k + 1
                    )
                } else {
                    format!(
                        "not the time step (ω_max Δt = {r:.3} for the highest mode {}): the \
                         damper's load on the structure (DEM bed forces; check the damper \
                         scenario's time step and contact stiffness)",
                        k + 1
                    )
                }
            }
            Some((k, w)) => format!(
                "not the time step (the Newmark rule is stable for any step; ω_max Δt = {:.3} for \
                 mode {}): the loads or the damper model (effective mass/damping updates)",
                w * self.dt_s,
                k + 1
            ),
            None => "a structure without modes".into(),
        }
    }

    /// Physical displacement $x = \phi^T q$ at a point [D Eq. 3.22/3.24].
    pub fn displacement(&self, shape: &[f64]) -> f64 {
        dot(shape, self.q.as_slice())
    }

    /// Velocity $\dot x = \phi^T \dot q$ [D Eq. 3.25].
    pub fn velocity(&self, shape: &[f64]) -> f64 {
        dot(shape, self.v.as_slice())
    }

    /// Acceleration $\ddot x = \phi^T \ddot q$ [D Eq. 3.26].
    pub fn acceleration(&self, shape: &[f64]) -> f64 {
        dot(shape, self.a.as_slice())
    }

    /// Total mechanical energy of the modal coordinates, ½q̇ᵀMq̇ + ½qᵀΩq, J.
    pub fn energy_j(&self) -> f64 {
        0.5 * (self.v.transpose() * &self.m * &self.v)[(0, 0)]
            + 0.5 * self.q.component_mul(&self.q).dot(&self.base_k)
    }
}

/// $\sum_i a_i b_i$.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Generalized force $\Phi^T f$ of a point force `force_n` at a point with shape `shape`.
pub fn generalized_force(shape: &[f64], force_n: f64) -> DVector<f64> {
    DVector::from_iterator(shape.len(), shape.iter().map(|p| p * force_n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undamped_sdof_period_and_amplitude() {
        let s = ModalStructure::single_mode(2.0, 800.0, 0.0);
        let w = 20.0;
        let period = std::f64::consts::TAU / w;
        let mut it = ModalIntegrator::new(&s, period / 400.0);
        let phi = s.point("damper").unwrap().to_vec();
        it.q[0] = 0.01 / phi[0];
        it.make_consistent(&DVector::zeros(1));
        let p0 = DVector::zeros(1);
        for _ in 0..4000 {
            it.step(&p0);
        }
        // after 10 periods: x = X cos(ω_num t) with relative period error (ωΔt)²/12
        let x = it.displacement(&phi);
        let err_phase = 10.0 * std::f64::consts::TAU * (w * it.dt_s).powi(2) / 12.0;
        assert!((x - 0.01 * err_phase.cos()).abs() < 1e-6, "{x}");
        assert!((it.energy_j() - 0.5 * 800.0 * 1e-4).abs() < 1e-10);
    }
}
