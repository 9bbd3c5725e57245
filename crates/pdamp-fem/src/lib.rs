//! The finite-element linear algebra shared by the structural level (`pdamp-structure`) and the
//! powder DEM–FEM model (`pdamp-powder`):
//!
//! - [`sparse::SymmetricCsr`] — the one sparse matrix type (symmetric, compressed rows with both
//!   triangles stored), assembled from triplets;
//! - [`factor`] — faer's sparse Cholesky $LL^T$ (AMD ordering, symbolic analysis reused by
//!   numeric refactorizations), in double precision and, for modified Newton iterations, in
//!   single precision; the positive-definiteness checks of imported matrices;
//! - [`eigen`] — the lowest modes of $K\phi = \omega^2 M\phi$ [D Eq. 3.20]: faer's Krylov–Schur
//!   (Lanczos) eigensolver on the shift-inverted, symmetrised pencil with a Rayleigh–Ritz
//!   refinement for sparse models, faer's dense self-adjoint eigensolver for small ones.
//!
//! Every factorization and eigenproblem of the finite elements goes through faer; nothing
//! here is hand-written linear algebra beyond matrix–vector products and Gram–Schmidt.
#![forbid(unsafe_code)]

pub mod eigen;
pub mod factor;
pub mod sparse;

pub use eigen::{EigenError, Modes, dense_lowest_modes, lowest_modes};
pub use factor::{Cholesky, FactorError, SingleCholesky, is_positive_definite};
pub use sparse::{SparseError, SymmetricCsr};
