//! Nonlinear structural finite elements (paper Sect. 2.2): hex8 meshes, Saint Venant–Kirchhoff
//! total-Lagrangian elements, assembly with Dirichlet/Neumann conditions, generalized-α with
//! Newton and a sparse direct solver (faer), eigenmodes, and a Timoshenko beam reference.

// index loops over element nodes/components read like the formulas; `!(x > 0)` also refuses NaN
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod beam_theory;
pub mod gen_alpha;
pub mod hex8;
pub mod mesh;
pub mod modes;
pub mod quad;
pub mod structure;
pub mod svk;

pub use gen_alpha::{Dynamics, DynamicsError, DynamicsState, GenAlpha, NewtonSettings, Rayleigh};
pub use mesh::{Aabb, BoxMeshDivisions, Face, HexMesh, MeshError, read_abaqus_inp, read_gmsh};
pub use structure::{Kinematics, LoadRamp, MassKind, Structure, SurfaceLoad};
pub use svk::SvkMaterial;
