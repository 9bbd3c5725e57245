//! Snapshot of everything in a [`World`] that changes while it runs, for checkpoints: restoring
//! a snapshot into a world built from the same scenario continues the run bit for bit (same
//! neighbour list, contact history, integrator history and ledger), so a resumed run ends with
//! the same numbers as an uninterrupted one.

use crate::body::BodyState;
use crate::energy::EnergyLedger;
use crate::forces::{PpContact, WallSlot};
use crate::integrate::GearState;
use crate::math::Vec3;
use crate::neighbor::{NeighborList, NeighborListError};
use crate::world::{Counters, World};
use serde::{Deserialize, Serialize};

/// Dynamic state of one rigid body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct BodySnapshot {
    name: String,
    state: BodyState,
    previous: BodyState,
    contact_force_n: Vec3,
    contact_torque_nm: Vec3,
}

/// The time-dependent state of a [`World`] (see the module docs). Static data (materials,
/// contact models, wall geometry, particle radii and masses) is not stored; it comes from the
/// scenario the world is rebuilt from, and [`World::restore_state`] checks that it matches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorldState {
    radius: Vec<f64>,
    material: Vec<u16>,
    id: Vec<u32>,
    position: Vec<Vec3>,
    velocity: Vec<Vec3>,
    angular_velocity: Vec<Vec3>,
    force: Vec<Vec3>,
    torque: Vec<Vec3>,
    external_force: Vec<Vec3>,
    bodies: Vec<BodySnapshot>,
    gravity_m_s2: Vec3,
    time_s: f64,
    dt_s: f64,
    ledger: EnergyLedger,
    counters: Counters,
    neighbors: NeighborList,
    contacts: Vec<PpContact>,
    wall_slots: Vec<Vec<WallSlot>>,
    gear: Option<GearState>,
    initialized: bool,
}

impl WorldState {
    /// Simulated time of the snapshot, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Number of particles of the snapshot.
    pub fn len(&self) -> usize {
        self.radius.len()
    }

    /// True when the snapshot holds no particles.
    pub fn is_empty(&self) -> bool {
        self.radius.is_empty()
    }
}

impl World {
    /// Copies the time-dependent state (does not change the world).
    pub fn save_state(&self) -> WorldState {
        debug_assert!(!self.step_pending(), "state read with a half kick pending");
        let p = &self.particles;
        WorldState {
            radius: p.radius.clone(),
            material: p.material.clone(),
            id: p.id.clone(),
            position: p.position.clone(),
            velocity: p.velocity.clone(),
            angular_velocity: p.angular_velocity.clone(),
            force: p.force.clone(),
            torque: p.torque.clone(),
            external_force: p.external_force.clone(),
            bodies: self
                .bodies
                .iter()
                .map(|b| BodySnapshot {
                    name: b.name.clone(),
                    state: b.state,
                    previous: b.previous,
                    contact_force_n: b.contact_force_n,
                    contact_torque_nm: b.contact_torque_nm,
                })
                .collect(),
            gravity_m_s2: self.gravity_m_s2,
            time_s: self.time_s,
            dt_s: self.dt_s,
            ledger: self.ledger,
            counters: self.counters,
            neighbors: self.neighbors.clone(),
            contacts: self.pp_contacts(),
            wall_slots: self.pass.wall_slots.clone(),
            gear: self.gear.clone(),
            initialized: self.initialized,
        }
    }

    /// Replaces the world's particles by the particles of `s` (radius, material and id; masses
    /// and inertias from the world's materials, positions at the origin until
    /// [`World::restore_state`] puts the state back). Rebuilds a world whose bed was prepared
    /// elsewhere — by another process of a sweep — from its scenario's bodies and walls, so that
    /// the restored world continues bit for bit. A material index outside the world's table is
    /// refused.
    pub fn set_particles_of(&mut self, s: &WorldState) -> Result<(), StateError> {
        if s.material.len() != s.radius.len() || s.id.len() != s.radius.len() {
            return Err(StateError::ColumnLengths);
        }
        if let Some(i) = s.radius.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(StateError::Radius {
                particle: i,
                radius_m: s.radius[i],
            });
        }
        if let Some((i, &m)) = s
            .material
            .iter()
            .enumerate()
            .find(|(_, m)| **m as usize >= self.materials.len())
        {
            return Err(StateError::Material {
                particle: i,
                material: m,
                materials: self.materials.len(),
            });
        }
        self.particles = crate::particles::ParticleSet::default();
        for (&r, &m) in s.radius.iter().zip(&s.material) {
            self.add_particle(Vec3::zeros(), r, m);
        }
        self.particles.id.clone_from(&s.id);
        Ok(())
    }

    /// Takes over the particles of `s`, a state of another world (a bed prepared between
    /// other walls): radii, materials and ids, positions, velocities, spins, the neighbour list
    /// and the particle–particle contacts with their history. Bodies, wall contacts, clock and
    /// ledger stay this world's; it initialises again at its next step (forces, wall contacts,
    /// ledger reset). A state whose contacts or neighbour pairs do not fit its particles is
    /// refused.
    pub fn adopt_particles(&mut self, s: &WorldState) -> Result<(), StateError> {
        let n = s.radius.len();
        if [
            s.position.len(),
            s.velocity.len(),
            s.angular_velocity.len(),
            s.external_force.len(),
        ]
        .iter()
        .any(|&l| l != n)
            || s.contacts.iter().any(|c| c.i >= c.j || c.j as usize >= n)
            || s.neighbors
                .first
                .iter()
                .chain(&s.neighbors.second)
                .any(|&i| i as usize >= n)
        {
            return Err(StateError::BedInconsistent);
        }
        s.neighbors
            .check_consistency(n)
            .map_err(StateError::BedNeighbors)?;
        self.set_particles_of(s)?;
        let p = &mut self.particles;
        p.position.clone_from(&s.position);
        p.velocity.clone_from(&s.velocity);
        p.angular_velocity.clone_from(&s.angular_velocity);
        p.external_force.clone_from(&s.external_force);
        self.neighbors = s.neighbors.clone();
        self.set_pp_contacts(&s.contacts);
        self.pass.wall_slots.clear();
        self.pass.wall_ref.clear();
        self.initialized = false;
        Ok(())
    }

    /// Puts a snapshot back. The world must have been built from the same scenario: same
    /// particles (radius, material, id) and the same bodies; otherwise an error says what differs
    /// and the world is left unchanged.
    pub fn restore_state(&mut self, s: WorldState) -> Result<(), StateError> {
        let p = &self.particles;
        if s.radius.len() != p.len() {
            return Err(StateError::ParticleCount {
                checkpoint: s.radius.len(),
                scenario: p.len(),
            });
        }
        if s.radius != p.radius || s.material != p.material || s.id != p.id {
            return Err(StateError::ParticlesDiffer);
        }
        let n = p.len();
        for (k, v) in [
            ("position", s.position.len()),
            ("velocity", s.velocity.len()),
            ("angular_velocity", s.angular_velocity.len()),
            ("force", s.force.len()),
            ("torque", s.torque.len()),
            ("external_force", s.external_force.len()),
        ] {
            if v != n {
                return Err(StateError::ColumnLength {
                    column: k,
                    len: v,
                    expected: n,
                });
            }
        }
        if s.bodies.len() != self.bodies.len()
            || s.bodies
                .iter()
                .zip(&self.bodies)
                .any(|(a, b)| a.name != b.name)
        {
            return Err(StateError::BodiesDiffer);
        }
        let np = s.neighbors.first.len();
        if s.neighbors.second.len() != np
            || s.contacts.iter().any(|c| c.i >= c.j || c.j as usize >= n)
            || s.contacts
                .windows(2)
                .any(|w| (w[0].i, w[0].j) >= (w[1].i, w[1].j))
            || s.neighbors
                .first
                .iter()
                .chain(&s.neighbors.second)
                .any(|&i| i as usize >= n)
            || (s.initialized && s.wall_slots.len() != n)
        {
            return Err(StateError::NeighborsInconsistent);
        }
        s.neighbors
            .check_consistency(n)
            .map_err(StateError::CheckpointNeighbors)?;
        let clock_ok = s.dt_s.is_finite() && s.dt_s > 0.0 && s.time_s.is_finite();
        if !(clock_ok && s.gravity_m_s2.iter().all(|g| g.is_finite())) {
            return Err(StateError::ClockNotFinite);
        }
        let walls_of = |b: u16| self.bodies.get(b as usize).map_or(0, |b| b.walls.len());
        if s.wall_slots
            .iter()
            .flatten()
            .any(|w| w.wall as usize >= walls_of(w.body))
        {
            return Err(StateError::WallContacts);
        }
        let p = &mut self.particles;
        p.position = s.position;
        p.velocity = s.velocity;
        p.angular_velocity = s.angular_velocity;
        p.force = s.force;
        p.torque = s.torque;
        p.external_force = s.external_force;
        for (b, snap) in self.bodies.iter_mut().zip(s.bodies) {
            b.state = snap.state;
            b.previous = snap.previous;
            b.contact_force_n = snap.contact_force_n;
            b.contact_torque_nm = snap.contact_torque_nm;
        }
        self.gravity_m_s2 = s.gravity_m_s2;
        self.time_s = s.time_s;
        self.dt_s = s.dt_s;
        self.ledger = s.ledger;
        self.counters = s.counters;
        self.neighbors = s.neighbors;
        self.set_pp_contacts(&s.contacts);
        self.pass.wall_slots = s.wall_slots;
        // The wall pass visits the candidates and the particles with wall contacts: recompute.
        self.pass.wall_ref.clear();
        self.gear = s.gear;
        self.initialized = s.initialized;
        Ok(())
    }
}

/// A state or checkpoint does not fit the world it is put into ([`World::set_particles_of`],
/// [`World::adopt_particles`], [`World::restore_state`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateError {
    /// Radius, material and id columns of different lengths.
    #[error("state: particle columns of different lengths")]
    ColumnLengths,
    /// A radius is not finite or not positive.
    #[error("state: particle {particle} has radius {radius_m} m")]
    Radius {
        /// Particle index.
        particle: usize,
        /// Its radius in m.
        radius_m: f64,
    },
    /// A material index outside the world's table.
    #[error(
        "state: particle {particle} has material index {material}, the world has {materials} materials"
    )]
    Material {
        /// Particle index.
        particle: usize,
        /// Its material index.
        material: u16,
        /// Materials of the world.
        materials: usize,
    },
    /// A bed state whose columns, contacts or neighbour pairs do not fit its particles.
    #[error("bed state: particle columns, contacts or neighbour pairs inconsistent")]
    BedInconsistent,
    /// A bed state's neighbour list is inconsistent.
    #[error("bed state: {0}")]
    BedNeighbors(NeighborListError),
    /// The checkpoint has another number of particles than the scenario builds.
    #[error("checkpoint has {checkpoint} particles, the scenario builds {scenario}")]
    ParticleCount {
        /// Particles in the checkpoint.
        checkpoint: usize,
        /// Particles of the scenario.
        scenario: usize,
    },
    /// Radius, material or id differ from the scenario's particles.
    #[error("checkpoint particles (radius, material or id) differ from the scenario's")]
    ParticlesDiffer,
    /// A checkpoint column has the wrong length.
    #[error("checkpoint {column} has {len} entries, expected {expected}")]
    ColumnLength {
        /// The column, e.g. `velocity`.
        column: &'static str,
        /// Its length.
        len: usize,
        /// The number of particles.
        expected: usize,
    },
    /// The checkpoint's bodies are not the scenario's.
    #[error("checkpoint bodies differ from the scenario's")]
    BodiesDiffer,
    /// The checkpoint's contacts or neighbour pairs do not fit its particles.
    #[error("checkpoint neighbour list is inconsistent")]
    NeighborsInconsistent,
    /// The checkpoint's neighbour list is inconsistent.
    #[error("checkpoint {0}")]
    CheckpointNeighbors(NeighborListError),
    /// Time step, time or gravity not finite.
    #[error("checkpoint time step, time or gravity not finite")]
    ClockNotFinite,
    /// Wall contacts that refer to walls the scenario does not have.
    #[error("checkpoint wall contacts refer to walls the scenario does not have")]
    WallContacts,
}

#[cfg(test)]
mod tests {
    use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
    use crate::walls::{BoxInside, Geometry};
    use crate::{
        BodyState, GearParams, HarmonicTranslation, Integrator, Material, Motion, RigidBody, Vec3,
        Wall, World,
    };
    use std::sync::Arc;

    fn shaken_box(n_side: usize) -> World {
        shaken_box_sized(n_side, Vec3::new(0.01, 0.01, 0.02))
    }

    /// A lattice of `n_side`³ steel spheres (r = 1 mm, spacing 2.2 mm, random velocities) in a
    /// box of half-extents `half` shaken vertically, the lattice starting one radius from the
    /// walls at the low corner.
    fn shaken_box_sized(n_side: usize, half: Vec3) -> World {
        let steel = Material::new("steel", 7850.0, 2.1e11, 0.3);
        let model = ContactModel {
            normal: NormalLaw::HertzMindlin {
                restitution: 0.7,
                clip_attractive: false,
            },
            friction: FrictionLaw::Mindlin {
                friction_coefficient: 0.3,
            },
            rolling: None,
            adhesion: None,
        };
        let mut w = World::new(vec![steel], model, 2e-7);
        let motion = HarmonicTranslation {
            direction: [0.0, 0.0, 1.0],
            amplitude_m: 1e-3,
            frequency_hz: 60.0,
            phase_rad: 0.0,
        };
        let mut body = RigidBody::new(
            "box",
            BodyState::at_rest(Vec3::zeros()),
            Motion::Prescribed(Arc::new(motion)),
        );
        body.walls.push(Wall {
            geometry: Geometry::BoxInside(BoxInside {
                center_m: Vec3::zeros(),
                half_extents_m: half,
            }),
            material: 0,
            name: "box".into(),
        });
        w.add_body(body);
        let r = 1e-3;
        for i in 0..n_side {
            for j in 0..n_side {
                for k in 0..n_side {
                    let x = Vec3::new(
                        -half.x + 2.0 * r + 2.2 * r * i as f64 + 1e-5 * k as f64,
                        -half.y + 2.0 * r + 2.2 * r * j as f64,
                        -half.z + 2.0 * r + 2.2 * r * k as f64,
                    );
                    let id = w.add_particle(x, r, 0);
                    let s = id as f64;
                    w.particles.velocity[id] = Vec3::new(s.sin(), (2.0 * s).cos(), (3.0 * s).sin());
                }
            }
        }
        w
    }

    /// Skipping the wall search for particles far from every wall (wall candidates) changes
    /// no bit of the result: a 4×4×4 bed in the shaken box, 20 000 steps (4 ms: the box
    /// travels about 1.4 mm, seven skins, so the candidates are refreshed many times, and the
    /// particles hit the walls), with and without.
    #[test]
    fn wall_candidates_change_nothing() {
        let run = |skip: bool| {
            let mut w = shaken_box(4);
            w.pass.wall_skip = skip;
            let mut wall_contacts = 0;
            for _ in 0..20000 {
                w.step();
                wall_contacts += w.num_pw_contacts();
            }
            (w, wall_contacts)
        };
        let ((a, ca), (b, cb)) = (run(true), run(false));
        assert!(ca > 100 && ca == cb, "{ca} {cb}");
        assert_eq!(a.particles.position, b.particles.position);
        assert_eq!(a.particles.velocity, b.particles.velocity);
        assert_eq!(a.particles.angular_velocity, b.particles.angular_velocity);
        assert_eq!(a.ledger, b.ledger);
        assert_eq!(a.bodies[0].contact_force_n, b.bodies[0].contact_force_n);
    }

    /// The loads of the bed on the box, summed per block of the pair pass and the blocks added
    /// in order, close the momentum balance of the particles: over a run of velocity Verlet the
    /// change of their momentum equals gravity's impulse minus the impulse of the box loads
    /// (trapezoidal rule, which is what velocity Verlet integrates), to round-off. 4 096
    /// spheres, so that the pair pass has several blocks; a block whose loads were lost or
    /// counted twice would miss by a share of the wall impulse.
    /// The drift's shortcut (no second look while twice the largest displacement stays below
    /// the skin) rebuilds the neighbour list exactly when the two largest displacements reach
    /// the skin [D Eq. 2.11], including the cases where only the shortcut's bound is exceeded.
    #[test]
    fn drift_shortcut_keeps_the_exact_rebuild_criterion() {
        let mut w = shaken_box(4);
        w.initialize();
        let skin = w.neighbors.skin_m;
        assert!(skin > 0.0);
        // (a, b): the two displacements as fractions of the skin.
        for &(a, b) in &[
            (0.3, 0.3),
            (0.55, 0.1),
            (0.49, 0.49),
            (0.6, 0.45),
            (0.2, 0.9),
            (0.0, 0.0),
        ] {
            let x0 = w.neighbors.reference_position.clone();
            w.particles.position.clone_from(&x0);
            w.particles.position[3].x += a * skin;
            w.particles.position[17].y -= b * skin;
            let max_d2 = w
                .particles
                .position
                .iter()
                .zip(&x0)
                .map(|(x, r)| (x - r).norm_squared())
                .fold(0.0, f64::max);
            let exact = w.neighbors.needs_rebuild(&w.particles.position);
            assert_eq!(exact, a + b >= 1.0, "({a}, {b})");
            let before = w.neighbors.builds;
            w.update_neighbors_given(Some(max_d2));
            assert_eq!(w.neighbors.builds > before, exact, "({a}, {b})");
        }
    }

    #[test]
    fn body_loads_close_the_momentum_balance() {
        let mut w = shaken_box_sized(16, Vec3::new(0.0185, 0.0185, 0.02));
        let momentum = |w: &World| {
            (0..w.particles.len()).fold(Vec3::zeros(), |a, i| {
                a + w.particles.velocity[i] * w.particles.mass[i]
            })
        };
        w.step();
        // (`block_start` holds the first chunk of every block and the end: at least 2 blocks)
        assert!(w.pass.block_start.len() > 2, "{:?}", w.pass.block_start);
        let m_total: f64 = w.particles.mass.iter().sum();
        let (p0, dt, steps) = (momentum(&w), w.dt_s, 8000);
        let (mut f_prev, mut impulse) = (w.bodies[0].contact_force_n, Vec3::zeros());
        for _ in 0..steps {
            w.step();
            let f = w.bodies[0].contact_force_n;
            impulse += (f_prev + f) * (0.5 * dt);
            f_prev = f;
        }
        let gravity_impulse = w.gravity_m_s2 * (m_total * dt * steps as f64);
        let dp = momentum(&w) - p0;
        let miss = (dp - (gravity_impulse - impulse)).norm();
        // the walls matter: their impulse is larger than gravity's
        assert!(impulse.norm() > gravity_impulse.norm(), "{impulse:?}");
        assert!(
            miss <= 1e-9 * impulse.norm(),
            "momentum change {dp:?}, gravity {gravity_impulse:?}, box {impulse:?}, miss {miss:e}"
        );
    }

    /// Restoring a snapshot after `first` steps and running `second` more equals running
    /// `first + second` steps without interruption, bit for bit.
    fn check_continuation(integrator: Integrator, first: usize, second: usize) {
        let mut a = shaken_box(4);
        a.integrator = integrator.clone();
        for _ in 0..first {
            a.step();
        }
        let snap = a.save_state();
        for _ in 0..second {
            a.step();
        }
        let mut b = shaken_box(4);
        b.integrator = integrator;
        b.restore_state(snap).unwrap();
        for _ in 0..second {
            b.step();
        }
        assert_eq!(a.particles.position, b.particles.position);
        assert_eq!(a.particles.velocity, b.particles.velocity);
        assert_eq!(a.particles.angular_velocity, b.particles.angular_velocity);
        assert_eq!(a.ledger, b.ledger);
        assert_eq!(a.dt_s, b.dt_s);
        assert!(
            a.counters.neighbor_builds > 1,
            "list was rebuilt in between"
        );
        assert!(a.ledger.dissipated_j() > 0.0, "contacts happened");
    }

    #[test]
    fn restored_world_continues_bit_for_bit_verlet() {
        check_continuation(Integrator::VelocityVerlet, 1500, 1500);
    }

    #[test]
    fn restored_world_continues_bit_for_bit_gear() {
        check_continuation(Integrator::Gear(GearParams::default()), 600, 600);
    }

    #[test]
    fn restore_rejects_other_scenario() {
        let a = shaken_box(3);
        let mut b = shaken_box(4);
        let e = b.restore_state(a.save_state()).unwrap_err();
        assert!(e.to_string().contains("27 particles"), "{e}");
        assert!(
            matches!(e, super::StateError::ParticleCount { checkpoint: 27, .. }),
            "{e:?}"
        );
    }
}
