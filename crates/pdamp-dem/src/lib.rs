//! # pdamp-dem — the discrete element engine of pdamp
//!
//! Spherical particles in containers made of analytic walls and triangle meshes, verified contact
//! laws (Hertz, Gonthier, Lankarani–Nikravesh, linear spring–dashpot, Hertz–Mindlin, regularized
//! and spring–dashpot friction, rolling resistance, DMT adhesion), cell-grid + Verlet neighbour
//! lists, velocity-Verlet and Gear predictor–corrector integration, and an energy ledger that
//! closes. References: \[D\] = the dissertation on the particle-damper design toolchain (chapter 2),
//! \[P\] = the DEM–FEM powder-damper paper (section 2.1). No file I/O lives here.

pub mod bed;
pub mod bed_statistics;
pub mod body;
pub mod contact;
pub mod deformable;
pub mod drop_down;
pub mod energy;
pub mod error;
mod forces;
pub mod generate;
pub mod health;
mod hm_block;
pub mod integrate;
pub mod interaction;
pub mod material;
pub mod math;
pub mod neighbor;
pub mod particles;
pub mod state;
pub mod time_loop;
pub mod wall_repeat;
pub mod walls;
pub mod world;

pub use bed::Bed;
pub use body::{
    BodyState, HarmonicTranslation, Motion, PrescribedMotion, RigidBody, TranslationTrack, Wall,
};
pub use contact::{ContactModel, FrictionLaw, NormalLaw};
pub use energy::EnergyLedger;
pub use error::ParameterError;
pub use forces::{PairState, PpContact, WallSlot};
pub use integrate::{GearParams, Integrator};
pub use material::Material;
pub use math::Vec3;
pub use particles::ParticleSet;
pub use state::WorldState;
pub use walls::Geometry;
pub use world::{AdaptiveSkin, World};
pub mod impact;
