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
//! **Pouring from an inlet** ([`Inlet`], D Fig. 2.2c's "inlet" insertion): instead of rounds,
//! the particles enter through an inlet region at a given rate while the world runs, and pile
//! up below it.
//!
//! **Filling with the lid open** ([`OpenLid`]; D L3085 "particles are filled into the container
//! from its top and the container's top cover plate is secured", L3093 "particles are poured up
//! to a marking … then the container cap is adjusted"): a container whose clearance to the lid is
//! less than a diameter cannot be filled through closed walls, because a sphere can only be
//! inserted where it fits whole. The drop-down then extends the container walls that end at the
//! region's top (the top face of a `box_inside` or `cylinder_inside`, a plane facing down) by
//! `headroom_m`, pours into the taller container under a temporary lid plane, and closes that
//! lid down to the real top: at once where the bed stays below it, else at `close_speed_m_s`,
//! pushing with at most the weight of the bed and, where set, while the container is tapped
//! along −g ([`Tapping`]) so that the spheres sticking out find the pockets below them; the last
//! 1 % of the smallest radius (the contacts' elastic give) it is pressed home. A bed
//! that still stands above the lid after `max_close_duration_s` is refused, naming the highest
//! particle.
//!
//! Deterministic for a seed (`ChaCha8Rng::seed_from_u64`) and independent of the thread count
//! (the DEM is).

use crate::generate::{CellGrid, Region, orthonormal_frame};
use crate::math::Vec3;
use crate::{Motion, World};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::ops::ControlFlow;

mod lid;
use lid::{close_lid, open_container};

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
    /// Fill with the lid open and close it afterwards (see the module docs); `None`: fill
    /// through the closed container.
    pub open_lid: Option<OpenLid>,
    /// Pour from an inlet over time instead of inserting in rounds (see [`Inlet`]).
    pub inlet: Option<Inlet>,
}

/// Pouring from an inlet (a funnel, a filling tube): the particles are inserted at random into
/// the inlet region at `rate_per_s` with the velocity `velocity_m_s` while the world runs, and
/// pile up below it, like a real filling; a particle that finds no free place in the inlet
/// waits for the next insertion. When the pile has reached the inlet and nothing has gone in
/// for 0.1 s (at least ten insertion intervals), the pour stops with [`DropDownError::InletBlocked`].
#[derive(Debug, Clone, PartialEq)]
pub struct Inlet {
    /// The inlet region (inside the container, above the bed), m.
    pub region: Region,
    /// Particles inserted per second of simulated time.
    pub rate_per_s: f64,
    /// Velocity of the inserted particles, m/s.
    pub velocity_m_s: Vec3,
}

/// Filling with the lid open, then closing it (D L3085, L3093; module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct OpenLid {
    /// How far the walls that end at the region's top are extended while the particles pour
    /// in, m.
    pub headroom_m: f64,
    /// Speed at which the lid closes onto a bed that stands above the real top, m/s.
    pub close_speed_m_s: f64,
    /// Longest closing before the drop-down gives up, s.
    pub max_close_duration_s: f64,
    /// Tapping of the container while the lid closes onto a bed that stands above it.
    pub tapping: Option<Tapping>,
}

/// Harmonic tapping of the container along −g while the lid closes: the spheres that stand
/// above the lid are lifted a little every cycle and find the pockets below them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tapping {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Acceleration amplitude over g, Γ = A/g.
    pub intensity: f64,
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
    /// Filling with the lid open: how far the highest particle top stood above the real top
    /// of the container after pouring, m (negative: below it; `None` without an open lid).
    #[serde(default)]
    pub bed_top_above_lid_m: Option<f64>,
    /// Filling with the lid open: simulated time of closing the lid (incl. tapping), s.
    #[serde(default)]
    pub lid_closing_time_s: f64,
    /// Pouring from an inlet: simulated time until the last particle was inserted, s.
    #[serde(default)]
    pub inlet_pour_time_s: f64,
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
    /// The lid could not be closed: the bed stands above the container's top.
    #[error(
        "drop-down with the lid open: after closing for {duration_s:.3} s the lid is still \
         {above_m:.4e} m above the container's top, held up by particle {particle}; raise the \
         container's top, lower the particle count, or tap while closing (open_lid.tap_intensity)"
    )]
    LidNotClosed {
        /// How far the lid stayed above the real top, m.
        above_m: f64,
        /// The particle with the highest top (index among all particles of the world).
        particle: usize,
        /// Simulated closing time, s.
        duration_s: f64,
    },
    /// The pile under the inlet has reached it: no particle went in for a while.
    #[error(
        "drop-down from the inlet placed only {placed} of {total} particles: nothing found a \
         free place in the inlet region for {blocked_s:.3} s (at t = {time_s:.3} s), so the pile \
         has reached the inlet; raise the inlet, enlarge the container, or lower the count"
    )]
    InletBlocked {
        /// Particles placed.
        placed: usize,
        /// Particles asked for.
        total: usize,
        /// How long nothing went in, s.
        blocked_s: f64,
        /// Simulated time of the pour, s.
        time_s: f64,
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
        if let Some(l) = &self.open_lid {
            let positive = |v: f64| v.is_finite() && v > 0.0;
            if !positive(l.headroom_m) {
                return bad(format!(
                    "open_lid.headroom_m must be finite and > 0, got {}",
                    l.headroom_m
                ));
            }
            if !positive(l.close_speed_m_s) {
                return bad(format!(
                    "open_lid.close_speed_m_s must be finite and > 0, got {}",
                    l.close_speed_m_s
                ));
            }
            if !positive(l.max_close_duration_s) {
                return bad(format!(
                    "open_lid.max_close_duration_s must be finite and > 0, got {}",
                    l.max_close_duration_s
                ));
            }
            if let Some(t) = &l.tapping
                && !(positive(t.frequency_hz) && positive(t.intensity))
            {
                return bad(format!(
                    "open_lid tapping: frequency {} Hz and intensity {} must be finite and > 0",
                    t.frequency_hz, t.intensity
                ));
            }
        }
        if let Some(i) = &self.inlet {
            i.region
                .validate()
                .map_err(|m| DropDownError::Invalid(format!("inlet.region: {m}")))?;
            if !(i.rate_per_s.is_finite() && i.rate_per_s > 0.0) {
                return bad(format!(
                    "inlet.rate_per_s must be finite and > 0, got {}",
                    i.rate_per_s
                ));
            }
            if !i.velocity_m_s.iter().all(|v| v.is_finite()) {
                return bad("inlet.velocity_m_s must be finite".into());
            }
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
    let r_max = radii
        .iter()
        .chain(&w.particles.radius)
        .fold(0.0f64, |a, &b| a.max(b));
    let r_min = radii
        .iter()
        .chain(&w.particles.radius)
        .fold(f64::INFINITY, |a, &b| a.min(b));
    // With the lid open: the walls ending at the region's top extended, a temporary lid above.
    let open = match &spec.open_lid {
        Some(l) => Some(open_container(
            &mut w,
            &spec.region,
            &up,
            l.headroom_m,
            1e-3 * r_min,
        )?),
        None => None,
    };
    let region = open.as_ref().map_or(&spec.region, |o| &o.fill_region);
    let ext = [
        region.extent_along(&e1),
        region.extent_along(&e2),
        region.extent_along(&up),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut report = DropDownReport::default();
    let mut next = 0usize;
    let mut scratch = Vec::new();
    let mut empty_rounds = 0;
    let n_total = radii.len();
    if let Some(inlet) = &spec.inlet {
        pour_from_inlet(
            &mut w,
            radii,
            material,
            inlet,
            spec,
            &mut rng,
            &mut report,
            &mut hook,
            r_max,
        )?;
        next = n_total;
    }
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
        let (inserted, bed_top) = insert_round(
            &mut w,
            region,
            &ext,
            (e1, e2, up),
            radii,
            &mut next,
            material,
            r_max,
            spec.max_attempts_per_particle,
            &mut rng,
            &mut scratch,
        );
        report.inserted_per_round.push(inserted);
        empty_rounds = if inserted == 0 { empty_rounds + 1 } else { 0 };
        // Fall: at least the free-fall time of the slab, then until the bed is calm.
        let height = (ext[2].1 - bed_top.max(ext[2].0)).max(0.0);
        let t_fall = (2.0 * height / g.norm()).sqrt();
        let t0 = w.time_s;
        report.steps += fall_round(&mut w, spec, t_fall, next, &mut hook)?;
        report.simulated_time_s += w.time_s - t0;
    }
    if let (Some(o), Some(l)) = (&open, &spec.open_lid) {
        close_lid(&mut w, o, l, &up, spec, &mut report, &mut hook, next)?;
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
/// One round of insertion: particles `next..` are put, as many as fit, at random above the bed
/// top and in the pockets of its surface layer (two diameters below the highest top), clear of
/// every particle and wall. Returns how many were placed and the bed top before the round.
#[allow(clippy::too_many_arguments)]
fn insert_round(
    w: &mut World,
    region: &Region,
    ext: &[(f64, f64); 3],
    (e1, e2, up): (Vec3, Vec3, Vec3),
    radii: &[f64],
    next: &mut usize,
    material: u16,
    r_max: f64,
    max_attempts: usize,
    rng: &mut ChaCha8Rng,
    scratch: &mut Vec<crate::walls::WallContact>,
) -> (usize, f64) {
    // The bed top and a grid of every particle there is.
    let p = &w.particles;
    let bed_top = (0..p.len())
        .map(|i| p.position[i].dot(&up) + p.radius[i])
        .fold(f64::NEG_INFINITY, f64::max);
    let (mut lo, mut hi) = region.bounding_box();
    for x in &p.position {
        lo = lo.inf(x);
        hi = hi.sup(x);
    }
    let mut pos: Vec<Vec3> = p.position.clone();
    let mut rad: Vec<f64> = p.radius.clone();
    let mut grid = CellGrid::new(lo, hi, 2.0 * r_max, pos.len() + radii.len() - *next);
    for (k, x) in pos.iter().enumerate() {
        grid.insert(k as u32, x);
    }
    let mut inserted = 0usize;
    while *next < radii.len() {
        let r = radii[*next];
        // Above the bed and in the pockets of its surface layer (two diameters below the
        // highest top), so that a bed can be poured up to about one radius under a lid.
        let z_lo = (ext[2].0 + r).max(bed_top - 4.0 * r_max + r);
        let z_hi = ext[2].1 - r;
        let (x_lo, x_hi) = (ext[0].0 + r, ext[0].1 - r);
        let (y_lo, y_hi) = (ext[1].0 + r, ext[1].1 - r);
        let mut found = None;
        if z_lo <= z_hi && x_lo <= x_hi && y_lo <= y_hi {
            for _ in 0..max_attempts {
                let (u, v, s): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
                let x = e1 * (x_lo + (x_hi - x_lo) * u)
                    + e2 * (y_lo + (y_hi - y_lo) * v)
                    + up * (z_lo + (z_hi - z_lo) * s);
                if region.contains_sphere(&x, r)
                    && !grid.overlaps(&x, r, &pos, &rad)
                    && w.wall_overlap(&x, r, scratch).is_none()
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
        *next += 1;
        inserted += 1;
    }
    (inserted, bed_top)
}

/// The fall of a round: at least the free-fall time `t_fall` of the slab, then until the bed is
/// calm (kinetic energy per particle below the spec's) or the round's longest duration; the
/// health check and `hook` every 200 steps. Returns the steps.
fn fall_round(
    w: &mut World,
    spec: &DropDownSpec,
    t_fall: f64,
    placed: usize,
    hook: &mut impl FnMut(&World, usize) -> ControlFlow<()>,
) -> Result<u64, DropDownError> {
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
            if hook(w, placed).is_break() {
                return Err(DropDownError::Interrupted);
            }
        }
        if t >= spec.max_round_duration_s
            || (t >= t_fall && w.ledger.kinetic_j / n < spec.kinetic_energy_per_particle_j)
        {
            return Ok(steps_in_round);
        }
    }
}

/// Pours `radii` from the inlet ([`Inlet`]) into `w` while it runs, then lets the pile fall
/// calm (at least the free-fall time from the inlet's top to its lowest particle).
#[allow(clippy::too_many_arguments)]
fn pour_from_inlet(
    w: &mut World,
    radii: &[f64],
    material: u16,
    inlet: &Inlet,
    spec: &DropDownSpec,
    rng: &mut ChaCha8Rng,
    report: &mut DropDownReport,
    hook: &mut impl FnMut(&World, usize) -> ControlFlow<()>,
    r_max: f64,
) -> Result<(), DropDownError> {
    let n_total = radii.len();
    let t0 = w.time_s;
    let dt = w.dt_s;
    // Insert in batches: every 1/rate, but not more often than every 20 steps.
    let interval_steps = ((1.0 / (inlet.rate_per_s * dt)).round() as u64).max(20);
    let blocked_limit_s = (10.0 * interval_steps as f64 * dt).max(0.1);
    let (ilo, ihi) = inlet.region.bounding_box();
    let reach = Vec3::repeat(2.0 * r_max);
    let (glo, ghi) = (ilo - reach, ihi + reach);
    let mut next = 0usize;
    let mut last_insert_s = t0;
    let mut steps = 0u64;
    let mut scratch = Vec::new();
    while next < n_total {
        if steps.is_multiple_of(interval_steps) {
            let due = ((inlet.rate_per_s * (w.time_s - t0 + dt)).ceil() as usize).min(n_total);
            if due > next {
                // The particles near the inlet, in a grid.
                let p = &w.particles;
                let near: Vec<usize> = (0..p.len())
                    .filter(|&i| {
                        let x = &p.position[i];
                        (0..3).all(|k| x[k] >= glo[k] && x[k] <= ghi[k])
                    })
                    .collect();
                let mut pos: Vec<Vec3> = near.iter().map(|&i| p.position[i]).collect();
                let mut rad: Vec<f64> = near.iter().map(|&i| p.radius[i]).collect();
                let mut grid = CellGrid::new(glo, ghi, 2.0 * r_max, pos.len() + due - next);
                for (k, x) in pos.iter().enumerate() {
                    grid.insert(k as u32, x);
                }
                while next < due {
                    let r = radii[next];
                    let mut found = None;
                    for _ in 0..spec.max_attempts_per_particle {
                        let Some(x) = inlet.region.sample_center(r, rng) else {
                            break;
                        };
                        if !grid.overlaps(&x, r, &pos, &rad)
                            && w.wall_overlap(&x, r, &mut scratch).is_none()
                        {
                            found = Some(x);
                            break;
                        }
                    }
                    let Some(x) = found else { break };
                    grid.insert(pos.len() as u32, &x);
                    pos.push(x);
                    rad.push(r);
                    let id = w.add_particle(x, r, material);
                    w.particles.velocity[id] = inlet.velocity_m_s;
                    next += 1;
                    last_insert_s = w.time_s;
                }
                if next < due && w.time_s - last_insert_s > blocked_limit_s {
                    return Err(DropDownError::InletBlocked {
                        placed: next,
                        total: n_total,
                        blocked_s: w.time_s - last_insert_s,
                        time_s: w.time_s - t0,
                    });
                }
            }
        }
        w.step();
        steps += 1;
        if steps.is_multiple_of(200) {
            w.check_health()
                .map_err(|e| DropDownError::Health(e.to_string()))?;
            if hook(w, next).is_break() {
                return Err(DropDownError::Interrupted);
            }
        }
    }
    report.inserted_per_round.push(n_total);
    report.inlet_pour_time_s = w.time_s - t0;
    // The last particles fall from the inlet onto the pile, then the pile falls calm.
    let g = w.gravity_m_s2.norm();
    let up = -w.gravity_m_s2 / g;
    let p = &w.particles;
    let bottom = (0..p.len())
        .map(|i| p.position[i].dot(&up))
        .fold(f64::INFINITY, f64::min);
    let height = (inlet.region.extent_along(&up).1 - bottom).max(0.0);
    let t_fall = (2.0 * height / g).sqrt();
    let t_calm = w.time_s;
    let n = w.particles.len().max(1) as f64;
    loop {
        w.step();
        steps += 1;
        if steps.is_multiple_of(200) {
            w.check_health()
                .map_err(|e| DropDownError::Health(e.to_string()))?;
            if hook(w, next).is_break() {
                return Err(DropDownError::Interrupted);
            }
        }
        let t = w.time_s - t_calm;
        if t >= spec.max_round_duration_s
            || (t >= t_fall && w.ledger.kinetic_j / n < spec.kinetic_energy_per_particle_j)
        {
            break;
        }
    }
    report.steps += steps;
    report.simulated_time_s += w.time_s - t0;
    Ok(())
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
