//! Level I of the toolchain [D Sect. 3.1, Chap. 4]: the coefficient of restitution ε(v) of a
//! sphere hitting a wall (or an identical sphere), computed from the materials.
//!
//! - [`hertz`]: elastic Hertz impact (contact time [D Eq. 4.8], max overlap [D Eq. 2.80], force
//!   history from the Hertz ODE).
//! - [`thornton`]: elastic–perfectly-plastic restitution (Thornton 1997).
//! - [`viscoelastic`]: Kuwabara–Kono / Brilliantov viscoelastic Hertz impact.
//! - [`material`]: materials (linear elastic, J2 elastic–viscoplastic with Perzyna rate
//!   dependence [D Eq. 4.2, Tab. 4.1], linear viscoelastic Prony series [D Eq. 4.3–4.7,
//!   Tab. 4.2]); built-ins `s235`, `al6060`, `saa9579`; TOML material files.
//! - [`constitutive`]: the integration-point updates (radial return, recursive Prony update).
//! - [`mesh`]: axisymmetric quad meshes of the sphere and the clamped cylinder [D Sect. 4.2.2].
//! - [`fe`]: explicit axisymmetric dynamic FE impact (B-bar Q4, lumped mass, central differences,
//!   frictionless node-to-segment penalty contact).
//! - [`study`]: ε(v) curves over many velocities (rayon), repeated impacts.
//!
//! Units are SI throughout. `[D Eq. n]` refers to the dissertation.

#![forbid(unsafe_code)]
pub mod constitutive;
pub mod fe;
pub mod hertz;
pub mod material;
pub mod mesh;
pub mod study;
pub mod thornton;
pub mod viscoelastic;

pub use fe::{EnergySplit, FeOptions, ImpactResult, Partner, simulate_impact};
pub use material::{Material, MaterialError, MaterialModel, MaterialSet};
pub use mesh::MeshDensity;
pub use study::{CorModel, CorPoint, cor_curve};
