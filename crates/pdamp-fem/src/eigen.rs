//! The lowest modes of the generalized eigenproblem $(K - \omega^2 M)\phi = 0$ [D Eq. 3.20],
//! mass-normalised ($\Phi^T M \Phi = E$), rigid-body modes below a threshold dropped.
//!
//! **Sparse models** ([`lowest_modes`]): shift-invert with $A = K - \sigma M$, σ < 0 below the
//! spectrum, so that A is positive definite also for free–free models with rigid-body modes
//! (faer sparse Cholesky, [`crate::factor::Cholesky`]). With the Cholesky factor of the mass
//! matrix $M = L_M L_M^T$ the pencil becomes the symmetric operator
//! $C = |\sigma|\, L_M^T A^{-1} L_M$ with eigenvalues $\theta = |\sigma|/(\lambda - \sigma) \in
//! (0, 1]$, largest for the lowest modes, whose dominant eigenpairs faer's Krylov–Schur
//! (restarted Lanczos) eigensolver computes; $\phi = A^{-1} L_M y / \theta$. A Rayleigh–Ritz
//! refinement on $\bar X = A^{-1} M \Phi$ ($\bar X^T A \bar X z = \mu \bar X^T M \bar X z$,
//! $\lambda = \mu + \sigma$, with $A\bar X = M\Phi$ so that no product with K enters, whose
//! round-off on stiff beam rotations would limit the eigenvalues to ~1e-7) is repeated until
//! the dual-norm residual $\|\phi - \mu A^{-1} M \phi\|_M$ of every wanted pair is below 1e-10
//! or its eigenvalue has stagnated (change < 1e-11 relative twice: the solves' round-off floors
//! the residual on stiff models).
//!
//! **Small models** ([`dense_lowest_modes`]): with the dense Cholesky factor $M = L L^T$ the
//! standard symmetric problem $L^{-1} K L^{-T} y = \omega^2 y$, $\phi = L^{-T} y$, by faer's
//! dense self-adjoint eigensolver.

use crate::factor::{Cholesky, ExplicitFactor, FactorError};
use crate::sparse::SymmetricCsr;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::LinOp;
use faer::{Mat, MatMut, MatRef, Par, Side};
use std::f64::consts::TAU;

/// Errors of the eigensolvers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// K and M differ in size or are not square.
    #[error("K is {k}×{k}, M is {m}×{m}: both must be square and equal")]
    Sizes {
        /// Size of K.
        k: usize,
        /// Size of M.
        m: usize,
    },
    /// An empty model or no modes requested.
    #[error("empty model (no active dof) or no modes requested")]
    Empty,
    /// A non-finite entry of K or M.
    #[error("K or M has non-finite entries")]
    NotFinite,
    /// The mass matrix has a non-positive pivot.
    #[error(
        "the mass matrix is not positive definite (a dof has stiffness but no mass: add rotary \
         inertia or a point mass, or fix the dof)"
    )]
    MassNotPositiveDefinite,
    /// The shifted stiffness $K - \sigma M$ (σ < 0) has a non-positive pivot.
    #[error(
        "K − σM with σ = {sigma:e} 1/s² is not positive definite ({source}): the stiffness \
         matrix has a negative eigenvalue or the model a dof without stiffness and mass"
    )]
    Shifted {
        /// The shift, 1/s².
        sigma: f64,
        /// The factorization's error.
        source: FactorError,
    },
    /// Every mode found lies below the lowest frequency kept.
    #[error("no mode above {min_frequency_hz} Hz")]
    NoMode {
        /// The lowest frequency kept, Hz.
        min_frequency_hz: f64,
    },
    /// The iterated vectors became linearly dependent.
    #[error("the eigensolver's vectors became linearly dependent")]
    Dependent,
    /// An iteration did not converge.
    #[error("the eigensolver did not converge ({0})")]
    NotConverged(String),
}

/// The lowest modes of a generalized eigenproblem.
#[derive(Debug, Clone)]
pub struct Modes {
    /// Angular eigenfrequencies ω_k, rad/s (ascending).
    pub omega_rad_s: Vec<f64>,
    /// Mass-normalised mode shapes Φ (n × modes), each with its largest component positive.
    pub shapes: Mat<f64>,
}

/// Dual-norm residual ‖φ − (λ − σ)A⁻¹Mφ‖_M (φ M-normalised) at which a wanted pair counts
/// as converged; the eigenvalue error is of its square.
const RESIDUAL_TOLERANCE: f64 = 1e-10;

/// [`lowest_modes`] solves models up to this many dof densely.
pub const DENSE_UP_TO_DOF: usize = 128;

/// Refinement steps allowed after the Krylov–Schur start.
const MAX_REFINEMENTS: usize = 60;

/// The shift-inverted, symmetrised pencil $C = |\sigma| L_M^T P A^{-1} P^T L_M$.
struct ShiftInvert<'a> {
    a: &'a Cholesky,
    lm: &'a ExplicitFactor,
    scale: f64,
}

impl std::fmt::Debug for ShiftInvert<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ShiftInvert(n = {})", self.a.n())
    }
}

impl LinOp<f64> for ShiftInvert<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.a.n()
    }
    fn ncols(&self) -> usize {
        self.a.n()
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _: &mut MemStack) {
        let n = self.a.n();
        let (mut u, mut s, mut x) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for c in 0..rhs.ncols() {
            for (i, x) in x.iter_mut().enumerate() {
                *x = rhs[(i, c)];
            }
            self.lm.mul_l(&x, &mut u, &mut s);
            self.a.solve_in_place(&mut u);
            self.lm.mul_lt(&u, &mut s);
            for (i, v) in s.iter().enumerate() {
                out[(i, c)] = self.scale * v;
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, st: &mut MemStack) {
        self.apply(out, rhs, par, st);
    }
}

/// Deterministic pseudo-random entries in [−0.5, 0.5).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Lowest `n_modes` modes with f ≥ `min_frequency_hz` of sparse K, M (module documentation).
/// Rigid-body modes below the threshold are computed and dropped (up to six are allowed for;
/// more widen the search automatically).
///
/// # Errors
/// Size mismatch, an empty model, a mass matrix or shifted stiffness that is not positive
/// definite, or no convergence.
pub fn lowest_modes(
    stiffness: &SymmetricCsr,
    mass: &SymmetricCsr,
    n_modes: usize,
    min_frequency_hz: f64,
) -> Result<Modes, EigenError> {
    let n = stiffness.n;
    if mass.n != n {
        return Err(EigenError::Sizes { k: n, m: mass.n });
    }
    if n == 0 || n_modes == 0 {
        return Err(EigenError::Empty);
    }
    let dense = || {
        let (k, m) = (stiffness.to_dense(), mass.to_dense());
        dense_lowest_modes(k.as_ref(), m.as_ref(), n_modes, min_frequency_hz)
    };
    if n <= DENSE_UP_TO_DOF {
        return dense();
    }
    let sigma = -(TAU * min_frequency_hz.max(0.1)).powi(2);
    let a = Cholesky::new(&stiffness.shifted(sigma, mass))
        .map_err(|source| EigenError::Shifted { sigma, source })?;
    let lm = ExplicitFactor::new(mass).map_err(|_| EigenError::MassNotPositiveDefinite)?;
    let op = ShiftInvert {
        a: &a,
        lm: &lm,
        scale: -sigma,
    };
    let lambda_drop = (TAU * min_frequency_hz).powi(2);
    let mut extra = 6usize; // allowance for modes below min_frequency_hz
    loop {
        let p = n_modes + extra;
        if 2 * p.max(32) >= n {
            // faer's Krylov–Schur needs a search space (2p vectors) smaller than the problem
            return dense();
        }
        let (lams, phis) = krylov_schur(&op, mass, p)?;
        let (lams, phis) = refine(&a, mass, sigma, lambda_drop, n_modes, lams, phis)?;
        let mut omegas = Vec::new();
        let mut cols = Vec::new();
        for (lam, phi) in lams.iter().zip(phis) {
            let w = lam.max(0.0).sqrt();
            if w / TAU < min_frequency_hz {
                continue;
            }
            if omegas.len() == n_modes {
                break;
            }
            omegas.push(w);
            cols.push(phi);
        }
        if omegas.len() == n_modes {
            return Ok(Modes {
                omega_rad_s: omegas,
                shapes: columns(n, cols),
            });
        }
        extra *= 2;
    }
}

/// Mode-shape columns as a matrix, each with its largest component positive.
fn columns(n: usize, cols: Vec<Vec<f64>>) -> Mat<f64> {
    let signs: Vec<f64> = cols
        .iter()
        .map(|c| {
            let imax = (0..n).fold(0, |b, k| if c[k].abs() > c[b].abs() { k } else { b });
            if c[imax] < 0.0 { -1.0 } else { 1.0 }
        })
        .collect();
    Mat::from_fn(n, cols.len(), |i, j| signs[j] * cols[j][i])
}

/// The `p` dominant eigenpairs of the shift-inverted operator (faer Krylov–Schur) as
/// eigenvalues λ (ascending) and M-normalised vectors.
fn krylov_schur(
    op: &ShiftInvert<'_>,
    mass: &SymmetricCsr,
    p: usize,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), EigenError> {
    use faer::matrix_free::eigen::{
        PartialEigenParams, partial_self_adjoint_eigen, partial_self_adjoint_eigen_scratch,
    };
    let n = op.a.n();
    let params = PartialEigenParams {
        max_restarts: 2000,
        ..Default::default()
    };
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let v0 = faer::Col::<f64>::from_fn(n, |_| 1.0 + lcg(&mut state));
    let mut vecs = Mat::<f64>::zeros(n, p);
    let mut vals = vec![0.0; p];
    let mut mem = MemBuffer::new(partial_self_adjoint_eigen_scratch::<f64>(
        op,
        p,
        Par::Seq,
        params,
    ));
    let info = partial_self_adjoint_eigen(
        vecs.as_mut(),
        &mut vals,
        op,
        v0.as_ref(),
        1e-13,
        Par::Seq,
        MemStack::new(&mut mem),
        params,
    );
    if info.n_converged_eigen < p {
        return Err(EigenError::NotConverged(format!(
            "Krylov–Schur: {} of {p} eigenpairs of the shift-inverted pencil",
            info.n_converged_eigen
        )));
    }
    let mut pairs: Vec<(f64, Vec<f64>)> = Vec::with_capacity(p);
    let (mut u, mut s) = (vec![0.0; n], vec![0.0; n]);
    let sigma = -op.scale;
    for (j, &theta) in vals.iter().enumerate() {
        if theta <= 0.0 {
            return Err(EigenError::Dependent);
        }
        let y: Vec<f64> = (0..n).map(|i| vecs[(i, j)]).collect();
        op.lm.mul_l(&y, &mut u, &mut s);
        op.a.solve_in_place(&mut u);
        let nrm = mass.quad(&u).max(0.0).sqrt();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return Err(EigenError::Dependent);
        }
        u.iter_mut().for_each(|v| *v /= nrm);
        pairs.push((sigma + op.scale / theta, u.clone()));
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(pairs.into_iter().unzip())
}

/// Rayleigh–Ritz refinement of the pairs (`lams`, `phis`) on $\bar X = A^{-1} M \Phi$ until the
/// first `wanted` pairs at or above `lambda_drop` have converged (module documentation).
fn refine(
    a: &Cholesky,
    m: &SymmetricCsr,
    sigma: f64,
    lambda_drop: f64,
    wanted: usize,
    mut lams: Vec<f64>,
    mut phis: Vec<Vec<f64>>,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), EigenError> {
    let (n, p) = (m.n, phis.len());
    let mut stagnant = vec![0usize; p];
    let mut mx = vec![0.0; n];
    for _ in 0..MAX_REFINEMENTS {
        // Ȳ = MΦ, X̄ = A⁻¹Ȳ
        let ys: Vec<Vec<f64>> = phis
            .iter()
            .map(|phi| {
                let mut y = vec![0.0; n];
                m.mul(phi, &mut y);
                y
            })
            .collect();
        let xs: Vec<Vec<f64>> = ys
            .iter()
            .map(|y| {
                let mut x = y.clone();
                a.solve_in_place(&mut x);
                x
            })
            .collect();
        let converged = (0..p)
            .filter(|&i| lams[i] >= lambda_drop)
            .take(wanted)
            .all(|i| {
                if stagnant[i] >= 2 {
                    return true;
                }
                let mu = lams[i] - sigma;
                let d: Vec<f64> = xs[i]
                    .iter()
                    .zip(&phis[i])
                    .map(|(x, f)| mu * x - f)
                    .collect();
                m.quad(&d).max(0.0).sqrt() <= RESIDUAL_TOLERANCE
            });
        if converged {
            return Ok((lams, phis));
        }
        // scale X̄ to unit M-norm (rigid-body columns are amplified by 1/(λ − σ))
        let mut xs = xs;
        let mut ys = ys;
        for (x, y) in xs.iter_mut().zip(ys.iter_mut()) {
            m.mul(x, &mut mx);
            let nrm = dot(x, &mx).max(0.0).sqrt();
            if !(nrm > 0.0 && nrm.is_finite()) {
                return Err(EigenError::Dependent);
            }
            x.iter_mut().for_each(|v| *v /= nrm);
            y.iter_mut().for_each(|v| *v /= nrm);
        }
        // Â = X̄ᵀ A X̄ = X̄ᵀ MΦ, B̂ = X̄ᵀ M X̄
        let mxs: Vec<Vec<f64>> = xs
            .iter()
            .map(|x| {
                let mut v = vec![0.0; n];
                m.mul(x, &mut v);
                v
            })
            .collect();
        let ah = Mat::<f64>::from_fn(p, p, |i, j| {
            0.5 * (dot(&xs[i], &ys[j]) + dot(&xs[j], &ys[i]))
        });
        let bh = Mat::<f64>::from_fn(p, p, |i, j| {
            0.5 * (dot(&xs[i], &mxs[j]) + dot(&xs[j], &mxs[i]))
        });
        let (mu, z) = dense_pencil(ah.as_ref(), bh.as_ref()).ok_or(EigenError::Dependent)?;
        let new: Vec<f64> = mu.iter().map(|m| m + sigma).collect();
        for i in 0..p {
            let rel = ((new[i] - lams[i]) / new[i]).abs();
            stagnant[i] = if rel < 1e-11 { stagnant[i] + 1 } else { 0 };
        }
        lams = new;
        phis = (0..p)
            .map(|c| {
                let mut v = vec![0.0; n];
                for (r, x) in xs.iter().enumerate() {
                    let w = z[(r, c)];
                    v.iter_mut().zip(x).for_each(|(a, b)| *a += w * b);
                }
                v
            })
            .collect();
    }
    Err(EigenError::NotConverged(format!(
        "Rayleigh–Ritz refinement: residual above {RESIDUAL_TOLERANCE:e} after \
         {MAX_REFINEMENTS} steps"
    )))
}

/// Eigenvalues (ascending) and orthonormal eigenvectors of a dense symmetric matrix (lower
/// triangle read), by faer's tridiagonalization and implicit QR iteration.
///
/// faer's divide-and-conquer stage (its default from 128 rows) returned eigenvectors with
/// residuals ‖Su − λu‖/‖S‖ of 8e-4 on the symmetrised pencil of a 648-dof hex8 cantilever
/// (faer 0.24.4; the eigenvalues alone were right, QR gives 1e-15), so the recursion threshold
/// is set beyond every size: QR throughout, O(n³) like the LAPACK `dsyev` path.
pub fn symmetric_evd(s: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    use faer::linalg::evd::{
        ComputeEigenvectors, SelfAdjointEvdParams, self_adjoint_evd, self_adjoint_evd_scratch,
    };
    let n = s.nrows();
    let params = SelfAdjointEvdParams {
        recursion_threshold: usize::MAX,
        ..<SelfAdjointEvdParams as faer::Auto<f64>>::auto()
    };
    let mut mem = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        params.into(),
    ));
    let mut d = faer::Col::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    self_adjoint_evd(
        s,
        d.as_mut().as_diagonal_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        params.into(),
    )
    .ok()?;
    Some(((0..n).map(|i| d[i]).collect(), u))
}

/// Eigenvalues (ascending) and B-orthonormal eigenvectors of the dense symmetric-definite
/// pencil $A z = \mu B z$, by faer: $B = LL^T$, $L^{-1} A L^{-T} y = \mu y$, $z = L^{-T} y$.
/// `None` if B is not positive definite or the eigensolver fails.
fn dense_pencil(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
    // faer's dense kernels read both triangles of a "self-adjoint" matrix in places (blocked
    // steps): the inputs are symmetrised exactly first
    let sym = |a: MatRef<'_, f64>| {
        Mat::<f64>::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
    };
    let b = sym(b);
    let llt = b.llt(Side::Lower).ok()?;
    let l = llt.L();
    let mut s = sym(a);
    solve_lower_triangular_in_place(l, s.as_mut(), Par::Seq);
    let mut s = s.transpose().to_owned();
    solve_lower_triangular_in_place(l, s.as_mut(), Par::Seq);
    let s = Mat::<f64>::from_fn(s.nrows(), s.ncols(), |i, j| 0.5 * (s[(i, j)] + s[(j, i)]));
    let (mu, mut z) = symmetric_evd(s.as_ref())?;
    solve_upper_triangular_in_place(l.transpose(), z.as_mut(), Par::Seq);
    Some((mu, z))
}

/// Lowest `n_modes` modes with f ≥ `min_frequency_hz` of dense K, M (module documentation).
///
/// # Errors
/// Non-square or mismatched matrices, non-finite entries, or a mass matrix that is not
/// positive definite (a dof with stiffness but no mass).
pub fn dense_lowest_modes(
    stiffness: MatRef<'_, f64>,
    mass: MatRef<'_, f64>,
    n_modes: usize,
    min_frequency_hz: f64,
) -> Result<Modes, EigenError> {
    let n = stiffness.nrows();
    if stiffness.ncols() != n || mass.nrows() != n || mass.ncols() != n {
        return Err(EigenError::Sizes {
            k: n,
            m: mass.nrows(),
        });
    }
    if n == 0 || n_modes == 0 {
        return Err(EigenError::Empty);
    }
    let finite = |a: MatRef<'_, f64>| (0..n).all(|j| (0..n).all(|i| a[(i, j)].is_finite()));
    if !finite(stiffness) || !finite(mass) {
        return Err(EigenError::NotFinite);
    }
    if mass.llt(Side::Lower).is_err() {
        return Err(EigenError::MassNotPositiveDefinite);
    }
    let (lams, z) = dense_pencil(stiffness, mass).ok_or(EigenError::MassNotPositiveDefinite)?;
    let mut omegas = Vec::new();
    let mut cols = Vec::new();
    for (j, &lam) in lams.iter().enumerate() {
        let w = lam.max(0.0).sqrt();
        if w / TAU < min_frequency_hz {
            continue;
        }
        if omegas.len() == n_modes {
            break;
        }
        omegas.push(w);
        cols.push((0..n).map(|i| z[(i, j)]).collect());
    }
    if cols.is_empty() {
        return Err(EigenError::NoMode { min_frequency_hz });
    }
    Ok(Modes {
        omega_rad_s: omegas,
        shapes: columns(n, cols),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fixed–free chain of `n` unit masses and unit springs: ω_k = 2 sin((2k − 1)π/(2(2n + 1))).
    fn chain(n: usize, lumped: bool) -> (SymmetricCsr, SymmetricCsr) {
        let mut k = Vec::new();
        let mut m = Vec::new();
        for i in 0..n {
            k.push((i, i, if i + 1 < n { 2.0 } else { 1.0 }));
            if i + 1 < n {
                k.push((i + 1, i, -1.0));
            }
            m.push((i, i, 1.0));
        }
        if !lumped {
            // a consistent-mass-like coupling that keeps M positive definite
            m.iter_mut().for_each(|e| e.2 = 0.8);
            for i in 0..n - 1 {
                m.push((i + 1, i, 0.1));
            }
        }
        (
            SymmetricCsr::from_triplets(n, &k, true).unwrap(),
            SymmetricCsr::from_triplets(n, &m, true).unwrap(),
        )
    }

    #[test]
    fn chain_frequencies_match_the_closed_form() {
        let n = 400;
        let (k, m) = chain(n, true);
        let modes = lowest_modes(&k, &m, 5, 0.0).unwrap();
        for (i, w) in modes.omega_rad_s.iter().enumerate() {
            let exact = 2.0
                * ((2.0 * (i + 1) as f64 - 1.0) * std::f64::consts::PI
                    / (2.0 * (2 * n + 1) as f64))
                    .sin();
            assert!((w / exact - 1.0).abs() < 1e-10, "mode {i}: {w} vs {exact}");
            // mass-normalised
            let phi: Vec<f64> = (0..n).map(|r| modes.shapes[(r, i)]).collect();
            assert!((m.quad(&phi) - 1.0).abs() < 1e-10);
        }
    }

    #[test]
    fn sparse_and_dense_agree_with_a_consistent_mass() {
        let n = 300;
        let (k, m) = chain(n, false);
        let sp = lowest_modes(&k, &m, 6, 0.0).unwrap();
        let dense = |a: &SymmetricCsr| {
            Mat::<f64>::from_fn(n, n, |i, j| {
                let (c, v) = a.row(i);
                c.binary_search(&j).map(|x| v[x]).unwrap_or(0.0)
            })
        };
        let de = dense_lowest_modes(dense(&k).as_ref(), dense(&m).as_ref(), 6, 0.0).unwrap();
        for i in 0..6 {
            let d = sp.omega_rad_s[i] / de.omega_rad_s[i] - 1.0;
            // the dense solver's round-off is ε·λ_max/λ_1 ≈ 1.5e5·ε ≈ 3e-11 relative here
            assert!(d.abs() < 1e-9, "mode {i}: {d:e}");
            let c: f64 = (0..n)
                .map(|r| sp.shapes[(r, i)] - de.shapes[(r, i)])
                .map(f64::abs)
                .sum();
            assert!(c < 1e-7, "mode {i}: shapes differ by {c}");
        }
    }

    #[test]
    fn a_free_chain_drops_its_rigid_mode_and_a_massless_dof_is_refused() {
        let n = 300;
        let mut t = Vec::new();
        for i in 0..n - 1 {
            t.extend([(i, i, 1.0), (i + 1, i + 1, 1.0), (i + 1, i, -1.0)]);
        }
        let k = SymmetricCsr::from_triplets(n, &t, true).unwrap();
        let m =
            SymmetricCsr::from_triplets(n, &(0..n).map(|i| (i, i, 1.0)).collect::<Vec<_>>(), false)
                .unwrap();
        let modes = lowest_modes(&k, &m, 2, 1e-4).unwrap();
        // free–free chain: ω_k = 2 sin(kπ/(2n)), k ≥ 1
        for (i, w) in modes.omega_rad_s.iter().enumerate() {
            let exact = 2.0 * (((i + 1) as f64) * std::f64::consts::PI / (2.0 * n as f64)).sin();
            assert!((w / exact - 1.0).abs() < 1e-10, "mode {i}: {w} vs {exact}");
        }
        let m0 =
            SymmetricCsr::from_triplets(n, &(1..n).map(|i| (i, i, 1.0)).collect::<Vec<_>>(), false)
                .unwrap();
        assert_eq!(
            lowest_modes(&k, &m0, 2, 1e-4).unwrap_err(),
            EigenError::MassNotPositiveDefinite
        );
    }
}
