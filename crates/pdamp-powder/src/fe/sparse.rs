//! Symmetric sparse matrices in compressed rows (equal to compressed columns for symmetric
//! storage) and their sparse Cholesky factorization with faer (supernodal/simplicial $LL^\top$,
//! AMD ordering; the symbolic factorization is computed once and reused).

use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// Square sparse matrix with a fixed pattern (both triangles stored).
#[derive(Debug, Clone, Default)]
pub struct CsrMatrix {
    /// Dimension.
    pub n: usize,
    /// Row pointers (`n + 1`).
    pub row_ptr: Vec<usize>,
    /// Column indices, sorted within each row.
    pub col_idx: Vec<usize>,
    /// Values.
    pub values: Vec<f64>,
}

impl CsrMatrix {
    /// Builds the matrix from (row, col, value) triplets, summing duplicates.
    pub fn from_triplets(n: usize, mut t: Vec<(usize, usize, f64)>) -> Self {
        t.sort_unstable_by_key(|a| (a.0, a.1));
        let mut m = CsrMatrix {
            n,
            row_ptr: vec![0; n + 1],
            ..Default::default()
        };
        let mut last = (usize::MAX, usize::MAX);
        for (r, c, v) in t {
            if (r, c) == last {
                *m.values.last_mut().expect("entry") += v;
            } else {
                m.col_idx.push(c);
                m.values.push(v);
                m.row_ptr[r + 1] += 1;
                last = (r, c);
            }
        }
        for r in 0..n {
            m.row_ptr[r + 1] += m.row_ptr[r];
        }
        m
    }

    /// `y = A x`.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        for r in 0..self.n {
            let mut s = 0.0;
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                s += self.values[k] * x[self.col_idx[k]];
            }
            y[r] = s;
        }
    }

    /// `xᵀ A x`.
    pub fn quad(&self, x: &[f64]) -> f64 {
        let mut s = 0.0;
        for r in 0..self.n {
            let mut t = 0.0;
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                t += self.values[k] * x[self.col_idx[k]];
            }
            s += x[r] * t;
        }
        s
    }

    /// `a·self + b·other` for matrices with the same pattern.
    ///
    /// # Panics
    /// If the patterns differ.
    #[track_caller]
    pub fn combine(&self, a: f64, other: &CsrMatrix, b: f64) -> CsrMatrix {
        assert_eq!(self.col_idx, other.col_idx, "patterns differ");
        let mut m = self.clone();
        for (v, w) in m.values.iter_mut().zip(&other.values) {
            *v = a * *v + b * w;
        }
        m
    }
}

/// Errors of the sparse factorization.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// The matrix is not symmetric positive definite (e.g. an unconstrained structure).
    #[error("sparse Cholesky failed: {0}")]
    Factor(String),
}

/// A sparse Cholesky factorization of a [`CsrMatrix`].
pub struct Cholesky {
    symbolic: SymbolicLlt<usize>,
    llt: Llt<usize, f64>,
    n: usize,
}

impl Cholesky {
    /// Factorizes `a` (symbolic and numeric).
    pub fn new(a: &CsrMatrix) -> Result<Self, SolverError> {
        let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.row_ptr, None, &a.col_idx);
        let symbolic = SymbolicLlt::try_new(sym, Side::Lower)
            .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
        let llt = Llt::try_new_with_symbolic(
            symbolic.clone(),
            SparseColMatRef::new(sym, &a.values),
            Side::Lower,
        )
        .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
        Ok(Self {
            symbolic,
            llt,
            n: a.n,
        })
    }

    /// Numeric refactorization of a matrix with the same pattern.
    pub fn refactor(&mut self, a: &CsrMatrix) -> Result<(), SolverError> {
        let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.row_ptr, None, &a.col_idx);
        self.llt = Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            SparseColMatRef::new(sym, &a.values),
            Side::Lower,
        )
        .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
        Ok(())
    }

    /// Solves `A x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        self.llt
            .solve_in_place(faer::MatMut::from_column_major_slice_mut(b, n, 1));
    }
}
