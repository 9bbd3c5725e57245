//! Symmetric sparse matrices in compressed rows (equal to compressed columns for symmetric
//! storage) and their sparse Cholesky factorization with faer (supernodal/simplicial $LL^\top$,
//! AMD ordering; the symbolic factorization is computed once and reused).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Par, Side};

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

    /// `y = A x`. Rows in parallel (each row's sum in the same order for any thread count).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        y[..self.n]
            .par_iter_mut()
            .with_min_len(2048)
            .enumerate()
            .for_each(|(r, y)| {
                let mut s = 0.0;
                for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                    s += self.values[k] * x[self.col_idx[k]];
                }
                *y = s;
            });
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

/// A sparse Cholesky factorization of a [`CsrMatrix`]. Factorization and solves run
/// sequentially (`Par::Seq`): faer's parallel supernodal kernels split the work by the number
/// of threads, which changes the rounding, so that results would depend on the thread count.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    n: usize,
}

const PAR: Par = Par::Seq;

/// The symbolic Cholesky factorization (AMD ordering) of the pattern of `a`.
fn symbolic_of(a: &CsrMatrix) -> Result<SymbolicCholesky<usize>, SolverError> {
    let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.row_ptr, None, &a.col_idx);
    factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), Default::default())
        .map_err(|e| SolverError::Factor(format!("{e:?}")))
}

/// Numeric $LL^\top$ factorization into `factor` of the matrix with `a`'s pattern and the
/// entries `values` (`a.values`, or those rounded to another precision).
fn factorize_numeric<T: faer::traits::ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    factor: &mut Vec<T>,
    a: &CsrMatrix,
    values: &[T],
) -> Result<(), SolverError> {
    let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.row_ptr, None, &a.col_idx);
    factor.resize(symbolic.len_val(), T::zero_impl());
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<T>(PAR, Default::default()))
            .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
    symbolic
        .factorize_numeric_llt::<T>(
            factor,
            SparseColMatRef::new(sym, values),
            Side::Lower,
            Default::default(),
            PAR,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
    Ok(())
}

impl Cholesky {
    /// Factorizes `a` (symbolic and numeric).
    pub fn new(a: &CsrMatrix) -> Result<Self, SolverError> {
        let mut c = Self {
            symbolic: symbolic_of(a)?,
            values: Vec::new(),
            n: a.n,
        };
        c.refactor(a)?;
        Ok(c)
    }

    /// Numeric refactorization of a matrix with the same pattern.
    pub fn refactor(&mut self, a: &CsrMatrix) -> Result<(), SolverError> {
        factorize_numeric(&self.symbolic, &mut self.values, a, &a.values)
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

/// A sparse Cholesky factorization stored in single precision, for the modified Newton
/// iterations of [`super::gen_alpha`]: there the factor is only an approximation of the
/// tangent anyway (the reference tangent), and the residual that decides convergence is
/// evaluated in double precision, so the converged displacement keeps double-precision
/// accuracy, while each solve reads half the bytes (the triangular solves are bound by memory
/// bandwidth: 5.1 M factor entries for the paper's beam, 6.4 ms per double-precision solve).
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
    pub fn new(a: &CsrMatrix) -> Result<Self, SolverError> {
        let symbolic = symbolic_of(a)?;
        let mem = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f32>(1, PAR))
            .map_err(|e| SolverError::Factor(format!("{e:?}")))?;
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
    pub fn refactor(&mut self, a: &CsrMatrix) -> Result<(), SolverError> {
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
