//! Two-way coupled DEM–FEM simulation of powder-filled cavities in deformable structures,
//! after Praegla, Mair, Wimmer, Fuchs, Zaeh, Wall & Meier, *Additively manufactured structures
//! with powder inclusions for controllable dissipation: the critical influence of packing
//! density*, Powder Technology 2024 ("paper" below; equation numbers refer to it).
//!
//! - [`fe`]: nonlinear hex8 solids (Saint Venant–Kirchhoff, total Lagrangian), generalized-α
//!   with Newton and faer's sparse Cholesky, meshes (structured box with cavity, Gmsh, Abaqus),
//!   modes and a Timoshenko beam reference (Sect. 2.2).
//! - [`law`], [`psd`], [`bed`]: the powder of Sect. 2.1 (contact law parameters and
//!   coarse-graining, log-normal size distributions) on the pdamp-dem engine, which evaluates
//!   the linear spring–dashpot, the Coulomb tangential spring with return mapping and DMT
//!   adhesion, and integrates with velocity Verlet.
//! - [`prep`]: powder preparation on pdamp-dem (grid, settling, plate compression to a packing
//!   density).
//! - [`couple`]: Dirichlet–Neumann coupling with Aitken relaxation (Sect. 2.3, Algorithm 1).
//! - [`cantilever`]: the cantilever study of Sect. 2.4, damping ratios as in Table 1.
//! - [`health`]: health checks of the DEM and the coupled run (typed errors, likely cause).
//! - [`fuzz`]: fuzz entry points of the mesh readers and the checkpoint decoder.
//! - [`analytic`]: the first-order shear and bending models of Sect. 4 (eq. 17–26).
//!
//! Details and measured results: `docs/powder.md`.

#![forbid(unsafe_code)]
// Index loops mirror the tensor notation of the equations; validation uses `!(x > 0.0)` on
// purpose so that NaN is rejected.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod analytic;
pub mod bed;
pub mod cantilever;
pub mod couple;
pub mod damping;
pub mod error;
pub use pdamp_fem::solid as fe;
pub mod fuzz;
pub mod health;
pub mod law;
pub mod prep;
pub mod psd;
pub mod study;
pub mod vtk;

pub use error::ParameterError;
