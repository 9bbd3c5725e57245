//! Lowest eigenpairs of $\mathbf K_0\boldsymbol\phi = \omega^2\mathbf M\boldsymbol\phi$ by
//! subspace iteration with a sparse Cholesky factor of $\mathbf K_0$ and a Jacobi
//! Rayleigh–Ritz step (M-orthonormal basis).

use super::sparse::{Cholesky, SolverError};
use super::structure::Structure;

/// Jacobi eigenvalues/vectors of a small symmetric matrix (row-major `n × n`); eigenvectors
/// in the columns of the returned matrix.
pub fn jacobi_eigen(a: &mut [f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|(i, j)| i != j)
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i].powi(2)).sum();
        if off <= 1e-30 * diag.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

/// Eigenfrequencies \[Hz\] (ascending) and mode shapes (all dofs) of the `count` lowest modes.
pub fn lowest_modes(
    s: &Structure,
    count: usize,
    iterations: usize,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), SolverError> {
    let nf = s.free_dofs.len();
    let p = (2 * count).max(count + 4).min(nf);
    let k = Cholesky::new(&s.k0)?;
    // deterministic start vectors
    let mut x: Vec<Vec<f64>> = (0..p)
        .map(|j| {
            (0..nf)
                .map(|i| {
                    (((i * (j + 3) * 7919 + j * 104_729) % 1000) as f64 / 1000.0) - 0.5
                        + if i % p == j { 1.0 } else { 0.0 }
                })
                .collect()
        })
        .collect();
    let mut mx = vec![0.0; nf];
    let mut lam = vec![0.0; p];
    for _ in 0..iterations {
        // y = K⁻¹ M x
        for xj in x.iter_mut() {
            s.mass.mul(xj, &mut mx);
            k.solve_in_place(&mut mx);
            xj.copy_from_slice(&mx);
        }
        // M-orthonormalize (modified Gram–Schmidt, twice)
        for _ in 0..2 {
            for j in 0..p {
                for i in 0..j {
                    s.mass.mul(&x[i], &mut mx);
                    let c: f64 = mx.iter().zip(&x[j]).map(|(a, b)| a * b).sum();
                    let xi = x[i].clone();
                    for (a, b) in x[j].iter_mut().zip(&xi) {
                        *a -= c * b;
                    }
                }
                let nrm = s.mass.quad(&x[j]).sqrt();
                x[j].iter_mut().for_each(|a| *a /= nrm);
            }
        }
        // Rayleigh–Ritz
        let mut kr = vec![0.0; p * p];
        for j in 0..p {
            s.k0.mul(&x[j], &mut mx);
            for i in 0..p {
                kr[i * p + j] = mx.iter().zip(&x[i]).map(|(a, b)| a * b).sum();
            }
        }
        for i in 0..p {
            for j in 0..i {
                let m = 0.5 * (kr[i * p + j] + kr[j * p + i]);
                kr[i * p + j] = m;
                kr[j * p + i] = m;
            }
        }
        let (ev, vecs) = jacobi_eigen(&mut kr, p);
        let mut order: Vec<usize> = (0..p).collect();
        order.sort_by(|&a, &b| ev[a].total_cmp(&ev[b]));
        let xn: Vec<Vec<f64>> = order
            .iter()
            .map(|&c| {
                let mut y = vec![0.0; nf];
                for (i, xi) in x.iter().enumerate() {
                    let w = vecs[i * p + c];
                    for (a, b) in y.iter_mut().zip(xi) {
                        *a += w * b;
                    }
                }
                y
            })
            .collect();
        x = xn;
        let new: Vec<f64> = order.iter().map(|&c| ev[c]).collect();
        let conv = new
            .iter()
            .zip(&lam)
            .take(count)
            .all(|(a, b)| ((a - b) / a).abs() < 1e-12);
        lam = new;
        if conv {
            break;
        }
    }
    let f = lam
        .iter()
        .take(count)
        .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let shapes = x
        .iter()
        .take(count)
        .map(|xf| {
            let mut full = vec![0.0; s.n_dof()];
            for (k, &g) in s.free_dofs.iter().enumerate() {
                full[g] = xf[k];
            }
            full
        })
        .collect();
    Ok((f, shapes))
}
