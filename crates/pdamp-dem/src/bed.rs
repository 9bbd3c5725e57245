//! A particle bed: the state of a packing that one simulation hands on to another — the settled
//! result of a drop-down [D Sect. 2.1, Fig. 2.2, 2.14], a bed imported from another DEM code, or
//! the start of an ensemble member. A bed carries what a new run needs to start from it (centres,
//! radii, materials by name, velocities and spins); the exact continuation of a run (contact
//! history, neighbour list, ledger) is the optional [`crate::WorldState`] stored beside it by the
//! native bed file of `pdamp-io`.

use crate::math::Vec3;
use crate::world::World;
use serde::{Deserialize, Serialize};

/// Particles of a bed, one entry per particle in every column (SI units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Bed {
    /// Material names; `material[i]` indexes this table.
    pub materials: Vec<String>,
    /// Centre positions, m.
    pub position_m: Vec<Vec3>,
    /// Radii, m.
    pub radius_m: Vec<f64>,
    /// Material index of each particle into [`Bed::materials`].
    pub material: Vec<u16>,
    /// Translational velocities, m/s.
    pub velocity_m_s: Vec<Vec3>,
    /// Angular velocities, rad/s.
    pub angular_velocity_rad_s: Vec<Vec3>,
}

impl Bed {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position_m.len()
    }

    /// True when the bed has no particles.
    pub fn is_empty(&self) -> bool {
        self.position_m.is_empty()
    }

    /// The particles of `world` (positions, radii, materials by the world's material names,
    /// velocities and spins), in the world's particle order.
    pub fn from_world(world: &World) -> Self {
        let p = &world.particles;
        Self {
            materials: world.materials.iter().map(|m| m.name.clone()).collect(),
            position_m: p.position.clone(),
            radius_m: p.radius.clone(),
            material: p.material.clone(),
            velocity_m_s: p.velocity.clone(),
            angular_velocity_rad_s: p.angular_velocity.clone(),
        }
    }

    /// Checks the columns: equal lengths, finite values, positive radii, material indices in
    /// range. The message names the first offending particle (0-based) and column.
    pub fn validate(&self) -> Result<(), BedError> {
        let n = self.len();
        for (name, len) in [
            ("radius_m", self.radius_m.len()),
            ("material", self.material.len()),
            ("velocity_m_s", self.velocity_m_s.len()),
            ("angular_velocity_rad_s", self.angular_velocity_rad_s.len()),
        ] {
            if len != n {
                return Err(BedError::ColumnLength {
                    column: name,
                    len,
                    expected: n,
                });
            }
        }
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        for i in 0..n {
            if !finite(&self.position_m[i]) {
                return Err(BedError::Particle {
                    index: i,
                    column: "position_m",
                    message: "position_m is not finite".into(),
                });
            }
            let r = self.radius_m[i];
            if !(r.is_finite() && r > 0.0) {
                return Err(BedError::Particle {
                    index: i,
                    column: "radius_m",
                    message: format!("radius_m must be finite and > 0, got {r}"),
                });
            }
            if self.material[i] as usize >= self.materials.len() {
                return Err(BedError::Particle {
                    index: i,
                    column: "material",
                    message: format!(
                        "material index {} but the bed names {} material(s)",
                        self.material[i],
                        self.materials.len()
                    ),
                });
            }
            if !finite(&self.velocity_m_s[i]) {
                return Err(BedError::Particle {
                    index: i,
                    column: "velocity_m_s",
                    message: "velocity_m_s is not finite".into(),
                });
            }
            if !finite(&self.angular_velocity_rad_s[i]) {
                return Err(BedError::Particle {
                    index: i,
                    column: "angular_velocity_rad_s",
                    message: "angular_velocity_rad_s is not finite".into(),
                });
            }
        }
        Ok(())
    }
}

/// A bed's columns do not fit together or hold a bad value ([`Bed::validate`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BedError {
    /// A column has another length than `position_m`.
    #[error("bed column {column} has {len} entries, position_m has {expected}")]
    ColumnLength {
        /// The column.
        column: &'static str,
        /// Its length.
        len: usize,
        /// Length of `position_m`.
        expected: usize,
    },
    /// A particle's value is not finite or out of range.
    #[error("bed particle {index}: {message}")]
    Particle {
        /// 0-based index of the particle in the bed.
        index: usize,
        /// The column.
        column: &'static str,
        /// What is wrong (starts with the column).
        message: String,
    },
}
