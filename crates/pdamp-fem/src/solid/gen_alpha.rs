//! Generalized-α time integration (Chung & Hulbert 1993, paper ref. \[32\]) of eq. 11 with Newton
//! iterations and a sparse Cholesky solver.
//!
//! Balance at the generalized midpoint (forces averaged, "TR-like"):
//! $\mathbf M\mathbf a_{n+1-\alpha_m} + \mathbf C\mathbf v_{n+1-\alpha_f} + (1-\alpha_f)\mathbf F_{int}(\mathbf d_{n+1}) + \alpha_f\mathbf F_{int}(\mathbf d_n) = (1-\alpha_f)\mathbf F_{ext,n+1} + \alpha_f\mathbf F_{ext,n}$,
//! with Newmark updates and
//! $\alpha_m = \frac{2\rho_\infty-1}{\rho_\infty+1}$, $\alpha_f = \frac{\rho_\infty}{\rho_\infty+1}$,
//! $\gamma = \tfrac12-\alpha_m+\alpha_f$, $\beta = \tfrac14(1-\alpha_m+\alpha_f)^2$.
//! For ρ∞ = 0.8 this gives β = 0.30864, γ = 0.61111 as in paper Table A.3 (which lists
//! α_f = 0.4 and α_m = 0.3 rounded to one digit; the exact values are 4/9 and 1/3).
//!
//! Newton: the effective tangent
//! $\frac{1-\alpha_m}{\beta\Delta t^2}\mathbf M + \frac{(1-\alpha_f)\gamma}{\beta\Delta t}\mathbf C + (1-\alpha_f)\mathbf K_T$
//! is factorized at the reference configuration, stored in single precision, and reused
//! ("modified Newton", the default: the strains of the studied structures are ~1e-4, so the
//! tangent barely changes and each iteration gains two to four digits); `full_newton`
//! refactorizes with the current tangent in every iteration (quadratic convergence, for large
//! deformations).

use super::structure::Structure;
use crate::{Cholesky, FactorError, SingleCholesky, SymmetricCsr};

/// The factor of the effective tangent: single precision for modified Newton (the residual
/// that decides convergence is double precision, see [`SingleCholesky`]; measured on the
/// paper's beam: the same iteration counts as the double-precision factor, 2.72 per step over
/// 500 steps, and 28.5 → 20.0 ms per step), double precision once full Newton refactorizes or
/// when an iteration with the single-precision factor reduces the residual by less than
/// [`SINGLE_CONTRACTION`] while it is still above the round-off floor (an ill-conditioned
/// effective matrix, where rounding the factor to single precision spoils the correction).
enum TangentFactor {
    Single(SingleCholesky),
    Double(Cholesky),
}

/// Least residual reduction per modified-Newton iteration that the single-precision factor must
/// achieve; below it the factor is recomputed in double precision for the rest of the run. The
/// reference tangent alone reduces the residual by 1e-4 … 1e-2 per iteration at the strains
/// of the studied structures (1.2e-2 in the first iteration after the paper beam's release,
/// measured), so only a reduction worse than one half counts as failing.
const SINGLE_CONTRACTION: f64 = 0.5;

impl TangentFactor {
    fn solve_in_place(&mut self, b: &mut [f64]) {
        match self {
            Self::Single(c) => c.solve_in_place(b),
            Self::Double(c) => c.solve_in_place(b),
        }
    }

    fn refactor(&mut self, a: &SymmetricCsr) -> Result<(), FactorError> {
        match self {
            Self::Double(c) => c.refactor(a),
            Self::Single(_) => {
                *self = Self::Double(Cholesky::new(a)?);
                Ok(())
            }
        }
    }
}

/// Parameters of the generalized-α method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenAlpha {
    /// α_m.
    pub alpha_m: f64,
    /// α_f.
    pub alpha_f: f64,
    /// Newmark β.
    pub beta: f64,
    /// Newmark γ.
    pub gamma: f64,
}

impl GenAlpha {
    /// Optimal parameters for spectral radius ρ∞ ∈ [0, 1] (Chung & Hulbert 1993).
    ///
    /// # Panics
    /// If ρ∞ is outside [0, 1].
    #[track_caller]
    pub fn from_rho_inf(rho_inf: f64) -> Self {
        assert!((0.0..=1.0).contains(&rho_inf), "rho_inf must be in [0, 1]");
        let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let alpha_f = rho_inf / (rho_inf + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        Self {
            alpha_m,
            alpha_f,
            beta,
            gamma,
        }
    }
}

/// Rayleigh damping $\mathbf C = a_M\mathbf M + a_K\mathbf K_0$ (off by default, paper Remark 1).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rayleigh {
    /// Mass-proportional coefficient [1/s].
    pub mass_coeff_per_s: f64,
    /// Stiffness-proportional coefficient \[s\].
    pub stiffness_coeff_s: f64,
}

/// Errors of the time integration.
#[derive(Debug, thiserror::Error)]
pub enum DynamicsError {
    /// Factorization failure.
    #[error(transparent)]
    Solver(#[from] FactorError),
    /// Newton did not converge.
    #[error(
        "Newton did not converge at t = {t_s} s after {iterations} iterations (residual {residual:e})"
    )]
    Newton {
        /// Time \[s\].
        t_s: f64,
        /// Iterations done.
        iterations: usize,
        /// Relative residual.
        residual: f64,
    },
    /// A checkpoint state was saved with another time step ([`Dynamics::restore_state`]).
    #[error("structure state: time step {saved_s} s, the scenario has {scenario_s} s")]
    StateTimeStep {
        /// Time step of the state \[s\].
        saved_s: f64,
        /// Time step of the scenario \[s\].
        scenario_s: f64,
    },
    /// A checkpoint state has another number of dofs ([`Dynamics::restore_state`]).
    #[error("structure state: {saved} dofs, the structure has {structure}")]
    StateDofs {
        /// Length of a vector of the state.
        saved: usize,
        /// Dofs of the structure.
        structure: usize,
    },
    /// The double-precision factor a checkpoint state asks for failed
    /// ([`Dynamics::restore_state`]).
    #[error("structure state: {0}")]
    StateFactor(#[source] FactorError),
}

/// Newton settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Relative residual tolerance (largest residual entry over the largest force term); a step
    /// also counts as converged when the Newton correction is below 1e-12 of the displacement
    /// (round-off floor), or when the residual stagnates below 1e-6.
    pub tolerance: f64,
    /// Maximum iterations per step.
    pub max_iterations: usize,
    /// Refactorize the current tangent in every iteration.
    pub full_newton: bool,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 30,
            full_newton: false,
        }
    }
}

/// State and workspace of the generalized-α integration; `d`, `v`, `a` are on all dofs.
pub struct Dynamics {
    /// Parameters.
    pub params: GenAlpha,
    /// Time step \[s\].
    pub dt: f64,
    /// Time of the committed state \[s\].
    pub t: f64,
    /// Committed displacement, velocity, acceleration.
    pub d: Vec<f64>,
    /// Velocity [m/s].
    pub v: Vec<f64>,
    /// Acceleration [m/s²].
    pub a: Vec<f64>,
    /// Trial displacement of the step in progress.
    pub d1: Vec<f64>,
    /// Trial velocity.
    pub v1: Vec<f64>,
    /// Trial acceleration.
    pub a1: Vec<f64>,
    fint_n: Vec<f64>,
    fext_n: Vec<f64>,
    fint1: Vec<f64>,
    fext1: Vec<f64>,
    /// Strain energy of the committed state \[J\].
    pub strain_energy: f64,
    strain_energy1: f64,
    /// Work of all external forces (loads, gravity, interface) up to `t` \[J\] (trapezoidal).
    pub external_work: f64,
    /// Newton iterations of the last solve.
    pub last_iterations: usize,
    /// Settings.
    pub newton: NewtonSettings,
    rayleigh: Rayleigh,
    keff: SymmetricCsr,
    factor: TangentFactor,
    // free-dof work vectors
    r: Vec<f64>,
    tmp: Vec<f64>,
    tmp2: Vec<f64>,
}

/// The dynamic state of a [`Dynamics`] between steps, for checkpoints: everything a step
/// reads that an earlier step wrote (committed and trial vectors, force vectors at the last
/// committed state, energies, counters). The effective matrix and its factorization are not
/// stored: with modified Newton they are those of the reference configuration (rebuilt by
/// [`Dynamics::new`]); with full Newton they are refactorized before every use.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DynamicsState {
    /// Time step \[s\] (checked on restore).
    pub dt: f64,
    /// Time \[s\].
    pub t: f64,
    /// d, v, a, d1, v1, a1, F_int,n, F_ext,n, F_int,n+1, F_ext,n+1 (all dofs).
    pub vectors: [Vec<f64>; 10],
    /// Strain energy (committed, trial) \[J\].
    pub strain_energy: [f64; 2],
    /// External work \[J\].
    pub external_work: f64,
    /// Newton iterations of the last solve.
    pub last_iterations: usize,
    /// The tangent factor had been switched to double precision (see [`Dynamics`]).
    pub double_factor: bool,
}

impl Dynamics {
    /// Starts at `t = 0` with displacement `d0`, velocity `v0` (all dofs; clamped entries
    /// ignored) and zero external interface force; the initial acceleration solves eq. 11.
    pub fn new(
        s: &mut Structure,
        params: GenAlpha,
        dt: f64,
        mut d0: Vec<f64>,
        mut v0: Vec<f64>,
        rayleigh: Rayleigh,
    ) -> Result<Self, DynamicsError> {
        let n = s.n_dof();
        for (g, &f) in s.free.iter().enumerate() {
            if f == usize::MAX {
                d0[g] = 0.0;
                v0[g] = 0.0;
            }
        }
        let nf = s.free_dofs.len();
        let mut fint = vec![0.0; n];
        let w = s.internal_force(&d0, &mut fint);
        let mut fext = vec![0.0; n];
        s.external_force(0.0, &mut fext);
        let mass_factor = Cholesky::new(&s.mass)?;
        let mut rhs: Vec<f64> = s.free_dofs.iter().map(|&g| fext[g] - fint[g]).collect();
        mass_factor.solve_in_place(&mut rhs);
        let mut a = vec![0.0; n];
        for (k, &g) in s.free_dofs.iter().enumerate() {
            a[g] = rhs[k];
        }
        let keff = effective_matrix(s, &params, dt, &rayleigh, &s.k0);
        // (a matrix whose single-precision rounding is no longer positive definite gets the
        // double-precision factor from the start, as a restored run of it does)
        let factor = match SingleCholesky::new(&keff) {
            Ok(c) => TangentFactor::Single(c),
            Err(_) => TangentFactor::Double(Cholesky::new(&keff)?),
        };
        Ok(Self {
            params,
            dt,
            t: 0.0,
            d1: d0.clone(),
            v1: v0.clone(),
            a1: a.clone(),
            d: d0,
            v: v0,
            a,
            fint_n: fint.clone(),
            fext_n: fext.clone(),
            fint1: fint,
            fext1: fext,
            strain_energy: w,
            strain_energy1: w,
            external_work: 0.0,
            last_iterations: 0,
            newton: NewtonSettings::default(),
            rayleigh,
            keff,
            factor,
            r: vec![0.0; nf],
            tmp: vec![0.0; nf],
            tmp2: vec![0.0; nf],
        })
    }

    /// The state for a checkpoint (see [`DynamicsState`]).
    pub fn save_state(&self) -> DynamicsState {
        DynamicsState {
            dt: self.dt,
            t: self.t,
            vectors: [
                self.d.clone(),
                self.v.clone(),
                self.a.clone(),
                self.d1.clone(),
                self.v1.clone(),
                self.a1.clone(),
                self.fint_n.clone(),
                self.fext_n.clone(),
                self.fint1.clone(),
                self.fext1.clone(),
            ],
            strain_energy: [self.strain_energy, self.strain_energy1],
            external_work: self.external_work,
            last_iterations: self.last_iterations,
            double_factor: matches!(self.factor, TangentFactor::Double(_)),
        }
    }

    /// Continues from `st` (saved by [`Dynamics::save_state`] from a `Dynamics` of the same
    /// structure, parameters and time step); the next step is then bit for bit that of the
    /// saved run.
    pub fn restore_state(&mut self, st: DynamicsState) -> Result<(), DynamicsError> {
        if st.dt.to_bits() != self.dt.to_bits() {
            return Err(DynamicsError::StateTimeStep {
                saved_s: st.dt,
                scenario_s: self.dt,
            });
        }
        let n = self.d.len();
        if let Some(v) = st.vectors.iter().find(|v| v.len() != n) {
            return Err(DynamicsError::StateDofs {
                saved: v.len(),
                structure: n,
            });
        }
        let [d, v, a, d1, v1, a1, fint_n, fext_n, fint1, fext1] = st.vectors;
        (self.d, self.v, self.a, self.d1, self.v1, self.a1) = (d, v, a, d1, v1, a1);
        (self.fint_n, self.fext_n, self.fint1, self.fext1) = (fint_n, fext_n, fint1, fext1);
        self.t = st.t;
        [self.strain_energy, self.strain_energy1] = st.strain_energy;
        self.external_work = st.external_work;
        self.last_iterations = st.last_iterations;
        if st.double_factor && !self.newton.full_newton {
            self.use_double_factor()
                .map_err(DynamicsError::StateFactor)?;
        }
        Ok(())
    }

    /// Recomputes the factor of the reference effective matrix in double precision and keeps
    /// it for the rest of the run (done automatically when the single-precision factor stops
    /// converging; callable for a run that wants it from the start).
    pub fn use_double_factor(&mut self) -> Result<(), FactorError> {
        if matches!(self.factor, TangentFactor::Single(_)) {
            self.factor = TangentFactor::Double(Cholesky::new(&self.keff)?);
        }
        Ok(())
    }

    /// Kinetic energy of the committed state \[J\].
    pub fn kinetic_energy(&self, s: &Structure) -> f64 {
        0.5 * s.mass_quad_all(&self.v)
    }

    /// Solves the step to `t + dt` with the additional nodal force `f_extra` (all dofs, e.g. the
    /// particle interface forces of eq. 15, or `None`) into the trial state `d1, v1, a1` without
    /// committing it. The trial displacement is used as starting guess, so repeated calls
    /// within a coupling loop start from the previous iterate.
    pub fn solve(
        &mut self,
        s: &mut Structure,
        f_extra: Option<&[f64]>,
        restart: bool,
    ) -> Result<usize, DynamicsError> {
        let GenAlpha {
            alpha_m: am,
            alpha_f: af,
            beta,
            gamma,
        } = self.params;
        let dt = self.dt;
        let t1 = self.t + dt;
        s.external_force(t1, &mut self.fext1);
        if let Some(f) = f_extra {
            for (x, y) in self.fext1.iter_mut().zip(f) {
                *x += y;
            }
        }
        if restart {
            // constant-velocity predictor (no acceleration term: robust when the acceleration
            // carries unresolved high-frequency content, e.g. consistent-mass initial
            // accelerations). Against the constant-displacement predictor it starts the
            // modified Newton iterations ≈ 100 × closer (one iteration in ten saved on the
            // reduced cantilever, results equal to 1e-11).
            for k in 0..self.d.len() {
                self.d1[k] = self.d[k] + dt * self.v[k];
            }
        }
        let c_on = self.rayleigh != Rayleigh::default();
        let mut it = 0;
        let mut small_update = false;
        let mut prev_rel = f64::INFINITY;
        loop {
            for k in 0..self.d.len() {
                self.a1[k] =
                    (self.d1[k] - self.d[k] - dt * self.v[k] - dt * dt * (0.5 - beta) * self.a[k])
                        / (beta * dt * dt);
                self.v1[k] = self.v[k] + dt * ((1.0 - gamma) * self.a[k] + gamma * self.a1[k]);
            }
            self.strain_energy1 = s.internal_force(&self.d1, &mut self.fint1);
            // inertia
            for (k, &g) in s.free_dofs.iter().enumerate() {
                self.tmp[k] = (1.0 - am) * self.a1[g] + am * self.a[g];
            }
            s.mass_mul(&self.tmp, &mut self.tmp2);
            let mut scale = 0.0f64;
            for (k, &g) in s.free_dofs.iter().enumerate() {
                let fi = (1.0 - af) * self.fint1[g] + af * self.fint_n[g];
                let fe = (1.0 - af) * self.fext1[g] + af * self.fext_n[g];
                self.r[k] = self.tmp2[k] + fi - fe;
                scale = scale.max(self.tmp2[k].abs()).max(fi.abs()).max(fe.abs());
            }
            if c_on {
                for (k, &g) in s.free_dofs.iter().enumerate() {
                    self.tmp[k] = (1.0 - af) * self.v1[g] + af * self.v[g];
                }
                s.mass_mul(&self.tmp, &mut self.tmp2);
                for k in 0..self.r.len() {
                    self.r[k] += self.rayleigh.mass_coeff_per_s * self.tmp2[k];
                }
                s.k0.mul(&self.tmp, &mut self.tmp2);
                for k in 0..self.r.len() {
                    self.r[k] += self.rayleigh.stiffness_coeff_s * self.tmp2[k];
                }
            }
            let rmax = self.r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let rel = if scale > 0.0 { rmax / scale } else { 0.0 };
            // stagnation below 1e-6: the residual has reached its round-off floor
            let stalled = it >= 2 && rel < 1e-6 && rel > 0.5 * prev_rel;
            let poor = it >= 1 && rel >= 1e-6 && rel > SINGLE_CONTRACTION * prev_rel;
            prev_rel = rel;
            if rel <= self.newton.tolerance || rmax < 1e-300 || small_update || stalled {
                self.last_iterations = it;
                return Ok(it);
            }
            if it >= self.newton.max_iterations {
                return Err(DynamicsError::Newton {
                    t_s: t1,
                    iterations: it,
                    residual: rel,
                });
            }
            if poor && !self.newton.full_newton {
                self.use_double_factor()?;
            }
            if self.newton.full_newton {
                let kt = s.tangent(&self.d1);
                self.keff = effective_matrix(s, &self.params, dt, &self.rayleigh, &kt);
                self.factor.refactor(&self.keff)?;
            }
            for x in self.r.iter_mut() {
                *x = -*x;
            }
            self.factor.solve_in_place(&mut self.r);
            let mut dmax = 0.0f64;
            let mut umax = 0.0f64;
            for (k, &g) in s.free_dofs.iter().enumerate() {
                self.d1[g] += self.r[k];
                dmax = dmax.max(self.r[k].abs());
                umax = umax.max(self.d1[g].abs());
            }
            // the correction is at round-off level: the residual cannot drop further
            small_update = dmax <= 1e-12 * umax;
            it += 1;
        }
    }

    /// Commits the trial state as the new state at `t + dt`.
    pub fn commit(&mut self) {
        let mut w = 0.0;
        for k in 0..self.d.len() {
            w += 0.5 * (self.d1[k] - self.d[k]) * (self.fext1[k] + self.fext_n[k]);
        }
        self.external_work += w;
        std::mem::swap(&mut self.d, &mut self.d1);
        std::mem::swap(&mut self.v, &mut self.v1);
        std::mem::swap(&mut self.a, &mut self.a1);
        std::mem::swap(&mut self.fint_n, &mut self.fint1);
        std::mem::swap(&mut self.fext_n, &mut self.fext1);
        self.d1.copy_from_slice(&self.d);
        self.strain_energy = self.strain_energy1;
        self.t += self.dt;
    }

    /// One uncoupled step (`solve` + `commit`).
    pub fn step(&mut self, s: &mut Structure) -> Result<usize, DynamicsError> {
        let it = self.solve(s, None, true)?;
        self.commit();
        Ok(it)
    }
}

fn effective_matrix(
    s: &Structure,
    p: &GenAlpha,
    dt: f64,
    ray: &Rayleigh,
    k: &SymmetricCsr,
) -> SymmetricCsr {
    let cm = (1.0 - p.alpha_m) / (p.beta * dt * dt);
    let cc = (1.0 - p.alpha_f) * p.gamma / (p.beta * dt);
    let ck = 1.0 - p.alpha_f;
    let mut m = s.mass.combine(cm + cc * ray.mass_coeff_per_s, k, ck);
    if ray.stiffness_coeff_s != 0.0 {
        m = m.combine(1.0, &s.k0, cc * ray.stiffness_coeff_s);
    }
    m
}
