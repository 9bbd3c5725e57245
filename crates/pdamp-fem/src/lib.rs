//! The finite elements of pdamp, shared by the structural level (`pdamp-structure`, which
//! re-exports [`linear`] as `fe` and [`matrix_market`]) and the powder DEM–FEM model
//! (`pdamp-powder`, which re-exports [`solid`] as `fe`):
//!
//! - [`linear`] — linear models for modal reduction [D Eq. 3.19]: 3D Euler–Bernoulli and
//!   Timoshenko beams, hex8 solids with incompatible modes, ACM plates, point masses, springs;
//!   dense and sparse assembly of K and M;
//! - [`solid`] — the nonlinear structure of the paper (Sect. 2.2): hex8 meshes (structured box
//!   with cavity, Gmsh and Abaqus readers), Saint Venant–Kirchhoff total-Lagrangian hex8,
//!   generalized-α with modified Newton, the structure's eigenmodes and a Timoshenko reference;
//! - [`matrix_market`] — import of exported K and M with a node/dof map and their checks;
//! - [`sparse::SymmetricCsr`] — the one sparse matrix type (symmetric, compressed rows with both
//!   triangles stored), assembled from triplets;
//! - [`factor`] — faer's sparse Cholesky $LL^T$ (AMD ordering, symbolic analysis reused by
//!   numeric refactorizations), in double precision and, for modified Newton iterations, in
//!   single precision; the positive-definiteness checks of imported matrices;
//! - [`dense`] — small dense systems of the structural level (inverse, least squares);
//! - [`eigen`] — the lowest modes of $K\phi = \omega^2 M\phi$ [D Eq. 3.20]: faer's Krylov–Schur
//!   (Lanczos) eigensolver on the shift-inverted, symmetrised pencil with a Rayleigh–Ritz
//!   refinement for sparse models, faer's dense self-adjoint eigensolver for small ones.
//!
//! Every factorization and eigenproblem of the finite elements goes through faer; nalgebra
//! remains for the fixed-size algebra inside an element (3×3 Jacobians, the 24×24 element
//! matrices, the ACM corner matrix).
#![forbid(unsafe_code)]

pub mod dense;
pub mod eigen;
pub mod factor;
pub mod linear;
pub mod matrix_market;
pub mod solid;
pub mod sparse;

pub use eigen::{EigenError, Modes, dense_lowest_modes, lowest_modes};
pub use factor::{Cholesky, FactorError, SingleCholesky, is_positive_definite};
pub use sparse::{SparseError, SymmetricCsr};
