//! Integration-point updates of the materials for the explicit FE solver.
//!
//! Axisymmetric tensors are stored as `[rr, zz, θθ, rz]` (tensor, not engineering, shear). Each
//! update takes the strain increment of a time step Δt and returns the dissipated energy density
//! (J/m³) of the step.
//!
//! - Linear elastic: $\sigma \mathrel{+}= \lambda\,\mathrm{tr}\,\Delta\epsilon\,I + 2G\Delta\epsilon$ [D Eq. 4.1].
//! - J2 viscoplastic: radial return (Simo & Hughes 1998, Box 3.1) with the Perzyna yield condition
//!   $q = \sigma_y(\bar\epsilon_{pl})\,[1 + (\Delta\bar\epsilon_{pl}/(\zeta\Delta t))^\lambda]$ [D Eq. 4.2]
//!   solved by safeguarded Newton; dissipation $q\,\Delta\bar\epsilon_{pl}$.
//! - Prony series: the recursive update of the hereditary integral [D Eq. 4.3]
//!   $h_i^{n+1} = e^{-\Delta t/\tau_i}h_i^n + 2G_0 g_i\,\frac{1-e^{-\Delta t/\tau_i}}{\Delta t/\tau_i}\Delta e$
//!   (exact for a constant strain rate over the step; Simo & Hughes 1998, Sect. 10.3). Branches with
//!   $e^{-\Delta t/\tau_i} < 10^{-12}$ keep no memory and are summed into one instantaneous term.

use crate::material::{Material, MaterialModel};

/// Deviatoric/tensor double contraction for `[rr, zz, θθ, rz]`.
#[inline(always)]
pub fn ddot(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + 2.0 * a[3] * b[3]
}

/// Splits `[rr, zz, θθ, rz]` into (mean, deviator).
#[inline(always)]
pub fn split(a: &[f64; 4]) -> (f64, [f64; 4]) {
    let m = (a[0] + a[1] + a[2]) / 3.0;
    (m, [a[0] - m, a[1] - m, a[2] - m, a[3]])
}

/// One Prony branch with memory.
#[derive(Debug, Clone, Copy)]
struct Branch {
    decay: f64,
    coef_dev: f64,
    coef_vol: f64,
    inv4g: f64,
    inv2k: f64,
}

/// The per-integration-point update of one material at a fixed time step.
#[derive(Debug, Clone)]
pub enum Kernel {
    /// Linear elastic.
    Elastic {
        /// Bulk modulus, Pa.
        k: f64,
        /// Shear modulus, Pa.
        g: f64,
    },
    /// J2 elastic–viscoplastic (state: equivalent plastic strain).
    J2 {
        /// Bulk modulus, Pa.
        k: f64,
        /// Shear modulus, Pa.
        g: f64,
        /// Hardening curve `[strain, Pa]`.
        curve: Vec<[f64; 2]>,
        /// ζΔt (infinite: rate independent).
        zeta_dt: f64,
        /// Perzyna exponent λ.
        lambda: f64,
    },
    /// Prony viscoelastic (state: s∞\[4\], p∞, then 5 values per memory branch).
    Prony {
        /// Long-term bulk modulus, Pa.
        k_inf: f64,
        /// Long-term shear modulus, Pa.
        g_inf: f64,
        /// Branches with memory.
        branches: Vec<BranchPub>,
        /// $2G_0\sum g_i\varphi_i$ of the memory-less branches.
        fast_dev: f64,
        /// $K_0\sum g_i\varphi_i$ of the memory-less branches (bulk relaxing only).
        fast_vol: f64,
        /// Whether the bulk modulus relaxes.
        bulk_relaxes: bool,
    },
}

/// A Prony branch with memory (public for inspection).
#[derive(Debug, Clone, Copy)]
pub struct BranchPub(Branch);

/// Threshold on $e^{-\Delta t/\tau}$ below which a branch keeps no memory.
const FAST_DECAY: f64 = 1e-12;

fn phi(x: f64) -> f64 {
    if x < 1e-8 {
        1.0 - 0.5 * x
    } else {
        -(-x).exp_m1() / x
    }
}

impl Kernel {
    /// Kernel of `mat` for time step `dt` (s).
    pub fn new(mat: &Material, dt: f64) -> Self {
        let k = mat.bulk_modulus();
        let g = mat.shear_modulus();
        match &mat.model {
            MaterialModel::Elastic => Kernel::Elastic { k, g },
            MaterialModel::ViscoplasticJ2 {
                hardening_pa,
                perzyna_zeta_1_s,
                perzyna_lambda,
            } => Kernel::J2 {
                k,
                g,
                curve: hardening_pa.clone(),
                zeta_dt: perzyna_zeta_1_s.map_or(f64::INFINITY, |z| z * dt),
                lambda: *perzyna_lambda,
            },
            MaterialModel::ViscoelasticProny {
                prony,
                bulk_relaxes,
            } => {
                let sum: f64 = prony.iter().map(|p| p[0]).sum();
                let g0 = g / (1.0 - sum);
                let k0 = k / (1.0 - sum);
                let mut branches = Vec::new();
                let (mut fast_dev, mut fast_vol) = (0.0, 0.0);
                for &[gi, tau] in prony {
                    let x = dt / tau;
                    let decay = (-x).exp();
                    let coef_dev = 2.0 * g0 * gi * phi(x);
                    let coef_vol = if *bulk_relaxes { k0 * gi * phi(x) } else { 0.0 };
                    if decay < FAST_DECAY {
                        fast_dev += coef_dev;
                        fast_vol += coef_vol;
                    } else {
                        branches.push(BranchPub(Branch {
                            decay,
                            coef_dev,
                            coef_vol,
                            inv4g: 1.0 / (4.0 * g0 * gi),
                            inv2k: if *bulk_relaxes {
                                1.0 / (2.0 * k0 * gi)
                            } else {
                                0.0
                            },
                        }));
                    }
                }
                Kernel::Prony {
                    k_inf: k,
                    g_inf: g,
                    branches,
                    fast_dev,
                    fast_vol,
                    bulk_relaxes: *bulk_relaxes,
                }
            }
        }
    }

    /// Number of state values per integration point.
    pub fn n_state(&self) -> usize {
        match self {
            Kernel::Elastic { .. } => 0,
            Kernel::J2 { .. } => 1,
            Kernel::Prony { branches, .. } => 5 + 5 * branches.len(),
        }
    }

    /// Moduli (K, G) governing the explicit stable step at time step `dt`: the elastic ones, or
    /// for Prony materials the algorithmic ones $G_0(g_\infty + 2\sum g_i\varphi_i)$ (memory-less
    /// branches act like dashpots on the increment, hence the factor 2).
    pub fn critical_moduli(mat: &Material, dt: f64) -> (f64, f64) {
        let k = mat.bulk_modulus();
        let g = mat.shear_modulus();
        match &mat.model {
            MaterialModel::ViscoelasticProny {
                prony,
                bulk_relaxes,
            } => {
                let sum: f64 = prony.iter().map(|p| p[0]).sum();
                let alg: f64 = prony.iter().map(|p| p[0] * phi(dt / p[1])).sum();
                let f = (1.0 - sum + 2.0 * alg) / (1.0 - sum);
                (if *bulk_relaxes { k * f } else { k }, g * f)
            }
            _ => (k, g),
        }
    }

    /// Updates stress `sig` and state `st` for the strain increment `de`; returns the
    /// dissipated energy density of the step, J/m³.
    #[inline(always)]
    pub fn update(&self, de: &[f64; 4], sig: &mut [f64; 4], st: &mut [f64]) -> f64 {
        match self {
            Kernel::Elastic { k, g } => {
                let (dm, dd) = split(de);
                let dp = 3.0 * k * dm;
                for c in 0..4 {
                    sig[c] += 2.0 * g * dd[c];
                }
                for s in sig.iter_mut().take(3) {
                    *s += dp;
                }
                0.0
            }
            Kernel::J2 {
                k,
                g,
                curve,
                zeta_dt,
                lambda,
            } => j2_update(*k, *g, curve, *zeta_dt, *lambda, de, sig, &mut st[0]),
            Kernel::Prony {
                k_inf,
                g_inf,
                branches,
                fast_dev,
                fast_vol,
                bulk_relaxes,
            } => {
                let (dm, dd) = split(de);
                let dth = 3.0 * dm;
                let mut diss = 0.0;
                let mut s = [0.0; 4];
                let mut p;
                // equilibrium spring
                for c in 0..4 {
                    st[c] += 2.0 * g_inf * dd[c];
                }
                s.copy_from_slice(&st[..4]);
                st[4] += k_inf * dth;
                p = st[4];
                for (b, h) in branches.iter().zip(st[5..].chunks_exact_mut(5)) {
                    let b = &b.0;
                    let old = [h[0], h[1], h[2], h[3]];
                    let psi_old = ddot(&old, &old) * b.inv4g;
                    let mut new = [0.0; 4];
                    for c in 0..4 {
                        new[c] = b.decay * old[c] + b.coef_dev * dd[c];
                        h[c] = new[c];
                        s[c] += new[c];
                    }
                    let psi_new = ddot(&new, &new) * b.inv4g;
                    let mid = [
                        0.5 * (old[0] + new[0]),
                        0.5 * (old[1] + new[1]),
                        0.5 * (old[2] + new[2]),
                        0.5 * (old[3] + new[3]),
                    ];
                    diss += ddot(&mid, &dd) - (psi_new - psi_old);
                    if *bulk_relaxes {
                        let po = h[4];
                        let pn = b.decay * po + b.coef_vol * dth;
                        h[4] = pn;
                        p += pn;
                        diss += 0.5 * (po + pn) * dth - (pn * pn - po * po) * b.inv2k;
                    }
                }
                // memory-less branches: all their work is dissipated
                for c in 0..4 {
                    s[c] += fast_dev * dd[c];
                }
                diss += fast_dev * ddot(&dd, &dd);
                if *bulk_relaxes {
                    p += fast_vol * dth;
                    diss += fast_vol * dth * dth;
                }
                sig[0] = s[0] + p;
                sig[1] = s[1] + p;
                sig[2] = s[2] + p;
                sig[3] = s[3];
                diss
            }
        }
    }

    /// Stored (recoverable) energy density, J/m³.
    pub fn stored_energy(&self, sig: &[f64; 4], st: &[f64]) -> f64 {
        match self {
            Kernel::Elastic { k, g } | Kernel::J2 { k, g, .. } => {
                let (m, d) = split(sig);
                m * m / (2.0 * k) + ddot(&d, &d) / (4.0 * g)
            }
            Kernel::Prony {
                k_inf,
                g_inf,
                branches,
                ..
            } => {
                let sinf = [st[0], st[1], st[2], st[3]];
                let mut e = ddot(&sinf, &sinf) / (4.0 * g_inf) + st[4] * st[4] / (2.0 * k_inf);
                for (b, h) in branches.iter().zip(st[5..].chunks_exact(5)) {
                    let hv = [h[0], h[1], h[2], h[3]];
                    e += ddot(&hv, &hv) * b.0.inv4g + h[4] * h[4] * b.0.inv2k;
                }
                e
            }
        }
    }
}

/// Piecewise-linear yield curve value and slope at equivalent plastic strain `ep`.
#[inline]
pub fn hardening(curve: &[[f64; 2]], ep: f64) -> (f64, f64) {
    for w in curve.windows(2) {
        if ep <= w[1][0] {
            let s = (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]);
            return (w[0][1] + s * (ep - w[0][0]), s);
        }
    }
    (curve[curve.len() - 1][1], 0.0)
}

/// Radial return with Perzyna overstress; returns the dissipation density $q\Delta\bar\epsilon_{pl}$.
#[allow(clippy::too_many_arguments)]
#[inline]
fn j2_update(
    k: f64,
    g: f64,
    curve: &[[f64; 2]],
    zeta_dt: f64,
    lambda: f64,
    de: &[f64; 4],
    sig: &mut [f64; 4],
    ep: &mut f64,
) -> f64 {
    let (dm, dd) = split(de);
    let (pm, sd) = split(sig);
    let p = pm + 3.0 * k * dm;
    let mut s = [0.0; 4];
    for c in 0..4 {
        s[c] = sd[c] + 2.0 * g * dd[c];
    }
    let q_tr = (1.5 * ddot(&s, &s)).sqrt();
    let (y0, _) = hardening(curve, *ep);
    let mut diss = 0.0;
    if q_tr > y0 {
        // rate-independent solution: q_tr − 3GΔ = σ_y(ε̄+Δ) (piecewise linear: Newton, ≤ a few steps)
        let mut x = 0.0;
        for _ in 0..50 {
            let (h, hp) = hardening(curve, *ep + x);
            let dx = (q_tr - 3.0 * g * x - h) / (3.0 * g + hp);
            x += dx;
            if dx.abs() <= 1e-14 * x {
                break;
            }
        }
        if zeta_dt.is_finite() {
            // Perzyna [D Eq. 4.2] in inverse form: φ(Δ) = Δ − ζΔt·u^{1/λ} = 0 with
            // u = (q_tr − 3GΔ)/σ_y(ε̄+Δ) − 1 ≥ 0. φ is concave and increasing on [0, Δ_ri], so
            // Newton from Δ = 0 converges monotonically (no overshoot).
            let x_ri = x;
            let inv_l = 1.0 / lambda;
            let mut y = 0.0;
            for _ in 0..100 {
                let (h, hp) = hardening(curve, *ep + y);
                let u = ((q_tr - 3.0 * g * y) / h - 1.0).max(0.0);
                let du = (-3.0 * g * h - (q_tr - 3.0 * g * y) * hp) / (h * h);
                let pw = u.powf(inv_l);
                let phi = y - zeta_dt * pw;
                let dphi = 1.0 - zeta_dt * inv_l * if u > 0.0 { pw / u } else { 0.0 } * du;
                let mut yn = y - phi / dphi;
                if !(yn.is_finite()) || yn > x_ri {
                    yn = 0.5 * (y + x_ri);
                }
                let done = (yn - y).abs() <= 1e-13 * x_ri;
                y = yn.max(0.0);
                if done {
                    break;
                }
            }
            x = y;
        }
        let scale = 1.0 - 3.0 * g * x / q_tr;
        for c in &mut s {
            *c *= scale;
        }
        *ep += x;
        diss = (q_tr - 3.0 * g * x) * x;
    }
    sig[0] = s[0] + p;
    sig[1] = s[1] + p;
    sig[2] = s[2] + p;
    sig[3] = s[3];
    diss
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;

    /// Drives one point in uniaxial stress (σ_rr = σ_θθ = 0 by iterating the lateral strain)
    /// with axial strain increment `dez` per step; returns (σ_zz, ε̄_pl) after each step.
    fn uniaxial(kern: &Kernel, mat: &Material, dez: f64, steps: usize) -> Vec<(f64, f64, f64)> {
        let mut sig = [0.0; 4];
        let mut st = vec![0.0; kern.n_state()];
        let e = mat.youngs_modulus_pa;
        let nu = mat.poisson_ratio;
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = mat.shear_modulus();
        let mut out = Vec::new();
        let mut ez = 0.0;
        for _ in 0..steps {
            let mut lat = -nu * dez;
            let (s0, st0) = (sig, st.clone());
            for _ in 0..200 {
                sig = s0;
                st.copy_from_slice(&st0);
                kern.update(&[lat, dez, lat, 0.0], &mut sig, &mut st);
                if sig[0].abs() < 1e-9 * sig[1].abs().max(1.0) {
                    break;
                }
                lat -= sig[0] / (2.0 * (lam + mu));
            }
            ez += dez;
            let ep = if st.is_empty() { 0.0 } else { st[0] };
            out.push((ez, sig[1], ep));
        }
        out
    }

    /// Rate-independent radial return in uniaxial tension follows the hardening curve:
    /// σ_zz = σ_y(ε̄_pl) to 1e-8 relative at every step, and ε_zz − σ/E = ε̄_pl.
    #[test]
    fn radial_return_follows_hardening_curve() {
        let mut mat = Material::s235();
        if let MaterialModel::ViscoplasticJ2 {
            perzyna_zeta_1_s, ..
        } = &mut mat.model
        {
            *perzyna_zeta_1_s = None;
        }
        let kern = Kernel::new(&mat, 1e-6);
        let path = uniaxial(&kern, &mat, 1e-4, 3000);
        let mut checked = 0;
        for (ez, s, ep) in path {
            if ep > 0.0 {
                let (y, _) = hardening(&crate::material::S235_HARDENING_PA, ep);
                assert!((s / y - 1.0).abs() < 1e-8, "ε = {ez}: σ = {s}, σ_y = {y}");
                assert!((ez - s / mat.youngs_modulus_pa - ep).abs() < 1e-9);
                checked += 1;
            } else {
                assert!((s - mat.youngs_modulus_pa * ez).abs() < 1e-6 * s.abs().max(1.0));
            }
        }
        assert!(checked > 2500);
    }

    /// Perzyna overstress [D Eq. 4.2]: at a constant plastic strain rate the flow stress is
    /// $\sigma_y(\bar\epsilon_{pl})(1 + (\dot{\bar\epsilon}_{pl}/\zeta)^\lambda)$; at 1000 1/s
    /// β = 2.614 for S235 and 1.18 for Al6060 (D L1684: "a factor of about three" for steel).
    #[test]
    fn perzyna_overstress() {
        for (mat, beta_ref) in [(Material::s235(), 2.6137), (Material::al6060(), 1.18025)] {
            let rate = 1000.0; // 1/s
            let dt = 1e-7;
            let kern = Kernel::new(&mat, dt);
            let path = uniaxial(&kern, &mat, rate * dt, 4000);
            let (_, s, ep) = *path.last().unwrap();
            // plastic strain rate of the last step
            let ep_prev = path[path.len() - 2].2;
            let rate_p = (ep - ep_prev) / dt;
            let (zeta, lambda, curve) = match &mat.model {
                MaterialModel::ViscoplasticJ2 {
                    perzyna_zeta_1_s,
                    perzyna_lambda,
                    hardening_pa,
                } => (
                    perzyna_zeta_1_s.unwrap(),
                    *perzyna_lambda,
                    hardening_pa.clone(),
                ),
                _ => unreachable!(),
            };
            let (y, _) = hardening(&curve, ep);
            let beta = 1.0 + (rate_p / zeta).powf(lambda);
            assert!(
                (s / (y * beta) - 1.0).abs() < 1e-8,
                "{}: {s} vs {}",
                mat.name,
                y * beta
            );
            assert!((rate_p / rate - 1.0).abs() < 0.02, "plastic rate {rate_p}");
            let beta1000 = 1.0 + (1000.0f64 / zeta).powf(lambda);
            assert!((beta1000 - beta_ref).abs() < 1e-3, "β(1000) = {beta1000}");
        }
    }

    /// Prony relaxation: a shear strain ramp of duration t_r, then held, gives
    /// $\sigma_{rz}(t) = \frac{2\gamma_0}{t_r}\int_0^{t_r} G_R(t-s)\,ds$ in closed form [D Eq. 4.3, 4.5];
    /// the recursive update is exact for piecewise-linear strain (1e-10 relative), also with
    /// time steps much longer than the shortest τ_i (SAA series, D Tab. 4.2).
    #[test]
    fn prony_relaxation_closed_form() {
        let mat = Material::saa9579();
        let g0 = mat.instantaneous_shear_modulus();
        let prony = crate::material::SAA9579_PRONY;
        let g_inf = mat.shear_modulus();
        let dt = 1e-6;
        let kern = Kernel::new(&mat, dt);
        let mut sig = [0.0; 4];
        let mut st = vec![0.0; kern.n_state()];
        let e0 = 1e-3; // tensor shear strain ε_rz
        let n_ramp = 10;
        let tr = n_ramp as f64 * dt;
        let closed = |t: f64| {
            // 2 (e0/tr) ∫_0^{min(t,tr)} G_R(t-s) ds
            let a = (t - tr).max(0.0);
            let mut v = g_inf * (t - a);
            for &[g, tau] in &prony {
                // e^{-a/τ} − e^{-t/τ} without cancellation
                v -= g0 * g * tau * (-a / tau).exp() * (-(t - a) / tau).exp_m1();
            }
            2.0 * e0 / tr * v
        };
        let mut t = 0.0;
        for n in 0..2000 {
            let de = if n < n_ramp { e0 / n_ramp as f64 } else { 0.0 };
            kern.update(&[0.0, 0.0, 0.0, de], &mut sig, &mut st);
            t += dt;
            if n % 97 == 0 || n == n_ramp - 1 {
                let c = closed(t);
                assert!(
                    (sig[3] / c - 1.0).abs() < 1e-9,
                    "t = {t}: {} vs {c}",
                    sig[3]
                );
            }
        }
    }

    /// Elastic update and stored energy: ψ = ½σ:ε for a general strain.
    #[test]
    fn elastic_energy() {
        let mat = Material::elastic("x", 200e9, 0.3, 7800.0);
        let kern = Kernel::new(&mat, 1e-8);
        let de = [1e-4, -3e-4, 2e-4, 5e-5];
        let mut sig = [0.0; 4];
        kern.update(&de, &mut sig, &mut []);
        let psi = kern.stored_energy(&sig, &[]);
        assert!((psi / (0.5 * ddot(&sig, &de)) - 1.0).abs() < 1e-12);
    }
}
