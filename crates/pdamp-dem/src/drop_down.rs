//! Drop-down bed preparation [D Sect. 2.1, Fig. 2.2c/d, 2.14; Sect. 5.1.1, 6.1, 8.1.1]: the
//! particles are inserted at random, without overlap with each other or with any wall or inner
//! structure of the container, into the free part of the insertion region above the bed, and
//! fall under gravity; round after round until all are in, then the bed falls to rest. The
//! result is a random packing (packing fraction ≈ 0.58–0.64 for frictional spheres), not a
//! crystal: the start state that the dissertation's simulations "load from previously performed
//! drop-down simulations".
//!
//! A round inserts as many of the waiting particles as find a place in
//! `max_attempts_per_particle` uniform trials each (in order; the first that finds none ends the
//! round), in the slab of the region above the current bed top (highest particle top along
//! −g) and in the pockets of the bed's surface layer (down to two largest diameters below that
//! top). Then the world is stepped with the bodies held until the kinetic energy per particle
//! falls below the round threshold (after at least the free-fall time of the slab) or the round's
//! time limit is reached. A dense fill thus pours in like a real filling; a bed that fits the
//! region in one random insertion needs one round.
//!
//! Deterministic for a seed (`ChaCha8Rng::seed_from_u64`) and independent of the thread count
//! (the DEM is).

use crate::generate::{CellGrid, Region, orthonormal_frame};
use crate::math::Vec3;
use crate::{Motion, World};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::ops::ControlFlow;

/// Settings of a drop-down.
#[derive(Debug, Clone, PartialEq)]
pub struct DropDownSpec {
    /// Insertion region (usually the container's inner volume), m.
    pub region: Region,
    /// Random trial centres per particle and round.
    pub max_attempts_per_particle: usize,
    /// Seed of the insertion.
    pub seed: u64,
    /// A round's fall ends once the kinetic energy per particle is below this, J.
    pub kinetic_energy_per_particle_j: f64,
    /// Longest fall of one round, s.
    pub max_round_duration_s: f64,
    /// Most insertion rounds before the drop-down gives up.
    pub max_rounds: usize,
}

/// What a drop-down did.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct DropDownReport {
    /// Particles inserted in each round.
    pub inserted_per_round: Vec<usize>,
    /// Simulated time of all falls, s.
    pub simulated_time_s: f64,
    /// Time steps of all falls.
    pub steps: u64,
}

/// Errors of a drop-down.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DropDownError {
    /// A setting is out of range.
    #[error("drop-down: {0}")]
    Invalid(String),
    /// The container is full: no further particle finds a place.
    #[error(
        "drop-down placed only {placed} of {total} particles: after {rounds} round(s) particle \
         {next} (radius {radius_m:.4e} m) finds no free place above the bed in the insertion \
         region; enlarge the region or the container, or lower the particle count or radius"
    )]
    Full {
        /// Particles placed.
        placed: usize,
        /// Particles asked for.
        total: usize,
        /// Rounds run.
        rounds: usize,
        /// Index of the first particle that did not fit.
        next: usize,
        /// Its radius, m.
        radius_m: f64,
    },
    /// The simulation of a fall failed its health check.
    #[error("drop-down: {0}")]
    Health(String),
    /// The hook asked to stop.
    #[error("drop-down interrupted")]
    Interrupted,
}

/// Final state after a drop-down: the dropped particles in the order of `radii`, and the
/// particles that were in the world before (they settle further under the new ones).
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedParticles {
    /// Final centres of the particles that were in the world before, in its order, m.
    pub earlier_position_m: Vec<Vec3>,
    /// Their final velocities, m/s.
    pub earlier_velocity_m_s: Vec<Vec3>,
    /// Their final angular velocities, rad/s.
    pub earlier_angular_velocity_rad_s: Vec<Vec3>,
    /// Centres, m.
    pub position_m: Vec<Vec3>,
    /// Velocities, m/s.
    pub velocity_m_s: Vec<Vec3>,
    /// Angular velocities, rad/s.
    pub angular_velocity_rad_s: Vec<Vec3>,
    /// What the drop-down did.
    pub report: DropDownReport,
}

impl DropDownSpec {
    fn validate(&self) -> Result<(), DropDownError> {
        let bad = |m: String| Err(DropDownError::Invalid(m));
        self.region
            .validate()
            .map_err(|m| DropDownError::Invalid(format!("region: {m}")))?;
        if self.max_attempts_per_particle == 0 {
            return bad("max_attempts_per_particle must be > 0".into());
        }
        if !(self.kinetic_energy_per_particle_j.is_finite()
            && self.kinetic_energy_per_particle_j >= 0.0)
        {
            return bad(format!(
                "kinetic_energy_per_particle_j must be finite and >= 0, got {}",
                self.kinetic_energy_per_particle_j
            ));
        }
        if !(self.max_round_duration_s.is_finite() && self.max_round_duration_s > 0.0) {
            return bad(format!(
                "max_round_duration_s must be finite and > 0, got {}",
                self.max_round_duration_s
            ));
        }
        if self.max_rounds == 0 {
            return bad("max_rounds must be > 0".into());
        }
        Ok(())
    }
}

/// Drops particles of `radii` (material `material`) into a copy of `world` (its bodies, walls
/// and particles already placed; gravity as set in it) as the module docs describe and returns
/// their final state; `world` itself is not changed. `hook(world, placed)` is called every 200
/// steps of a fall and may stop the drop-down.
pub fn drop_down(
    world: &World,
    radii: &[f64],
    material: u16,
    spec: &DropDownSpec,
    mut hook: impl FnMut(&World, usize) -> ControlFlow<()>,
) -> Result<DroppedParticles, DropDownError> {
    spec.validate()?;
    if let Some((i, r)) = radii
        .iter()
        .enumerate()
        .find(|(_, r)| !(r.is_finite() && **r > 0.0))
    {
        return Err(DropDownError::Invalid(format!(
            "radius of particle {i} must be finite and > 0, got {r}"
        )));
    }
    let g = world.gravity_m_s2;
    let Some((e1, e2, up)) = orthonormal_frame(&(-g)) else {
        return Err(DropDownError::Invalid(
            "needs gravity (the particles fall into place): set simulation.gravity_m_s2 or \
             settle.gravity_m_s2"
                .into(),
        ));
    };
    let mut w = world.clone();
    for b in &mut w.bodies {
        b.motion = Motion::Fixed;
    }
    let first = w.particles.len();
    let ext = [
        spec.region.extent_along(&e1),
        spec.region.extent_along(&e2),
        spec.region.extent_along(&up),
    ];
    let r_max = radii
        .iter()
        .chain(&w.particles.radius)
        .fold(0.0f64, |a, &b| a.max(b));
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut report = DropDownReport::default();
    let mut next = 0usize;
    let mut scratch = Vec::new();
    let mut empty_rounds = 0;
    let n_total = radii.len();
    while next < n_total {
        if report.inserted_per_round.len() >= spec.max_rounds || empty_rounds >= 2 {
            return Err(DropDownError::Full {
                placed: next,
                total: n_total,
                rounds: report.inserted_per_round.len(),
                next,
                radius_m: radii[next],
            });
        }
        // The bed top and a grid of every particle there is.
        let p = &w.particles;
        let bed_top = (0..p.len())
            .map(|i| p.position[i].dot(&up) + p.radius[i])
            .fold(f64::NEG_INFINITY, f64::max);
        let (mut lo, mut hi) = spec.region.bounding_box();
        for x in &p.position {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        let mut pos: Vec<Vec3> = p.position.clone();
        let mut rad: Vec<f64> = p.radius.clone();
        let mut grid = CellGrid::new(lo, hi, 2.0 * r_max, pos.len() + n_total - next);
        for (k, x) in pos.iter().enumerate() {
            grid.insert(k as u32, x);
        }
        let mut inserted = 0usize;
        while next < n_total {
            let r = radii[next];
            // Above the bed and in the pockets of its surface layer (two diameters below the
            // highest top), so that a bed can be poured up to about one radius under a lid.
            let z_lo = (ext[2].0 + r).max(bed_top - 4.0 * r_max + r);
            let z_hi = ext[2].1 - r;
            let (x_lo, x_hi) = (ext[0].0 + r, ext[0].1 - r);
            let (y_lo, y_hi) = (ext[1].0 + r, ext[1].1 - r);
            let mut found = None;
            if z_lo <= z_hi && x_lo <= x_hi && y_lo <= y_hi {
                for _ in 0..spec.max_attempts_per_particle {
                    let (u, v, s): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
                    let x = e1 * (x_lo + (x_hi - x_lo) * u)
                        + e2 * (y_lo + (y_hi - y_lo) * v)
                        + up * (z_lo + (z_hi - z_lo) * s);
                    if spec.region.contains_sphere(&x, r)
                        && !grid.overlaps(&x, r, &pos, &rad)
                        && w.wall_overlap(&x, r, &mut scratch).is_none()
                    {
                        found = Some(x);
                        break;
                    }
                }
            }
            let Some(x) = found else { break };
            grid.insert(pos.len() as u32, &x);
            pos.push(x);
            rad.push(r);
            w.add_particle(x, r, material);
            next += 1;
            inserted += 1;
        }
        report.inserted_per_round.push(inserted);
        empty_rounds = if inserted == 0 { empty_rounds + 1 } else { 0 };
        // Fall: at least the free-fall time of the slab, then until the bed is calm.
        let height = (ext[2].1 - bed_top.max(ext[2].0)).max(0.0);
        let t_fall = (2.0 * height / g.norm()).sqrt();
        let t0 = w.time_s;
        let n = w.particles.len().max(1) as f64;
        let mut steps_in_round = 0u64;
        loop {
            w.step();
            steps_in_round += 1;
            let t = w.time_s - t0;
            if steps_in_round.is_multiple_of(200) {
                w.check_health()
                    .map_err(|e| DropDownError::Health(e.to_string()))?;
                if hook(&w, next).is_break() {
                    return Err(DropDownError::Interrupted);
                }
            }
            if t >= spec.max_round_duration_s
                || (t >= t_fall && w.ledger.kinetic_j / n < spec.kinetic_energy_per_particle_j)
            {
                break;
            }
        }
        report.steps += steps_in_round;
        report.simulated_time_s += w.time_s - t0;
    }
    let p = &w.particles;
    Ok(DroppedParticles {
        earlier_position_m: p.position[..first].to_vec(),
        earlier_velocity_m_s: p.velocity[..first].to_vec(),
        earlier_angular_velocity_rad_s: p.angular_velocity[..first].to_vec(),
        position_m: p.position[first..].to_vec(),
        velocity_m_s: p.velocity[first..].to_vec(),
        angular_velocity_rad_s: p.angular_velocity[first..].to_vec(),
        report,
    })
}

impl World {
    /// The first wall that a sphere (centre `x`, radius `r`, world frame; bodies at their current
    /// poses) would start inside or across: `(body, wall, overlap_m)`, with `f64::INFINITY` for
    /// a centre behind a closed mesh; `None` when the sphere is clear of every wall (touching
    /// allowed to 1e-9 r). See [`crate::Geometry::sphere_overlap`].
    pub fn wall_overlap(
        &self,
        x: &Vec3,
        r: f64,
        scratch: &mut Vec<crate::walls::WallContact>,
    ) -> Option<(usize, usize, f64)> {
        for (bi, b) in self.bodies.iter().enumerate() {
            let xb = b.state.to_body(x);
            for (wi, wall) in b.walls.iter().enumerate() {
                if let Some(o) = wall.geometry.sphere_overlap(&xb, r, 1e-9 * r, scratch) {
                    return Some((bi, wi, o));
                }
            }
        }
        None
    }
}
