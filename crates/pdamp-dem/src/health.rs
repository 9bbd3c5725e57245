//! Numerical health of a running simulation: non-finite states, runaway overlaps and a broken
//! energy balance are found early and reported with the particle, time, position and the likely
//! cause, instead of running on with garbage.

use crate::walls::Geometry;
use crate::world::World;

/// Largest particle–particle or particle–wall overlap, relative to the (smaller) radius, that
/// a healthy run reaches. Hertz contacts of engineering materials stay below a few per cent;
/// 25 % means particles are passing through each other.
pub const MAX_RELATIVE_OVERLAP: f64 = 0.25;

/// A wall whose Young's modulus is below this fraction of the particle's is a soft layer — a
/// rubber or polymer coating (D Sect. 8.1.5, moduli of 0.27–55 MPa against 208 GPa steel) —
/// for the overlap check.
pub const SOFT_WALL_MODULUS_RATIO: f64 = 1e-2;

/// Largest particle–wall overlap, relative to the radius, on a soft wall: a bed pressed into a
/// coating by its own impact (D's compression collect-and-collide, Sect. 8.1.5) legitimately
/// indents it by tens of per cent of a sphere's radius. A plane's Hertz force grows with the
/// indentation, so a particle passing through it shows as an overlap approaching the radius,
/// which this still catches. Beyond ≈ 10 % Hertz is outside its small-strain range, as D notes
/// for its coating design formula (Eq. 8.3–8.11).
pub const SOFT_WALL_MAX_RELATIVE_OVERLAP: f64 = 0.75;

/// The particle–wall overlap limit of a particle material against a wall material:
/// [`SOFT_WALL_MAX_RELATIVE_OVERLAP`] for a soft wall ([`SOFT_WALL_MODULUS_RATIO`]),
/// [`MAX_RELATIVE_OVERLAP`] otherwise.
pub fn wall_overlap_limit(particle: &crate::Material, wall: &crate::Material) -> f64 {
    if wall.youngs_modulus_pa < SOFT_WALL_MODULUS_RATIO * particle.youngs_modulus_pa {
        SOFT_WALL_MAX_RELATIVE_OVERLAP
    } else {
        MAX_RELATIVE_OVERLAP
    }
}

/// Relative energy-balance residual |W − ΔE − D| / scale beyond which the run has blown up
/// (healthy runs close to 1e-4 or better; Gear runs to their error tolerance).
pub const MAX_CLOSURE_ERROR: f64 = 0.5;

/// A cumulative dissipation term below −`NEGATIVE_DISSIPATION` × the energy turnover means a
/// contact creates energy (dissipation is never negative; the trapezoidal bookkeeping of a
/// healthy run stays above −1e-9 of the turnover).
pub const NEGATIVE_DISSIPATION: f64 = 1e-3;

/// What went wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct HealthError {
    /// Simulated time, s.
    pub time_s: f64,
    /// Particle concerned (index), if one is.
    pub particle: Option<usize>,
    /// Its position, m.
    pub position_m: Option<[f64; 3]>,
    /// Diagnosis with the likely cause and what to change.
    pub message: String,
}

impl std::fmt::Display for HealthError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "numerical failure at t = {:.6e} s", self.time_s)?;
        if let (Some(i), Some(x)) = (self.particle, self.position_m) {
            write!(
                f,
                ", particle {i} at [{:.6e}, {:.6e}, {:.6e}] m",
                x[0], x[1], x[2]
            )?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for HealthError {}

/// Time-step ratio Δt / t_c (shortest Hertz contact time at 1 m/s) above which a blow-up is
/// put down to the time step; below it the step is ruled out and other causes are named.
const SUSPECT_STEP_RATIO: f64 = 0.2;

/// The likely cause of a failure, chosen from the evidence: the time step only where it is a
/// sizeable fraction of the contact time; otherwise what else makes a run blow up.
fn cause(w: &World) -> String {
    let tc = w.min_contact_time_s(1.0);
    let ratio = w.dt_s / tc;
    if tc.is_finite() && ratio >= SUSPECT_STEP_RATIO {
        format!(
            "likely cause: the time step {:.3e} s is too large for the contact stiffness \
             (shortest Hertz contact time at 1 m/s: {:.3e} s, ratio {:.2}); reduce \
             simulation.time_step_s (≤ 1/20 of the contact time), or check youngs_modulus_pa \
             and the impact velocities",
            w.dt_s, tc, ratio
        )
    } else if tc.is_finite() {
        let fastest = (0..w.particles.len())
            .map(|i| w.particles.velocity[i].norm())
            .fold(0.0, f64::max);
        format!(
            "the time step is not the cause (ratio {ratio:.2} of the shortest contact time \
             {tc:.3e} s at 1 m/s; fastest particle {fastest:.3e} m/s): look for particles \
             placed into each other or into a wall at the start, a wall or body moving faster \
             than the particles can follow (motion amplitude × frequency), a mesh with a gap or \
             a wrong orientation, or material data in the wrong unit"
        )
    } else {
        format!(
            "likely cause: the time step {:.3e} s is too large, or the material data are not \
             in SI units; reduce simulation.time_step_s",
            w.dt_s
        )
    }
}

impl World {
    /// Checks the state: every position and velocity finite, no overlap beyond
    /// [`MAX_RELATIVE_OVERLAP`] of the radius, energy balance within [`MAX_CLOSURE_ERROR`].
    /// O(N + contacts); meant to be called every few hundred steps.
    pub fn check_health(&self) -> Result<(), HealthError> {
        debug_assert!(!self.step_pending(), "state read with a half kick pending");
        self.check_finite()?;
        self.check_pair_overlaps()?;
        self.check_wall_overlaps()?;
        self.check_energy()
    }

    /// The error of a health check at the current time, about particle `i` (with its position).
    fn health_error(&self, i: Option<usize>, message: String) -> HealthError {
        let p = &self.particles;
        HealthError {
            time_s: self.time_s,
            particle: i,
            position_m: i.map(|i| [p.position[i].x, p.position[i].y, p.position[i].z]),
            message,
        }
    }

    /// Every position, velocity and spin finite.
    fn check_finite(&self) -> Result<(), HealthError> {
        let p = &self.particles;
        for i in 0..p.len() {
            let bad_x = !p.position[i].iter().all(|c| c.is_finite());
            let bad_v = !p.velocity[i].iter().all(|c| c.is_finite())
                || !p.angular_velocity[i].iter().all(|c| c.is_finite());
            if bad_x || bad_v {
                return Err(self.health_error(
                    Some(i),
                    format!(
                        "non-finite {} (id {}); {}",
                        if bad_x { "position" } else { "velocity" },
                        p.id[i],
                        cause(self)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// No particle–particle overlap beyond [`MAX_RELATIVE_OVERLAP`] of the smaller radius.
    fn check_pair_overlaps(&self) -> Result<(), HealthError> {
        let p = &self.particles;
        // Particle–particle overlaps.
        let mut worst = (0.0, usize::MAX, usize::MAX);
        for k in 0..self.neighbors.num_pairs() {
            let (i, j) = (
                self.neighbors.first[k] as usize,
                self.neighbors.second[k] as usize,
            );
            let ov = p.radius[i] + p.radius[j] - (p.position[i] - p.position[j]).norm();
            let rel = ov / p.radius[i].min(p.radius[j]);
            if rel > worst.0 {
                worst = (rel, i, j);
            }
        }
        if worst.0 > MAX_RELATIVE_OVERLAP {
            let (rel, i, j) = worst;
            return Err(self.health_error(
                Some(i),
                format!(
                    "particles {i} and {j} overlap by {:.0} % of the smaller radius (runaway \
                     overlap, limit {:.0} %); {}",
                    100.0 * rel,
                    100.0 * MAX_RELATIVE_OVERLAP,
                    cause(self)
                ),
            ));
        }
        Ok(())
    }

    /// No particle deeper in a wall than the limit of its pair of materials.
    fn check_wall_overlaps(&self) -> Result<(), HealthError> {
        let p = &self.particles;
        // Particle–wall overlaps (from the last force evaluation).
        let mut out = Vec::new();
        for (i, slots) in self.pass.wall_slots.iter().enumerate() {
            for s in slots {
                let b = &self.bodies[s.body as usize];
                let wall = &b.walls[s.wall as usize];
                let x = b.state.to_body(&p.position[i]);
                out.clear();
                wall.geometry
                    .sphere_contacts(&x, p.radius[i], 0.0, &mut out);
                let limit = wall_overlap_limit(
                    &self.materials[p.material[i] as usize],
                    &self.materials[wall.material as usize],
                );
                if let Some(c) = out.iter().find(|c| c.overlap_m > limit * p.radius[i]) {
                    return Err(self.health_error(
                        Some(i),
                        format!(
                            "particle {i} penetrates wall '{}' of body '{}' by {:.0} % of its \
                             radius (runaway overlap, limit {:.0} %{}; a particle may have left \
                             the container); {}",
                            wall.name,
                            b.name,
                            100.0 * c.overlap_m / p.radius[i],
                            100.0 * limit,
                            if limit > MAX_RELATIVE_OVERLAP {
                                " for a soft wall"
                            } else {
                                ""
                            },
                            cause(self)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Dissipation never negative, no particle escaped, the ledger closed (to [`MAX_CLOSURE_ERROR`] of the energy turnover).
    fn check_energy(&self) -> Result<(), HealthError> {
        let p = &self.particles;
        let l = &self.ledger;
        let scale = l
            .turnover_j()
            .max(l.initial_kinetic_j.abs() + l.initial_elastic_j.abs());
        // Dissipation is never negative: energy created by a contact.
        let terms = [
            (
                l.dissipated_normal_pw_j,
                "normal dissipation of particle–wall contacts",
                true,
            ),
            (
                l.dissipated_tangential_pw_j,
                "tangential dissipation of particle–wall contacts",
                true,
            ),
            (
                l.dissipated_normal_pp_j,
                "normal dissipation of particle–particle contacts",
                false,
            ),
            (
                l.dissipated_tangential_pp_j,
                "tangential dissipation of particle–particle contacts",
                false,
            ),
        ];
        if let Some(&(d, what, wall)) = terms
            .iter()
            .find(|(d, _, _)| *d < -NEGATIVE_DISSIPATION * scale && *d < -1e-15)
        {
            let i = fastest(p);
            let why = if wall {
                "likely cause: a wall whose normal points out of the particle region (a reversed \
                 mesh, or flip_normals set on a mesh that was right) lets particles be pushed \
                 through it; check the wall's orientation"
                    .to_string()
            } else {
                cause(self)
            };
            return Err(self.health_error(
                i,
                format!(
                    "energy is being created: the {what} is {d:.3e} J (negative, against \
                     {scale:.3e} J of energy turnover); fastest particle shown; {why}"
                ),
            ));
        }
        if let Some(e) = self.escaped_particle() {
            return Err(self.health_error(Some(e.0), e.1));
        }
        let closure = l.closure_error_j();
        if !closure.is_finite() || (scale > 0.0 && closure.abs() > MAX_CLOSURE_ERROR * scale) {
            // Blame the fastest particle.
            let i = fastest(p);
            return Err(self.health_error(
                i,
                format!(
                    "energy balance broken (residual {:.3e} J against {:.3e} J of energy \
                     turnover; energy is being created); fastest particle shown; {}",
                    closure,
                    scale,
                    cause(self)
                ),
            ));
        }
        Ok(())
    }

    /// The first particle that has left every closed container of the world (a box or
    /// cylinder container, a closed mesh whose normals point inwards, or an open mesh, which
    /// can only hold a bed inside its bounding box): its centre lies outside the bounding boxes
    /// of all of them (in each body's frame), by more than a particle diameter. `None` when
    /// the world has no container or every particle is in one. O(N × containers).
    fn escaped_particle(&self) -> Option<(usize, String)> {
        let p = &self.particles;
        let mut boxes = Vec::new();
        for (b, body) in self.bodies.iter().enumerate() {
            for (w, wall) in body.walls.iter().enumerate() {
                let confines = match &wall.geometry {
                    Geometry::BoxInside(_) | Geometry::CylinderInside(_) => true,
                    Geometry::Mesh(m) => !m.is_closed() || m.enclosed_volume_m3() < 0.0,
                    Geometry::Plane(_) | Geometry::CylinderOutside(_) => false,
                };
                if confines && let Some(bb) = wall.geometry.bounding_box() {
                    boxes.push((b, w, bb));
                }
            }
        }
        if boxes.is_empty() {
            return None;
        }
        for i in 0..p.len() {
            let margin = 2.0 * p.radius[i];
            let mut nearest = (f64::INFINITY, 0, 0);
            for &(b, w, (lo, hi)) in &boxes {
                let x = self.bodies[b].state.to_body(&p.position[i]);
                let d = (0..3)
                    .map(|k| (lo[k] - x[k]).max(x[k] - hi[k]).max(0.0))
                    .fold(0.0, f64::max);
                if d <= margin {
                    nearest = (0.0, b, w);
                    break;
                }
                if d < nearest.0 {
                    nearest = (d, b, w);
                }
            }
            if nearest.0 > 0.0 {
                let (d, b, w) = nearest;
                let body = &self.bodies[b];
                let wall = &body.walls[w];
                let open = match &wall.geometry {
                    Geometry::Mesh(m) if !m.is_closed() => {
                        " The mesh is not closed (it has edges used by one triangle only): \
                         close it, or add the walls that close it."
                    }
                    _ => "",
                };
                return Some((
                    i,
                    format!(
                        "particle {i} (id {}) has left its container: it is {d:.3e} m outside \
                         the bounding box of wall '{}' of body '{}'.{open} Likely cause: a \
                         gap in the container's walls, or particles pushed through a wall \
                         ({})",
                        p.id[i],
                        wall.name,
                        body.name,
                        cause(self)
                    ),
                ));
            }
        }
        None
    }
}

/// Index of the fastest particle (the one a broken balance is shown with).
fn fastest(p: &crate::particles::ParticleSet) -> Option<usize> {
    (0..p.len()).max_by(|&a, &b| {
        p.velocity[a]
            .norm_squared()
            .total_cmp(&p.velocity[b].norm_squared())
    })
}

#[cfg(test)]
mod tests {
    use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
    use crate::{Material, Vec3, World};

    fn pair(dt: f64, v: f64) -> World {
        let steel = Material::new("steel", 7850.0, 2.1e11, 0.3);
        let model = ContactModel {
            normal: NormalLaw::Hertz,
            friction: FrictionLaw::Frictionless,
            rolling: None,
            adhesion: None,
        };
        let mut w = World::new(vec![steel], model, dt);
        w.gravity_m_s2 = Vec3::zeros();
        let a = w.add_particle(Vec3::new(-1.05e-3, 0.0, 0.0), 1e-3, 0);
        let b = w.add_particle(Vec3::new(1.05e-3, 0.0, 0.0), 1e-3, 0);
        w.particles.velocity[a] = Vec3::new(v, 0.0, 0.0);
        w.particles.velocity[b] = Vec3::new(-v, 0.0, 0.0);
        w
    }

    #[test]
    fn healthy_collision_passes() {
        let mut w = pair(5e-8, 1.0);
        for _ in 0..4_000 {
            w.step();
            if w.counters.steps.is_multiple_of(100) {
                w.check_health().unwrap();
            }
        }
        assert!(w.particles.velocity[0].x < 0.0, "they bounced");
    }

    #[test]
    fn time_step_far_too_large_is_diagnosed() {
        // Contact time ≈ 8 µs; a 5 µs step lets the spheres run deep into each other.
        let mut w = pair(5e-6, 5.0);
        let mut found = None;
        for _ in 0..400 {
            w.step();
            if let Err(e) = w.check_health() {
                found = Some(e);
                break;
            }
        }
        let e = found.expect("the failure is detected");
        let text = e.to_string();
        assert!(e.particle.is_some() && e.position_m.is_some(), "{text}");
        assert!(text.contains("time step"), "{text}");
        assert!(text.contains("simulation.time_step_s"), "{text}");
    }

    /// A 10 mm box container with one particle inside.
    fn boxed() -> World {
        use crate::body::{BodyState, Motion, RigidBody};
        use crate::walls::{BoxInside, Geometry};
        let mut w = pair(1e-7, 0.0);
        w.particles.position[1] = Vec3::new(1.05e-3, 3e-3, 0.0);
        w.add_body(
            RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
                "container",
                Geometry::BoxInside(BoxInside::new(Vec3::zeros(), Vec3::new(5e-3, 5e-3, 5e-3))),
                0,
            ),
        );
        w.initialize();
        w
    }

    #[test]
    fn a_particle_outside_every_container_is_named() {
        let mut w = boxed();
        w.check_health().unwrap();
        // Moved 62 m away (the reversed-facet defect of issue 31 ended like this).
        w.particles.position[1] = Vec3::new(0.0, 0.0, -62.0);
        let e = w.check_health().unwrap_err();
        assert_eq!(e.particle, Some(1));
        let text = e.to_string();
        assert!(text.contains("has left its container"), "{text}");
        assert!(text.contains("'container' of body 'box'"), "{text}");
        // Just outside by less than a diameter: a contact, not an escape.
        w.particles.position[1] = Vec3::new(0.0, 0.0, 5.5e-3);
        assert!(
            !w.check_health()
                .is_err_and(|e| e.to_string().contains("left its container"))
        );
    }

    /// A sphere pressed into a wall by 40 % of its radius: a runaway on a steel wall, a
    /// legitimate indentation of a rubber coating (E_w < 1 % of the particle's), where only an
    /// overlap beyond 75 % is refused.
    #[test]
    fn soft_walls_may_be_indented_deeper() {
        use crate::body::{BodyState, Motion, RigidBody};
        use crate::walls::{Geometry, Plane};
        let indented = |wall_modulus_pa: f64, depth: f64| {
            let steel = Material::new("steel", 7850.0, 2.1e11, 0.3);
            let coating = Material::new("coating", 1190.0, wall_modulus_pa, 0.49);
            let model = ContactModel {
                normal: NormalLaw::Hertz,
                friction: FrictionLaw::Frictionless,
                rolling: None,
                adhesion: None,
            };
            let mut w = World::new(vec![steel, coating], model, 1e-7);
            w.gravity_m_s2 = Vec3::zeros();
            w.add_particle(Vec3::new(0.0, 0.0, (1.0 - depth) * 1e-3), 1e-3, 0);
            w.add_body(
                RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
                    "floor",
                    Geometry::Plane(Plane::new(Vec3::zeros(), Vec3::new(0.0, 0.0, 1.0), false)),
                    1,
                ),
            );
            w.initialize();
            w.check_health()
        };
        let e = indented(2.1e11, 0.4).unwrap_err().to_string();
        assert!(
            e.contains("penetrates wall 'floor'") && e.contains("limit 25 %"),
            "{e}"
        );
        indented(0.72e6, 0.4).unwrap();
        let e = indented(0.72e6, 0.8).unwrap_err().to_string();
        assert!(e.contains("limit 75 % for a soft wall"), "{e}");
    }

    #[test]
    fn negative_dissipation_is_energy_created() {
        let mut w = boxed();
        w.ledger.wall_work_j = 0.2;
        w.ledger.kinetic_j += 0.2;
        w.ledger.dissipated_normal_pw_j = -0.2;
        let e = w.check_health().unwrap_err();
        let text = e.to_string();
        assert!(text.contains("energy is being created"), "{text}");
        assert!(text.contains("wall's orientation"), "{text}");
        // Round-off below the threshold is not a failure.
        w.ledger.dissipated_normal_pw_j = -1e-7;
        w.ledger.wall_work_j = 0.2 - 1e-7;
        assert!(
            !w.check_health()
                .is_err_and(|e| e.to_string().contains("energy is being created")),
        );
    }

    #[test]
    fn non_finite_state_is_named() {
        let mut w = pair(1e-8, 1.0);
        w.step();
        w.particles.velocity[1].y = f64::NAN;
        let e = w.check_health().unwrap_err();
        assert_eq!(e.particle, Some(1));
        assert!(e.to_string().contains("non-finite velocity"), "{e}");
        // A step of 1e-8 s is ≈ 1/800 of the contact time: not blamed (issue 31).
        assert!(e.to_string().contains("time step is not the cause"), "{e}");
        assert!(!e.to_string().contains("too large"), "{e}");
    }
}
