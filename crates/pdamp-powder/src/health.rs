//! Numerical health of the powder DEM (preparation) and of the coupled DEM–FEM run: a run
//! stops with a [`HealthError`] — never a panic and never silent nonsense — when a particle or
//! structural state becomes non-finite, a particle leaves the closed cavity, an overlap runs
//! away, or the energy ledger shows energy created (negative dissipation, a balance that grows
//! beyond round-off). The message names the particle (or node and element), the time, the
//! evidence (time-step ratio to the shortest contact time, largest overlap, dissipation) and
//! the likely cause chosen from that evidence.
//!
//! Thresholds (healthy runs stay far below them, see docs/powder.md):
//! - overlap: [`MAX_RELATIVE_OVERLAP`] of the smaller diameter (the over-compressed 62 % bed of
//!   the D50 = 1 mm study reaches 0.29);
//! - a particle centre outside the cavity (plus the structure's displacement) has passed the
//!   wall by more than its radius;
//! - energy: cumulative dissipation below −[`NEGATIVE_DISSIPATION_FRACTION`] of the energy
//!   scale, or a balance (stored + dissipated − work) grown by more than
//!   [`ENERGY_CREATED_FRACTION`] of it (loose beds drift by ≤ 0.11).

use crate::fe::Aabb;
use crate::law::PowderLaw;
use pdamp_dem::World;

/// Largest healthy overlap relative to the smaller diameter of a pair.
pub const MAX_RELATIVE_OVERLAP: f64 = 0.5;
/// Largest healthy negative cumulative dissipation, relative to the energy scale.
pub const NEGATIVE_DISSIPATION_FRACTION: f64 = 0.1;
/// Largest healthy growth of the energy balance, relative to the energy scale.
pub const ENERGY_CREATED_FRACTION: f64 = 0.5;
/// Time step over the shortest contact time above which the step is blamed.
pub const MAX_STEP_RATIO: f64 = 0.3;

/// What went wrong.
#[derive(Debug, Clone, PartialEq)]
pub enum Symptom {
    /// A particle's position, velocity or spin is NaN or infinite.
    NonFiniteParticle {
        /// Particle index.
        particle: usize,
        /// `position`, `velocity` or `angular velocity`.
        quantity: &'static str,
        /// The value.
        value: [f64; 3],
    },
    /// A structural displacement is NaN or infinite.
    NonFiniteStructure {
        /// Node index.
        node: usize,
        /// First element holding the node.
        element: Option<usize>,
    },
    /// A particle centre lies outside the closed cavity.
    Escaped {
        /// Particle index.
        particle: usize,
        /// Its position \[m\].
        position: [f64; 3],
        /// Distance outside the cavity \[m\].
        distance_m: f64,
    },
    /// A pair overlaps by more than [`MAX_RELATIVE_OVERLAP`] of the smaller diameter.
    Overlap {
        /// First particle.
        particle: usize,
        /// Second particle.
        partner: usize,
        /// Overlap / smaller diameter.
        relative: f64,
    },
    /// The cumulative dissipation is negative beyond round-off.
    NegativeDissipation {
        /// Dissipated energy so far \[J\].
        dissipated_j: f64,
        /// Energy scale \[J\].
        scale_j: f64,
    },
    /// The energy balance grew: energy was created.
    EnergyCreated {
        /// Growth of stored + dissipated − work since the start \[J\].
        created_j: f64,
        /// Energy scale \[J\].
        scale_j: f64,
    },
}

impl std::fmt::Display for Symptom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFiniteParticle {
                particle,
                quantity,
                value,
            } => write!(f, "particle {particle}: non-finite {quantity} {value:?}"),
            Self::NonFiniteStructure { node, element } => {
                write!(f, "structure node {node}")?;
                if let Some(e) = element {
                    write!(f, " (element {e})")?;
                }
                write!(f, ": non-finite displacement")
            }
            Self::Escaped {
                particle,
                position,
                distance_m,
            } => write!(
                f,
                "particle {particle} at [{:.4e}, {:.4e}, {:.4e}] m left the closed cavity by {distance_m:.3e} m",
                position[0], position[1], position[2]
            ),
            Self::Overlap {
                particle,
                partner,
                relative,
            } => write!(
                f,
                "particles {particle} and {partner} overlap by {relative:.3} of the smaller diameter (limit {MAX_RELATIVE_OVERLAP})"
            ),
            Self::NegativeDissipation {
                dissipated_j,
                scale_j,
            } => write!(
                f,
                "negative dissipation {dissipated_j:.3e} J (energy scale {scale_j:.3e} J): energy was created"
            ),
            Self::EnergyCreated { created_j, scale_j } => write!(
                f,
                "the energy balance grew by {created_j:.3e} J (energy scale {scale_j:.3e} J): energy was created"
            ),
        }
    }
}

/// What the run looked like when it failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evidence {
    /// Time step \[s\].
    pub time_step_s: f64,
    /// Shortest particle–particle contact time $\pi\sqrt{m_{eff}/k_N}$ \[s\].
    pub contact_time_s: f64,
    /// Largest overlap / smaller diameter over the pair list (finite pairs).
    pub max_relative_overlap: f64,
    /// Dissipated energy so far \[J\].
    pub dissipated_j: f64,
}

impl Evidence {
    /// Time step over the shortest contact time.
    pub fn step_ratio(&self) -> f64 {
        self.time_step_s / self.contact_time_s
    }

    /// The evidence of a pdamp-dem world whose contacts follow `law`.
    pub fn of_world(w: &World, law: &PowderLaw) -> Self {
        let m = w
            .particles
            .mass
            .iter()
            .fold(f64::INFINITY, |a, &b| a.min(b));
        Self {
            time_step_s: w.dt_s,
            contact_time_s: std::f64::consts::PI * (0.5 * m / law.normal_stiffness_n_m).sqrt(),
            max_relative_overlap: world_max_relative_overlap(w).0,
            dissipated_j: w.ledger.dissipated_j(),
        }
    }

    /// The likely cause of `symptom`, chosen from the evidence, with the fix.
    pub fn likely_cause(&self, symptom: &Symptom) -> String {
        let (r, o, tc) = (
            self.step_ratio(),
            self.max_relative_overlap,
            self.contact_time_s,
        );
        if r > MAX_STEP_RATIO {
            return format!(
                "the time step {:.3e} s is {r:.2} of the shortest contact time {tc:.3e} s (above {MAX_STEP_RATIO}); use run.time_step_s ≤ {:.3e} s (1/10 of the contact time) or a smaller powder.law.normal_stiffness_n_m",
                self.time_step_s,
                0.1 * tc
            );
        }
        let fine = format!("time step ratio {r:.2} is fine");
        if o > MAX_RELATIVE_OVERLAP || matches!(symptom, Symptom::Overlap { .. }) {
            return format!(
                "the contacts are too soft for the load: largest overlap {o:.2} of the smaller diameter ({fine}); increase powder.law.normal_stiffness_n_m or lower powder.prep.packing_density, powder.prep.settling_gravity_factor or the gravity"
            );
        }
        match symptom {
            Symptom::NegativeDissipation { .. } | Symptom::EnergyCreated { .. } => format!(
                "energy created at the particle–wall interface ({fine}, largest overlap {o:.2}, dissipated {:.3e} J): tighten run.coupling.tolerance; interface faces whose normals do not point into the cavity (an inverted mesh) create energy too",
                self.dissipated_j
            ),
            Symptom::Escaped { .. } => format!(
                "a particle passed through a cavity wall ({fine}, largest overlap {o:.2}): a wall moved by more than a particle radius in one step or the cavity is not closed; lower load.pressure_pa or run.time_step_s and check the mesh"
            ),
            Symptom::NonFiniteStructure { .. } => format!(
                "the structural solve diverged ({fine}, largest overlap {o:.2}): check load.pressure_pa against beam.material.youngs_modulus_pa and the element sizes"
            ),
            Symptom::NonFiniteParticle { .. } | Symptom::Overlap { .. } => format!(
                "not the time step ({fine}, largest overlap {o:.2}): check powder.law (surface_energy_j_m2, hamaker_j, restitution) and run.gravity_m_s2"
            ),
        }
    }
}

/// The stage name of the preparation's plate compression (see [`crate::prep`]).
pub const COMPRESSION_STAGE: &str = "preparation: plate compression";

/// A failed health check (see the module docs).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("numerical failure at t = {time_s:.6e} s ({stage}): {symptom}; likely cause: {cause}")]
pub struct HealthError {
    /// Simulated time \[s\].
    pub time_s: f64,
    /// Stage of the run (`settling`, `coupled run`, …).
    pub stage: &'static str,
    /// What went wrong.
    pub symptom: Symptom,
    /// The state of the run.
    pub evidence: Evidence,
    /// The likely cause and its fix.
    pub cause: String,
}

impl HealthError {
    /// The error for `symptom` in a pdamp-dem world whose contacts follow `law`.
    pub fn of_world(
        time_s: f64,
        stage: &'static str,
        symptom: Symptom,
        w: &World,
        law: &PowderLaw,
    ) -> Self {
        Self::with_evidence(time_s, stage, symptom, Evidence::of_world(w, law))
    }

    fn with_evidence(
        time_s: f64,
        stage: &'static str,
        symptom: Symptom,
        evidence: Evidence,
    ) -> Self {
        let cause = match symptom {
            // the plate drives the bed into the side walls: the bed is too stiff or too
            // dense for the packing density asked
            Symptom::Escaped { .. } if stage == COMPRESSION_STAGE => format!(
                "the bed resists the plate and is pressed through a side wall (largest overlap \
                 {:.2} of the smaller diameter): the settled bed is too far below the packing \
                 density asked; lower powder.prep.packing_density, make the bed less loose \
                 (a smaller powder.prep.friction or surface_energy_j_m2) or raise \
                 powder.law.normal_stiffness_n_m",
                evidence.max_relative_overlap
            ),
            _ => evidence.likely_cause(&symptom),
        };
        Self {
            time_s,
            stage,
            symptom,
            evidence,
            cause,
        }
    }
}

/// Non-finite positions, velocities and spins of the particles of a pdamp-dem world; particle
/// centres outside `container` enlarged by `margin_m` (when given).
pub fn check_world_particles(
    w: &World,
    container: Option<(&Aabb, f64)>,
) -> Result<(), (usize, Symptom)> {
    let p = &w.particles;
    let a = |v: &pdamp_dem::Vec3| [v.x, v.y, v.z];
    check_states(
        p.len(),
        |i| {
            [
                a(&p.position[i]),
                a(&p.velocity[i]),
                a(&p.angular_velocity[i]),
            ]
        },
        container,
    )
}

/// The checks of [`check_world_particles`] on `n` particles whose position, velocity and spin
/// `state(i)` gives.
fn check_states(
    n: usize,
    state: impl Fn(usize) -> [[f64; 3]; 3],
    container: Option<(&Aabb, f64)>,
) -> Result<(), (usize, Symptom)> {
    for i in 0..n {
        let [x, v, w] = state(i);
        for (quantity, v) in [("position", x), ("velocity", v), ("angular velocity", w)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err((
                    i,
                    Symptom::NonFiniteParticle {
                        particle: i,
                        quantity,
                        value: v,
                    },
                ));
            }
        }
        if let Some((b, margin)) = container {
            let out = (0..3)
                .map(|k| (b.min[k] - margin - x[k]).max(x[k] - b.max[k] - margin))
                .fold(0.0f64, f64::max);
            if out > 0.0 {
                return Err((
                    i,
                    Symptom::Escaped {
                        particle: i,
                        position: x,
                        distance_m: out,
                    },
                ));
            }
        }
    }
    Ok(())
}

/// The largest particle–particle overlap of a pdamp-dem world relative to the smaller
/// diameter, with its pair (over the neighbour pairs).
pub fn world_max_relative_overlap(w: &World) -> (f64, usize, usize) {
    let p = &w.particles;
    w.neighbor_pairs()
        .map(|(i, j)| {
            let overlap = p.radius[i] + p.radius[j] - (p.position[i] - p.position[j]).norm();
            (overlap / (2.0 * p.radius[i].min(p.radius[j])), i, j)
        })
        .fold((0.0, 0, 0), |a, b| if b.0 > a.0 { b } else { a })
}

/// The first pair whose overlap exceeds [`MAX_RELATIVE_OVERLAP`] of the smaller diameter.
pub fn check_world_overlaps(w: &World) -> Result<(), Symptom> {
    let (rel, i, j) = world_max_relative_overlap(w);
    if rel > MAX_RELATIVE_OVERLAP {
        return Err(Symptom::Overlap {
            particle: i,
            partner: j,
            relative: rel,
        });
    }
    Ok(())
}

/// Energy check: `dissipated_j` below −[`NEGATIVE_DISSIPATION_FRACTION`]·`scale_j`, or a
/// balance growth `created_j` above [`ENERGY_CREATED_FRACTION`]·`scale_j`.
pub fn check_energy(dissipated_j: f64, created_j: f64, scale_j: f64) -> Result<(), Symptom> {
    let scale_j = scale_j.abs().max(1e-300);
    if !dissipated_j.is_finite() || dissipated_j < -NEGATIVE_DISSIPATION_FRACTION * scale_j {
        return Err(Symptom::NegativeDissipation {
            dissipated_j,
            scale_j,
        });
    }
    if !created_j.is_finite() || created_j > ENERGY_CREATED_FRACTION * scale_j {
        return Err(Symptom::EnergyCreated { created_j, scale_j });
    }
    Ok(())
}
