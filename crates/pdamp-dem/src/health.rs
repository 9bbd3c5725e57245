//! Numerical health of a running simulation: non-finite states, runaway overlaps and a broken
//! energy balance are found early and reported with the particle, time, position and the likely
//! cause, instead of running on with garbage.

use crate::world::World;

/// Largest particle–particle or particle–wall overlap, relative to the (smaller) radius, that
/// a healthy run reaches. Hertz contacts of engineering materials stay below a few per cent;
/// 25 % means particles are passing through each other.
pub const MAX_RELATIVE_OVERLAP: f64 = 0.25;

/// Relative energy-balance residual |W − ΔE − D| / scale beyond which the run has blown up
/// (healthy runs close to 1e-4 or better; Gear runs to their error tolerance).
pub const MAX_CLOSURE_ERROR: f64 = 0.5;

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

fn cause(w: &World) -> String {
    let tc = w.min_contact_time_s(1.0);
    if tc.is_finite() {
        format!(
            "likely cause: the time step {:.3e} s is too large for the contact stiffness \
             (shortest Hertz contact time at 1 m/s: {:.3e} s, ratio {:.2}); reduce \
             simulation.time_step_s (≤ 1/20 of the contact time), or check youngs_modulus_pa \
             and the impact velocities",
            w.dt_s,
            tc,
            w.dt_s / tc
        )
    } else {
        format!(
            "likely cause: the time step {:.3e} s is too large; reduce simulation.time_step_s",
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
        let p = &self.particles;
        let err = |i: Option<usize>, message: String| HealthError {
            time_s: self.time_s,
            particle: i,
            position_m: i.map(|i| [p.position[i].x, p.position[i].y, p.position[i].z]),
            message,
        };
        for i in 0..p.len() {
            let bad_x = !p.position[i].iter().all(|c| c.is_finite());
            let bad_v = !p.velocity[i].iter().all(|c| c.is_finite())
                || !p.angular_velocity[i].iter().all(|c| c.is_finite());
            if bad_x || bad_v {
                return Err(err(
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
            return Err(err(
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
        // Particle–wall overlaps (from the last force evaluation).
        let mut out = Vec::new();
        for (i, slots) in self.wall_slots.iter().enumerate() {
            for s in slots {
                let b = &self.bodies[s.body as usize];
                let wall = &b.walls[s.wall as usize];
                let x = b.state.to_body(&p.position[i]);
                out.clear();
                wall.geometry
                    .sphere_contacts(&x, p.radius[i], 0.0, &mut out);
                if let Some(c) = out
                    .iter()
                    .find(|c| c.overlap_m > MAX_RELATIVE_OVERLAP * p.radius[i])
                {
                    return Err(err(
                        Some(i),
                        format!(
                            "particle {i} penetrates wall '{}' of body '{}' by {:.0} % of its \
                             radius (runaway overlap; a particle may have left the container); {}",
                            wall.name,
                            b.name,
                            100.0 * c.overlap_m / p.radius[i],
                            cause(self)
                        ),
                    ));
                }
            }
        }
        let l = &self.ledger;
        let scale = l
            .turnover_j()
            .max(l.initial_kinetic_j.abs() + l.initial_elastic_j.abs());
        let closure = l.closure_error_j();
        if !closure.is_finite() || (scale > 0.0 && closure.abs() > MAX_CLOSURE_ERROR * scale) {
            // Blame the fastest particle.
            let i = (0..p.len()).max_by(|&a, &b| {
                p.velocity[a]
                    .norm_squared()
                    .total_cmp(&p.velocity[b].norm_squared())
            });
            return Err(err(
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

    #[test]
    fn non_finite_state_is_named() {
        let mut w = pair(1e-8, 1.0);
        w.step();
        w.particles.velocity[1].y = f64::NAN;
        let e = w.check_health().unwrap_err();
        assert_eq!(e.particle, Some(1));
        assert!(e.to_string().contains("non-finite velocity"), "{e}");
    }
}
