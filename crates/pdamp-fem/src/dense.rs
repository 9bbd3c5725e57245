//! Small dense systems of the structural level through faer, on nalgebra matrices (the
//! structure's modal quantities are nalgebra `DMatrix`/`DVector`): the inverse of a modal
//! system matrix (LU with partial pivoting) and rank-revealing least squares (thin SVD).

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, MatRef};
use nalgebra::{DMatrix, DVector};

fn to_faer(a: &DMatrix<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

fn to_nalgebra(a: MatRef<'_, f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

/// $A^{-1}$ of a square matrix by faer's LU with partial pivoting; `None` if A is singular
/// (an exactly zero pivot) or the inverse is not finite.
pub fn inverse(a: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if a.nrows() != a.ncols() {
        return None;
    }
    if a.nrows() == 0 {
        return Some(a.clone());
    }
    let lu = to_faer(a).partial_piv_lu();
    let u = lu.U();
    if (0..a.nrows()).any(|i| u[(i, i)] == 0.0) {
        return None;
    }
    let inv = to_nalgebra(lu.inverse().as_ref());
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

/// The least-squares solution of $A x = b$ with the singular values of A at or below `eps`
/// treated as zero (minimum-norm solution), by faer's thin SVD; `None` if the SVD fails.
pub fn least_squares(a: &DMatrix<f64>, b: &DVector<f64>, eps: f64) -> Option<DVector<f64>> {
    let svd = to_faer(a).thin_svd().ok()?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    let mut x = DVector::<f64>::zeros(a.ncols());
    for k in 0..s.nrows() {
        if s[k] <= eps {
            continue;
        }
        let c: f64 = (0..a.nrows()).map(|i| u[(i, k)] * b[i]).sum::<f64>() / s[k];
        for j in 0..a.ncols() {
            x[j] += c * v[(j, k)];
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_least_squares_solve_small_systems() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0]);
        let ai = inverse(&a).unwrap();
        assert!((&a * &ai - DMatrix::identity(3, 3)).norm() < 1e-15);
        assert!(inverse(&DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0])).is_none());
        // overdetermined line fit y = 2 + 3 t through exact points
        let t = [0.0, 1.0, 2.0, 3.0];
        let a = DMatrix::from_fn(4, 2, |i, j| if j == 0 { 1.0 } else { t[i] });
        let b = DVector::from_iterator(4, t.iter().map(|t| 2.0 + 3.0 * t));
        let x = least_squares(&a, &b, 1e-13).unwrap();
        assert!(
            (x[0] - 2.0).abs() < 1e-13 && (x[1] - 3.0).abs() < 1e-13,
            "{x}"
        );
        // a rank-deficient system: the minimum-norm solution
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let x = least_squares(&a, &DVector::from_vec(vec![2.0, 2.0]), 1e-13).unwrap();
        assert!(
            (x[0] - 1.0).abs() < 1e-13 && (x[1] - 1.0).abs() < 1e-13,
            "{x}"
        );
    }
}
