//! Sparse modal reduction for large models [D Eq. 3.20–3.22] on the finite-element linear
//! algebra of `pdamp-fem`: [`SymmetricCsr`] matrices (both triangles, assembled from
//! triplets), faer's sparse Cholesky of the shifted pencil $K - \sigma M$ (σ < 0 below the
//! spectrum, positive definite also for free–free models) and faer's Krylov–Schur eigensolver
//! on the shift-inverted pencil, refined by Rayleigh–Ritz ([`pdamp_fem::eigen`] documents the
//! method and its convergence test). The dense solver of [`crate::modal`] remains the default
//! for small models (`solver = "auto"` switches at [`AUTO_SPARSE_ABOVE_DOF`]).

use crate::modal::ModalBasis;
use nalgebra::DMatrix;
pub use pdamp_fem::eigen::EigenError;
pub use pdamp_fem::sparse::SymmetricCsr;

/// Errors of the sparse matrices and the sparse eigen solver.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SparseError {
    /// A matrix could not be assembled (an entry outside it or not finite).
    #[error(transparent)]
    Matrix(#[from] pdamp_fem::SparseError),
    /// The eigensolver failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

/// `solver = "auto"` uses the sparse solver above this many active dof.
pub const AUTO_SPARSE_ABOVE_DOF: usize = 1500;

/// Lowest `n_modes` modes with f ≥ `min_frequency_hz` of sparse K, M (module documentation).
/// Rigid-body modes below the threshold are computed and dropped.
///
/// # Errors
/// Size mismatch, an empty model, a mass matrix or shifted stiffness that is not positive
/// definite, or no convergence.
pub fn lowest_modes_sparse(
    stiffness: &SymmetricCsr,
    mass: &SymmetricCsr,
    n_modes: usize,
    min_frequency_hz: f64,
) -> Result<ModalBasis, SparseError> {
    Ok(ModalBasis::from(pdamp_fem::lowest_modes(
        stiffness,
        mass,
        n_modes,
        min_frequency_hz,
    )?))
}

/// `Y = A X` column by column.
pub fn mul_columns(a: &SymmetricCsr, x: &DMatrix<f64>) -> DMatrix<f64> {
    let mut y = DMatrix::<f64>::zeros(a.n, x.ncols());
    let mut out = vec![0.0; a.n];
    for c in 0..x.ncols() {
        a.mul(x.column(c).as_slice(), &mut out);
        y.column_mut(c).copy_from_slice(&out);
    }
    y
}

/// A dense symmetric matrix as a [`SymmetricCsr`] (non-zero entries).
///
/// # Panics
/// On a non-finite entry.
pub fn from_dense(a: &DMatrix<f64>) -> SymmetricCsr {
    SymmetricCsr::from_dense(a.nrows(), |i, j| a[(i, j)]).expect("finite dense entries")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_modes_match_dense_on_a_chain() {
        let n = 200;
        let kd = DMatrix::from_fn(n, n, |i, j| match i.abs_diff(j) {
            0 => 2.0e4,
            1 => -1.0e4,
            _ => 0.0,
        });
        let md = DMatrix::from_fn(n, n, |i, j| if i == j { 1.0 + (i % 3) as f64 } else { 0.0 });
        let dense = crate::modal::lowest_modes(&kd, &md, 5, 0.0).unwrap();
        let sp = lowest_modes_sparse(&from_dense(&kd), &from_dense(&md), 5, 0.0).unwrap();
        for i in 0..5 {
            let e = sp.omega_rad_s[i] / dense.omega_rad_s[i] - 1.0;
            assert!(e.abs() < 1e-10, "mode {i}: {e}");
            let c = (sp.shapes.column(i).transpose() * &md * dense.shapes.column(i))[(0, 0)];
            assert!((c.abs() - 1.0).abs() < 1e-8, "mode {i}: MAC-like {c}");
        }
    }
}
