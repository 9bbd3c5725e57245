//! Coupling approach 1: full DEM [D Sect. 3.3, Fig. 3.6]. The container of a settled
//! [`pdamp_design::Damper`] is moved every step with the damper node of the modal structure,
//! and the contact loads of the particles on the container go back into the modal equations as
//! $f_{pd}$ [D Eq. 3.23].
//!
//! Kinematics ([`DemKinematics`]):
//! - 1D (default): the container translates along the damper's excitation direction $e$ with
//!   the damper point, $x = \phi_{pd}^T q$ [D Eq. 3.24–3.26]; $Q = \phi_{pd}(F\cdot e)$.
//! - rigid body: the three translations $u = \Phi_u q$ of the damper node (one structure point
//!   per axis of the DEM frame, which is taken as the structure's global frame) and, where the
//!   mode shapes provide rotational dof at the node, the three small rotations
//!   $\theta = \Phi_\theta q$ [D Eq. 3.21–3.26 per dof]. A material point $y$ of the container
//!   moves to $a + u + R(\theta)(y - a)$ about the attachment point $a$ ($R = \exp[\theta]_\times$,
//!   angular velocity $\dot\theta$), so wall velocities are $v + \omega\times r$ in the contacts.
//!   The contact force $F$ and the torque about the moving attachment point
//!   $T_a = T_{ref} + (x_{ref} - a)\times F$ are projected back:
//!   $Q = \Phi_u^T F + \Phi_\theta^T T_a$ (virtual work of the rigid container).
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
//! weight of the bed (and in the rigid-body mode its moment about the attachment point in the
//! settled configuration) is subtracted when `compensate_static_weight` is set, so
//! displacements are measured from the loaded equilibrium (D Sect. 7.2.1 neglects the static
//! deflection by the particles).
//!
//! Energy: [`DemEnergy`] accumulates the work the structure does on the bed,
//! $W_{s\to b} = -\sum \tfrac12(Q_n + Q_{n+1})\cdot(q_{n+1} - q_n)$, next to the DEM ledger
//! (wall work, bed energy change, dissipation), so the exchange can be checked to close.

mod checkpoint;
use crate::StructureError;
use crate::forced::SweepSpec;
use crate::free::{FreeVibrationSpec, TimeHistory};
use crate::integrate::{ModalIntegrator, generalized_force};
use crate::modal::ModalStructure;
use checkpoint::{COUPLE_KIND, CoupledState};
use nalgebra::DVector;
use pdamp_dem::math::Rotation;
use pdamp_dem::time_loop::{self, CancelToken, Flow, LoopControl, LoopEnd, LoopEvent};
use pdamp_dem::{BodyState, Motion, PrescribedMotion, Vec3};
use pdamp_design::Damper;
use pdamp_scenario::run::SnapshotSeries;
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
    /// ParaView output of the bed during the run (`None`: none).
    pub bed_vtk: Option<BedVtk>,
    /// Cancelling it makes the run write its checkpoint and end with
    /// [`StructureError::Interrupted`].
    pub cancel: CancelToken,
}

/// ParaView output of a coupled run's DEM bed: particles and container walls every
/// `interval_s` of simulated time, as `dir/pvd_name` with the frames in `dir/subdir/`.
#[derive(Debug, Clone, PartialEq)]
pub struct BedVtk {
    /// Output directory.
    pub dir: PathBuf,
    /// Name of the `.pvd` collection, e.g. `particles.pvd`.
    pub pvd_name: String,
    /// Folder of the frames inside `dir`, e.g. `vtk`.
    pub subdir: String,
    /// Simulated seconds between frames (the damper scenario's `output.vtk_interval_s`).
    pub interval_s: f64,
    /// Array encoding (the damper scenario's `output.vtk_format`).
    pub encoding: pdamp_io::vtk::VtkEncoding,
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

/// Rigid-body container motion over one step: translation $u$ of the attachment point and
/// small rotation $\theta$ about it, both extrapolated quadratically from `t1`. The offset of
/// the body reference point (lever `arm` = reference point − attachment point at rest) is
/// $u + (R - I)\,arm$, its velocity $\dot u + \omega \times R\,arm$, with $R = \exp[\theta]_\times$
/// and $\omega = \dot\theta$ (small rotations, D Eq. 3.24–3.26 per dof).
#[derive(Debug, Clone, Copy)]
struct RigidTrack {
    t1: f64,
    u1: Vec3,
    v1: Vec3,
    a1: Vec3,
    th1: Vec3,
    w1: Vec3,
    al1: Vec3,
    arm: Vec3,
    rotate: bool,
}

impl PrescribedMotion for RigidTrack {
    fn offset(&self, t_s: f64) -> BodyState {
        let s = t_s - self.t1;
        let mut b = BodyState::at_rest(self.u1 + self.v1 * s + self.a1 * (0.5 * s * s));
        b.velocity_m_s = self.v1 + self.a1 * s;
        if self.rotate {
            let th = self.th1 + self.w1 * s + self.al1 * (0.5 * s * s);
            let w = self.w1 + self.al1 * s;
            let r = Rotation::from_scaled_axis(th);
            let ra = r.transform_vector(&self.arm);
            b.position_m += ra - self.arm;
            b.velocity_m_s += w.cross(&ra);
            b.orientation = r;
            b.angular_velocity_rad_s = w;
        }
        b
    }
}

/// Which rigid-body dof of the container follow the structure.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum DemKinematics {
    /// 1D translation along the damper's excitation direction at the damper point.
    #[default]
    OneDimensional,
    /// Rigid container: translations and optionally small rotations of the damper node.
    Rigid(RigidKinematics),
}

/// Structure points of the rigid-body coupling: one point per axis of the DEM frame (x, y, z);
/// `None` = that dof is not moved (e.g. a fixed dof of a planar model).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RigidKinematics {
    /// Points of the translations u_x, u_y, u_z (m per modal coordinate).
    pub translation_points: [Option<String>; 3],
    /// Points of the rotations θ_x, θ_y, θ_z (rad per modal coordinate); `None`: translation only.
    pub rotation_points: Option<[Option<String>; 3]>,
    /// Attachment point a in the damper scenario's frame, m (rotation centre, torque
    /// reference); `None`: the container's reference position.
    pub attachment_point_m: Option<Vec3>,
}

/// Options of the DEM coupling.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DemCoupling {
    /// Subtract the static bed weight along the direction from the contact force.
    pub compensate_static_weight: bool,
    /// 1D or rigid-body kinematics.
    pub kinematics: DemKinematics,
}

/// Energy exchange of a coupled DEM run since its start, J (see the module documentation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct DemEnergy {
    /// Work done by the structure on the bed through the container,
    /// $-\sum\tfrac12(Q_n+Q_{n+1})\cdot\Delta q$ (with the static weight compensated, the
    /// compensating load is included).
    pub structure_work_on_bed_j: f64,
    /// Work of the moving walls on the particles from the DEM ledger.
    pub wall_work_j: f64,
    /// Change of kinetic + potential + elastic contact energy of the bed.
    pub bed_energy_change_j: f64,
    /// Energy dissipated in the contacts.
    pub dissipated_j: f64,
    /// Change of the modal energy ½q̇ᵀq̇ + ½qᵀΩq of the structure.
    pub structure_energy_change_j: f64,
}

/// Mode-shape rows of the rigid-body coupling, resolved against the structure.
struct RigidRows {
    tr: [Vec<f64>; 3],
    rot: Option<[Vec<f64>; 3]>,
    arm: Vec3,
    attach: Vec3,
    static_torque: Vec3,
}

impl RigidRows {
    fn vec(rows: &[Vec<f64>; 3], x: &DVector<f64>) -> Vec3 {
        Vec3::new(
            crate::integrate::dot(&rows[0], x.as_slice()),
            crate::integrate::dot(&rows[1], x.as_slice()),
            crate::integrate::dot(&rows[2], x.as_slice()),
        )
    }
    fn rot_vec(&self, x: &DVector<f64>) -> Vec3 {
        self.rot.as_ref().map_or(Vec3::zeros(), |r| Self::vec(r, x))
    }
    /// $Q = \Phi_u^T F + \Phi_\theta^T T$.
    fn project(&self, f: &Vec3, t: &Vec3) -> DVector<f64> {
        let n = self.tr[0].len();
        DVector::from_iterator(
            n,
            (0..n).map(|k| {
                let mut q = self.tr[0][k] * f.x + self.tr[1][k] * f.y + self.tr[2][k] * f.z;
                if let Some(r) = &self.rot {
                    q += r[0][k] * t.x + r[1][k] * t.y + r[2][k] * t.z;
                }
                q
            }),
        )
    }
}

/// Kinematics resolved for one run.
enum Resolved {
    OneD { pd: Vec<f64>, e: Vec3 },
    Rigid(RigidRows),
}

fn resolve_kinematics(
    structure: &ModalStructure,
    damper: &Damper,
    damper_point: &str,
    k: &DemKinematics,
) -> Result<Resolved, StructureError> {
    let n = structure.modes.len();
    let rows = |pts: &[Option<String>; 3], what: &str| -> Result<[Vec<f64>; 3], StructureError> {
        let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for (o, p) in out.iter_mut().zip(pts) {
            if let Some(p) = p {
                *o = structure.point(p).map_err(|e| e.context(what))?.to_vec();
            }
        }
        Ok(out)
    };
    match k {
        DemKinematics::OneDimensional => Ok(Resolved::OneD {
            pd: structure.point(damper_point)?.to_vec(),
            e: damper.direction,
        }),
        DemKinematics::Rigid(r) => {
            let tr = rows(&r.translation_points, "translation_points")?;
            let rot = match &r.rotation_points {
                Some(p) => Some(rows(p, "rotation_points")?),
                None => None,
            };
            let w = &damper.settled;
            let xref = w.bodies[damper.container].reference.position_m;
            let attach = r.attachment_point_m.unwrap_or(xref);
            // moment of the settled bed's weight about the attachment point
            let mut static_torque = Vec3::zeros();
            for (p, m) in w.particles.position.iter().zip(&w.particles.mass) {
                static_torque += (p - attach).cross(&(w.gravity_m_s2 * *m));
            }
            Ok(Resolved::Rigid(RigidRows {
                tr,
                rot,
                arm: xref - attach,
                attach,
                static_torque,
            }))
        }
    }
}

/// Excitation of a coupled DEM run.
enum Load<'a> {
    Free,
    Sweep(&'a SweepSpec, Vec<f64>),
}

/// Result of [`coupled_run`].
struct CoupledResult {
    history: TimeHistory,
    energy: DemEnergy,
}

/// One DEM bed of a coupled run: a settled damper, the structure point its container
/// follows and the coupling options.
#[derive(Debug, Clone, Copy)]
pub struct DemBed<'a> {
    /// The settled bed in its container.
    pub damper: &'a Damper,
    /// The structure point of the container (1D kinematics; the rigid kinematics name their
    /// own points).
    pub point: &'a str,
    /// Kinematics and static-weight compensation.
    pub coupling: &'a DemCoupling,
}

/// One bed during a coupled run: its world, kinematics and the last raw load.
struct BedRun {
    w: pdamp_dem::World,
    c: usize,
    kin: Resolved,
    weight1d: f64,
    weight: Vec3,
    compensate: bool,
    q_raw: DVector<f64>,
}

impl BedRun {
    /// The bed of `b` moved to the structure's initial state (`it`).
    fn start(
        structure: &ModalStructure,
        b: &DemBed,
        it: &ModalIntegrator,
    ) -> Result<Self, StructureError> {
        let damper = b.damper;
        let kin = resolve_kinematics(structure, damper, b.point, &b.coupling.kinematics)?;
        let mut w = damper.settled.clone();
        let c = damper.container;
        w.dt_s = damper.time_step_s;
        match &kin {
            Resolved::OneD { pd, e } => {
                let x0 = it.displacement(pd);
                let vx0 = it.velocity(pd);
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
                w.bodies[c].motion = Motion::Prescribed(Arc::new(Track {
                    direction: *e,
                    t1: 0.0,
                    x1: x0,
                    v1: vx0,
                    a1: 0.0,
                }));
            }
            Resolved::Rigid(r) => {
                let (u0, du0) = (RigidRows::vec(&r.tr, &it.q), RigidRows::vec(&r.tr, &it.v));
                let (th0, dth0) = (r.rot_vec(&it.q), r.rot_vec(&it.v));
                let rot = Rotation::from_scaled_axis(th0);
                for (p, v) in w
                    .particles
                    .position
                    .iter_mut()
                    .zip(w.particles.velocity.iter_mut())
                {
                    let rel = rot.transform_vector(&(*p - r.attach));
                    *p = r.attach + u0 + rel;
                    *v = rot.transform_vector(v) + du0 + dth0.cross(&rel);
                }
                for wv in w.particles.angular_velocity.iter_mut() {
                    *wv = rot.transform_vector(wv) + dth0;
                }
                w.bodies[c].motion = Motion::Prescribed(Arc::new(RigidTrack {
                    t1: 0.0,
                    u1: u0,
                    v1: du0,
                    a1: Vec3::zeros(),
                    th1: th0,
                    w1: dth0,
                    al1: Vec3::zeros(),
                    arm: r.arm,
                    rotate: r.rot.is_some(),
                }));
            }
        }
        w.restart_clock();
        let compensate = b.coupling.compensate_static_weight;
        let weight1d = match (&kin, compensate) {
            (Resolved::OneD { e, .. }, true) => damper.bed_mass_kg * w.gravity_m_s2.dot(e),
            _ => 0.0,
        };
        let weight = if compensate {
            w.gravity_m_s2 * damper.bed_mass_kg
        } else {
            Vec3::zeros()
        };
        let mut bed = BedRun {
            w,
            c,
            kin,
            weight1d,
            weight,
            compensate,
            q_raw: DVector::zeros(structure.modes.len()),
        };
        bed.q_raw = bed.load(&it.q).1;
        Ok(bed)
    }

    /// Generalized loads of the particles on the container at the modal state q: the one
    /// entering the modal equations (static weight compensated if asked) and the raw one (for
    /// the work the structure does on the bed).
    fn load(&self, q: &DVector<f64>) -> (DVector<f64>, DVector<f64>) {
        let b = &self.w.bodies[self.c];
        match &self.kin {
            Resolved::OneD { pd, e } => {
                let f = b.contact_force_n.dot(e);
                (
                    generalized_force(pd, f - self.weight1d),
                    generalized_force(pd, f),
                )
            }
            Resolved::Rigid(r) => {
                let f = b.contact_force_n;
                let mut t = b.contact_torque_nm;
                if r.rot.is_some() {
                    // torque about the moving attachment point: T_a = T_ref + (x_ref − a) × F
                    let lever = b.state.position_m - (r.attach + RigidRows::vec(&r.tr, q));
                    t += lever.cross(&f);
                }
                let raw = r.project(&f, &t);
                if self.compensate {
                    (r.project(&(f - self.weight), &(t - r.static_torque)), raw)
                } else {
                    (raw.clone(), raw)
                }
            }
        }
    }

    /// The container's motion over the step to `t1`: the structure's state at `t1`.
    fn follow(&mut self, it: &ModalIntegrator, t1: f64, dt: f64) {
        self.w.bodies[self.c].motion = match &self.kin {
            Resolved::OneD { pd, e } => Motion::Prescribed(Arc::new(Track {
                direction: *e,
                t1,
                x1: it.displacement(pd),
                v1: it.velocity(pd) + 0.5 * dt * it.acceleration(pd),
                a1: it.acceleration(pd),
            })),
            Resolved::Rigid(r) => {
                let v1 = &it.v + &it.a * (0.5 * dt);
                Motion::Prescribed(Arc::new(RigidTrack {
                    t1,
                    u1: RigidRows::vec(&r.tr, &it.q),
                    v1: RigidRows::vec(&r.tr, &v1),
                    a1: RigidRows::vec(&r.tr, &it.a),
                    th1: r.rot_vec(&it.q),
                    w1: r.rot_vec(&v1),
                    al1: r.rot_vec(&it.a),
                    arm: r.arm,
                    rotate: r.rot.is_some(),
                }))
            }
        };
    }
}

#[allow(clippy::too_many_arguments)] // private driver shared by the public entry points
fn coupled_run(
    structure: &ModalStructure,
    beds: &[DemBed],
    output_point: &str,
    q0: DVector<f64>,
    v0: DVector<f64>,
    duration_s: f64,
    sample_every: usize,
    load: Load,
    progress: &mut dyn FnMut(f64),
    ck: Option<&CouplingCheckpoint>,
) -> Result<CoupledResult, StructureError> {
    use pdamp_io::checkpoint as cp;
    structure.validate()?;
    let first_bed = beds
        .first()
        .ok_or_else(|| StructureError::inconsistent("a coupled DEM run needs a DEM bed"))?;
    let out = structure.point(output_point)?.to_vec();
    let dt = first_bed.damper.time_step_s;
    check_same_time_step(beds, dt)?;
    crate::integrate::validate_settings(structure, dt, duration_s, sample_every, true)
        .map_err(|e| StructureError::DemTimeStep { error: e })?;
    let mut it = ModalIntegrator::new(structure, dt);
    it.q = q0;
    it.v = v0;
    let mut runs = beds
        .iter()
        .enumerate()
        .map(|(i, b)| {
            BedRun::start(structure, b, &it)
                .map_err(|e| e.context(format!("DEM bed {} at '{}'", i + 1, b.point)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let total_load = |runs: &[BedRun], q: &DVector<f64>| -> (DVector<f64>, Vec<DVector<f64>>) {
        let mut sum = DVector::zeros(q.len());
        let mut raw = Vec::with_capacity(runs.len());
        for r in runs {
            let (l, rw) = r.load(q);
            sum += l;
            raw.push(rw);
        }
        (sum, raw)
    };
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
    let (q_pd, _) = total_load(&runs, &it.q);
    it.make_consistent(&(f_ex(0.0) + q_pd));
    let e_structure0 = it.energy_j();
    let mut energy = DemEnergy::default();
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
        && let Some(st) = cp::load::<CoupledState>(&c.path, COUPLE_KIND, &c.inputs_digest)
            .map_err(StructureError::from)?
    {
        first = st.restore(&c.path, &mut runs, &mut it, &mut hist, &mut energy)?;
    }
    // Without checkpoints a run is not stopped (it has nowhere to continue from).
    let cancel = ck.map_or_else(CancelToken::new, |c| c.cancel.clone());
    let _armed = ck.map(|_| cancel.arm());
    let mut control = LoopControl::new(&cancel, ck.map_or(0.0, |c| c.interval_s));
    let n_steps = (duration_s / dt).round() as usize;
    let mut snapshots = bed_snapshots(ck, dt, first, &runs[0].w)?;
    let every = sample_every.max(1);
    let report = (n_steps / 200).max(1);
    let mut step = first - 1;
    let end = time_loop::run(&mut control, |event| {
        if event == LoopEvent::Checkpoint {
            if let (Some(c), Some(h)) = (ck, &header) {
                let st = CoupledState::capture(step, &it, &runs, &hist, energy);
                cp::save(&c.path, h, &st).map_err(StructureError::from)?;
            }
            return Ok(Flow::Continue);
        }
        if step == n_steps {
            return Ok(Flow::Finished);
        }
        step += 1;
        let t1 = step as f64 * dt;
        let q_prev = it.q.clone();
        it.verlet_drift();
        let mut q_pd = f_ex(t1);
        for (i, r) in runs.iter_mut().enumerate() {
            r.follow(&it, t1, dt);
            r.w.dt_s = t1 - r.w.time_s;
            r.w.step();
            let (l, q_new) = r.load(&it.q);
            energy.structure_work_on_bed_j -= 0.5 * (&r.q_raw + &q_new).dot(&(&it.q - &q_prev));
            r.q_raw = q_new;
            if !l.iter().all(|x| x.is_finite()) || !r.w.ledger.kinetic_j.is_finite() {
                return Err(StructureError::BedLoadNonFinite {
                    time_s: t1,
                    bed: i + 1,
                    point: beds[i].point.to_string(),
                    kinetic_j: r.w.ledger.kinetic_j,
                    time_step_s: dt,
                });
            }
            q_pd += l;
        }
        it.verlet_kick(&q_pd);
        it.check_health(structure, step == n_steps)?;
        if step % every == 0 {
            push(&it, &mut hist);
        }
        if let Some(s) = snapshots.as_mut() {
            s.on_step(step as u64, t1, &runs[0].w)
                .map_err(StructureError::from)?;
        }
        if step % report == 0 {
            progress(step as f64 / n_steps as f64);
        }
        Ok(Flow::Continue)
    })?;
    if end == LoopEnd::Cancelled
        && let Some(c) = ck
    {
        return Err(StructureError::Interrupted(cp::Interrupted {
            time_s: it.time_s,
            path: c.path.clone(),
        }));
    }
    add_bed_ledgers(&mut energy, &runs);
    energy.structure_energy_change_j = it.energy_j() - e_structure0;
    Ok(CoupledResult {
        history: hist,
        energy,
    })
}

/// The beds of one coupled run step together: every bed's time step must be `dt` (bed 1's).
fn check_same_time_step(beds: &[DemBed], dt: f64) -> Result<(), StructureError> {
    for (i, b) in beds.iter().enumerate() {
        if b.damper.time_step_s != dt {
            return Err(StructureError::invalid(
                format!("DEM bed {} at '{}'", i + 1, b.point),
                format!(
                    "time step {:e} s, but bed 1's is {dt:e} s; the beds of one coupled run step \
                     together: give their damper scenarios the same time_step_s",
                    b.damper.time_step_s
                ),
            ));
        }
    }
    Ok(())
}

/// The first bed's ParaView series of a checkpointed run: a frame every `interval_s` of its
/// `bed_vtk` settings (`None` without them), started at step `first` (frame 0 written; the
/// frames of a resumed run's earlier steps are the interrupted run's).
fn bed_snapshots(
    ck: Option<&CouplingCheckpoint>,
    dt: f64,
    first: usize,
    bed: &pdamp_dem::World,
) -> Result<Option<SnapshotSeries>, StructureError> {
    let Some(b) = ck.and_then(|c| c.bed_vtk.as_ref()) else {
        return Ok(None);
    };
    let Some(every) = SnapshotSeries::every_steps_for(b.interval_s, dt) else {
        return Ok(None);
    };
    let mut s = SnapshotSeries::new(&b.dir, &b.pvd_name, &b.subdir, every, b.encoding);
    match first {
        1 => s.on_step(0, 0.0, bed)?,
        _ => s.resume_after((first - 1) as u64, dt, bed)?,
    }
    Ok(Some(s))
}

/// Every bed's energy ledger added to the run's energy exchange: wall work, change of the
/// bed's mechanical energy and dissipation.
fn add_bed_ledgers(energy: &mut DemEnergy, runs: &[BedRun]) {
    for r in runs {
        let l = &r.w.ledger;
        energy.wall_work_j += l.wall_work_j;
        energy.bed_energy_change_j += l.total_mechanical_j()
            - (l.initial_kinetic_j + l.initial_potential_j + l.initial_elastic_j);
        energy.dissipated_j += l.dissipated_j();
    }
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
    opts: &DemCoupling,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<TimeHistory, StructureError> {
    run_dem_free_with_energy(
        structure,
        damper,
        damper_point,
        spec,
        opts,
        progress,
        checkpoint,
    )
    .map(|(h, _)| h)
}

/// [`run_dem_free`] that also returns the energy exchange [`DemEnergy`].
///
/// # Errors
/// See [`run_dem_free`].
pub fn run_dem_free_with_energy(
    structure: &ModalStructure,
    damper: &Damper,
    damper_point: &str,
    spec: &FreeVibrationSpec,
    opts: &DemCoupling,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<(TimeHistory, DemEnergy), StructureError> {
    let bed = DemBed {
        damper,
        point: damper_point,
        coupling: opts,
    };
    run_dem_free_beds(structure, &[bed], spec, progress, checkpoint)
}

/// Free vibration with several DEM beds (one per container, each at its point), stepped
/// together with the structure; the energy exchange sums the beds. With
/// `scale_initial_by_bed_mass` the release is scaled by the beds' total mass (D Eq. 5.19).
///
/// # Errors
/// See [`run_dem_free`]; beds with different time steps.
pub fn run_dem_free_beds(
    structure: &ModalStructure,
    beds: &[DemBed],
    spec: &FreeVibrationSpec,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<(TimeHistory, DemEnergy), StructureError> {
    let init = structure.point(&spec.initial_point)?;
    let k = spec.mode;
    if k >= structure.modes.len() || init[k] == 0.0 {
        return Err(StructureError::rule(
            format!("mode {}", k + 1),
            format!(
                "cannot carry the initial condition at '{}'",
                spec.initial_point
            ),
        ));
    }
    let n = structure.modes.len();
    let mut q0 = DVector::zeros(n);
    let mut v0 = DVector::zeros(n);
    let scale = if spec.scale_initial_by_bed_mass {
        let mass: f64 = beds.iter().map(|b| b.damper.bed_mass_kg).sum();
        crate::free::bed_mass_scale(init[k], mass)
    } else {
        1.0
    };
    q0[k] = scale * spec.initial_displacement_m / init[k];
    v0[k] = scale * spec.initial_velocity_m_s / init[k];
    let r = coupled_run(
        structure,
        beds,
        &spec.output_point,
        q0,
        v0,
        spec.duration_s,
        spec.sample_every,
        Load::Free,
        progress,
        checkpoint,
    )?;
    Ok((r.history, r.energy))
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
    opts: &DemCoupling,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<TimeHistory, StructureError> {
    let bed = DemBed {
        damper,
        point: damper_point,
        coupling: opts,
    };
    run_dem_sweep_beds(structure, &[bed], spec, progress, checkpoint).map(|(h, _)| h)
}

/// [`run_dem_sweep`] with several DEM beds, returning the energy exchange [`DemEnergy`] too
/// (the shaker's work enters the structure's side: the coupling closure compares the
/// structure's work on the beds with the walls' work on the particles, which the load does not
/// touch).
///
/// # Errors
/// See [`run_dem_sweep`]; beds with different time steps.
pub fn run_dem_sweep_beds(
    structure: &ModalStructure,
    beds: &[DemBed],
    spec: &SweepSpec,
    progress: &mut dyn FnMut(f64),
    checkpoint: Option<&CouplingCheckpoint>,
) -> Result<(TimeHistory, DemEnergy), StructureError> {
    spec.sweep.validate()?;
    let ex = structure.point(&spec.excitation_point)?.to_vec();
    let n = structure.modes.len();
    coupled_run(
        structure,
        beds,
        &spec.output_point,
        DVector::zeros(n),
        DVector::zeros(n),
        spec.sweep.duration_s,
        spec.sample_every,
        Load::Sweep(spec, ex),
        progress,
        checkpoint,
    )
    .map(|r| (r.history, r.energy))
}
