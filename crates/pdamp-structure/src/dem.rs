//! Coupling approach 1: full DEM [D Sect. 3.3, Fig. 3.6]. The container of a settled
//! [`pdamp_design::Damper`] is moved every step with the damper point of the modal structure
//! (1D along the damper's excitation direction, D Eq. 3.24–3.26), and the contact force of the
//! particles on the container goes back into the modal equations as $f_{pd}$ [D Eq. 3.23].
//!
//! Scheme: the modal coordinates are advanced by the same velocity-Verlet rule as the particles,
//! interleaved with the DEM step, so structure + particles form one explicit symplectic system
//! (a lagged force with an implicit structure step was found to pump energy into stiff
//! particle–container contacts): drift $q_{n+1} = q_n + \Delta t(\dot q_n + \tfrac{\Delta t}{2}
//! \ddot q_n)$; the container gets the structure's state at $t_{n+1}$ (a prescribed motion
//! rebuilt each step, so the DEM's step velocity is the true displacement over the step); the
//! DEM step gives the contact force at $t_{n+1}$; kick $\dot q_{n+1}$ with it. The modal time
//! step is the DEM step (stable while $\omega_{max}\Delta t < 2$). The container's
//! own mass belongs to the structure model (a point mass at the damper point). The static
//! weight of the bed along the direction is subtracted when `compensate_static_weight` is set,
//! so displacements are measured from the loaded equilibrium (D Sect. 7.2.1 neglects the static
//! deflection by the particles).

use crate::forced::SweepSpec;
use crate::free::{FreeVibrationSpec, TimeHistory};
use crate::integrate::{ModalIntegrator, generalized_force};
use crate::modal::ModalStructure;
use nalgebra::DVector;
use pdamp_dem::{BodyState, Motion, PrescribedMotion, Vec3, WorldState};
use pdamp_design::Damper;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::Arc;

/// Checkpointing of a coupled DEM run (see docs/reliability.md): the modal state, the DEM
/// state and the response so far are written to `path` every `interval_s` of wall-clock time
/// and on Ctrl-C; with `resume`, the run continues from the file and ends bit for bit as an
/// uninterrupted run.
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingCheckpoint {
    /// Checkpoint file.
    pub path: PathBuf,
    /// Digest of the inputs (coupling and damper scenarios); a file of other inputs is refused.
    pub inputs_digest: String,
    /// Wall-clock seconds between checkpoints (≤ 0: only on Ctrl-C).
    pub interval_s: f64,
    /// Continue from `path` if it exists.
    pub resume: bool,
}

/// Kind tag of coupled-DEM checkpoints.
const COUPLE_KIND: &str = "couple-dem";

/// State of [`coupled_run`] after a step.
#[derive(Serialize, Deserialize)]
struct CoupledState {
    step: usize,
    time_s: f64,
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
    world: WorldState,
    time: Vec<f64>,
    displacement: Vec<f64>,
    velocity: Vec<f64>,
    force: Vec<f64>,
}

/// Container motion over one step: the structure's state at `t1` extrapolated quadratically.
#[derive(Debug, Clone, Copy)]
struct Track {
    direction: Vec3,
    t1: f64,
    x1: f64,
    v1: f64,
    a1: f64,
}

impl PrescribedMotion for Track {
    fn offset(&self, t_s: f64) -> BodyState {
        let s = t_s - self.t1;
        let mut b =
            BodyState::at_rest(self.direction * (self.x1 + self.v1 * s + 0.5 * self.a1 * s * s));
        b.velocity_m_s = self.direction * (self.v1 + self.a1 * s);
        b
    }
}

/// Options of the DEM coupling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemCoupling {
    /// Subtract the static bed weight along the direction from the contact force.
    pub compensate_static_weight: bool,
}

/// Excitation of a coupled DEM run.
enum Load<'a> {
    Free,
    Sweep(&'a SweepSpec, Vec<f64>),
}

#[allow(clippy::too_many_arguments)] // private driver shared by the two public entry points
fn coupled_run(
    structure: &ModalStructure,
    damper: &Damper,
    damper_point: &str,
    output_point: &str,
    opts: DemCoupling,
    q0: DVector<f64>,
    v0: DVector<f64>,
    duration_s: f64,
    sample_every: usize,
    load: Load,
    progress: &mut dyn FnMut(f64),
    ck: Option<&CouplingCheckpoint>,
) -> Result<TimeHistory, String> {
    use pdamp_io::checkpoint as cp;
    structure.validate()?;
    let pd = structure.point(damper_point)?.to_vec();
    let out = structure.point(output_point)?.to_vec();
    let dt = damper.time_step_s;
    let e = damper.direction;
    let mut it = ModalIntegrator::new(structure, dt);
    it.q = q0;
    it.v = v0;
    let x0 = it.displacement(&pd);
    let vx0 = it.velocity(&pd);
    let mut w = damper.settled.clone();
    // Move the settled bed with the container's initial displacement and velocity.
    for (p, v) in w
        .particles
        .position
        .iter_mut()
        .zip(w.particles.velocity.iter_mut())
    {
        *p += e * x0;
        *v += e * vx0;
    }
    let c = damper.container;
    w.dt_s = dt;
    w.bodies[c].motion = Motion::Prescribed(Arc::new(Track {
        direction: e,
        t1: 0.0,
        x1: x0,
        v1: vx0,
        a1: 0.0,
    }));
    w.restart_clock();
    let weight = if opts.compensate_static_weight {
        damper.bed_mass_kg * w.gravity_m_s2.dot(&e)
    } else {
        0.0
    };
    let force = |w: &pdamp_dem::World| w.bodies[c].contact_force_n.dot(&e) - weight;
    let f_ex = |t: f64| match &load {
        Load::Free => DVector::zeros(structure.modes.len()),
        Load::Sweep(s, ex) => {
            generalized_force(ex, s.force_amplitude_n * s.sweep.phase_rad(t).cos())
        }
    };
    let f_ex_scalar = |t: f64| match &load {
        Load::Free => 0.0,
        Load::Sweep(s, _) => s.force_amplitude_n * s.sweep.phase_rad(t).cos(),
    };
    let mut f_pd = force(&w);
    it.make_consistent(&(f_ex(0.0) + generalized_force(&pd, f_pd)));
    let mut hist = TimeHistory::default();
    let push = |it: &ModalIntegrator, h: &mut TimeHistory| {
        h.time_s.push(it.time_s);
        h.displacement_m.push(it.displacement(&out));
        h.velocity_m_s.push(it.velocity(&out));
        h.force_n.push(f_ex_scalar(it.time_s));
    };
    push(&it, &mut hist);
    let mut first = 1;
    let header = ck.map(|c| cp::CheckpointHeader::new(COUPLE_KIND, &c.inputs_digest));
    if let Some(c) = ck.filter(|c| c.resume)
        && let Some(st) = cp::load::<CoupledState>(&c.path, COUPLE_KIND, &c.inputs_digest)?
    {
        w.restore_state(st.world)?;
        (it.time_s, it.q, it.v, it.a) = (st.time_s, st.q, st.v, st.a);
        hist.time_s = st.time;
        hist.displacement_m = st.displacement;
        hist.velocity_m_s = st.velocity;
        hist.force_n = st.force;
        first = st.step + 1;
    }
    let _stoppable = ck.map(|_| cp::StoppableSection::enter());
    let mut timer = cp::CheckpointTimer::new(ck.map_or(0.0, |c| c.interval_s));
    let n_steps = (duration_s / dt).round() as usize;
    let every = sample_every.max(1);
    let report = (n_steps / 200).max(1);
    for step in first..=n_steps {
        let t1 = step as f64 * dt;
        it.verlet_drift();
        w.bodies[c].motion = Motion::Prescribed(Arc::new(Track {
            direction: e,
            t1,
            x1: it.displacement(&pd),
            v1: it.velocity(&pd) + 0.5 * dt * it.acceleration(&pd),
            a1: it.acceleration(&pd),
        }));
        w.dt_s = t1 - w.time_s;
        w.step();
        f_pd = force(&w);
        it.verlet_kick(&(f_ex(t1) + generalized_force(&pd, f_pd)));
        if !f_pd.is_finite() || !w.ledger.kinetic_j.is_finite() {
            return Err(format!("DEM coupling became unstable at t = {t1:.6} s"));
        }
        if step % every == 0 {
            push(&it, &mut hist);
        }
        if step % report == 0 {
            progress(step as f64 / n_steps as f64);
        }
        if let (Some(c), Some(h)) = (ck, &header) {
            let stop = cp::stop_requested();
            if stop || timer.due() {
                let st = CoupledState {
                    step,
                    time_s: it.time_s,
                    q: it.q.clone(),
                    v: it.v.clone(),
                    a: it.a.clone(),
                    world: w.save_state(),
                    time: hist.time_s.clone(),
                    displacement: hist.displacement_m.clone(),
                    velocity: hist.velocity_m_s.clone(),
                    force: hist.force_n.clone(),
                };
                cp::save(&c.path, h, &st)?;
                if stop {
                    return Err(cp::Interrupted {
                        time_s: it.time_s,
                        path: c.path.clone(),
                    }
                    .to_string());
                }
            }
        }
    }
    Ok(hist)
}

/// Free vibration with a full DEM damper at `damper_point` (approach 1).
///
/// # Errors
/// Unknown points, a node of the mode at the initial point, DEM instability.
pub fn run_dem_free(
    structure: &ModalStructure,
    damper: &Damper,
    damper_point: &str,
    spec: &FreeVibrationSpec,
    opts: DemCoupling,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<TimeHistory, String> {
    let init = structure.point(&spec.initial_point)?;
    let k = spec.mode;
    if k >= structure.modes.len() || init[k] == 0.0 {
        return Err(format!(
            "mode {} cannot carry the initial condition at '{}'",
            k + 1,
            spec.initial_point
        ));
    }
    let n = structure.modes.len();
    let mut q0 = DVector::zeros(n);
    let mut v0 = DVector::zeros(n);
    q0[k] = spec.initial_displacement_m / init[k];
    v0[k] = spec.initial_velocity_m_s / init[k];
    coupled_run(
        structure,
        damper,
        damper_point,
        &spec.output_point,
        opts,
        q0,
        v0,
        spec.duration_s,
        spec.sample_every,
        Load::Free,
        progress,
        checkpoint,
    )
}

/// Sine sweep with a full DEM damper at `damper_point` (approach 1, time-domain approach of
/// D Sect. 3.3.2 when the sweep covers only the resonance).
///
/// # Errors
/// Unknown points, DEM instability.
pub fn run_dem_sweep(
    structure: &ModalStructure,
    damper: &Damper,
    damper_point: &str,
    spec: &SweepSpec,
    opts: DemCoupling,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<TimeHistory, String> {
    spec.sweep.validate()?;
    let ex = structure.point(&spec.excitation_point)?.to_vec();
    let n = structure.modes.len();
    coupled_run(
        structure,
        damper,
        damper_point,
        &spec.output_point,
        opts,
        DVector::zeros(n),
        DVector::zeros(n),
        spec.sweep.duration_s,
        spec.sample_every,
        Load::Sweep(spec, ex),
        progress,
        checkpoint,
    )
}
