//! Sparse Cholesky factorizations $A = P^T L L^T P$ of a [`SymmetricCsr`] with faer
//! (AMD fill-reducing ordering; the symbolic analysis is done once and reused by every numeric
//! refactorization of a matrix with the same pattern).
//!
//! Factorizations and solves run sequentially (`Par::Seq`): faer's parallel supernodal kernels
//! split the work by the number of threads, which changes the rounding, so results would
//! depend on the thread count.

use crate::sparse::SymmetricCsr;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Par, Side};

/// Errors of the sparse factorizations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FactorError {
    /// The matrix is not symmetric positive definite (e.g. an unconstrained structure, a dof
    /// without mass), or the factor does not fit in memory.
    #[error("sparse Cholesky factorization failed: {0}")]
    Factor(String),
}

const PAR: Par = Par::Seq;

fn pattern(a: &SymmetricCsr) -> SymbolicSparseColMatRef<'_, usize> {
    // both triangles stored: the compressed rows are the compressed columns of Aᵀ = A
    SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.row_ptr, None, &a.col_idx)
}

/// The symbolic Cholesky factorization (AMD ordering) of the pattern of `a`; `simplicial`
/// forces the column-by-column (simplicial) layout, whose factor is a plain compressed-column
/// matrix.
fn symbolic_of(a: &SymmetricCsr, simplicial: bool) -> Result<SymbolicCholesky<usize>, FactorError> {
    let params = if simplicial {
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        }
    } else {
        Default::default()
    };
    factorize_symbolic_cholesky(pattern(a), Side::Lower, Default::default(), params)
        .map_err(|e| FactorError::Factor(format!("{e:?}")))
}

/// Numeric $LL^T$ factorization into `factor` of the matrix with `a`'s pattern and the
/// entries `values` (`a.values`, or those rounded to another precision).
fn factorize_numeric<T: faer::traits::ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    factor: &mut Vec<T>,
    a: &SymmetricCsr,
    values: &[T],
) -> Result<(), FactorError> {
    factor.resize(symbolic.len_val(), T::zero_impl());
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<T>(PAR, Default::default()))
            .map_err(|e| FactorError::Factor(format!("{e:?}")))?;
    symbolic
        .factorize_numeric_llt::<T>(
            factor,
            SparseColMatRef::new(pattern(a), values),
            Side::Lower,
            Default::default(),
            PAR,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| FactorError::Factor(format!("{e:?}")))?;
    Ok(())
}

/// Whether `a` is positive definite: its $LL^T$ factorization succeeds (every pivot positive).
pub fn is_positive_definite(a: &SymmetricCsr) -> bool {
    Cholesky::new(a).is_ok()
}

/// A sparse Cholesky factorization of a [`SymmetricCsr`] in double precision.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    n: usize,
}

impl Cholesky {
    /// Factorizes `a` (symbolic and numeric).
    ///
    /// # Errors
    /// `a` is not positive definite.
    pub fn new(a: &SymmetricCsr) -> Result<Self, FactorError> {
        Self::with_layout(a, false)
    }

    fn with_layout(a: &SymmetricCsr, simplicial: bool) -> Result<Self, FactorError> {
        let mut c = Self {
            symbolic: symbolic_of(a, simplicial)?,
            values: Vec::new(),
            n: a.n,
        };
        c.refactor(a)?;
        Ok(c)
    }

    /// Numeric refactorization of a matrix with the same pattern.
    ///
    /// # Errors
    /// `a` is not positive definite.
    pub fn refactor(&mut self, a: &SymmetricCsr) -> Result<(), FactorError> {
        factorize_numeric(&self.symbolic, &mut self.values, a, &a.values)
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Stored entries of the factor.
    pub fn nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Solves `A x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, PAR));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(b, n, 1),
            PAR,
            MemStack::new(&mut mem),
        );
    }
}

/// A Cholesky factor $A = P^T L L^T P$ kept as an explicit compressed-column `L` with its
/// permutation, for products with the factor itself ($x \mapsto P^T L x$, $x \mapsto L^T P x$):
/// the symmetrisation of a generalized eigenproblem by the factor of its mass matrix
/// ([`crate::eigen`]). The factorization is faer's, forced to the simplicial layout.
pub struct ExplicitFactor {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// `fwd[i]`: the original index of permuted row i.
    fwd: Vec<usize>,
    n: usize,
}

impl ExplicitFactor {
    /// Factorizes `a`.
    ///
    /// # Errors
    /// `a` is not positive definite.
    pub fn new(a: &SymmetricCsr) -> Result<Self, FactorError> {
        let c = Cholesky::with_layout(a, true)?;
        let SymbolicCholeskyRaw::Simplicial(s) = c.symbolic.raw() else {
            return Err(FactorError::Factor(
                "a simplicial factor was requested".into(),
            ));
        };
        let fwd = match c.symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..a.n).collect(),
        };
        Ok(Self {
            col_ptr: s.col_ptr().to_vec(),
            row_idx: s.row_idx().to_vec(),
            values: c.values,
            fwd,
            n: a.n,
        })
    }

    /// `y = Pᵀ L x` (`x` in the factor's ordering, `y` in the matrix's).
    pub fn mul_l(&self, x: &[f64], y: &mut [f64], scratch: &mut [f64]) {
        scratch[..self.n].fill(0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                scratch[self.row_idx[k]] += self.values[k] * xj;
            }
        }
        for (i, &s) in scratch.iter().enumerate().take(self.n) {
            y[self.fwd[i]] = s;
        }
    }

    /// `y = Lᵀ P x` (`x` in the matrix's ordering, `y` in the factor's).
    pub fn mul_lt(&self, x: &[f64], y: &mut [f64]) {
        for (j, y) in y.iter_mut().enumerate().take(self.n) {
            let mut s = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                s += self.values[k] * x[self.fwd[self.row_idx[k]]];
            }
            *y = s;
        }
    }
}

/// A sparse Cholesky factorization stored in single precision, for modified Newton
/// iterations: there the factor is only an approximation of the tangent anyway (the reference
/// tangent), and the residual that decides convergence is evaluated in double precision, so
/// the converged displacement keeps double-precision accuracy, while each solve reads half the
/// bytes (the triangular solves are bound by memory bandwidth: 5.1 M factor entries for the
/// paper's beam, 6.4 ms per double-precision solve).
pub struct SingleCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f32>,
    n: usize,
    rhs: Vec<f32>,
    mem: MemBuffer,
}

impl SingleCholesky {
    /// Factorizes `a` (symbolic and numeric): the entries are rounded to single precision
    /// and factorized in single precision.
    ///
    /// # Errors
    /// `a` is not positive definite (in single precision).
    pub fn new(a: &SymmetricCsr) -> Result<Self, FactorError> {
        let symbolic = symbolic_of(a, false)?;
        let mem = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f32>(1, PAR))
            .map_err(|e| FactorError::Factor(format!("{e:?}")))?;
        let mut c = Self {
            symbolic,
            values: Vec::new(),
            n: a.n,
            rhs: vec![0.0; a.n],
            mem,
        };
        c.refactor(a)?;
        Ok(c)
    }

    /// Numeric refactorization of a matrix with the same pattern.
    ///
    /// # Errors
    /// `a` is not positive definite (in single precision).
    pub fn refactor(&mut self, a: &SymmetricCsr) -> Result<(), FactorError> {
        let single: Vec<f32> = a.values.iter().map(|&v| v as f32).collect();
        factorize_numeric(&self.symbolic, &mut self.values, a, &single)
    }

    /// Solves `A x = b` approximately in place: the right-hand side is scaled by a power of two
    /// to a largest entry of about 1 (a structure at rest has residuals of 1e-46 N and less,
    /// below the single-precision range) and rounded to single precision; the solution is
    /// scaled back and returned in double precision.
    pub fn solve_in_place(&mut self, b: &mut [f64]) {
        let top = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if top == 0.0 || !top.is_finite() {
            // zero stays zero; NaN/∞ pass through for the caller's health check
            b.iter_mut().for_each(|x| *x *= 0.0);
            return;
        }
        let scale = 2f64.powi(-(top.log2().round() as i32));
        for (r, &x) in self.rhs.iter_mut().zip(b.iter()) {
            *r = (x * scale) as f32;
        }
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut self.rhs, self.n, 1),
            PAR,
            MemStack::new(&mut self.mem),
        );
        for (x, &r) in b.iter_mut().zip(&self.rhs) {
            *x = r as f64 / scale;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian plus a diagonal shift, with a long-range coupling (so AMD permutes).
    fn spd(n: usize) -> SymmetricCsr {
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 2.5 + i as f64 * 0.01));
            if i + 1 < n {
                t.push((i + 1, i, -1.0));
            }
        }
        t.push((n - 1, 0, 0.3));
        SymmetricCsr::from_triplets(n, &t, true).unwrap()
    }

    #[test]
    fn cholesky_solves_and_the_explicit_factor_reproduces_the_matrix() {
        let a = spd(40);
        let x: Vec<f64> = (0..40).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b = vec![0.0; 40];
        a.mul(&x, &mut b);
        let c = Cholesky::new(&a).unwrap();
        c.solve_in_place(&mut b);
        for (u, v) in b.iter().zip(&x) {
            assert!((u - v).abs() < 1e-13, "{u} vs {v}");
        }
        // Pᵀ L Lᵀ P x = A x
        let f = ExplicitFactor::new(&a).unwrap();
        let (mut z, mut y, mut s) = (vec![0.0; 40], vec![0.0; 40], vec![0.0; 40]);
        f.mul_lt(&x, &mut z);
        f.mul_l(&z, &mut y, &mut s);
        let mut ax = vec![0.0; 40];
        a.mul(&x, &mut ax);
        for (u, v) in y.iter().zip(&ax) {
            assert!((u - v).abs() < 1e-13, "{u} vs {v}");
        }
        let mut single = SingleCholesky::new(&a).unwrap();
        let mut b = ax.clone();
        single.solve_in_place(&mut b);
        for (u, v) in b.iter().zip(&x) {
            assert!((u - v).abs() < 1e-5, "{u} vs {v}");
        }
    }

    #[test]
    fn an_indefinite_matrix_is_refused() {
        let a =
            SymmetricCsr::from_triplets(2, &[(0, 0, 1.0), (1, 0, 2.0), (1, 1, 1.0)], true).unwrap();
        assert!(!is_positive_definite(&a));
        assert!(is_positive_definite(&spd(5)));
    }
}
