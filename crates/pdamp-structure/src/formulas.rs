//! Analytical damper formulas for coupling approach 3 [D Sect. 3.3]: dissipated energy per
//! cycle and effective particle mass as closed-form functions of amplitude X and frequency Ω.
//!
//! | model | equations | validity |
//! |---|---|---|
//! | [`RollingDamper`] | rolling collect-and-collide / scattered, D Eq. 5.1–5.14 | horizontal, $A = X\Omega^2 < g$, one layer of spheres rolling on the base |
//! | [`HorizontalDamper`] | combined rolling/bouncing model D Eq. 6.12 (with 5.2, 5.10, 6.2, 6.8) | horizontal, any A; bouncing needs $A$ "sufficiently" above g |
//! | [`VerticalDamper`] | vertical single/double collect-and-collide, solid-like, scattered, D Eq. 7.1–7.19 | vertical, bed as one block, inelastic wall impacts; 7.19 masses are DEM fits |
//! | [`ConstantLossFactor`] | $\tilde E = 2\pi\bar\eta E_{kin}$ [D Eq. 3.15] with fixed η̄, m̄ | reference and efficiency studies (D Eq. 3.51) |
//! | [`PowderFrictionDamper`] | powder-filled cavity, pure shear (paper eq. 17–20) or pure bending (eq. 21–26) sliding friction, $\tilde E = 4W(\varphi)$ | dense packing, every contact sliding, no impacts, no wall slip, $N_x, N_y \gg 1$, small φ (below) |
//!
//! All formulas give $\tilde E_{diss} = \pi\bar\eta\, m_{bed} V^2$ with $V = X\Omega$ (i.e.
//! Ẽ = 2π η̄ E_kin, E_kin = ½ m_bed V², D Eq. 3.15; the text's Eq. 5.2/6.2 give the per-radian
//! E_diss, converted here).

use crate::StructureError;
use crate::effective::{EffectiveDamper, EffectiveState};
use pdamp_dem::math::STANDARD_GRAVITY_M_S2;
use std::f64::consts::{PI, TAU};

/// $S(\tau) = \int_0^\tau \sqrt{25 + 10\sin^2 s}\,ds$ (Simpson, 400 intervals; smooth integrand).
pub fn rolling_path_integral(tau: f64) -> f64 {
    let n = 400;
    let h = tau / n as f64;
    let f = |s: f64| (25.0 + 10.0 * s.sin().powi(2)).sqrt();
    let mut sum = f(0.0) + f(tau);
    for i in 1..n {
        sum += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// Clearance of a layer $h = L(1 - n_p/n_p^{max})$ [D Eq. 5.1, 6.1, 7.4], m.
pub fn clearance_m(container_length_m: f64, particles: f64, particles_max: f64) -> f64 {
    container_length_m * (1.0 - particles / particles_max)
}

/// $S(\pi)$, the path integral over a half cycle (computed once).
fn rolling_path_integral_pi() -> f64 {
    static S_PI: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *S_PI.get_or_init(|| rolling_path_integral(PI))
}

/// Least container acceleration amplitude at which a bed collected at the lower wall of a
/// container tilted by `tilt_rad` about the axis normal to gravity and excitation can leave
/// it: $A\cos\alpha > g\sin\alpha$, i.e. $A > g\tan\alpha$ [D L2229–2233: 0.51 m/s² for
/// α = 3°]. D's design condition asks for $A\cos\alpha \gg g\sin\alpha$ at the operating point.
pub fn tilt_lift_off_acceleration_m_s2(tilt_rad: f64) -> f64 {
    STANDARD_GRAVITY_M_S2 * tilt_rad.tan()
}

/// Optimal stroke of the rolling collect-and-collide mode, $X^{opt}_{rol} = 7h/S(\pi)
/// \approx 0.4075\,h$ [D Eq. 5.13, exact form of Eq. 5.8 with Ωt_imp = π].
pub fn rolling_optimal_stroke_m(clearance_m: f64) -> f64 {
    7.0 * clearance_m / rolling_path_integral_pi()
}

/// Impact phase τ = Ωt_imp of the rolling bed [D Eq. 5.8 with 5.6]:
/// $\tfrac17[S(\tau) - 5\sin\tau] = h/X$; `None` below the optimal stroke (no impact before π).
///
/// $g(\tau) = \tfrac17[S(\tau) - 5\sin\tau] - h/X$ is increasing and convex on (0, π]
/// ($g' = \tfrac17[\sqrt{25+10\sin^2\tau} - 5\cos\tau] \ge 0$,
/// $g'' = \tfrac17\sin\tau\,[10\cos\tau/\sqrt{25+10\sin^2\tau} + 5] > 0$), so Newton's method
/// from τ = π (where g ≥ 0) falls monotonically onto the root: a handful of evaluations of S
/// instead of the 60 of a bisection (the root is the same to round-off).
pub fn rolling_impact_phase(amplitude_m: f64, clearance_m: f64) -> Option<f64> {
    let target = clearance_m / amplitude_m;
    let g = |t: f64| (rolling_path_integral(t) - 5.0 * t.sin()) / 7.0 - target;
    let dg = |t: f64| ((25.0 + 10.0 * t.sin().powi(2)).sqrt() - 5.0 * t.cos()) / 7.0;
    let g_pi = (rolling_path_integral_pi() - 5.0 * PI.sin()) / 7.0 - target;
    if g_pi < 0.0 {
        return None;
    }
    let mut t = PI;
    let mut gt = g_pi;
    for _ in 0..200 {
        let d = dg(t);
        if d.is_nan() || d <= 0.0 || gt <= 0.0 {
            break;
        }
        let next = (t - gt / d).max(0.0);
        if (t - next).abs() <= 1e-15 * PI {
            t = next;
            break;
        }
        t = next;
        gt = g(t);
    }
    Some(t)
}

/// Effective loss factor of the rolling collect-and-collide mode at impact phase τ
/// [D Eq. 5.10 with 3.15]: $\bar\eta = (\sqrt{25+10\sin^2\tau} - 5\cos\tau)^2/(35\pi)$;
/// maximum $20/(7\pi) \approx 0.909$ at τ = π [D Eq. 5.12].
pub fn rolling_loss_factor(tau: f64) -> f64 {
    ((25.0 + 10.0 * tau.sin().powi(2)).sqrt() - 5.0 * tau.cos()).powi(2) / (35.0 * PI)
}

/// One layer of spheres in a horizontally excited container, rolling/scattered model
/// [D Sect. 5.1.3]: scattered $\bar\eta = X/h$ (Eq. 5.3) for $X \le X^{opt}_{rol}$, rolling
/// collect-and-collide (Eq. 5.8, 5.10) above; effective mass Eq. 5.14 (1.0 m_bed rolling,
/// 0.3 m_bed scattered). Valid for $A < g$ (the rolling condition). Several layers are summed by
/// [`LayeredDamper`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingDamper {
    /// Particle bed mass of the layer, kg.
    pub bed_mass_kg: f64,
    /// Clearance h_rol, m (Eq. 5.1).
    pub clearance_m: f64,
    /// Optional smoothing of the jump at X_opt (the dissertation smooths for the forced
    /// iteration, D Fig. 5.22, without giving the form): logistic blend in ln X with this
    /// width (e.g. 0.1); `None` keeps the jump.
    pub smoothing_log_width: Option<f64>,
}

impl RollingDamper {
    /// (η̄, m̄/m_bed) at amplitude X.
    pub fn loss_factor_and_mass_ratio(&self, amplitude_m: f64) -> (f64, f64) {
        if self.clearance_m <= 0.0 {
            return (0.0, 1.0); // full layer: no relative motion
        }
        let x_opt = rolling_optimal_stroke_m(self.clearance_m);
        let scattered = (amplitude_m / self.clearance_m, 0.3);
        let rolling = |x: f64| {
            let tau = rolling_impact_phase(x.max(x_opt), self.clearance_m).unwrap_or(PI);
            (rolling_loss_factor(tau), 1.0)
        };
        match self.smoothing_log_width {
            None => {
                if amplitude_m > x_opt {
                    rolling(amplitude_m)
                } else {
                    scattered
                }
            }
            Some(w) => {
                let s = 1.0 / (1.0 + (-(amplitude_m / x_opt).ln() / w).exp());
                let r = rolling(amplitude_m);
                let sc = (amplitude_m.min(x_opt) / self.clearance_m, 0.3);
                (sc.0 + (r.0 - sc.0) * s, sc.1 + (r.1 - sc.1) * s)
            }
        }
    }
}

fn state(bed_mass_kg: f64, eta: f64, ratio: f64, amplitude_m: f64, omega: f64) -> EffectiveState {
    let v = amplitude_m * omega;
    EffectiveState {
        effective_mass_kg: ratio * bed_mass_kg,
        dissipated_energy_per_cycle_j: PI * eta * bed_mass_kg * v * v,
    }
}

impl EffectiveDamper for RollingDamper {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        let (eta, ratio) = self.loss_factor_and_mass_ratio(amplitude_m);
        state(self.bed_mass_kg, eta, ratio, amplitude_m, omega_rad_s)
    }
    fn bed_mass_kg(&self) -> f64 {
        self.bed_mass_kg
    }
}

/// Combined horizontal model [D Eq. 6.12]: for $A < g$ the rolling model (Eq. 5.2/5.10, mass
/// Eq. 5.14), for $A \ge g$ scattered bouncing $\bar\eta = 2X/h_{bou}$ (Eq. 6.3) below
/// $X^{opt}_{bou} = h_{bou}/\pi$ (Eq. 6.11) and bouncing collect-and-collide
/// $\bar\eta = (1-\cos\theta)^2/\pi$ with $X(\theta - \sin\theta) = h_{bou}$ (Eq. 6.6, 6.8)
/// above. The dissertation gives no effective-mass formula for bouncing; `bouncing_mass_ratio`
/// is an input (1.0 assumes the bed is fully coupled, as for rolling).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HorizontalDamper {
    /// Rolling part (A < g).
    pub rolling: RollingDamper,
    /// Clearance of the bouncing mode h_bou (Eq. 6.1), m.
    pub bouncing_clearance_m: f64,
    /// m̄_bed/m_bed used for A ≥ g.
    pub bouncing_mass_ratio: f64,
}

/// Impact phase θ of bouncing collect-and-collide, $X(\theta - \sin\theta) = h_{bou}$
/// [D Eq. 6.6 with 6.4]; `None` below $X^{opt}_{bou} = h/\pi$.
pub fn bouncing_impact_phase(amplitude_m: f64, clearance_m: f64) -> Option<f64> {
    let target = clearance_m / amplitude_m;
    if target > PI {
        return None;
    }
    let (mut a, mut b) = (0.0, PI);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if m - m.sin() > target {
            b = m;
        } else {
            a = m;
        }
    }
    Some(0.5 * (a + b))
}

impl HorizontalDamper {
    /// (η̄, m̄/m_bed) at (X, Ω).
    pub fn loss_factor_and_mass_ratio(&self, amplitude_m: f64, omega_rad_s: f64) -> (f64, f64) {
        let a = amplitude_m * omega_rad_s * omega_rad_s;
        if a < STANDARD_GRAVITY_M_S2 {
            return self.rolling.loss_factor_and_mass_ratio(amplitude_m);
        }
        let h = self.bouncing_clearance_m;
        if h <= 0.0 {
            return (0.0, 1.0);
        }
        match bouncing_impact_phase(amplitude_m, h) {
            Some(theta) => ((1.0 - theta.cos()).powi(2) / PI, self.bouncing_mass_ratio),
            None => (2.0 * amplitude_m / h, self.bouncing_mass_ratio),
        }
    }
}

impl EffectiveDamper for HorizontalDamper {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        let (eta, ratio) = self.loss_factor_and_mass_ratio(amplitude_m, omega_rad_s);
        state(
            self.rolling.bed_mass_kg,
            eta,
            ratio,
            amplitude_m,
            omega_rad_s,
        )
    }
    fn bed_mass_kg(&self) -> f64 {
        self.rolling.bed_mass_kg
    }
}

/// A fixed effective loss factor and mass ratio: $\tilde E = \pi\bar\eta m_{bed}V^2$.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantLossFactor {
    /// Bed mass, kg.
    pub bed_mass_kg: f64,
    /// η̄.
    pub effective_loss_factor: f64,
    /// m̄_bed/m_bed.
    pub effective_mass_ratio: f64,
}

impl EffectiveDamper for ConstantLossFactor {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        state(
            self.bed_mass_kg,
            self.effective_loss_factor,
            self.effective_mass_ratio,
            amplitude_m,
            omega_rad_s,
        )
    }
    fn bed_mass_kg(&self) -> f64 {
        self.bed_mass_kg
    }
}

/// Several independent layers (e.g. the layered containers of D Sect. 5.2.1): energies and
/// effective masses add.
#[derive(Debug)]
pub struct LayeredDamper {
    /// The layers.
    pub layers: Vec<Box<dyn EffectiveDamper>>,
}

impl EffectiveDamper for LayeredDamper {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        let mut s = EffectiveState {
            effective_mass_kg: 0.0,
            dissipated_energy_per_cycle_j: 0.0,
        };
        for l in &self.layers {
            let e = l.evaluate(amplitude_m, omega_rad_s);
            s.effective_mass_kg += e.effective_mass_kg;
            s.dissipated_energy_per_cycle_j += e.dissipated_energy_per_cycle_j;
        }
        s
    }
    fn bed_mass_kg(&self) -> f64 {
        self.layers.iter().map(|l| l.bed_mass_kg()).sum()
    }
}

/// Motion mode of a vertically excited bed [D Sect. 7.1.1, Fig. 7.2].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VerticalMode {
    /// A < g: the bed rests on the base (Eq. 7.5).
    SolidLike,
    /// One (bottom) impact per cycle; `n_imp` container cycles in flight (Eq. 7.6–7.9).
    SingleCollectAndCollide {
        /// Container vibrations until the impact (0: harmonic).
        n_imp: usize,
    },
    /// Top and bottom impact (Eq. 7.10–7.15).
    DoubleCollectAndCollide {
        /// Container vibrations until the bottom impact (0: harmonic).
        n_imp: usize,
    },
    /// Subharmonic top impact or late bottom impact: treated with Eq. 7.5.
    Scattered,
}

/// Result of the vertical collect-and-collide model at one (X, Ω).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct VerticalState {
    /// Motion mode.
    pub mode: VerticalMode,
    /// Effective loss factor η̄ = Ẽ/(π m_bed V²).
    pub effective_loss_factor: f64,
    /// m̄_bed/m_bed of Eq. 7.19.
    pub effective_mass_ratio: f64,
}

/// Vertical bed of D Sect. 7.1.1: the bed moves as one block, takes off from the base when
/// $\ddot x_c \le -g$ (Eq. 7.1, $A\sin\Omega t^{bot}_{off} = g$), flies freely and collides
/// completely inelastically with the top wall (clearance h, Eq. 7.4) or the base. Container
/// $x_c = X\sin\Omega t$. Modes and energies:
///
/// - solid-like (A < g) and scattered: $\tilde E = \pi m_{bed}V^2/1000$ (Eq. 7.5);
/// - single collect-and-collide (base hit first): $\tilde E = \kappa\frac12 m_{bed}\Delta v_{st}^2$
///   (Eq. 7.6–7.8), κ = 1/(1 + n_imp) with the container cycles n_imp of Eq. 7.9;
/// - double collect-and-collide (top hit first): the bed stays pressed to the top until
///   $\Omega t = \pi - \Omega t^{bot}_{off}$ or rebounds at once (Eq. 7.10), flies to the base,
///   $\tilde E = \kappa\frac12 m_{bed}(\Delta v_{st}^2 + \Delta v_{nd}^2)$ (Eq. 7.11–7.14); the
///   bottom impact must come before the take-off of the cycle it falls in (Eq. 7.15 in the
///   prose-consistent reading: harmonic/subharmonic if
///   $\frac52\pi + 2\pi(n-1) < \Omega t^{nd}_{imp} < \Omega t^{bot}_{off} + 2\pi(n+1)$, scattered
///   otherwise); a top impact after the first cycle (subharmonic top impact) is scattered.
///
/// Effective mass Eq. 7.19: 0.75 m_bed solid-like and harmonic double, 0.65 harmonic single,
/// 0.2 subharmonic single/double, 0.1 scattered. For A ≫ g the model tends to the zero-gravity
/// bouncing limit $X_{opt} = h/\pi$, $\bar\eta_{max} = 4/\pi$ (Eq. 7.16–7.18).
/// D's equations 7.3/7.6 print $\dot x^{bot}_{off}$ for the take-off position (typo).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerticalDamper {
    /// Bed mass, kg.
    pub bed_mass_kg: f64,
    /// Clearance h between the bed and the top wall (Eq. 7.4), m.
    pub clearance_m: f64,
}

impl VerticalDamper {
    /// Mode, η̄ and m̄/m_bed at amplitude X and angular frequency Ω.
    pub fn state(&self, amplitude_m: f64, omega_rad_s: f64) -> VerticalState {
        let g = STANDARD_GRAVITY_M_S2;
        let (x, w, h) = (amplitude_m, omega_rad_s, self.clearance_m);
        let a = x * w * w;
        let solid = VerticalState {
            mode: VerticalMode::SolidLike,
            effective_loss_factor: 1e-3,
            effective_mass_ratio: 0.75,
        };
        let scattered = VerticalState {
            mode: VerticalMode::Scattered,
            effective_loss_factor: 1e-3,
            effective_mass_ratio: 0.1,
        };
        let valid = a > g && x > 0.0 && w > 0.0; // false also for NaN
        if !valid {
            return solid;
        }
        if h <= 0.0 {
            return solid; // full container: no relative motion
        }
        let xc = |p: f64| x * p.sin();
        let vc = |p: f64| x * w * p.cos();
        // phase φ = Ωt; take-off from the base (Eq. 7.1)
        let p_off = (g / a).asin();
        // free flight from (phase p0, position y0, velocity v0)
        let flight = |p0: f64, y0: f64, v0: f64, p: f64| {
            let dt = (p - p0) / w;
            (y0 + v0 * dt - 0.5 * g * dt * dt, v0 - g * dt)
        };
        // first event after p0: Some((phase, hit_top))
        let first_event = |p0: f64, y0: f64, v0: f64, top_allowed: bool| -> Option<(f64, bool)> {
            let gap_bot = |p: f64| flight(p0, y0, v0, p).0 - xc(p);
            let gap_top = |p: f64| xc(p) + h - flight(p0, y0, v0, p).0;
            let n = 2000;
            let dp = TAU / n as f64;
            let mut prev = p0;
            for i in 1..=(40 * n) {
                let p = p0 + i as f64 * dp;
                let (b, t) = (gap_bot(p), gap_top(p));
                let hit_top = top_allowed && t < 0.0;
                // skip the first step's tangency at take-off (gap starts at 0)
                let hit_bot = b < 0.0 && i > 1;
                if hit_top || hit_bot {
                    let f = |q: f64| if hit_top { gap_top(q) } else { gap_bot(q) };
                    let (mut lo, mut hi) = (prev, p);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if f(mid) < 0.0 {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    return Some((0.5 * (lo + hi), hit_top));
                }
                prev = p;
            }
            None
        };
        // container cycles until the impact (Eq. 7.9): cycles count from π/2 to 5π/2
        let n_imp = |p: f64| -> usize {
            let k = ((p - 2.5 * PI) / TAU).floor() + 1.0;
            k.max(0.0) as usize
        };
        let y_off = xc(p_off);
        let v_off = vc(p_off);
        let Some((p1, top)) = first_event(p_off, y_off, v_off, true) else {
            return scattered;
        };
        let mass_v2 = |dv: f64| 0.5 * dv * dv; // per unit bed mass
        let v_ref2 = (x * w) * (x * w);
        if !top {
            // single collect-and-collide (Eq. 7.6–7.9)
            let (_, vp) = flight(p_off, y_off, v_off, p1);
            let dv = vp - vc(p1);
            let n = n_imp(p1);
            let e = mass_v2(dv) / (1.0 + n as f64);
            return VerticalState {
                mode: VerticalMode::SingleCollectAndCollide { n_imp: n },
                effective_loss_factor: e / (PI * v_ref2),
                effective_mass_ratio: if n == 0 { 0.65 } else { 0.2 },
            };
        }
        // double collect-and-collide
        if p1 > 2.5 * PI {
            return scattered; // subharmonic top impact (not modelled, D L2905)
        }
        let (_, vp) = flight(p_off, y_off, v_off, p1);
        let dv_st = vp - vc(p1);
        // take-off from the top (Eq. 7.10)
        let p_top = p1.max(PI - p_off);
        let y_top = xc(p_top) + h;
        let v_top = vc(p_top);
        let Some((p2, _)) = first_event(p_top, y_top, v_top, false) else {
            return scattered;
        };
        let (_, vp2) = flight(p_top, y_top, v_top, p2);
        let dv_nd = vp2 - vc(p2);
        let n = n_imp(p2);
        if p2 > p_off + TAU * (n as f64 + 1.0) {
            return scattered; // lands after the next take-off (Eq. 7.15, prose)
        }
        let e = (mass_v2(dv_st) + mass_v2(dv_nd)) / (1.0 + n as f64);
        VerticalState {
            mode: VerticalMode::DoubleCollectAndCollide { n_imp: n },
            effective_loss_factor: e / (PI * v_ref2),
            effective_mass_ratio: if n == 0 { 0.75 } else { 0.2 },
        }
    }
}

impl EffectiveDamper for VerticalDamper {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        let s = self.state(amplitude_m, omega_rad_s);
        state(
            self.bed_mass_kg,
            s.effective_loss_factor,
            s.effective_mass_ratio,
            amplitude_m,
            omega_rad_s,
        )
    }
    fn bed_mass_kg(&self) -> f64 {
        self.bed_mass_kg
    }
}

// ---------------------------------------------------------------------------------------------
// Powder-filled cavities: first-order friction models of the paper (Praegla et al., Powder
// Technology 2024, Sect. 4, eq. 17–26; "the paper" in docs/powder.md).
// ---------------------------------------------------------------------------------------------

/// Paper eq. 18–20 before the large-N approximation: frictional work of a box of length l
/// filled with equal spheres of radius R under a shear deformation by the angle φ,
/// $W = N_x(N_y-1)\,\mu\frac{F_{N,y}}{N_x}\Delta d$ with $\Delta d = 2R\tan\varphi$ and
/// $N_y = l/(2R)$ (eq. 17), J.
pub fn shear_work_discrete(l: f64, r: f64, mu: f64, f_ny: f64, phi: f64) -> f64 {
    let n_y = l / (2.0 * r);
    (n_y - 1.0) * mu * f_ny * 2.0 * r * phi.tan()
}

/// Paper eq. 20: $W = l\,\mu F_{N,y}\tan\varphi$, J (independent of R).
pub fn shear_work(l: f64, mu: f64, f_ny: f64, phi: f64) -> f64 {
    l * mu * f_ny * phi.tan()
}

/// Paper eq. 21–25 with the exact sums: $W = f\,2R\,\mu\frac{F_{N,x}}{N_y}\sum_i y_i$,
/// $\sum_i y_i = (N_x-1)\,2R\,\frac{N_y}{2}\frac{N_y/2+1}{2}$, $f = 4\Delta y_{max}/(bl)$,
/// $\Delta y_{max} = \frac b2\tan\varphi$, $N_x = b/(2R)$, $N_y = l/(2R)$, J.
pub fn bending_work_discrete(l: f64, b: f64, r: f64, mu: f64, f_nx: f64, phi: f64) -> f64 {
    let (n_x, n_y) = (b / (2.0 * r), l / (2.0 * r));
    let f = 4.0 * (0.5 * b * phi.tan()) / (b * l);
    let sum_y = (n_x - 1.0) * 2.0 * r * (n_y / 2.0) * (n_y / 2.0 + 1.0) / 2.0;
    f * 2.0 * r * mu * f_nx / n_y * sum_y
}

/// Paper eq. 26: $W = \frac{f\,b\,l}{8}\mu F_{N,x}$ with $f = 2\tan\varphi/l$, i.e.
/// $W = \tfrac14 b\,\mu F_{N,x}\tan\varphi$, J (independent of R).
pub fn bending_work(l: f64, b: f64, mu: f64, f_nx: f64, phi: f64) -> f64 {
    let f = 4.0 * (0.5 * b * phi.tan()) / (b * l);
    f * b * l / 8.0 * mu * f_nx
}

/// Deformation mode of a powder-filled cavity (paper Fig. 7b/c).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionMechanism {
    /// Pure shear by the angle φ (eq. 17–20), wall normal force $F_{N,y}$.
    Shear,
    /// Pure bending, end faces rotated by ±φ (eq. 21–26), wall normal force $F_{N,x}$.
    Bending,
}

/// Approach-3 model of a powder-filled cavity (paper Sect. 4): all particles in sliding contact
/// under constant wall normal forces (set by the compaction), so each contact dissipates
/// μF_N·|slip|. Over one vibration cycle of deformation amplitude φ every slip path is run
/// four times (0 → φ → 0 → −φ → 0), hence
/// $\tilde E_{diss} = 4\,W(\varphi)$ with W from eq. 20 (shear) or eq. 26 (bending) and
/// $\varphi = \kappa X$, κ the deformation angle per unit displacement of the damper point in
/// the analysed mode (from the mode shapes, e.g. half the difference of the cross-section
/// rotations at the cavity ends for bending). Ẽ ∝ X: a Coulomb (friction) damper,
/// $\bar\eta \propto 1/X$, equivalent to a dry-friction force $F_{eq} = \tilde E/(4X)$.
///
/// Range of validity (the paper's assumptions): dense packing with every particle in contact
/// and **every contact sliding** (no stick — at high packing densities contacts stick and the
/// model overestimates, at low densities contacts open and F_N vanishes); friction only (no
/// impacts); no slip at the walls; $N_x, N_y \gg 1$ (relative error of the R-free limits 2R/l
/// for shear, ≤ 2R/b + 4R/l for bending); small angles (tan φ ≈ φ enters exactly, but the
/// linear deformation fields of Fig. 7 are small-strain); the normal forces do not change with
/// the vibration. The powder's mass belongs to the structure model (it moves with the walls);
/// `effective_mass_kg` adds an extra m̄ at the damper point if wanted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowderFrictionDamper {
    /// Shear or bending.
    pub mechanism: FrictionMechanism,
    /// Cavity length l (along the beam axis, y in paper Fig. 7), m.
    pub cavity_length_m: f64,
    /// Cavity width b (across, x in paper Fig. 7; bending only), m.
    pub cavity_width_m: f64,
    /// Coefficient of friction μ.
    pub friction: f64,
    /// Wall normal force: $F_{N,y}$ (shear) or $F_{N,x}$ (bending), N.
    pub wall_normal_force_n: f64,
    /// κ = φ / X, rad/m.
    pub angle_per_displacement_rad_m: f64,
    /// Powder mass (for η̄ and the efficiency yardstick only), kg.
    pub bed_mass_kg: f64,
    /// Effective mass added at the damper point, kg.
    pub effective_mass_kg: f64,
}

impl PowderFrictionDamper {
    /// Frictional work W(φ) of one quarter cycle, J (eq. 20 or 26).
    pub fn work_j(&self, phi: f64) -> f64 {
        let phi = phi.abs();
        match self.mechanism {
            FrictionMechanism::Shear => shear_work(
                self.cavity_length_m,
                self.friction,
                self.wall_normal_force_n,
                phi,
            ),
            FrictionMechanism::Bending => bending_work(
                self.cavity_length_m,
                self.cavity_width_m,
                self.friction,
                self.wall_normal_force_n,
                phi,
            ),
        }
    }

    /// Checks the parameters; messages name the scenario key.
    ///
    /// # Errors
    /// Non-positive or non-finite values.
    pub fn validate(&self) -> Result<(), StructureError> {
        let pos = |v: f64, k: &str| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(StructureError::invalid(
                    "powder_friction",
                    format!("{k} must be > 0, got {v}"),
                ))
            }
        };
        pos(self.cavity_length_m, "cavity_length_m")?;
        if self.mechanism == FrictionMechanism::Bending {
            pos(self.cavity_width_m, "cavity_width_m")?;
        }
        pos(self.bed_mass_kg, "bed_mass_kg")?;
        for (v, k) in [
            (self.friction, "friction"),
            (self.wall_normal_force_n, "wall_normal_force_n"),
            (self.effective_mass_kg, "effective_mass_kg"),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(StructureError::invalid(
                    "powder_friction",
                    format!("{k} must be ≥ 0, got {v}"),
                ));
            }
        }
        if !self.angle_per_displacement_rad_m.is_finite() {
            return Err(StructureError::invalid(
                "powder_friction",
                "angle_per_displacement_rad_m must be finite",
            ));
        }
        Ok(())
    }
}

impl EffectiveDamper for PowderFrictionDamper {
    fn evaluate(&self, amplitude_m: f64, _omega_rad_s: f64) -> EffectiveState {
        EffectiveState {
            effective_mass_kg: self.effective_mass_kg,
            dissipated_energy_per_cycle_j: 4.0
                * self.work_j(self.angle_per_displacement_rad_m * amplitude_m),
        }
    }
    fn bed_mass_kg(&self) -> f64 {
        self.bed_mass_kg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values (notes B.4.4, from D Eq. 5.3, 5.8, 5.10, 3.15; starred ones are quoted
    /// in the dissertation: 0.91, 0.69, 0.46, 0.38, 0.25).
    #[test]
    fn rolling_model_matches_reference_table() {
        let h = 0.03;
        let xo = rolling_optimal_stroke_m(h);
        assert!((xo / h - 0.407518).abs() < 2e-6, "{}", xo / h);
        assert!((rolling_loss_factor(PI) - 20.0 / (7.0 * PI)).abs() < 1e-12);
        let d = RollingDamper {
            bed_mass_kg: 0.149,
            clearance_m: h,
            smoothing_log_width: None,
        };
        for (xh, tau, eta) in [
            (0.5, Some(2.8222), 0.8814),
            (1.0, Some(2.0554), 0.5906),
            (4.0 / 3.0, Some(1.8252), 0.4611),
            (2.0, Some(1.5557), 0.3102),
            (5.0, Some(1.1070), 0.1119),
            (0.2, None, 0.2),
        ] {
            let t = rolling_impact_phase(xh * h, h);
            match (t, tau) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 2e-4, "{xh}: {a} vs {b}"),
                (None, None) => {}
                _ => panic!("{xh}: regime mismatch {t:?}"),
            }
            let (e, _) = d.loss_factor_and_mass_ratio(xh * h);
            assert!((e - eta).abs() < 2e-4, "{xh}: η̄ {e} vs {eta}");
        }
        // Newton lands on the root of the same S (a 60-step bisection's root, 1e-13), from the
        // optimal stroke (τ = π) to far above it (τ → 0)
        for xh in [0.40752, 0.41, 0.7, 1.0, 3.0, 30.0, 3000.0] {
            let target = 1.0 / xh;
            let g = |t: f64| (rolling_path_integral(t) - 5.0 * t.sin()) / 7.0 - target;
            let (mut a, mut b) = (0.0, PI);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if g(m) > 0.0 {
                    b = m;
                } else {
                    a = m;
                }
            }
            let t = rolling_impact_phase(xh * h, h).unwrap();
            assert!(
                (t - 0.5 * (a + b)).abs() < 1e-13,
                "{xh}: {t} vs {}",
                0.5 * (a + b)
            );
        }
        // Eq. 5.14 mass switch
        assert_eq!(d.loss_factor_and_mass_ratio(0.5 * xo).1, 0.3);
        assert_eq!(d.loss_factor_and_mass_ratio(1.5 * xo).1, 1.0);
    }

    /// Vertical model [D Eq. 7.1–7.19], h = 0.1 m (D Sect. 7.1, 32 spheres): the zero-gravity
    /// limit η̄_max = 4/π at X_opt = h/π (Eq. 7.16–7.18) for A ≫ g, the bouncing values of
    /// Eq. 6.6/6.8 at 2 X_opt, solid-like below g, and the mode map of D Fig. 7.3a (harmonic
    /// single collect-and-collide just above A = g; harmonic double at 5 Hz, X = 40 mm).
    #[test]
    fn vertical_model_limits_and_mode_map() {
        let d = VerticalDamper {
            bed_mass_kg: 0.131,
            clearance_m: 0.1,
        };
        let w = |f: f64| TAU * f;
        // A ≫ g: 200 Hz at X = h/π (Γ ≈ 5000)
        let s = d.state(0.1 / PI, w(200.0));
        assert!(
            matches!(s.mode, VerticalMode::DoubleCollectAndCollide { n_imp: 0 }),
            "{s:?}"
        );
        assert!((s.effective_loss_factor - 4.0 / PI).abs() < 0.01, "{s:?}");
        let s = d.state(2.0 * 0.1 / PI, w(200.0));
        assert!((s.effective_loss_factor - 0.892).abs() < 0.01, "{s:?}");
        // D Fig. 7.3 / notes: 20 Hz, 32 mm → 1.27; 5 Hz, 40 mm harmonic double ≈ 1.04;
        // 4 Hz, 40 mm harmonic single ≈ 0.72 (D: single CaC "up to 0.7" in DEM)
        let s = d.state(0.032, w(20.0));
        assert!((s.effective_loss_factor - 1.271).abs() < 0.01, "{s:?}");
        let s = d.state(0.040, w(5.0));
        assert!(
            matches!(s.mode, VerticalMode::DoubleCollectAndCollide { n_imp: 0 }),
            "{s:?}"
        );
        assert!((s.effective_loss_factor - 1.036).abs() < 0.01, "{s:?}");
        let s = d.state(0.040, w(4.0));
        assert!(
            matches!(s.mode, VerticalMode::SingleCollectAndCollide { n_imp: 0 }),
            "{s:?}"
        );
        assert!((s.effective_loss_factor - 0.719).abs() < 0.01, "{s:?}");
        assert_eq!(s.effective_mass_ratio, 0.65);
        // solid-like below g (Eq. 7.5)
        let s = d.state(0.005, w(5.0));
        assert_eq!(s.mode, VerticalMode::SolidLike);
        assert_eq!(s.effective_loss_factor, 1e-3);
        // far above the optimum (X = 200 mm) → 0.27
        let s = d.state(0.2, w(10.0));
        assert!((s.effective_loss_factor - 0.27).abs() < 0.01, "{s:?}");
    }

    /// Bouncing: η̄ at X/X_opt = 1⁺, 2, 4 (notes 1.3 from D Eq. 6.6/6.8): 1.2732, 0.892, 0.454.
    #[test]
    fn bouncing_model_reference_values() {
        let h = 0.0925;
        let xo = h / PI;
        for (r, eta) in [(1.000001, 1.2732), (2.0, 0.892), (4.0, 0.454)] {
            let th = bouncing_impact_phase(r * xo, h).unwrap();
            let e = (1.0 - th.cos()).powi(2) / PI;
            assert!((e - eta).abs() < 1.5e-3, "{r}: {e}");
        }
        assert!(bouncing_impact_phase(0.9 * xo, h).is_none());
    }

    #[test]
    fn powder_friction_hand_values_and_limits() {
        // bending, l = 110 mm, b = 18 mm, μ = 0.4, F_N,x = 100 N, κ = 5 rad/m, X = 0.1 mm:
        // φ = 5e-4, W = b μ F tanφ / 4 = 0.018·0.4·100·tan(5e-4)/4 = 9.0000008e-5 J, Ẽ = 4W
        let mut d = PowderFrictionDamper {
            mechanism: FrictionMechanism::Bending,
            cavity_length_m: 0.11,
            cavity_width_m: 0.018,
            friction: 0.4,
            wall_normal_force_n: 100.0,
            angle_per_displacement_rad_m: 5.0,
            bed_mass_kg: 0.165,
            effective_mass_kg: 0.0,
        };
        d.validate().unwrap();
        let e = d.evaluate(1e-4, 3000.0).dissipated_energy_per_cycle_j;
        assert!((e / 3.600_000_3e-4 - 1.0).abs() < 1e-7, "{e}");
        // shear: W = l μ F tanφ = 0.11·0.4·100·tan(5e-4) = 2.2000002e-3 J
        d.mechanism = FrictionMechanism::Shear;
        let e = d.evaluate(1e-4, 3000.0).dissipated_energy_per_cycle_j;
        assert!((e / 8.800_000_7e-3 - 1.0).abs() < 1e-7, "{e}");
        // limits: Ẽ ∝ X for small X (Coulomb damper, η̄ ∝ 1/X), Ẽ = 0 without friction or
        // normal force, independent of frequency
        let e1 = d.evaluate(1e-6, 100.0).dissipated_energy_per_cycle_j;
        let e2 = d.evaluate(2e-6, 1000.0).dissipated_energy_per_cycle_j;
        assert!((e2 / e1 - 2.0).abs() < 1e-9);
        d.friction = 0.0;
        assert_eq!(d.evaluate(1e-4, 100.0).dissipated_energy_per_cycle_j, 0.0);
        d.friction = -1.0;
        assert!(d.validate().unwrap_err().to_string().contains("friction"));
    }

    #[test]
    fn friction_work_is_independent_of_particle_size() {
        let (l, b, mu, f, phi) = (0.11, 0.018, 0.4, 10.0, 1e-3);
        let ws = shear_work(l, mu, f, phi);
        let wb = bending_work(l, b, mu, f, phi);
        // halving R repeatedly: the exact sums approach the R-free limits, error ∝ R
        let mut prev_s = f64::INFINITY;
        let mut prev_b = f64::INFINITY;
        for k in 0..6 {
            let r = 0.5e-3 / 2f64.powi(k); // D50 = 1 mm … 31 µm
            let es = (shear_work_discrete(l, r, mu, f, phi) / ws - 1.0).abs();
            let eb = (bending_work_discrete(l, b, r, mu, f, phi) / wb - 1.0).abs();
            // shear: exactly 2R/l; bending: O(R/b)
            assert!((es - 2.0 * r / l).abs() < 1e-12, "{es}");
            assert!(eb < 4.0 * r / b.min(l) + 2.0 * r / l);
            assert!(es < prev_s && eb < prev_b);
            prev_s = es;
            prev_b = eb;
        }
        // the paper sizes D50 = 0.25, 0.5, 1 mm change the bending work by < 6 % in total
        let w: Vec<f64> = [0.125e-3, 0.25e-3, 0.5e-3]
            .iter()
            .map(|&r| bending_work_discrete(l, b, r, mu, f, phi))
            .collect();
        assert!((w[2] / w[0] - 1.0).abs() < 0.06, "{w:?}");
        // values: eq. 20 and 26
        assert!((ws - l * mu * f * phi.tan()).abs() < 1e-18);
        assert!((wb - 0.25 * b * phi.tan() * mu * f).abs() < 1e-18);
    }
}
