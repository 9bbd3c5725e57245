//! Powder preparation (paper Sect. 2.4, Fig. 1a): particles drawn from the size distribution
//! until their volume equals ϕ·V_cavity, placed on a Cartesian grid above the cavity floor,
//! settled under gravity, then compressed by a displacement-controlled plate down to the cavity
//! height, so that the packing density (particle volume / cavity volume) is the prescribed ϕ;
//! finally relaxed with the plate held. The particles are prepared directly in the cavity's
//! coordinates, so "extraction and insertion" is removing the box walls and the plate.
//!
//! [`Preparation`] holds the whole state of a preparation in progress (particles, walls, wall
//! spring history, stage and step counters) and is serializable, so a long preparation can be
//! checkpointed and continued bit for bit; [`prepare`] runs one from start to end.

use std::ops::ControlFlow;
use std::time::Instant;

use crate::dem::wall::{self, EMPTY_SLOTS, WallSlots};
use crate::dem::{LogNormal, PlaneWall, Powder, PowderLaw, Rng};
use crate::fe::Aabb;
use crate::health::{self, HealthError};

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
    /// Finished.
    Done,
}

/// A powder preparation in progress (see the module docs). Serializable: a preparation saved
/// with [`Preparation::snapshot`] and continued with [`Preparation::run`] ends bit for bit as
/// an uninterrupted one.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct Preparation {
    powder: Powder,
    planes: Vec<PlaneWall>,
    hist: Vec<WallSlots>,
    on_wall: [[f64; 3]; 6],
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
    wall_time_s: f64,
    #[serde(skip)]
    segment_start: Option<Instant>,
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
        let mut rng = Rng::new(s.seed);
        let vcav = cavity.volume();
        let diam = psd.fill_volume(s.packing_density * vcav, &mut rng);
        let spacing = psd.d_max_m * 1.02;
        let (lx, ly) = (cavity.max[0] - cavity.min[0], cavity.max[1] - cavity.min[1]);
        let nx = ((lx / spacing).floor() as usize).max(1);
        let ny = ((ly / spacing).floor() as usize).max(1);
        let ox = cavity.min[0] + 0.5 * (lx - (nx as f64 - 1.0) * spacing);
        let oy = cavity.min[1] + 0.5 * (ly - (ny as f64 - 1.0) * spacing);
        let mut pos = Vec::with_capacity(diam.len());
        for (q, _) in diam.iter().enumerate() {
            let layer = q / (nx * ny);
            let rem = q % (nx * ny);
            let (i, j) = (rem % nx, rem / nx);
            let jit = 0.005 * spacing;
            pos.push([
                ox + i as f64 * spacing + jit * (rng.uniform() - 0.5),
                oy + j as f64 * spacing + jit * (rng.uniform() - 0.5),
                cavity.min[2] + 0.5 * spacing + layer as f64 * spacing,
            ]);
        }
        let radius: Vec<f64> = diam.iter().map(|d| 0.5 * d).collect();
        let p = Powder::new(
            law,
            pos,
            radius,
            density_kg_m3,
            [0.0, 0.0, -9.81 * s.settling_gravity_factor],
            dt,
        );
        let n = p.len();
        let top_start = p
            .pos
            .iter()
            .zip(&p.radius)
            .map(|(x, r)| x[2] + r)
            .fold(cavity.max[2], f64::max)
            + spacing;
        let plane = |point: [f64; 3], normal: [f64; 3]| PlaneWall {
            point,
            normal,
            velocity: [0.0; 3],
        };
        let planes = vec![
            plane(cavity.min, [1.0, 0.0, 0.0]),
            plane(cavity.max, [-1.0, 0.0, 0.0]),
            plane(cavity.min, [0.0, 1.0, 0.0]),
            plane(cavity.max, [0.0, -1.0, 0.0]),
            plane(cavity.min, [0.0, 0.0, 1.0]),
            plane([cavity.min[0], cavity.min[1], top_start], [0.0, 0.0, -1.0]),
        ];
        let mtot: f64 = p.mass.iter().sum();
        // settling: until the mean kinetic energy per particle is below 1e-4 of m g_eff d50
        let e_ref = 1e-4 * mtot * 9.81 * s.settling_gravity_factor * psd.d50_m;
        let e_ref_1g = 1e-4 * mtot * 9.81 * psd.d50_m;
        Self {
            powder: p,
            planes,
            hist: vec![EMPTY_SLOTS; n],
            on_wall: [[0.0; 3]; 6],
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
            wall_time_s: 0.0,
            segment_start: None,
        }
    }

    /// Number of particles.
    pub fn particles(&self) -> usize {
        self.powder.len()
    }

    /// Simulated preparation time so far \[s\].
    pub fn time_s(&self) -> f64 {
        self.powder.t
    }

    /// Checks that a deserialized preparation is self-consistent (array lengths, finite and
    /// positive time step and cavity, finite walls and reference energies).
    pub fn check_consistency(&self) -> Result<(), String> {
        self.powder.check_consistency()?;
        if self.hist.len() != self.powder.len() || self.planes.len() != 6 {
            return Err("preparation state: wall history does not match the particles".into());
        }
        let c = &self.cavity;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let ok = self.powder.dt > 0.0
            && self.powder.dt.is_finite()
            && finite(&c.min)
            && finite(&c.max)
            && (0..3).all(|k| c.min[k] < c.max[k])
            && self
                .planes
                .iter()
                .all(|w| finite(&w.point) && finite(&w.normal) && finite(&w.velocity))
            && finite(&[self.e_ref, self.e_ref_1g, self.bed_top, self.settled]);
        if !ok {
            return Err(
                "preparation state: time step, cavity, walls or reference energies not finite"
                    .into(),
            );
        }
        Ok(())
    }

    /// Name of the current stage (for messages).
    fn stage_name(&self) -> &'static str {
        match self.stage {
            Stage::Settling { .. } => "preparation: settling",
            Stage::Relaxing { .. } => "preparation: relaxing under 1 g",
            Stage::Compressing { .. } => "preparation: plate compression",
            Stage::Holding { .. } => "preparation: relaxing with the plate held",
            Stage::Done => "preparation: done",
        }
    }

    /// Health of the bed (see [`crate::health`]): finite states, particle centres inside the
    /// box walls and below the plate, no runaway overlap, no negative dissipation beyond a
    /// tenth of the bed's potential-energy scale M·g·H.
    pub fn check_health(&self) -> Result<(), Box<HealthError>> {
        let p = &self.powder;
        let fail = |s| Box::new(HealthError::new(p.t, self.stage_name(), s, p));
        let c = self.cavity;
        let top = self.planes[5].point[2].max(c.max[2]);
        let bx = Aabb {
            min: c.min,
            max: [c.max[0], c.max[1], top],
        };
        let size = (0..3).map(|k| bx.max[k] - bx.min[k]).fold(0.0, f64::max);
        health::check_particles(p, Some((&bx, 1e-9 * size))).map_err(|(_, s)| fail(s))?;
        health::check_overlaps(p).map_err(fail)?;
        let g = (0..3)
            .map(|k| p.gravity[k] * p.gravity[k])
            .sum::<f64>()
            .sqrt()
            .max(9.81);
        let scale = p.mass.iter().sum::<f64>() * g * size;
        let diss = p.ledger.dissipated_pp_j + p.ledger.dissipated_pw_j;
        health::check_energy(diss, 0.0, scale).map_err(fail)?;
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
        let p = &mut self.powder;
        p.predict();
        p.pair_forces();
        wall::plane_forces(p, &self.planes, &mut self.hist, &mut self.on_wall);
        p.finish();
        self.steps += 1;
        if self.steps.is_multiple_of(SETTLE_CHUNK as u64) {
            self.check_health()?;
        }
        Ok(())
    }

    fn end_settling(&mut self) {
        // switch to real gravity and let the bed relax briefly
        self.powder.gravity = G0;
        self.stage = Stage::Relaxing {
            done: 0,
            moved: false,
        };
    }

    fn start_compression(&mut self) {
        let (p, cavity, s) = (&self.powder, self.cavity, self.settings);
        let bed_top = p
            .pos
            .iter()
            .zip(&p.radius)
            .map(|(x, r)| x[2] + r)
            .fold(f64::NEG_INFINITY, f64::max);
        let area = (cavity.max[0] - cavity.min[0]) * (cavity.max[1] - cavity.min[1]);
        self.settled = p.volume() / (area * (bed_top - cavity.min[2]));
        self.compressed = bed_top > cavity.max[2];
        self.bed_top = bed_top;
        let dt = p.dt;
        if !self.compressed {
            self.start_holding();
            return;
        }
        // compression: plate from just above the bed down to the cavity top
        let dist = bed_top - cavity.max[2];
        let nsteps = (dist / (s.plate_speed_m_s * dt)).ceil() as u64;
        let dz = dist / nsteps as f64;
        self.planes[5].point[2] = bed_top;
        self.planes[5].velocity = [0.0, 0.0, -dz / dt];
        self.stage = Stage::Compressing { q: 0, nsteps, dz };
    }

    fn start_holding(&mut self) {
        self.planes[5].point[2] = self.cavity.max[2];
        self.planes[5].velocity = [0.0; 3];
        self.stage = Stage::Holding { q: 0 };
    }

    /// One step (or one change of stage); false once finished.
    fn advance(&mut self, progress: &mut dyn FnMut(&str, f64)) -> Result<bool, Box<HealthError>> {
        match self.stage {
            Stage::Settling { chunk } => {
                let t_end = self.settings.max_settling_time_s;
                if chunk == 0 && self.powder.t >= t_end {
                    self.end_settling();
                    return Ok(true);
                }
                self.step()?;
                self.stage = Stage::Settling {
                    chunk: (chunk + 1) % SETTLE_CHUNK,
                };
                if chunk + 1 == SETTLE_CHUNK {
                    let ke = self.powder.kinetic_energy();
                    progress("settling", self.powder.t / t_end);
                    let dt = self.powder.dt;
                    if ke < self.e_ref && self.powder.t > 10.0 * dt * SETTLE_CHUNK as f64 {
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
                    + (self.settings.max_settling_time_s / self.powder.dt).ceil() as u64;
                let chunk = SETTLE_CHUNK as u64;
                if done >= t_max
                    || (done >= self.relax_steps && done % chunk == 0 && done > 0 && {
                        let ke = self.powder.kinetic_energy();
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
                    let ke = self.powder.kinetic_energy();
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
                    self.planes[5].point[2] = self.bed_top - dz * (q + 1) as f64;
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
                    self.plate_force = self.on_wall[5][2];
                    if q % 500 == 0 {
                        progress("relaxing", q as f64 / self.relax_steps as f64);
                    }
                    self.stage = Stage::Holding { q: q + 1 };
                } else {
                    self.stage = Stage::Done;
                }
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

    /// The prepared powder (at rest, clock and ledger reset) and the report; call after
    /// [`Preparation::run`] returned `Continue`.
    pub fn finish(mut self) -> (Powder, PrepReport) {
        let wall_time_s = self.wall_time_s();
        let p = &mut self.powder;
        for v in p.vel.iter_mut() {
            *v = [0.0; 3];
        }
        for w in p.omega.iter_mut() {
            *w = [0.0; 3];
        }
        for w in p.wall_force.iter_mut() {
            *w = [0.0; 3];
        }
        let rep = PrepReport {
            particles: p.len(),
            settled_packing_density: self.settled,
            packing_density: p.volume() / self.cavity.volume(),
            compressed: self.compressed,
            plate_force_n: self.plate_force,
            max_relative_overlap: p.max_relative_overlap(),
            simulated_time_s: p.t,
            steps: self.steps,
            wall_time_s,
        };
        p.t = 0.0;
        p.ledger = Default::default();
        (self.powder, rep)
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
) -> Result<(Powder, PrepReport), Box<HealthError>> {
    let mut prep = Preparation::new(cavity, psd, law, density_kg_m3, dt, s);
    let _ = prep.run(progress, &mut |_| ControlFlow::Continue(()))?;
    Ok(prep.finish())
}
