//! Hertz–Mindlin contacts evaluated in blocks of [`LANES`] (structure of arrays).
//!
//! The law is LIGGGHTS' `hertz` + `tangential history` (the same as
//! `contact::model::hertz_mindlin_history` with the kinematics and the ledger fused in): $k_n = \tfrac43\bar E a$, $S_n = 2\bar E a$,
//! $k_t = 8\bar G a$, $a = \sqrt{\bar R\delta}$, $\gamma = -2\sqrt{5/6}\,\beta\sqrt{S\bar M}$,
//! spring $\xi$ projected on the tangent plane and cut at $\mu|F_n|$; contact kinematics
//! [D Eq. 2.12–2.27] and the trapezoidal work of the energy ledger. Evaluated one contact at a
//! time, the chain of square roots and divisions of one contact leaves the processor waiting;
//! a block of independent contacts in arrays is one straight loop without branches (sticking
//! and sliding are both computed and selected), which the compiler turns into vector
//! instructions. Where the processor has AVX2 or AVX-512 the same loop is compiled for those too
//! and chosen at run time. IEEE arithmetic rounds a vector lane as it rounds a scalar, and no
//! fused multiply–add is formed (Rust does not contract `a * b + c`), so every variant gives
//! the same bits (tested) and results do not depend on the processor's vector width.

/// Contacts per block.
pub(crate) const LANES: usize = 8;

/// Inputs of a block of contacts (lane `k` = one contact of partners `i < j`).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct HmInput {
    /// Distance vector x_i − x_j, m.
    pub dx: [f64; LANES],
    pub dy: [f64; LANES],
    pub dz: [f64; LANES],
    /// Radii, m.
    pub ri: [f64; LANES],
    pub rj: [f64; LANES],
    /// Velocity difference v_i − v_j, m/s.
    pub vx: [f64; LANES],
    pub vy: [f64; LANES],
    pub vz: [f64; LANES],
    /// Angular velocities, rad/s.
    pub wix: [f64; LANES],
    pub wiy: [f64; LANES],
    pub wiz: [f64; LANES],
    pub wjx: [f64; LANES],
    pub wjy: [f64; LANES],
    pub wjz: [f64; LANES],
    /// Masses, kg.
    pub mi: [f64; LANES],
    pub mj: [f64; LANES],
    /// Effective Young's modulus, Pa.
    pub e_eff: [f64; LANES],
    /// Effective shear modulus, Pa.
    pub g_eff: [f64; LANES],
    /// Damping factor $-2\sqrt{5/6}\,\beta(e)$.
    pub damping: [f64; LANES],
    /// Friction coefficient.
    pub mu: [f64; LANES],
    /// Clip the normal force at zero.
    pub clip: [bool; LANES],
}

/// Contact state carried from step to step (read and written by the kernel).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct HmState {
    /// Tangential spring ξ, m.
    pub sx: [f64; LANES],
    pub sy: [f64; LANES],
    pub sz: [f64; LANES],
    /// Normal force on i at the previous evaluation, N.
    pub fnx: [f64; LANES],
    pub fny: [f64; LANES],
    pub fnz: [f64; LANES],
    /// Tangential force on i at the previous evaluation, N.
    pub ftx: [f64; LANES],
    pub fty: [f64; LANES],
    pub ftz: [f64; LANES],
    /// Stored normal and tangential energy at the previous evaluation, J.
    pub en: [f64; LANES],
    pub et: [f64; LANES],
}

/// Outputs of a block.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct HmOutput {
    /// Force on i (j gets the opposite), N.
    pub fx: [f64; LANES],
    pub fy: [f64; LANES],
    pub fz: [f64; LANES],
    /// Torque on i, N·m.
    pub tix: [f64; LANES],
    pub tiy: [f64; LANES],
    pub tiz: [f64; LANES],
    /// Torque on j, N·m.
    pub tjx: [f64; LANES],
    pub tjy: [f64; LANES],
    pub tjz: [f64; LANES],
    /// Normal approach rate −n·(v_i − v_j), m/s.
    pub rate: [f64; LANES],
    /// Energy dissipated in this step, normal and tangential, J.
    pub dn: [f64; LANES],
    pub dt: [f64; LANES],
    /// Elastic energy stored now, J.
    pub el: [f64; LANES],
}

/// One block, lane by lane.
#[inline(always)]
fn eval_body(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
    for k in 0..LANES {
        let (dx, dy, dz) = (b.dx[k], b.dy[k], b.dz[k]);
        let dist = ((dx * dx + dy * dy) + dz * dz).sqrt();
        let inv = 1.0 / dist;
        let (nx, ny, nz) = (dx * inv, dy * inv, dz * inv);
        let (ri, rj) = (b.ri[k], b.rj[k]);
        let delta = ri + rj - dist;
        let rb_i = ri - 0.5 * delta;
        let rb_j = rj - 0.5 * delta;
        let (vx, vy, vz) = (b.vx[k], b.vy[k], b.vz[k]);
        // v_rel = Δv − (r_b,i ω_i + r_b,j ω_j) × n
        let ax = b.wix[k] * rb_i + b.wjx[k] * rb_j;
        let ay = b.wiy[k] * rb_i + b.wjy[k] * rb_j;
        let az = b.wiz[k] * rb_i + b.wjz[k] * rb_j;
        let ux = vx - (ay * nz - az * ny);
        let uy = vy - (az * nx - ax * nz);
        let uz = vz - (ax * ny - ay * nx);
        let rate = -((nx * vx + ny * vy) + nz * vz);
        let (mi, mj) = (b.mi[k], b.mj[k]);
        let r_eff = ri * rj / (ri + rj);
        let m_eff = mi * mj / (mi + mj);
        let a = (r_eff * delta).sqrt();
        let e = b.e_eff[k];
        let sn = 2.0 * e * a;
        let kn = 4.0 / 3.0 * e * a;
        let damping = b.damping[k];
        let gamma_n = damping * (sn * m_eff).sqrt();
        let elastic = kn * delta;
        let dissipative0 = gamma_n * rate;
        let dissipative = if b.clip[k] {
            dissipative0.max(-elastic)
        } else {
            dissipative0
        };
        let un = (nx * ux + ny * uy) + nz * uz;
        let (tx, ty, tz) = (ux - nx * un, uy - ny * un, uz - nz * un);
        let kt = 8.0 * b.g_eff[k] * a;
        let gamma_t = damping * (kt * m_eff).sqrt();
        let (mut xx, mut xy, mut xz) = (s.sx[k] + tx * dt, s.sy[k] + ty * dt, s.sz[k] + tz * dt);
        let xn = (xx * nx + xy * ny) + xz * nz;
        xx -= nx * xn;
        xy -= ny * xn;
        xz -= nz * xn;
        let shear2 = (xx * xx + xy * xy) + xz * xz;
        let fnorm = elastic + dissipative;
        let ft_friction = b.mu[k] * fnorm.abs();
        let slide = kt * kt * shear2 > ft_friction * ft_friction;
        // Sliding: force cut at μ|F_n| along −ξ, spring shortened to match.
        let fac = ft_friction / shear2.sqrt();
        let (sfx, sfy, sfz) = (-xx * fac, -xy * fac, -xz * fac);
        let fx = if slide { sfx } else { -kt * xx - gamma_t * tx };
        let fy = if slide { sfy } else { -kt * xy - gamma_t * ty };
        let fz = if slide { sfz } else { -kt * xz - gamma_t * tz };
        let nxx = if slide { -sfx / kt } else { xx };
        let nxy = if slide { -sfy / kt } else { xy };
        let nxz = if slide { -sfz / kt } else { xz };
        s.sx[k] = nxx;
        s.sy[k] = nxy;
        s.sz[k] = nxz;
        let (gx, gy, gz) = (nx * fnorm, ny * fnorm, nz * fnorm);
        let e_n = 0.4 * kn * delta * delta;
        let e_t = 0.5 * kt * ((nxx * nxx + nxy * nxy) + nxz * nxz);
        // Ledger: trapezoidal work minus the change of stored energy.
        let w_n =
            -0.5 * (((s.fnx[k] + gx) * ux + (s.fny[k] + gy) * uy) + (s.fnz[k] + gz) * uz) * dt;
        let w_t =
            -0.5 * (((s.ftx[k] + fx) * ux + (s.fty[k] + fy) * uy) + (s.ftz[k] + fz) * uz) * dt;
        o.dn[k] = w_n - (e_n - s.en[k]);
        o.dt[k] = w_t - (e_t - s.et[k]);
        o.el[k] = e_n + e_t;
        o.rate[k] = rate;
        s.fnx[k] = gx;
        s.fny[k] = gy;
        s.fnz[k] = gz;
        s.ftx[k] = fx;
        s.fty[k] = fy;
        s.ftz[k] = fz;
        s.en[k] = e_n;
        s.et[k] = e_t;
        o.fx[k] = gx + fx;
        o.fy[k] = gy + fy;
        o.fz[k] = gz + fz;
        // n × F_t, shared by both torques.
        let cx = ny * fz - nz * fy;
        let cy = nz * fx - nx * fz;
        let cz = nx * fy - ny * fx;
        o.tix[k] = -rb_i * cx;
        o.tiy[k] = -rb_i * cy;
        o.tiz[k] = -rb_i * cz;
        o.tjx[k] = -rb_j * cx;
        o.tjy[k] = -rb_j * cy;
        o.tjz[k] = -rb_j * cz;
    }
}

/// A block kernel: inputs, state (updated), outputs, time step. A value exists only for a
/// variant this processor runs ([`kernel`], [`variants`]), so calling it is safe.
#[derive(Clone, Copy)]
pub(crate) struct Kernel(unsafe fn(&HmInput, &mut HmState, &mut HmOutput, f64));

impl Kernel {
    /// The baseline variant (every processor).
    pub(crate) const SCALAR: Kernel = Kernel(eval_scalar);

    /// Evaluates a block.
    #[inline]
    pub(crate) fn eval(self, b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
        // SAFETY: a `Kernel` is built only by `kernel`, `variants` and `SCALAR`, each after
        // detecting the instruction set its function is compiled for.
        unsafe { (self.0)(b, s, o, dt) }
    }
}

/// The kernel compiled for the baseline instruction set.
pub(crate) fn eval_scalar(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
    eval_body(b, s, o, dt)
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;

    #[target_feature(enable = "avx2")]
    fn avx2(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
        eval_body(b, s, o, dt)
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512dq")]
    fn avx512(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
        eval_body(b, s, o, dt)
    }

    /// AVX2 version.
    ///
    /// # Safety
    /// The processor must have AVX2 (wrapped in a [`super::Kernel`] only after detecting it).
    pub(super) unsafe fn eval_avx2(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
        // SAFETY: the caller guarantees AVX2.
        unsafe { avx2(b, s, o, dt) }
    }

    /// AVX-512 version.
    ///
    /// # Safety
    /// The processor must have AVX-512 F/VL/DQ (wrapped in a [`super::Kernel`] only after
    /// detecting them).
    pub(super) unsafe fn eval_avx512(b: &HmInput, s: &mut HmState, o: &mut HmOutput, dt: f64) {
        // SAFETY: the caller guarantees AVX-512 F/VL/DQ.
        unsafe { avx512(b, s, o, dt) }
    }
}

/// The widest kernel this processor runs (all give the same bits; see the module docs).
pub(crate) fn kernel() -> Kernel {
    static CHOICE: std::sync::OnceLock<Kernel> = std::sync::OnceLock::new();
    *CHOICE.get_or_init(|| {
        #[cfg(target_arch = "x86_64")]
        {
            if std::env::var_os("PDAMP_NO_SIMD").is_none() {
                if is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                    && is_x86_feature_detected!("avx512dq")
                {
                    return Kernel(x86::eval_avx512);
                }
                if is_x86_feature_detected!("avx2") {
                    return Kernel(x86::eval_avx2);
                }
            }
        }
        Kernel::SCALAR
    })
}

/// Every kernel variant this processor can run, with its name (for tests).
#[cfg(test)]
pub(crate) fn variants() -> Vec<(&'static str, Kernel)> {
    let mut v: Vec<(&'static str, Kernel)> = vec![("scalar", Kernel::SCALAR)];
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx2") {
            v.push(("avx2", Kernel(x86::eval_avx2)));
        }
        if is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512dq")
        {
            v.push(("avx512", Kernel(x86::eval_avx512)));
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Random blocks (sticking and sliding lanes, fresh and loaded springs, clipped and not):
    /// every kernel variant of this processor gives the scalar kernel's bits.
    #[test]
    fn all_variants_give_the_same_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut u = |a: f64, b: f64| a + (b - a) * rng.random::<f64>();
        let variants = variants();
        eprintln!(
            "kernel variants: {:?}",
            variants.iter().map(|v| v.0).collect::<Vec<_>>()
        );
        let (mut slid, mut stuck) = (0, 0);
        for _ in 0..500 {
            let mut b = HmInput::default();
            let mut s = HmState::default();
            for k in 0..LANES {
                let (ri, rj) = (u(0.5e-3, 1.5e-3), u(0.5e-3, 1.5e-3));
                let dir = Vec3Lite::unit(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                let dist = (ri + rj) * u(0.995, 0.99999);
                (b.dx[k], b.dy[k], b.dz[k]) = (dir.0 * dist, dir.1 * dist, dir.2 * dist);
                (b.ri[k], b.rj[k]) = (ri, rj);
                (b.vx[k], b.vy[k], b.vz[k]) = (u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                (b.wix[k], b.wiy[k], b.wiz[k]) = (u(-300.0, 300.0), u(-300.0, 300.0), u(-1.0, 1.0));
                (b.wjx[k], b.wjy[k], b.wjz[k]) = (u(-1.0, 1.0), u(-300.0, 300.0), u(-300.0, 300.0));
                (b.mi[k], b.mj[k]) = (u(1e-6, 1e-4), u(1e-6, 1e-4));
                b.e_eff[k] = u(1e8, 1e11);
                b.g_eff[k] = b.e_eff[k] * u(0.3, 0.45);
                b.damping[k] = u(-1.5, 0.0);
                b.mu[k] = u(0.0, 1.0);
                b.clip[k] = u(0.0, 1.0) < 0.5;
                let sc = u(0.0, 3e-6) * (u(0.0, 1.0) < 0.7) as u8 as f64;
                (s.sx[k], s.sy[k], s.sz[k]) = (u(-sc, sc), u(-sc, sc), u(-sc, sc));
                (s.fnx[k], s.fny[k], s.fnz[k]) = (u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                (s.ftx[k], s.fty[k], s.ftz[k]) = (u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                (s.en[k], s.et[k]) = (u(0.0, 1e-6), u(0.0, 1e-6));
            }
            let dt = u(1e-8, 1e-5);
            let (mut s0, mut o0) = (s, HmOutput::default());
            eval_scalar(&b, &mut s0, &mut o0, dt);
            for k in 0..LANES {
                let ft = (s0.ftx[k].powi(2) + s0.fty[k].powi(2) + s0.ftz[k].powi(2)).sqrt();
                let fnorm = (s0.fnx[k].powi(2) + s0.fny[k].powi(2) + s0.fnz[k].powi(2)).sqrt();
                if ft >= b.mu[k] * fnorm * (1.0 - 1e-9) {
                    slid += 1;
                } else {
                    stuck += 1;
                }
            }
            for (name, kern) in &variants {
                let (mut s1, mut o1) = (s, HmOutput::default());
                kern.eval(&b, &mut s1, &mut o1, dt);
                let bits = |x: &[f64; LANES]| x.map(f64::to_bits);
                for (x, y) in [
                    (&o0.fx, &o1.fx),
                    (&o0.fy, &o1.fy),
                    (&o0.fz, &o1.fz),
                    (&o0.tix, &o1.tix),
                    (&o0.tjz, &o1.tjz),
                    (&o0.dn, &o1.dn),
                    (&o0.dt, &o1.dt),
                    (&o0.el, &o1.el),
                    (&o0.rate, &o1.rate),
                    (&s0.sx, &s1.sx),
                    (&s0.sy, &s1.sy),
                    (&s0.sz, &s1.sz),
                    (&s0.ftx, &s1.ftx),
                    (&s0.en, &s1.en),
                    (&s0.et, &s1.et),
                ] {
                    assert_eq!(bits(x), bits(y), "variant {name}");
                }
            }
        }
        assert!(
            slid > 200 && stuck > 200,
            "sliding and sticking lanes: {slid}, {stuck}"
        );
    }

    /// A unit direction from three numbers (test helper).
    struct Vec3Lite(f64, f64, f64);

    impl Vec3Lite {
        fn unit(x: f64, y: f64, z: f64) -> Self {
            let n = (x * x + y * y + z * z).sqrt().max(1e-9);
            Self(x / n, y / n, z / n)
        }
    }
}
