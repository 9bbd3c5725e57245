//! [`SymmetricCsr`]: the sparse matrix of pdamp's finite elements — a symmetric matrix in
//! compressed rows with both triangles stored (so that a row is also a column, and the same
//! arrays are the compressed-column form faer's factorizations read).

/// Errors of assembling a [`SymmetricCsr`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SparseError {
    /// A triplet lies outside the matrix.
    #[error("entry ({i}, {j}) outside the {n}×{n} matrix")]
    OutsideMatrix {
        /// Row (0-based).
        i: usize,
        /// Column (0-based).
        j: usize,
        /// Size of the matrix.
        n: usize,
    },
    /// A triplet's value is not finite.
    #[error("entry ({i}, {j}) is not finite")]
    NotFinite {
        /// Row (0-based).
        i: usize,
        /// Column (0-based).
        j: usize,
    },
}

/// Symmetric sparse matrix, compressed rows with both triangles stored, column indices
/// ascending within a row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SymmetricCsr {
    /// Dimension.
    pub n: usize,
    /// Row pointers (`n + 1`).
    pub row_ptr: Vec<usize>,
    /// Column indices, ascending within each row.
    pub col_idx: Vec<usize>,
    /// Values.
    pub values: Vec<f64>,
}

impl SymmetricCsr {
    /// From (row, col, value) triplets of the full matrix, or of one triangle with
    /// `mirror = true` (the transpose of every off-diagonal triplet is added). Duplicates are
    /// summed (element assembly).
    ///
    /// # Errors
    /// An index out of range or a non-finite value, named by its (row, column).
    pub fn from_triplets(
        n: usize,
        triplets: &[(usize, usize, f64)],
        mirror: bool,
    ) -> Result<Self, SparseError> {
        let mut t: Vec<(usize, usize, f64)> =
            Vec::with_capacity(triplets.len() * if mirror { 2 } else { 1 });
        for &(i, j, v) in triplets {
            if i >= n || j >= n {
                return Err(SparseError::OutsideMatrix { i, j, n });
            }
            if !v.is_finite() {
                return Err(SparseError::NotFinite { i, j });
            }
            t.push((i, j, v));
            if mirror && i != j {
                t.push((j, i, v));
            }
        }
        // stable sort: duplicates are summed in the order the elements gave them
        t.sort_by_key(|a| (a.0, a.1));
        Ok(Self::compress(n, t))
    }

    /// Assembles element contributions (row, col, value) of the full matrix, duplicates
    /// summed in the order given. For matrices a program computes itself: values are not
    /// checked (a non-finite entry passes through to the solver's health checks).
    ///
    /// # Panics
    /// An index outside the matrix.
    #[track_caller]
    pub fn assemble(n: usize, mut triplets: Vec<(usize, usize, f64)>) -> Self {
        assert!(
            triplets.iter().all(|&(i, j, _)| i < n && j < n),
            "an element entry lies outside the {n}×{n} matrix"
        );
        triplets.sort_by_key(|a| (a.0, a.1));
        Self::compress(n, triplets)
    }

    /// Sorted triplets to compressed rows, duplicates summed.
    fn compress(n: usize, t: Vec<(usize, usize, f64)>) -> Self {
        let mut m = SymmetricCsr {
            n,
            row_ptr: vec![0; n + 1],
            col_idx: Vec::with_capacity(t.len()),
            values: Vec::with_capacity(t.len()),
        };
        let mut last = None;
        for (i, j, v) in t {
            if last == Some((i, j)) {
                *m.values.last_mut().expect("an entry was pushed") += v;
            } else {
                m.col_idx.push(j);
                m.values.push(v);
                m.row_ptr[i + 1] += 1;
                last = Some((i, j));
            }
        }
        for r in 0..n {
            m.row_ptr[r + 1] += m.row_ptr[r];
        }
        m
    }

    /// From a dense symmetric matrix given entrywise (`a(i, j)`, entries equal to 0 omitted).
    ///
    /// # Errors
    /// A non-finite entry.
    pub fn from_dense(n: usize, a: impl Fn(usize, usize) -> f64) -> Result<Self, SparseError> {
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let v = a(i, j);
                if v != 0.0 {
                    t.push((i, j, v));
                }
            }
        }
        Self::from_triplets(n, &t, false)
    }

    /// The dense matrix.
    pub fn to_dense(&self) -> faer::Mat<f64> {
        let mut a = faer::Mat::<f64>::zeros(self.n, self.n);
        for i in 0..self.n {
            let (c, v) = self.row(i);
            for (&j, &x) in c.iter().zip(v) {
                a[(i, j)] = x;
            }
        }
        a
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row `i` as (columns, values).
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        let (a, b) = (self.row_ptr[i], self.row_ptr[i + 1]);
        (&self.col_idx[a..b], &self.values[a..b])
    }

    /// Diagonal entry `a_ii` (0 where none is stored).
    pub fn diagonal(&self, i: usize) -> f64 {
        let (c, v) = self.row(i);
        c.binary_search(&i).map(|k| v[k]).unwrap_or(0.0)
    }

    /// `y = A x`. Rows in parallel; each row's sum runs in the same order for any thread count,
    /// so the result does not depend on it.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        y[..self.n]
            .par_iter_mut()
            .with_min_len(2048)
            .enumerate()
            .for_each(|(r, y)| *y = self.row_dot(r, x));
    }

    /// `(A x)_r`.
    #[inline]
    pub fn row_dot(&self, r: usize, x: &[f64]) -> f64 {
        let mut s = 0.0;
        for k in self.row_ptr[r]..self.row_ptr[r + 1] {
            s += self.values[k] * x[self.col_idx[k]];
        }
        s
    }

    /// `xᵀ A x`.
    pub fn quad(&self, x: &[f64]) -> f64 {
        (0..self.n).map(|r| x[r] * self.row_dot(r, x)).sum()
    }

    /// `a·self + b·other` for matrices with the same pattern.
    ///
    /// # Panics
    /// If the patterns differ.
    #[track_caller]
    pub fn combine(&self, a: f64, other: &SymmetricCsr, b: f64) -> SymmetricCsr {
        assert_eq!(self.col_idx, other.col_idx, "patterns differ");
        let mut m = self.clone();
        for (v, w) in m.values.iter_mut().zip(&other.values) {
            *v = a * *v + b * w;
        }
        m
    }

    /// `self − σ·b` entrywise on the union of the two patterns (the shifted pencil
    /// $K - \sigma M$).
    ///
    /// # Panics
    /// If the sizes differ.
    #[track_caller]
    pub fn shifted(&self, sigma: f64, b: &SymmetricCsr) -> SymmetricCsr {
        assert_eq!(self.n, b.n, "sizes differ");
        let mut t = Vec::with_capacity(self.nnz() + b.nnz());
        for i in 0..self.n {
            let (c, v) = self.row(i);
            t.extend(c.iter().zip(v).map(|(&j, &x)| (i, j, x)));
            let (c, v) = b.row(i);
            t.extend(c.iter().zip(v).map(|(&j, &x)| (i, j, -sigma * x)));
        }
        SymmetricCsr::from_triplets(self.n, &t, false).expect("entries of valid matrices")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triplets_are_summed_mirrored_and_checked() {
        let a = SymmetricCsr::from_triplets(
            3,
            &[
                (0, 0, 2.0),
                (1, 0, -1.0),
                (1, 1, 2.0),
                (0, 0, 1.0),
                (2, 2, 4.0),
            ],
            true,
        )
        .unwrap();
        assert_eq!(a.row_ptr, vec![0, 2, 4, 5]);
        assert_eq!(a.diagonal(0), 3.0);
        assert_eq!(a.row(0), (&[0usize, 1][..], &[3.0, -1.0][..]));
        let mut y = vec![0.0; 3];
        a.mul(&[1.0, 2.0, 3.0], &mut y);
        assert_eq!(y, vec![1.0, 3.0, 12.0]);
        assert_eq!(a.quad(&[1.0, 2.0, 3.0]), 1.0 + 6.0 + 36.0);
        let s = a.shifted(2.0, &a);
        assert_eq!(s.diagonal(2), -4.0);
        assert_eq!(
            SymmetricCsr::from_triplets(2, &[(2, 0, 1.0)], false),
            Err(SparseError::OutsideMatrix { i: 2, j: 0, n: 2 })
        );
        assert_eq!(
            SymmetricCsr::from_triplets(2, &[(1, 0, f64::NAN)], true),
            Err(SparseError::NotFinite { i: 1, j: 0 })
        );
    }
}
