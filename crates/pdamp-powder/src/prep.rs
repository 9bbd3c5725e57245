//! Powder preparation (paper Sect. 2.4, Fig. 1a) on pdamp-dem: particles drawn from the size
//! distribution until their volume equals ϕ·V_cavity, placed on a Cartesian grid above the
//! cavity floor, settled under gravity, then compressed by a displacement-controlled plate down
//! to the cavity height, so that the packing density (particle volume / cavity volume) is the
//! prescribed ϕ; finally relaxed with the plate held. The particles are prepared directly in
//! the cavity's coordinates, so "extraction and insertion" is removing the box walls and the
//! plate: the coupled run takes over the particles with their contacts
//! ([`crate::bed::PowderBed`]). The bed may be made with its own friction and adhesion
//! ([`PrepSettings::friction`], [`PrepSettings::surface_energy_j_m2`]) and handed over with the
//! law of the run: a looser settled bed, so that low packing densities fill the cavity as in
//! the paper ("the cavity is always completely filled", Sect. 3.1) instead of leaving a gap.
//! Such a bed is then handed over: with the plate still held, the contacts take the run's law
//! and the bed relaxes under it until it is at rest again, so that the coupled run starts from
//! a bed in equilibrium under its own law (a bed compressed under μ = 1 and adhesion otherwise
//! unloads its pre-stress in the first milliseconds of the run, where that release would be
//! counted as damping and the integrator's error on it spoils the energy closure).
//!
//! The box is five one-sided planes on a fixed body, the plate a sixth on a body that moves
//! along a prescribed track (at constant speed while compressing, then held). [`Preparation`]
//! holds the whole state of a preparation in progress (the world with its contact history, the
//! plate's track, stage and step counters) and is serializable, so a long preparation can be
//! checkpointed and continued bit for bit; [`prepare`] runs one from start to end.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use pdamp_dem::walls::{Geometry, Plane};
use pdamp_dem::{BodyState, Motion, RigidBody, TranslationTrack, Vec3, World, WorldState};
use rand::{RngExt, SeedableRng};

use crate::bed::{PARTICLE_MATERIAL, PowderBed, WALL_MATERIAL, powder_world};
use crate::error::ParameterError;
use crate::fe::Aabb;
use crate::health::{self, HealthError};
use crate::law::PowderLaw;
use crate::psd::LogNormal;

/// Preparation settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrepSettings {
    /// Target packing density ϕ = particle volume / cavity volume.
    pub packing_density: f64,
    /// Random seed (sizes and grid jitter).
    pub seed: u64,
    /// Gravity magnification during settling (1 = real gravity; larger settles faster).
    pub settling_gravity_factor: f64,
    /// Plate speed during compression [m/s].
    pub plate_speed_m_s: f64,
    /// Relaxation after compression with the plate held \[s\].
    pub relax_time_s: f64,
    /// Longest settling time \[s\].
    pub max_settling_time_s: f64,
    /// Coefficient of friction while the bed is made (settling, relaxation, compression,
    /// holding); `None`: the law's. The coupled run always uses the law's. A larger value
    /// settles a looser bed (frictional random loose packing), so that a low packing density
    /// fills the cavity instead of leaving a gap under its top (see docs/powder.md, "Loose,
    /// fully filled cavities").
    #[serde(default)]
    pub friction: Option<f64>,
    /// Surface energy of the DMT adhesion while the bed is made \[J/m²\]; `None`: the
    /// law's. Cohesion holds a bed looser than friction alone can.
    #[serde(default)]
    pub surface_energy_j_m2: Option<f64>,
}

impl Default for PrepSettings {
    fn default() -> Self {
        Self {
            packing_density: 0.58,
            seed: 1,
            settling_gravity_factor: 20.0,
            plate_speed_m_s: 0.2,
            relax_time_s: 2e-3,
            max_settling_time_s: 0.5,
            friction: None,
            surface_energy_j_m2: None,
        }
    }
}

impl PrepSettings {
    /// The contact law while the bed is made: `law` with the preparation's friction and
    /// surface energy where they are set.
    pub fn law_of_preparation(&self, law: &PowderLaw) -> PowderLaw {
        PowderLaw {
            friction: self.friction.unwrap_or(law.friction),
            surface_energy_j_m2: self.surface_energy_j_m2.unwrap_or(law.surface_energy_j_m2),
            ..*law
        }
    }
}

/// Outcome of the preparation.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PrepReport {
    /// Particles.
    pub particles: usize,
    /// Packing density reached after settling (bed height from the highest particle top).
    pub settled_packing_density: f64,
    /// Packing density in the cavity (particle volume / cavity volume).
    pub packing_density: f64,
    /// Whether the settled bed was higher than the cavity (so the plate compressed it).
    pub compressed: bool,
    /// Force on the plate at the end \[N\].
    pub plate_force_n: f64,
    /// Largest overlap / smaller diameter at the end.
    pub max_relative_overlap: f64,
    /// Simulated preparation time \[s\].
    pub simulated_time_s: f64,
    /// DEM steps.
    pub steps: u64,
    /// Wall time \[s\].
    pub wall_time_s: f64,
    /// Force on the plate at the end of the hold under the preparation's law \[N\] (equal to
    /// `plate_force_n` when the bed was made with the run's law).
    #[serde(default)]
    pub plate_force_before_handover_n: f64,
    /// Simulated time of the handover to the run's law \[s\] (0 when the bed was made with
    /// the run's law).
    #[serde(default)]
    pub handover_time_s: f64,
    /// Height between the cavity top and the highest particle top at the end \[m\] (0 for a
    /// filled cavity; what the bed leaves empty).
    #[serde(default)]
    pub top_gap_m: f64,
}

/// Gravity of the relaxation, compression and of the prepared bed [m/s²].
const G0: [f64; 3] = [0.0, 0.0, -9.81];

/// Steps between the kinetic-energy checks of the settling.
const SETTLE_CHUNK: u32 = 200;

/// Stage of a preparation in progress.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
enum Stage {
    /// Settling under magnified gravity; `chunk` steps of the current block done.
    Settling { chunk: u32 },
    /// Relaxation under 1 g before the compression; `done` steps; `moved`: the kinetic energy
    /// has exceeded the 1 g rest limit since gravity was reduced (the bed is releasing the
    /// elastic energy stored under the magnified gravity).
    Relaxing { done: u64, moved: bool },
    /// Plate compression: step `q` of `nsteps` with the plate increment `dz` [m].
    Compressing { q: u64, nsteps: u64, dz: f64 },
    /// Relaxation with the plate held at the cavity top; `q` steps.
    Holding { q: u64 },
    /// Handover of a bed made with its own law: the run's law, the plate held, until at rest
    /// again; `done` steps; `force_mark`: the plate force at the last check \[N\].
    Handover { done: u64, force_mark: f64 },
    /// Finished.
    Done,
}

/// The body carrying the plate (body 0 is the box).
const PLATE: usize = 1;

/// The plate's track: `(t1_s, z offset from its start height at t1 in m, vertical speed in
/// m/s)`.
type PlateTrack = (f64, f64, f64);

/// A powder preparation in progress (see the module docs). Serializable: a preparation saved
/// with [`Preparation::snapshot`] and continued with [`Preparation::run`] ends bit for bit as
/// an uninterrupted one.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "PreparationData", into = "PreparationData")]
pub struct Preparation {
    world: World,
    plate: PlateTrack,
    /// Height of the plate when the walls were built, m.
    top_start: f64,
    law: PowderLaw,
    density_kg_m3: f64,
    stage: Stage,
    steps: u64,
    cavity: Aabb,
    settings: PrepSettings,
    e_ref: f64,
    /// Rest limit of the kinetic energy under 1 g (the settling criterion at g = 9.81 m/s²), J.
    e_ref_1g: f64,
    relax_steps: u64,
    settled: f64,
    compressed: bool,
    bed_top: f64,
    plate_force: f64,
    /// Plate force at the end of the hold, before the handover \[N\].
    plate_force_held: f64,
    /// Steps of the handover so far.
    handover_steps: u64,
    wall_time_s: f64,
    segment_start: Option<Instant>,
}

/// The serialized form of a [`Preparation`]: the world's state and what rebuilds its walls.
#[derive(serde::Serialize, serde::Deserialize)]
struct PreparationData {
    world: WorldState,
    plate: PlateTrack,
    top_start: f64,
    law: PowderLaw,
    density_kg_m3: f64,
    stage: Stage,
    steps: u64,
    cavity: Aabb,
    settings: PrepSettings,
    e_ref: f64,
    e_ref_1g: f64,
    relax_steps: u64,
    settled: f64,
    compressed: bool,
    bed_top: f64,
    plate_force: f64,
    plate_force_held: f64,
    handover_steps: u64,
    wall_time_s: f64,
}

impl From<Preparation> for PreparationData {
    fn from(p: Preparation) -> Self {
        Self {
            world: p.world.save_state(),
            plate: p.plate,
            top_start: p.top_start,
            law: p.law,
            density_kg_m3: p.density_kg_m3,
            stage: p.stage,
            steps: p.steps,
            cavity: p.cavity,
            settings: p.settings,
            e_ref: p.e_ref,
            e_ref_1g: p.e_ref_1g,
            relax_steps: p.relax_steps,
            settled: p.settled,
            compressed: p.compressed,
            bed_top: p.bed_top,
            plate_force: p.plate_force,
            plate_force_held: p.plate_force_held,
            handover_steps: p.handover_steps,
            wall_time_s: p.wall_time_s(),
        }
    }
}

/// Why a preparation (from a checkpoint) is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PrepError {
    /// The cavity, the plate or the density of a saved preparation is not finite.
    #[error("preparation state: cavity, plate or density not finite")]
    StateNotFinite,
    /// The time step or the reference energies of a saved preparation are not finite.
    #[error("preparation state: time step or reference energies not finite")]
    Inconsistent,
    /// The contact law of a saved preparation is out of range.
    #[error(transparent)]
    Law(#[from] ParameterError),
    /// The particle state was refused by pdamp-dem.
    #[error(transparent)]
    State(#[from] pdamp_dem::state::StateError),
}

impl TryFrom<PreparationData> for Preparation {
    type Error = PrepError;
    fn try_from(d: PreparationData) -> Result<Self, PrepError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let c = &d.cavity;
        let cavity_ok = finite(&c.min) && finite(&c.max) && (0..3).all(|k| c.min[k] < c.max[k]);
        let plate_ok = finite(&[d.plate.0, d.plate.1, d.plate.2, d.top_start]);
        let density_ok = d.density_kg_m3 > 0.0 && d.density_kg_m3.is_finite();
        if !(cavity_ok && plate_ok && density_ok) {
            return Err(PrepError::StateNotFinite);
        }
        d.law.validate("preparation state: law.")?;
        let prep_law = d.settings.law_of_preparation(&d.law);
        prep_law.validate("preparation state: settings.")?;
        let mut world = walls_world(&d.cavity, &prep_law, d.density_kg_m3, 1.0, d.top_start);
        world.set_particles_of(&d.world)?;
        world.set_adaptive_skin(Some(world.default_adaptive_skin()));
        let mut p = Self {
            world,
            plate: d.plate,
            top_start: d.top_start,
            law: d.law,
            density_kg_m3: d.density_kg_m3,
            stage: d.stage,
            steps: d.steps,
            cavity: d.cavity,
            settings: d.settings,
            e_ref: d.e_ref,
            e_ref_1g: d.e_ref_1g,
            relax_steps: d.relax_steps,
            settled: d.settled,
            compressed: d.compressed,
            bed_top: d.bed_top,
            plate_force: d.plate_force,
            plate_force_held: d.plate_force_held,
            handover_steps: d.handover_steps,
            wall_time_s: d.wall_time_s,
            segment_start: None,
        };
        if matches!(p.stage, Stage::Handover { .. } | Stage::Done) {
            p.use_law_of_run();
        }
        p.set_plate_track(p.plate, false);
        p.world.restore_state(d.world)?;
        Ok(p)
    }
}

/// Height of the highest particle top \[m\].
fn bed_top(p: &pdamp_dem::ParticleSet) -> f64 {
    p.position
        .iter()
        .zip(&p.radius)
        .map(|(x, r)| x.z + r)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A world of the powder inside `cavity`: the five box walls on a fixed body, the plate at
/// `top_start` (m) on a body that moves along a track (set by the caller).
fn walls_world(
    cavity: &Aabb,
    law: &PowderLaw,
    density_kg_m3: f64,
    dt_s: f64,
    top_start: f64,
) -> World {
    let mut w = powder_world(law, density_kg_m3, [0.0; 3], dt_s);
    let (lo, hi) = (Vec3::from(cavity.min), Vec3::from(cavity.max));
    let plane = |p: Vec3, n: [f64; 3]| Geometry::Plane(Plane::new(p, Vec3::from(n), false));
    let mut sides = RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed);
    for (name, p, n) in [
        ("x_min", lo, [1.0, 0.0, 0.0]),
        ("x_max", hi, [-1.0, 0.0, 0.0]),
        ("y_min", lo, [0.0, 1.0, 0.0]),
        ("y_max", hi, [0.0, -1.0, 0.0]),
        ("floor", lo, [0.0, 0.0, 1.0]),
    ] {
        sides = sides.with_wall(name, plane(p, n), WALL_MATERIAL);
    }
    w.add_body(sides);
    let top = Vec3::new(cavity.min[0], cavity.min[1], top_start);
    w.add_body(
        RigidBody::new(
            "plate",
            BodyState::at_rest(Vec3::zeros()),
            Motion::Prescribed(Arc::new(TranslationTrack {
                t1_s: 0.0,
                displacement_m: Vec3::zeros(),
                velocity_m_s: Vec3::zeros(),
                acceleration_m_s2: Vec3::zeros(),
            })),
        )
        .with_wall("plate", plane(top, [0.0, 0.0, -1.0]), WALL_MATERIAL),
    );
    w
}

impl Preparation {
    /// Particles drawn and placed on the grid in `cavity` (gravity along −z during
    /// preparation, as in the paper), nothing simulated yet.
    pub fn new(
        cavity: Aabb,
        psd: &LogNormal,
        law: PowderLaw,
        density_kg_m3: f64,
        dt: f64,
        s: &PrepSettings,
    ) -> Self {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(s.seed);
        let vcav = cavity.volume();
        let diam = psd.fill_volume(s.packing_density * vcav, &mut rng);
        let spacing = psd.d_max_m * 1.02;
        let (lx, ly) = (cavity.max[0] - cavity.min[0], cavity.max[1] - cavity.min[1]);
        let nx = ((lx / spacing).floor() as usize).max(1);
        let ny = ((ly / spacing).floor() as usize).max(1);
        let ox = cavity.min[0] + 0.5 * (lx - (nx as f64 - 1.0) * spacing);
        let oy = cavity.min[1] + 0.5 * (ly - (ny as f64 - 1.0) * spacing);
        let mut pos = Vec::with_capacity(diam.len());
        for (q, d) in diam.iter().enumerate() {
            let layer = q / (nx * ny);
            let rem = q % (nx * ny);
            let (i, j) = (rem % nx, rem / nx);
            let jit = 0.005 * spacing;
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            pos.push((
                Vec3::new(
                    ox + i as f64 * spacing + jit * (u - 0.5),
                    oy + j as f64 * spacing + jit * (v - 0.5),
                    cavity.min[2] + 0.5 * spacing + layer as f64 * spacing,
                ),
                0.5 * d,
            ));
        }
        let top_start = pos
            .iter()
            .map(|(x, r)| x.z + r)
            .fold(cavity.max[2], f64::max)
            + spacing;
        let prep_law = s.law_of_preparation(&law);
        let mut world = walls_world(&cavity, &prep_law, density_kg_m3, dt, top_start);
        world.gravity_m_s2 = Vec3::new(0.0, 0.0, -9.81 * s.settling_gravity_factor);
        for (x, r) in pos {
            world.add_particle(x, r, PARTICLE_MATERIAL);
        }
        // the grid falls and bounces: a skin sized by the fastest particle saves most of the
        // neighbour builds (same trajectory, see `pdamp_dem::AdaptiveSkin`)
        world.set_adaptive_skin(Some(world.default_adaptive_skin()));
        let mtot = world.particles.total_mass();
        // settling: until the mean kinetic energy per particle is below 1e-4 of m g_eff d50
        let e_ref = 1e-4 * mtot * 9.81 * s.settling_gravity_factor * psd.d50_m;
        let e_ref_1g = 1e-4 * mtot * 9.81 * psd.d50_m;
        let mut p = Self {
            world,
            plate: (0.0, 0.0, 0.0),
            top_start,
            law,
            density_kg_m3,
            stage: Stage::Settling { chunk: 0 },
            steps: 0,
            cavity,
            settings: *s,
            e_ref,
            e_ref_1g,
            relax_steps: (s.relax_time_s / dt).ceil() as u64,
            settled: 0.0,
            compressed: false,
            bed_top: 0.0,
            plate_force: 0.0,
            plate_force_held: 0.0,
            handover_steps: 0,
            wall_time_s: 0.0,
            segment_start: None,
        };
        p.world.initialize();
        p
    }

    /// Puts the plate on `track` from now on; with `jump`, its pose is set to the track's at
    /// the current time at once (a placement, not a motion over the next step).
    fn set_plate_track(&mut self, track: PlateTrack, jump: bool) {
        self.plate = track;
        let b = &mut self.world.bodies[PLATE];
        b.motion = Motion::Prescribed(Arc::new(TranslationTrack {
            t1_s: track.0,
            displacement_m: Vec3::new(0.0, 0.0, track.1),
            velocity_m_s: Vec3::new(0.0, 0.0, track.2),
            acceleration_m_s2: Vec3::zeros(),
        }));
        if jump {
            let s = b.prescribed_state(self.world.time_s);
            b.state = s;
            b.previous = s;
        }
    }

    /// Height of the plate now, m.
    fn plate_height(&self) -> f64 {
        self.top_start + self.world.bodies[PLATE].state.position_m.z
    }

    /// The world being prepared (particles, box and plate).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to set diagnostics such as [`World::profile`].
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// Number of particles.
    pub fn particles(&self) -> usize {
        self.world.particles.len()
    }

    /// Simulated preparation time so far \[s\].
    pub fn time_s(&self) -> f64 {
        self.world.time_s
    }

    /// Checks that a deserialized preparation is self-consistent (the world's checks ran when
    /// it was restored; here the time step and the reference energies).
    pub fn check_consistency(&self) -> Result<(), PrepError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let ok = self.world.dt_s > 0.0
            && self.world.dt_s.is_finite()
            && finite(&[self.e_ref, self.e_ref_1g, self.bed_top, self.settled]);
        if !ok {
            return Err(PrepError::Inconsistent);
        }
        Ok(())
    }

    /// Name of the current stage (for messages).
    fn stage_name(&self) -> &'static str {
        match self.stage {
            Stage::Settling { .. } => "preparation: settling",
            Stage::Relaxing { .. } => "preparation: relaxing under 1 g",
            Stage::Compressing { .. } => health::COMPRESSION_STAGE,
            Stage::Holding { .. } => "preparation: relaxing with the plate held",
            Stage::Handover { .. } => "preparation: handover to the run's law",
            Stage::Done => "preparation: done",
        }
    }

    /// Health of the bed (see [`crate::health`]): finite states, particle centres inside the
    /// box walls and below the plate, no runaway overlap, no negative dissipation beyond a
    /// tenth of the bed's potential-energy scale M·g·H.
    pub fn check_health(&self) -> Result<(), Box<HealthError>> {
        let w = &self.world;
        let fail = |s| {
            Box::new(HealthError::of_world(
                w.time_s,
                self.stage_name(),
                s,
                w,
                &self.law,
            ))
        };
        let c = self.cavity;
        let top = self.plate_height().max(c.max[2]);
        let bx = Aabb {
            min: c.min,
            max: [c.max[0], c.max[1], top],
        };
        let size = (0..3).map(|k| bx.max[k] - bx.min[k]).fold(0.0, f64::max);
        health::check_world_particles(w, Some((&bx, 1e-9 * size))).map_err(|(_, s)| fail(s))?;
        health::check_world_overlaps(w).map_err(fail)?;
        let g = w.gravity_m_s2.norm().max(9.81);
        let scale = w.particles.total_mass() * g * size;
        health::check_energy(w.ledger.dissipated_j(), 0.0, scale).map_err(fail)?;
        Ok(())
    }

    /// Wall-clock time spent in this preparation so far, over all runs \[s\].
    pub fn wall_time_s(&self) -> f64 {
        self.wall_time_s
            + self
                .segment_start
                .map_or(0.0, |t| t.elapsed().as_secs_f64())
    }

    /// A copy for a checkpoint (its wall time includes the running segment).
    pub fn snapshot(&self) -> Self {
        Self {
            wall_time_s: self.wall_time_s(),
            segment_start: None,
            ..self.clone()
        }
    }

    fn step(&mut self) -> Result<(), Box<HealthError>> {
        self.world.step();
        self.steps += 1;
        if self.steps.is_multiple_of(SETTLE_CHUNK as u64) {
            self.check_health()?;
        }
        Ok(())
    }

    fn end_settling(&mut self) {
        // switch to real gravity and let the bed relax briefly
        self.world.gravity_m_s2 = Vec3::from(G0);
        self.stage = Stage::Relaxing {
            done: 0,
            moved: false,
        };
    }

    fn start_compression(&mut self) {
        let (cavity, s) = (self.cavity, self.settings);
        let p = &self.world.particles;
        let bed_top = bed_top(p);
        let volume: f64 = p
            .radius
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
            .sum();
        let area = (cavity.max[0] - cavity.min[0]) * (cavity.max[1] - cavity.min[1]);
        self.settled = volume / (area * (bed_top - cavity.min[2]));
        self.compressed = bed_top > cavity.max[2];
        self.bed_top = bed_top;
        let dt = self.world.dt_s;
        if !self.compressed {
            self.start_holding();
            return;
        }
        // compression: plate from just above the bed down to the cavity top
        let dist = bed_top - cavity.max[2];
        let nsteps = (dist / (s.plate_speed_m_s * dt)).ceil() as u64;
        let dz = dist / nsteps as f64;
        let t0 = self.world.time_s;
        self.set_plate_track((t0, bed_top - self.top_start, -dz / dt), true);
        self.stage = Stage::Compressing { q: 0, nsteps, dz };
    }

    /// Gives every contact the run's law (particle–particle and particle–wall); the contact
    /// histories are kept (the tangential springs are mapped onto the new Coulomb limit at the
    /// next force evaluation).
    fn use_law_of_run(&mut self) {
        let model = crate::bed::contact_model(&self.law);
        self.world
            .set_contact_model(PARTICLE_MATERIAL, PARTICLE_MATERIAL, model.clone());
        self.world
            .set_contact_model(PARTICLE_MATERIAL, WALL_MATERIAL, model);
    }

    fn start_holding(&mut self) {
        let t = self.world.time_s;
        self.set_plate_track((t, self.cavity.max[2] - self.top_start, 0.0), true);
        self.stage = Stage::Holding { q: 0 };
    }

    /// One step (or one change of stage); false once finished.
    fn advance(&mut self, progress: &mut dyn FnMut(&str, f64)) -> Result<bool, Box<HealthError>> {
        match self.stage {
            Stage::Settling { chunk } => {
                let t_end = self.settings.max_settling_time_s;
                if chunk == 0 && self.world.time_s >= t_end {
                    self.end_settling();
                    return Ok(true);
                }
                self.step()?;
                self.stage = Stage::Settling {
                    chunk: (chunk + 1) % SETTLE_CHUNK,
                };
                if chunk + 1 == SETTLE_CHUNK {
                    let ke = self.world.ledger.kinetic_j;
                    progress("settling", self.world.time_s / t_end);
                    let dt = self.world.dt_s;
                    if ke < self.e_ref && self.world.time_s > 10.0 * dt * SETTLE_CHUNK as f64 {
                        self.end_settling();
                    }
                }
            }
            Stage::Relaxing { done, moved } => {
                // A bed settled under g·f holds f² times the contact elastic energy of a bed at
                // rest under g (linear springs): when gravity drops to 1 g it springs up and
                // releases it. Relax at least `relax_time_s`, then until the bed has moved
                // (kinetic energy above the 1 g rest limit) and come to rest again (below it),
                // or until `max_settling_time_s` more. Otherwise the prepared bed carries the
                // excess into the coupled run, where its release looks like damping.
                let t_max = self.relax_steps
                    + (self.settings.max_settling_time_s / self.world.dt_s).ceil() as u64;
                let chunk = SETTLE_CHUNK as u64;
                if done >= t_max
                    || (done >= self.relax_steps && done % chunk == 0 && done > 0 && {
                        let ke = self.world.ledger.kinetic_j;
                        // a bed settled under 1 g has nothing to release: rest suffices
                        (moved || self.settings.settling_gravity_factor <= 1.0)
                            && ke < self.e_ref_1g
                    })
                {
                    self.start_compression();
                    return Ok(true);
                }
                self.step()?;
                let mut moved = moved;
                if (done + 1) % chunk == 0 {
                    let ke = self.world.ledger.kinetic_j;
                    moved |= ke >= self.e_ref_1g;
                    if (done + 1) % (50 * chunk) == 0 {
                        progress("relaxing under 1 g", (done + 1) as f64 / t_max as f64);
                    }
                }
                self.stage = Stage::Relaxing {
                    done: done + 1,
                    moved,
                };
            }
            Stage::Compressing { q, nsteps, dz } => {
                if q < nsteps {
                    self.step()?;
                    if q % 500 == 0 {
                        progress("compressing", q as f64 / nsteps as f64);
                    }
                    self.stage = Stage::Compressing {
                        q: q + 1,
                        nsteps,
                        dz,
                    };
                } else {
                    self.start_holding();
                }
            }
            Stage::Holding { q } => {
                if q < self.relax_steps {
                    self.step()?;
                    self.plate_force = self.world.body_load(PLATE).0.z;
                    if q % 500 == 0 {
                        progress("relaxing", q as f64 / self.relax_steps as f64);
                    }
                    self.stage = Stage::Holding { q: q + 1 };
                } else {
                    self.plate_force_held = self.plate_force;
                    self.stage = if self.settings.law_of_preparation(&self.law) != self.law {
                        self.use_law_of_run();
                        Stage::Handover {
                            done: 0,
                            force_mark: f64::NAN,
                        }
                    } else {
                        Stage::Done
                    };
                }
            }
            Stage::Handover { done, force_mark } => {
                // At least `relax_time_s`; then, every `relax_time_s`, done when the bed is at
                // rest under 1 g (the relaxation's criterion) or when the bed presses the plate
                // with more than its weight and that force has settled (changed by less than
                // 1e-3 of itself since the last check: a pre-stressed bed keeps a small creep,
                // whose kinetic energy stays above the rest limit), or after
                // `max_settling_time_s` more.
                let window = self.relax_steps.max(SETTLE_CHUNK as u64);
                let t_max = self.relax_steps
                    + (self.settings.max_settling_time_s / self.world.dt_s).ceil() as u64;
                let check = done >= self.relax_steps && done.is_multiple_of(window);
                let f = self.plate_force;
                let weight = self.world.particles.total_mass() * G0[2].abs();
                // (a plate without force says nothing: the bed may be falling away)
                let steady =
                    f.abs() > weight && (f - force_mark).abs() <= 1e-3 * f.abs().max(weight);
                let at_rest = self.world.ledger.kinetic_j < self.e_ref_1g;
                if (check && (steady || at_rest)) || done >= t_max {
                    self.handover_steps = done;
                    self.stage = Stage::Done;
                    return Ok(true);
                }
                let force_mark = if check { f } else { force_mark };
                self.step()?;
                self.plate_force = self.world.body_load(PLATE).0.z;
                if (done + 1) % (50 * SETTLE_CHUNK as u64) == 0 {
                    progress(
                        "handover to the run's law",
                        (done + 1) as f64 / t_max as f64,
                    );
                }
                self.stage = Stage::Handover {
                    done: done + 1,
                    force_mark,
                };
            }
            Stage::Done => return Ok(false),
        }
        Ok(true)
    }

    /// Runs the preparation to its end; `hook` is called after every step (with the state at
    /// a point where [`Preparation::snapshot`] can be taken) and stops the run at once when it
    /// returns `Break` (then the result is `Break`; calling `run` again continues). A failed
    /// health check (every 200 steps, [`Preparation::check_health`]) ends it with the error.
    pub fn run(
        &mut self,
        progress: &mut dyn FnMut(&str, f64),
        hook: &mut dyn FnMut(&Preparation) -> ControlFlow<()>,
    ) -> Result<ControlFlow<()>, Box<HealthError>> {
        self.segment_start = Some(Instant::now());
        while self.advance(progress)? {
            if hook(self).is_break() {
                return Ok(ControlFlow::Break(()));
            }
        }
        self.check_health()?;
        Ok(ControlFlow::Continue(()))
    }

    /// The prepared particles (at rest, with their contacts) and the report; call after
    /// [`Preparation::run`] returned `Continue`.
    pub fn finish(mut self) -> (PowderBed, PrepReport) {
        let wall_time_s = self.wall_time_s();
        let w = &mut self.world;
        w.particles
            .velocity
            .iter_mut()
            .for_each(|v| *v = Vec3::zeros());
        w.particles
            .angular_velocity
            .iter_mut()
            .for_each(|v| *v = Vec3::zeros());
        let volume: f64 = w
            .particles
            .radius
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
            .sum();
        let rep = PrepReport {
            particles: w.particles.len(),
            settled_packing_density: self.settled,
            packing_density: volume / self.cavity.volume(),
            compressed: self.compressed,
            plate_force_n: self.plate_force,
            max_relative_overlap: health::world_max_relative_overlap(w).0,
            simulated_time_s: w.time_s,
            steps: self.steps,
            wall_time_s,
            plate_force_before_handover_n: self.plate_force_held,
            handover_time_s: self.handover_steps as f64 * w.dt_s,
            top_gap_m: (self.cavity.max[2] - bed_top(&w.particles)).max(0.0),
        };
        let mut bed = PowderBed::at_rest(self.law, &[], &[], self.density_kg_m3, G0, w.dt_s);
        bed.world
            .adopt_particles(&w.save_state())
            .expect("a world's own state fits its particles");
        (bed, rep)
    }
}

/// Prepares the powder in `cavity` (gravity along −z during preparation, as in the paper);
/// fails with the health check's error ([`Preparation::check_health`]).
pub fn prepare(
    cavity: Aabb,
    psd: &LogNormal,
    law: PowderLaw,
    density_kg_m3: f64,
    dt: f64,
    s: &PrepSettings,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(PowderBed, PrepReport), Box<HealthError>> {
    let mut prep = Preparation::new(cavity, psd, law, density_kg_m3, dt, s);
    let _ = prep.run(progress, &mut |_| ControlFlow::Continue(()))?;
    Ok(prep.finish())
}
