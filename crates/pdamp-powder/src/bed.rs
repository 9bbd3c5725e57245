//! The powder on pdamp-dem: the contact model of the paper's law (Sect. 2.1, eq. 2–7) and a
//! bed of particles — prepared ([`crate::prep`]) or placed by hand — that a coupled run takes
//! over ([`crate::couple::Coupled::new`]).

use pdamp_dem::contact::{ContactModel, DmtAdhesion, FrictionLaw, NormalLaw};
use pdamp_dem::{Material, Vec3, World};

use crate::law::PowderLaw;

/// Young's modulus of the particle and wall materials of the world, Pa: not used by the
/// powder's linear contact law (its stiffness is `normal_stiffness_n_m`), only a nominal value
/// for the engine's material table (equal on both sides: no soft-wall rules).
const NOMINAL_MODULUS_PA: f64 = 200e9;

/// Material index of the particles in a powder world.
pub const PARTICLE_MATERIAL: u16 = 0;
/// Material index of the walls (cavity, plate, structure surface) in a powder world.
pub const WALL_MATERIAL: u16 = 1;

/// The pdamp-dem contact model of the powder law (paper eq. 2–7): the linear spring–dashpot
/// clipped at zero (eq. 2–4), the Coulomb-limited tangential spring with
/// $k_T = \frac{1-\nu}{1-\nu/2}k_N$ and $d_T = d_N$ (eq. 5), DMT adhesion when γ > 0 (eq. 6–7).
/// Walls enter with $r_{eff} = r_i$ and $m_{eff} = m_i$, as in the paper.
pub fn contact_model(law: &PowderLaw) -> ContactModel {
    ContactModel {
        normal: NormalLaw::Linear {
            stiffness_n_m: law.normal_stiffness_n_m,
            restitution: law.restitution,
            clip_attractive: true,
        },
        friction: FrictionLaw::CoulombSpring {
            friction_coefficient: law.friction,
            stiffness_ratio: Some(law.tangential_ratio()),
            damping_ratio: 1.0,
        },
        rolling: None,
        adhesion: (law.surface_energy_j_m2 > 0.0).then_some(DmtAdhesion {
            surface_energy_j_m2: law.surface_energy_j_m2,
            hamaker_constant_j: law.hamaker_j,
            cutoff_ratio: law.adhesion_cutoff,
        }),
    }
}

/// An empty world for powder of `law` and density (kg/m³): the particle and wall materials,
/// the contact model of [`contact_model`] for every pair, gravity (m/s²) and time step (s).
pub fn powder_world(law: &PowderLaw, density_kg_m3: f64, gravity: [f64; 3], dt_s: f64) -> World {
    let materials = vec![
        Material::new(
            "powder",
            density_kg_m3,
            NOMINAL_MODULUS_PA,
            law.poisson_ratio,
        ),
        Material::new("wall", density_kg_m3, NOMINAL_MODULUS_PA, law.poisson_ratio),
    ];
    let mut w = World::new(materials, contact_model(law), dt_s);
    w.gravity_m_s2 = Vec3::from(gravity);
    w
}

/// Particles for a coupled run: a world holding only them (no walls), with their law and
/// density. Velocities, spins and particle–particle contacts (with their spring history) carry
/// over into the coupled run.
#[derive(Debug, Clone)]
pub struct PowderBed {
    /// The particles.
    pub world: World,
    /// Their contact law.
    pub law: PowderLaw,
    /// Their density, kg/m³.
    pub density_kg_m3: f64,
}

impl PowderBed {
    /// Particles at rest at `positions` (m) with `radii` (m).
    ///
    /// # Panics
    /// If the lengths differ.
    #[track_caller]
    pub fn at_rest(
        law: PowderLaw,
        positions: &[[f64; 3]],
        radii: &[f64],
        density_kg_m3: f64,
        gravity: [f64; 3],
        dt_s: f64,
    ) -> Self {
        assert_eq!(positions.len(), radii.len());
        let mut world = powder_world(&law, density_kg_m3, gravity, dt_s);
        for (x, &r) in positions.iter().zip(radii) {
            world.add_particle(Vec3::from(*x), r, PARTICLE_MATERIAL);
        }
        Self {
            world,
            law,
            density_kg_m3,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.world.particles.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.world.particles.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scenario's coarse-grained law (`PowderLaw::coarse_grained`, what `reference_d50_m`
    /// selects) is the engine's coarse-graining transform of the real law.
    #[test]
    fn coarse_grained_law_is_the_engines_transform() {
        let law = PowderLaw {
            surface_energy_j_m2: 0.085,
            ..PowderLaw::PAPER
        };
        for f in [0.5, 2.0, 4.0] {
            let ours = contact_model(&law.coarse_grained(f));
            let engine = contact_model(&law).coarse_grained(f).unwrap();
            match (&ours.normal, &engine.normal) {
                (
                    NormalLaw::Linear {
                        stiffness_n_m: a, ..
                    },
                    NormalLaw::Linear {
                        stiffness_n_m: b, ..
                    },
                ) => assert!((a / b - 1.0).abs() < 1e-15),
                _ => panic!("linear law expected"),
            }
            let (a, b) = (ours.adhesion.unwrap(), engine.adhesion.unwrap());
            assert!((a.surface_energy_j_m2 / b.surface_energy_j_m2 - 1.0).abs() < 1e-15);
            assert_eq!(ours.friction, engine.friction);
        }
    }
}
