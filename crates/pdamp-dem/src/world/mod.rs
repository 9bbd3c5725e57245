//! The simulation world: particles, materials, contact models, rigid bodies with walls, and the
//! time loop state. `World::step` advances by one time step with the chosen integrator.

use crate::body::RigidBody;
use crate::contact::{ContactModel, PairProps};
use crate::energy::{EnergyIncrements, EnergyLedger};
use crate::forces::{ForcePass, PpContact, WallSlot};
use crate::integrate::{GearState, Integrator};
use crate::interaction::InteractionTable;
use crate::material::{Material, effective_mass, effective_radius};
use crate::math::Vec3;
use crate::neighbor::NeighborList;
use crate::particles::ParticleSet;
use rayon::prelude::*;

mod step;

/// Counters of work done, for diagnostics and benchmarks.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Counters {
    /// Accepted time steps.
    pub steps: u64,
    /// Rejected time steps (Gear step control).
    pub rejected_steps: u64,
    /// Force evaluations.
    pub force_evaluations: u64,
    /// Neighbour-list builds.
    pub neighbor_builds: u64,
}

/// Wall-clock time spent in the phases of the time step, s (collected when
/// [`World::profile`] is `Some`; for benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct PhaseTimes {
    /// Kicks and drift of the integrator.
    pub integrate_s: f64,
    /// Neighbour-list displacement check and rebuilds.
    pub neighbors_s: f64,
    /// The block pass of the force evaluation: packing, gravity and external loads, the
    /// particle–particle and particle–wall contact laws.
    pub pair_forces_s: f64,
    /// Shares of second partners from other blocks of the pair pass.
    pub particle_forces_s: f64,
    /// Energy ledger update (kinetic, potential) and body loads.
    pub energies_s: f64,
}

/// A DEM simulation.
#[derive(Debug, Clone)]
pub struct World {
    /// The particles.
    pub particles: ParticleSet,
    /// Material table (particles and walls refer to it by index).
    pub materials: Vec<Material>,
    /// Contact model per material pair.
    pub interactions: InteractionTable,
    /// Rigid bodies carrying walls.
    pub bodies: Vec<RigidBody>,
    /// Gravitational acceleration, m/s².
    pub gravity_m_s2: Vec3,
    /// Simulated time, s.
    pub time_s: f64,
    /// Current time step, s (changes under Gear step control).
    pub dt_s: f64,
    /// Time integration scheme.
    pub integrator: Integrator,
    /// Energy balance.
    pub ledger: EnergyLedger,
    /// Work counters.
    pub counters: Counters,
    /// Phase timing, collected when `Some` (see [`PhaseTimes`]).
    pub profile: Option<PhaseTimes>,
    pub(crate) neighbors: NeighborList,
    /// The force pass: contact history of pairs and walls, block layout, wall candidates and
    /// the pass's scratch (see [`ForcePass`]).
    pub(crate) pass: ForcePass,
    /// Per-block kinetic and potential energy (scratch of `refresh_state_energies`).
    pub(crate) scratch_energy: Vec<[f64; 2]>,
    /// Largest squared displacement since the last neighbour build, per chunk of the drift
    /// (scratch).
    pub(crate) scratch_top: Vec<f64>,
    pub(crate) gear: Option<GearState>,
    pub(crate) initialized: bool,
    /// Half the time step of the last velocity-Verlet step while its second half kick is
    /// pending (see [`World::step_deferred`]), s.
    pub(crate) pending_half_kick_s: Option<f64>,
    /// Skin chosen anew at every neighbour build from the fastest particle, when `Some` (see
    /// [`World::set_adaptive_skin`]).
    pub(crate) adaptive_skin: Option<AdaptiveSkin>,
}

/// A neighbour-list skin chosen at every build from the fastest particle: large enough that the
/// list lasts about `steps` steps, never below `min_m` (the fixed skin of a bed at rest) nor
/// above `max_m` (the dissertation's $d_v^{max} = 0.8\,\min r_i$ [D Eq. 2.10]).
///
/// The list is valid for any skin (the rebuild criterion [D Eq. 2.11] uses the skin the list was
/// built with) and the forces come from the touching pairs alone, in list order: the contacts
/// and the physics are those of the fixed skin. Only the cost changes (falling and bouncing
/// beds rebuild every few steps with the small skin, and each build costs several steps) and
/// the round-off: the pair pass cuts its blocks by the number of listed pairs, so with more
/// than one block the force sums are grouped differently, and a chaotic bed then follows a
/// different, equally valid path (like a run on another build). With one block (beds of fewer
/// than 4 096 particles) the trajectory is the same bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSkin {
    /// Smallest skin, m.
    pub min_m: f64,
    /// Largest skin, m.
    pub max_m: f64,
    /// Steps a list should last at the current largest speed.
    pub steps: f64,
}

impl AdaptiveSkin {
    /// The skin for a largest particle speed `v_max_m_s` and time step `dt_s`, m: the two
    /// fastest particles, moving apart at `v_max`, use it up in `steps` steps.
    pub fn skin_m(&self, v_max_m_s: f64, dt_s: f64) -> f64 {
        let s = 2.0 * v_max_m_s * dt_s * self.steps;
        if s.is_finite() {
            s.clamp(self.min_m, self.max_m.max(self.min_m))
        } else {
            self.min_m
        }
    }
}

/// Kinetic energy (translation + rotation) and `m g·x` of one particle, J.
#[inline]
pub(crate) fn particle_energy(
    m: f64,
    inv_inertia: f64,
    v: &Vec3,
    w: &Vec3,
    x: &Vec3,
    g: &Vec3,
) -> (f64, f64) {
    (
        0.5 * m * v.norm_squared() + 0.5 * w.norm_squared() / inv_inertia,
        m * g.dot(x),
    )
}

/// Particles per block of the kinetic and potential energy sums (fixed, so that the sums do not
/// depend on the thread count).
pub(crate) const ENERGY_BLOCK: usize = crate::forces::PP_CHUNK;

impl World {
    /// A world with the given materials; every material pair uses `default_model` until
    /// [`World::set_contact_model`] says otherwise.
    pub fn new(materials: Vec<Material>, default_model: ContactModel, dt_s: f64) -> Self {
        let interactions = InteractionTable::new(&materials, default_model);
        Self {
            particles: ParticleSet::default(),
            materials,
            interactions,
            bodies: Vec::new(),
            gravity_m_s2: Vec3::new(0.0, 0.0, -9.81),
            time_s: 0.0,
            dt_s,
            integrator: Integrator::VelocityVerlet,
            ledger: EnergyLedger::default(),
            counters: Counters::default(),
            profile: None,
            neighbors: NeighborList::new(0.0),
            pass: ForcePass::default(),
            scratch_energy: Vec::new(),
            scratch_top: Vec::new(),
            gear: None,
            initialized: false,
            pending_half_kick_s: None,
            adaptive_skin: None,
        }
    }

    /// Uses `model` for contacts between materials `a` and `b`.
    pub fn set_contact_model(&mut self, a: u16, b: u16, model: ContactModel) {
        self.interactions.set(a, b, model);
        self.initialized = false;
    }

    /// Adds a particle at rest and returns its index.
    pub fn add_particle(&mut self, position: Vec3, radius_m: f64, material: u16) -> usize {
        let rho = self.materials[material as usize].density_kg_m3;
        self.initialized = false;
        self.particles.push(position, radius_m, rho, material)
    }

    /// Adds a rigid body and returns its index.
    pub fn add_body(&mut self, body: RigidBody) -> usize {
        self.bodies.push(body);
        self.initialized = false;
        self.bodies.len() - 1
    }

    /// Number of particle–particle pairs in the neighbour list.
    pub fn num_neighbor_pairs(&self) -> usize {
        self.neighbors.num_pairs()
    }

    /// The particle pairs of the neighbour list `(i, j)`, `i < j`.
    pub fn neighbor_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let nl = &self.neighbors;
        (0..nl.num_pairs()).map(|k| (nl.first[k] as usize, nl.second[k] as usize))
    }

    /// Number of touching particle–particle contacts.
    pub fn num_pp_contacts(&self) -> usize {
        self.pass.pp_chunks.iter().map(|c| c.len()).sum()
    }

    /// Number of touching particle–wall contacts.
    pub fn num_pw_contacts(&self) -> usize {
        self.pass.wall_slots.iter().map(|s| s.len()).sum()
    }

    /// Refreshes of the particles' wall candidates since the world was built (at neighbour-list
    /// rebuilds and when a body has moved by one skin; not kept in checkpoints).
    pub fn wall_candidate_refreshes(&self) -> u64 {
        self.pass.wall_refreshes
    }

    /// Number of wall contacts of particle `i` at the last evaluation.
    pub fn num_wall_contacts_of(&self, i: usize) -> usize {
        self.pass.wall_slots.get(i).map_or(0, |s| s.len())
    }

    /// Largest overlap relative to the smaller radius over all particle–particle contacts.
    pub fn max_relative_overlap(&self) -> f64 {
        let p = &self.particles;
        self.neighbor_pairs()
            .map(|(i, j)| {
                let ov = p.radius[i] + p.radius[j] - (p.position[i] - p.position[j]).norm();
                ov / p.radius[i].min(p.radius[j])
            })
            .fold(0.0, f64::max)
    }

    /// Default Verlet skin: 0.2 × the smallest radius (kept under the dissertation's
    /// $d_v^{max} = 0.8\,\min r_i$ [D Eq. 2.10]).
    pub fn default_skin(&self) -> f64 {
        0.2 * self.particles.min_radius()
    }

    /// Sets the neighbour-list skin (m); ends an adaptive skin.
    pub fn set_skin(&mut self, skin_m: f64) {
        self.neighbors.skin_m = skin_m;
        self.neighbors.builds = 0;
        self.adaptive_skin = None;
    }

    /// Chooses the skin at every neighbour build from the fastest particle (`Some`, see
    /// [`AdaptiveSkin`]), or keeps the skin fixed at its current value (`None`). For falling,
    /// bouncing or poured beds: the same contacts, far fewer builds (round-off aside, see
    /// [`AdaptiveSkin`]).
    pub fn set_adaptive_skin(&mut self, skin: Option<AdaptiveSkin>) {
        self.adaptive_skin = skin;
    }

    /// The adaptive skin for this world's particles: from the default skin (0.2 × the smallest
    /// radius) up to the dissertation's bound 0.8 × the smallest radius [D Eq. 2.10], sized to
    /// last 20 steps.
    pub fn default_adaptive_skin(&self) -> AdaptiveSkin {
        AdaptiveSkin {
            min_m: self.default_skin(),
            max_m: 0.8 * self.particles.min_radius(),
            steps: 20.0,
        }
    }

    /// Smallest Hertz contact time over the particle materials at `impact_velocity_m_s` for
    /// the smallest particle (eq. 4.8 or the law's own estimate), s. Used to check the time step.
    pub fn min_contact_time_s(&self, impact_velocity_m_s: f64) -> f64 {
        let p = &self.particles;
        if p.is_empty() {
            return f64::INFINITY;
        }
        let mut t = f64::INFINITY;
        let mut mats: Vec<u16> = p.material.clone();
        mats.sort_unstable();
        mats.dedup();
        let (mut imin, mut rmin) = (0, f64::INFINITY);
        for i in 0..p.len() {
            if p.radius[i] < rmin {
                rmin = p.radius[i];
                imin = i;
            }
        }
        let m = p.mass[imin];
        for &a in &mats {
            let mut partners: Vec<u16> = mats.clone();
            for b in &self.bodies {
                partners.extend(b.walls.iter().map(|w| w.material));
            }
            for &b in &partners {
                let (model, el) = self.interactions.get(a, b);
                let props = PairProps {
                    e_eff_pa: el.e_eff_pa,
                    g_eff_pa: el.g_eff_pa,
                    poisson_mean: el.poisson_mean,
                    r_eff_m: effective_radius(rmin, rmin),
                    m_eff_kg: effective_mass(m, m),
                };
                t = t.min(model.contact_time_estimate_s(&props, impact_velocity_m_s));
            }
        }
        t
    }

    /// Default largest Gear step $\Delta t_{max} = \pi / \max_i \omega_{con,i}$ [D Tab. 2.3] with
    /// $\omega_{con} = \sqrt{k_n / m_i}$ [D Eq. 2.83], s. For Hertz-type laws $k_n$ is the Hertz
    /// constant $\tfrac43 E^* \sqrt{R^*}$ [D Eq. 2.79] (N/m^1.5) used, as in the dissertation, by its
    /// SI value as if it were a linear stiffness; for mm-size steel spheres this gives roughly
    /// 1/15 of the contact time at 1 m/s, which keeps the entry into a contact resolved. For the
    /// linear law $k_n = k_N$. Smallest particle, all particle and wall partners.
    pub fn gear_default_dt_max_s(&self) -> f64 {
        let p = &self.particles;
        if p.is_empty() {
            return f64::INFINITY;
        }
        let mut mats: Vec<u16> = p.material.clone();
        mats.sort_unstable();
        mats.dedup();
        let mut omega: f64 = 0.0;
        let (mut imin, mut mmin) = (0, f64::INFINITY);
        for i in 0..p.len() {
            if p.mass[i] < mmin {
                mmin = p.mass[i];
                imin = i;
            }
        }
        let r = p.radius[imin];
        let mut walls: Vec<u16> = Vec::new();
        for b in &self.bodies {
            walls.extend(b.walls.iter().map(|w| w.material));
        }
        for &a in &mats {
            let partners = mats
                .iter()
                .map(|&b| (b, 0.5 * r))
                .chain(walls.iter().map(|&b| (b, r)));
            for (b, r_eff) in partners {
                let (model, el) = self.interactions.get(a, b);
                let k = match model.normal {
                    crate::contact::NormalLaw::Linear { stiffness_n_m, .. } => stiffness_n_m,
                    _ => crate::contact::hertz::hertz_stiffness(el.e_eff_pa, r_eff),
                };
                omega = omega.max((k / mmin).sqrt());
            }
        }
        std::f64::consts::PI / omega.max(1e-300)
    }

    /// Neighbour-list skin in m (0 before the first [`World::initialize`] picks the default).
    pub fn skin_m(&self) -> f64 {
        self.neighbors.skin_m
    }

    /// The active particle–particle contacts with their state (history, previous forces and
    /// stored energies), sorted by `(i, j)`: what another backend needs to continue the run
    /// exactly (see `pdamp-gpu`).
    pub fn particle_contacts(&self) -> Vec<PpContact> {
        self.pp_contacts()
    }

    /// The particle–wall contacts of every particle with their state (see
    /// [`World::particle_contacts`]).
    pub fn wall_contacts(&self) -> &[Vec<WallSlot>] {
        &self.pass.wall_slots
    }

    /// All active particle–particle contacts, sorted by `(i, j)`, appended to `out` (see
    /// `ForcePass::collect_pp_contacts`).
    pub(crate) fn collect_pp_contacts(&self, out: &mut Vec<PpContact>) {
        self.pass
            .collect_pp_contacts(&self.neighbors, self.particles.len(), out);
    }

    /// All active particle–particle contacts, sorted by `(i, j)`.
    pub(crate) fn pp_contacts(&self) -> Vec<PpContact> {
        let mut v = Vec::new();
        self.collect_pp_contacts(&mut v);
        v
    }

    /// Replaces the active particle–particle contacts (sorted by `(i, j)`) and attaches them to
    /// the pairs of the current neighbour list (see `ForcePass::set_pp_contacts`).
    pub(crate) fn set_pp_contacts(&mut self, contacts: &[PpContact]) {
        self.pass
            .set_pp_contacts(&self.neighbors, self.particles.len(), contacts);
    }

    /// Adds the particles that hold wall contacts but are missing from the wall pass's list
    /// (after wall contacts were restored from a backup).
    pub(crate) fn include_wall_holders(&mut self) {
        self.pass.include_wall_holders();
    }

    /// Prepares neighbour lists and evaluates the initial forces (called by the first step).
    pub fn initialize(&mut self) {
        self.complete_step();
        let n = self.particles.len();
        if self.neighbors.skin_m <= 0.0 {
            self.neighbors.skin_m = self.default_skin();
        }
        self.neighbors.extra_range_m = self
            .interactions
            .models()
            .iter()
            .map(|m| {
                let r = self.particles.max_radius();
                let props = PairProps {
                    e_eff_pa: 1.0,
                    g_eff_pa: 1.0,
                    poisson_mean: 0.3,
                    r_eff_m: r,
                    m_eff_kg: 1.0,
                };
                m.max_interaction_gap_m(&props)
            })
            .fold(0.0, f64::max);
        self.pass.wall_slots.resize(n, Vec::new());
        self.pass.wall_ref.clear();
        self.neighbors.builds = 0;
        self.update_neighbors();
        for b in self.bodies.iter_mut() {
            let s = b.prescribed_state(self.time_s);
            b.state = s;
            b.previous = s;
        }
        let inc = self.evaluate_forces(0.0);
        self.counters.force_evaluations += 1;
        self.ledger.elastic_j = inc.elastic_j;
        self.refresh_state_energies();
        self.ledger.reset();
        self.initialized = true;
    }

    /// Starts timing a phase (only when profiling).
    #[inline]
    pub(crate) fn tick(&self) -> Option<std::time::Instant> {
        self.profile.map(|_| std::time::Instant::now())
    }

    /// Adds the time since `t` to a phase (only when profiling).
    #[inline]
    pub(crate) fn tock(
        &mut self,
        t: Option<std::time::Instant>,
        phase: fn(&mut PhaseTimes) -> &mut f64,
    ) {
        if let (Some(p), Some(t)) = (self.profile.as_mut(), t) {
            *phase(p) += t.elapsed().as_secs_f64();
        }
    }

    /// Rebuilds the neighbour list when the displacement criterion asks for it.
    pub(crate) fn update_neighbors(&mut self) {
        self.update_neighbors_given(None);
    }

    /// [`World::update_neighbors`], knowing the largest squared displacement since the last
    /// build (`max_d2`, m²): while twice the largest displacement stays below the skin, the
    /// two largest cannot reach it [D Eq. 2.11] and the particles need not be visited again;
    /// otherwise the exact criterion decides.
    pub(crate) fn update_neighbors_given(&mut self, max_d2: Option<f64>) {
        let t = self.tick();
        let surely_valid = max_d2.is_some_and(|d2| 2.0 * d2.sqrt() < self.neighbors.skin_m);
        if !surely_valid && self.neighbors.needs_rebuild(&self.particles.position) {
            self.rebuild_neighbors();
        }
        self.tock(t, |p| &mut p.neighbors_s);
    }

    fn rebuild_neighbors(&mut self) {
        // Contacts are attached to the pairs of the list: take them off, rebuild, put them
        // back onto the new pairs (in (i, j) order, which also compacts the slabs).
        let mut contacts = std::mem::take(&mut self.pass.remap_scratch);
        contacts.clear();
        self.collect_pp_contacts(&mut contacts);
        if let Some(a) = self.adaptive_skin {
            let v2 = self
                .particles
                .velocity
                .par_iter()
                .map(|v| v.norm_squared())
                .reduce(|| 0.0, f64::max);
            self.neighbors.skin_m = a.skin_m(v2.sqrt(), self.dt_s);
        }
        self.neighbors
            .rebuild(&self.particles.position, &self.particles.radius);
        self.set_pp_contacts(&contacts);
        self.pass.remap_scratch = contacts;
        self.counters.neighbor_builds += 1;
    }

    /// Recomputes kinetic and potential energy in the ledger from the state.
    pub(crate) fn refresh_state_energies(&mut self) {
        // In parallel over blocks of particles, the blocks added in order (the result does not
        // depend on the thread count).
        const BLOCK: usize = ENERGY_BLOCK;
        let p = &self.particles;
        let g = self.gravity_m_s2;
        let sums = &mut self.scratch_energy;
        sums.clear();
        sums.resize(p.len().div_ceil(BLOCK), [0.0; 2]);
        sums.par_iter_mut().enumerate().for_each(|(b, e)| {
            let r = b * BLOCK..((b + 1) * BLOCK).min(p.len());
            let (mut kin, mut pot) = (0.0, 0.0);
            for i in r {
                let (k, u) = particle_energy(
                    p.mass[i],
                    p.inv_inertia[i],
                    &p.velocity[i],
                    &p.angular_velocity[i],
                    &p.position[i],
                    &g,
                );
                kin += k;
                pot += u;
            }
            *e = [kin, pot];
        });
        self.ledger_energies_from_blocks();
    }

    /// Kinetic and potential energy of the ledger: the per-block sums of `scratch_energy`,
    /// added in block order.
    pub(crate) fn ledger_energies_from_blocks(&mut self) {
        let (mut kin, mut pot) = (0.0, 0.0);
        for e in self.scratch_energy.iter() {
            kin += e[0];
            pot += e[1];
        }
        self.ledger.kinetic_j = kin;
        self.ledger.potential_j = -pot;
    }

    /// Advances by one time step (or one accepted step under Gear step control).
    pub fn step(&mut self) {
        self.step_deferred();
        self.complete_step();
    }

    /// Like [`World::step`], but under velocity Verlet the second half kick of the step is left
    /// pending and done by the next step, in the same pass over the particles as that step's
    /// first half kick and drift (one pass over velocities, forces, masses and positions less
    /// per step; the arithmetic and so the results are the same to the bit).
    ///
    /// Until [`World::complete_step`] (or [`World::step`]) is called, only the positions, the
    /// clock, the bodies (poses and contact loads), the counters and the ledger's work and
    /// dissipation terms are current: particle velocities and spins are half a step behind,
    /// particle forces lack shares of the pair pass, and the ledger's kinetic and potential
    /// energy are those of the previous step. Nothing that reads particle state may run
    /// between deferred steps (observers of [`World::run_until_or_break_deferred`] included).
    pub fn step_deferred(&mut self) {
        if !self.initialized {
            self.initialize();
        }
        let inc: EnergyIncrements = match self.integrator.clone() {
            Integrator::VelocityVerlet => self.step_velocity_verlet(true),
            Integrator::Gear(params) => {
                self.complete_step();
                self.step_gear(&params)
            }
        };
        if let Some(r) = self.pass.wall_repeat.as_deref_mut() {
            r.step_taken(
                &self.ledger,
                matches!(self.integrator, Integrator::VelocityVerlet),
            );
        }
        let t = self.tick();
        self.ledger.add(&inc);
        if matches!(self.integrator, Integrator::Gear(_)) {
            self.refresh_state_energies();
        }
        self.tock(t, |p| &mut p.energies_s);
        self.counters.steps += 1;
    }

    /// Does the second half kick left pending by [`World::step_deferred`], if any: afterwards
    /// velocities, spins, forces and the ledger's kinetic and potential energy are those of
    /// the current time.
    pub fn complete_step(&mut self) {
        if let Some(half) = self.pending_half_kick_s.take() {
            let t = self.tick();
            self.second_half_kick(half);
            self.tock(t, |p| &mut p.integrate_s);
        }
    }

    /// True while a half kick is pending (between [`World::step_deferred`] and
    /// [`World::complete_step`]).
    pub fn step_pending(&self) -> bool {
        self.pending_half_kick_s.is_some()
    }

    /// Steps until `time_s` reaches `t_end_s` (the last step is shortened to land on it).
    pub fn run_until(&mut self, t_end_s: f64, mut observer: impl FnMut(&World)) {
        self.run_until_or_break(t_end_s, |w| {
            observer(w);
            std::ops::ControlFlow::Continue(())
        });
    }

    /// Like [`World::run_until`], but stops after the step at which `observer` returns
    /// `Break`; returns true if `t_end_s` was reached.
    pub fn run_until_or_break(
        &mut self,
        t_end_s: f64,
        mut observer: impl FnMut(&World) -> std::ops::ControlFlow<()>,
    ) -> bool {
        self.run_until_impl(t_end_s, |w| observer(w), false)
    }

    /// Like [`World::run_until_or_break`], with the steps taken by [`World::step_deferred`]
    /// (faster under velocity Verlet, the same results). After a step `observer` may read the
    /// clock, the bodies, the counters and the ledger's work and dissipation terms; before it
    /// reads anything else (particles, the ledger's kinetic and potential energy, a health
    /// check, a snapshot, a checkpoint) it calls [`World::complete_step`]. The state is complete
    /// again when this returns.
    pub fn run_until_or_break_deferred(
        &mut self,
        t_end_s: f64,
        observer: impl FnMut(&mut World) -> std::ops::ControlFlow<()>,
    ) -> bool {
        self.run_until_impl(t_end_s, observer, true)
    }

    fn run_until_impl(
        &mut self,
        t_end_s: f64,
        mut observer: impl FnMut(&mut World) -> std::ops::ControlFlow<()>,
        deferred: bool,
    ) -> bool {
        let tol = 1e-12 * t_end_s.abs().max(1e-300);
        let mut reached = true;
        while self.time_s < t_end_s - tol {
            self.step_towards(t_end_s, deferred);
            if observer(self).is_break() {
                reached = self.time_s >= t_end_s - tol;
                break;
            }
        }
        self.complete_step();
        reached
    }

    /// One step towards `t_end_s`, shortened to land on it (velocity Verlet keeps its nominal
    /// step afterwards); deferred half kick under [`World::step_deferred`].
    #[inline]
    fn step_towards(&mut self, t_end_s: f64, deferred: bool) {
        let dt_nominal = self.dt_s;
        let remaining = t_end_s - self.time_s;
        let short = remaining < dt_nominal;
        if short {
            self.dt_s = remaining;
        }
        if deferred {
            self.step_deferred();
        } else {
            self.step();
        }
        if short && matches!(self.integrator, Integrator::VelocityVerlet) {
            self.dt_s = dt_nominal;
        }
    }

    /// Steps until `t_end_s` on the engine's time loop ([`crate::time_loop::run`]): after each
    /// step `on(world, LoopEvent::Step)` observes it (`Break` ends the run early); when
    /// `control` has a checkpoint due or is cancelled, `on(world, LoopEvent::Checkpoint)` writes
    /// one on the completed state, and a cancelled run stops after it. With `deferred` the steps
    /// are [`World::step_deferred`] (`on` calls [`World::complete_step`] before it reads
    /// particles, as for [`World::run_until_or_break_deferred`]). The state is complete again
    /// when this returns.
    pub fn run_controlled<E>(
        &mut self,
        t_end_s: f64,
        deferred: bool,
        control: &mut crate::time_loop::LoopControl,
        mut on: impl FnMut(
            &mut World,
            crate::time_loop::LoopEvent,
        ) -> Result<std::ops::ControlFlow<()>, E>,
    ) -> Result<crate::time_loop::LoopEnd, E> {
        use crate::time_loop::{Flow, LoopEvent};
        let tol = 1e-12 * t_end_s.abs().max(1e-300);
        let end = crate::time_loop::run(control, |ev| match ev {
            LoopEvent::Step => {
                if self.time_s >= t_end_s - tol {
                    return Ok(Flow::Finished);
                }
                self.step_towards(t_end_s, deferred);
                Ok(match on(self, LoopEvent::Step)? {
                    std::ops::ControlFlow::Continue(()) => Flow::Continue,
                    std::ops::ControlFlow::Break(()) => Flow::Break,
                })
            }
            LoopEvent::Checkpoint => {
                self.complete_step();
                let _ = on(self, LoopEvent::Checkpoint)?;
                Ok(Flow::Continue)
            }
        });
        self.complete_step();
        end
    }

    /// Sets the clock back to zero and re-initialises (forces, body poses, ledger) while keeping
    /// particles and contact history: used after settling.
    pub fn restart_clock(&mut self) {
        self.time_s = 0.0;
        self.gear = None;
        self.initialize();
    }

    /// Total contact force and torque the particles exert on body `b`, N and N·m.
    pub fn body_load(&self, b: usize) -> (Vec3, Vec3) {
        (
            self.bodies[b].contact_force_n,
            self.bodies[b].contact_torque_nm,
        )
    }
}
