//! Particle size distributions: monodisperse, uniform in radius, or (truncated) log-normal in
//! diameter as in [P Table A.2], with the normal CDF and quantile they need.

use crate::ParameterError;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Distribution of particle sizes. All values are SI (metres).
///
/// Serialized with a `type` tag, e.g. in TOML
/// `{ type = "log_normal", median_diameter_m = 1.0e-3, sigma = 0.2707, min_radius_m = 3.53414e-4,
/// max_radius_m = 7.07385e-4 }` ([P Table A.2]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SizeDistribution {
    /// All particles have the same radius.
    Monodisperse {
        /// Particle radius in m.
        radius_m: f64,
    },
    /// Radius uniformly distributed in `[min_radius_m, max_radius_m]`.
    Uniform {
        /// Smallest radius in m.
        min_radius_m: f64,
        /// Largest radius in m.
        max_radius_m: f64,
    },
    /// Log-normal in diameter: ln D ~ N(ln D50, σ²), optionally truncated to
    /// `[2 min_radius_m, 2 max_radius_m]` (samples outside are redrawn).
    LogNormal {
        /// Median diameter D50 in m.
        median_diameter_m: f64,
        /// Standard deviation σ of ln D (dimensionless).
        sigma: f64,
        /// Lower radius cut-off in m (none: unbounded below).
        #[serde(default)]
        min_radius_m: Option<f64>,
        /// Upper radius cut-off in m (none: unbounded above).
        #[serde(default)]
        max_radius_m: Option<f64>,
    },
}

/// Smallest probability mass a log-normal truncation window may keep (else `validate` fails).
const MIN_TRUNCATION_MASS: f64 = 1e-6;

impl SizeDistribution {
    /// The scaled distribution of [P Table A.2]: D50 = 1.0 mm, σ = 0.2707,
    /// r_min = 0.353414 mm, r_max = 0.707385 mm.
    pub fn paper_table_a2() -> Self {
        SizeDistribution::LogNormal {
            median_diameter_m: 1.0e-3,
            sigma: 0.2707,
            min_radius_m: Some(0.353414e-3),
            max_radius_m: Some(0.707385e-3),
        }
    }

    /// Checks ranges; returns a message naming the offending field.
    pub fn validate(&self) -> Result<(), ParameterError> {
        fn positive(name: &str, v: f64) -> Result<(), ParameterError> {
            ParameterError::check(v.is_finite() && v > 0.0, name, "be finite and > 0", v)
        }
        match *self {
            SizeDistribution::Monodisperse { radius_m } => positive("radius_m", radius_m),
            SizeDistribution::Uniform {
                min_radius_m,
                max_radius_m,
            } => {
                positive("min_radius_m", min_radius_m)?;
                positive("max_radius_m", max_radius_m)?;
                if min_radius_m > max_radius_m {
                    return Err(ParameterError::invalid(
                        "min_radius_m",
                        format!(
                            "min_radius_m ({min_radius_m}) must not exceed max_radius_m ({max_radius_m})"
                        ),
                    ));
                }
                Ok(())
            }
            SizeDistribution::LogNormal {
                median_diameter_m,
                sigma,
                min_radius_m,
                max_radius_m,
            } => {
                positive("median_diameter_m", median_diameter_m)?;
                if !(sigma.is_finite() && sigma >= 0.0) {
                    return Err(ParameterError::out_of_range(
                        "sigma",
                        "be finite and >= 0",
                        sigma,
                    ));
                }
                if let Some(r) = min_radius_m {
                    positive("min_radius_m", r)?;
                }
                if let Some(r) = max_radius_m {
                    positive("max_radius_m", r)?;
                }
                match (min_radius_m, max_radius_m) {
                    (Some(lo), Some(hi)) if lo >= hi => {
                        return Err(ParameterError::invalid(
                            "min_radius_m",
                            format!("min_radius_m ({lo}) must be below max_radius_m ({hi})"),
                        ));
                    }
                    _ => {}
                }
                let r50 = 0.5 * median_diameter_m;
                if sigma == 0.0 {
                    if min_radius_m.is_some_and(|lo| r50 < lo)
                        || max_radius_m.is_some_and(|hi| r50 > hi)
                    {
                        return Err(ParameterError::invalid(
                            "sigma",
                            format!(
                                "with sigma = 0 the median radius {r50} m must lie within min_radius_m/max_radius_m"
                            ),
                        ));
                    }
                    return Ok(());
                }
                let mass = self
                    .lognormal_window()
                    .map_or(1.0, |(a, b)| normal_cdf(b) - normal_cdf(a));
                if mass < MIN_TRUNCATION_MASS {
                    return Err(ParameterError::invalid(
                        "min_radius_m/max_radius_m",
                        format!(
                            "min_radius_m/max_radius_m keep only {mass:.3e} of the log-normal probability mass (need >= {MIN_TRUNCATION_MASS:e})"
                        ),
                    ));
                }
                Ok(())
            }
        }
    }

    /// Standardized truncation window (α, β) of a log-normal distribution, `None` otherwise.
    fn lognormal_window(&self) -> Option<(f64, f64)> {
        match *self {
            SizeDistribution::LogNormal {
                median_diameter_m,
                sigma,
                min_radius_m,
                max_radius_m,
            } => {
                let std = |r: Option<f64>, default: f64| {
                    r.map_or(default, |r| (2.0 * r / median_diameter_m).ln() / sigma)
                };
                Some((
                    std(min_radius_m, f64::NEG_INFINITY),
                    std(max_radius_m, f64::INFINITY),
                ))
            }
            _ => None,
        }
    }

    /// Draws one radius in m.
    ///
    /// The truncated log-normal redraws samples outside the cut-offs; after 64 rejections in a row
    /// (only for narrow windows) it switches to exact inverse-CDF sampling of the same truncated
    /// distribution, so the call always terminates. Never panics, also not on invalid parameters
    /// (whose results are then meaningless; call [`validate`](Self::validate) first).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            SizeDistribution::Monodisperse { radius_m } => radius_m,
            SizeDistribution::Uniform {
                min_radius_m,
                max_radius_m,
            } => {
                let u: f64 = rng.random();
                min_radius_m + (max_radius_m - min_radius_m) * u
            }
            SizeDistribution::LogNormal {
                median_diameter_m,
                sigma,
                min_radius_m,
                max_radius_m,
            } => {
                let lo = min_radius_m.unwrap_or(0.0);
                let hi = max_radius_m.unwrap_or(f64::INFINITY);
                for _ in 0..64 {
                    let z: f64 = rng.sample(StandardNormal);
                    let r = 0.5 * median_diameter_m * (sigma * z).exp();
                    if r >= lo && r <= hi {
                        return r;
                    }
                }
                let u: f64 = rng.random();
                self.quantile_radius_m(u).max(lo).min(hi)
            }
        }
    }

    /// `n` radii drawn deterministically from `ChaCha8Rng::seed_from_u64(seed)`.
    pub fn sample_n(&self, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| self.sample(&mut rng)).collect()
    }

    /// Smallest possible radius in m (0 for a log-normal without lower cut-off).
    pub fn min_radius_m(&self) -> f64 {
        match *self {
            SizeDistribution::Monodisperse { radius_m } => radius_m,
            SizeDistribution::Uniform { min_radius_m, .. } => min_radius_m,
            SizeDistribution::LogNormal { min_radius_m, .. } => min_radius_m.unwrap_or(0.0),
        }
    }

    /// Largest possible radius in m (+∞ for a log-normal without upper cut-off; size packings
    /// from the largest radius actually drawn in that case).
    pub fn max_radius_m(&self) -> f64 {
        match *self {
            SizeDistribution::Monodisperse { radius_m } => radius_m,
            SizeDistribution::Uniform { max_radius_m, .. } => max_radius_m,
            SizeDistribution::LogNormal { max_radius_m, .. } => {
                max_radius_m.unwrap_or(f64::INFINITY)
            }
        }
    }

    /// Radius in m below which the fraction `p ∈ [0, 1]` (by number) of particles lies, i.e. the
    /// quantile function of the (truncated) distribution. For the untruncated log-normal this is
    /// `exp(ln D50 + σ Φ⁻¹(p)) / 2`; D10/D90 use p = 0.1/0.9.
    pub fn quantile_radius_m(&self, p: f64) -> f64 {
        let p = if p.is_nan() { 0.5 } else { p.clamp(0.0, 1.0) };
        match *self {
            SizeDistribution::Monodisperse { radius_m } => radius_m,
            SizeDistribution::Uniform {
                min_radius_m,
                max_radius_m,
            } => min_radius_m + (max_radius_m - min_radius_m) * p,
            SizeDistribution::LogNormal {
                median_diameter_m,
                sigma,
                ..
            } => {
                let (a, b) = self
                    .lognormal_window()
                    .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                let (fa, fb) = (normal_cdf(a), normal_cdf(b));
                let z = normal_quantile(fa + p * (fb - fa));
                let z = if sigma > 0.0 { z.clamp(a, b) } else { 0.0 };
                0.5 * median_diameter_m * (sigma * z).exp()
            }
        }
    }

    /// Raw moment E[r^k] of the radius in m^k, exact (closed form) for every variant.
    ///
    /// For the truncated log-normal with standardized window (α, β):
    /// E[D^k] = D50^k exp(k²σ²/2) [Φ(β − kσ) − Φ(α − kσ)] / [Φ(β) − Φ(α)].
    pub fn radius_moment(&self, k: i32) -> f64 {
        match *self {
            SizeDistribution::Monodisperse { radius_m } => radius_m.powi(k),
            SizeDistribution::Uniform {
                min_radius_m: a,
                max_radius_m: b,
            } => {
                if b <= a {
                    a.powi(k)
                } else if k == -1 {
                    (b / a).ln() / (b - a)
                } else {
                    let kp = k + 1;
                    (b.powi(kp) - a.powi(kp)) / (f64::from(kp) * (b - a))
                }
            }
            SizeDistribution::LogNormal {
                median_diameter_m,
                sigma,
                ..
            } => {
                let kf = f64::from(k);
                let r50k = (0.5 * median_diameter_m).powi(k);
                if sigma == 0.0 {
                    return r50k;
                }
                let (a, b) = self
                    .lognormal_window()
                    .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                let mass = normal_cdf(b) - normal_cdf(a);
                let shifted = normal_cdf(b - kf * sigma) - normal_cdf(a - kf * sigma);
                r50k * (0.5 * kf * kf * sigma * sigma).exp() * shifted / mass
            }
        }
    }

    /// Mean radius in m (exact, see [`radius_moment`](Self::radius_moment)).
    pub fn mean_radius_m(&self) -> f64 {
        self.radius_moment(1)
    }

    /// Mean particle volume (4/3) π E\[r³\] in m³. Computed in closed form (not by sampling or
    /// quadrature), see [`radius_moment`](Self::radius_moment).
    pub fn mean_volume_m3(&self) -> f64 {
        4.0 / 3.0 * PI * self.radius_moment(3)
    }
}

/// Complementary error function, accurate to ~1e-15 relative for x ≥ 0 up to erfc ≈ 1e-300.
fn erfc(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    if x < 3.0 {
        // erf(x) = 2/√π e^{−x²} Σ 2ⁿ x^{2n+1} / (1·3·…·(2n+1)) — all terms positive.
        let x2 = x * x;
        let mut term = x;
        let mut sum = x;
        for n in 1..400 {
            term *= 2.0 * x2 / f64::from(2 * n + 1);
            sum += term;
            if term < 1e-17 * sum {
                break;
            }
        }
        1.0 - 2.0 / PI.sqrt() * (-x2).exp() * sum
    } else if x > 27.0 {
        0.0
    } else {
        // Continued fraction erfc(x) = e^{−x²}/√π · 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + …)))).
        let mut f = x;
        for k in (1..=80).rev() {
            f = x + 0.5 * f64::from(k) / f;
        }
        (-x * x).exp() / (PI.sqrt() * f)
    }
}

/// Standard normal CDF Φ(x).
pub fn normal_cdf(x: f64) -> f64 {
    if x == f64::INFINITY {
        1.0
    } else if x == f64::NEG_INFINITY {
        0.0
    } else {
        0.5 * erfc(-x / std::f64::consts::SQRT_2)
    }
}

/// Standard normal quantile Φ⁻¹(p) (Acklam's rational approximation refined by two Newton steps;
/// ±∞ at p = 0 and 1). Example: Φ⁻¹(0.9) = 1.2815515655….
pub fn normal_quantile(p: f64) -> f64 {
    if p.is_nan() {
        return f64::NAN;
    }
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let mut x = if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    for _ in 0..2 {
        let pdf = (-0.5 * x * x).exp() / (2.0 * PI).sqrt();
        if pdf > 0.0 {
            // Work with the smaller tail to keep relative accuracy far out.
            let err = if x > 0.0 {
                (1.0 - p) - normal_cdf(-x)
            } else {
                normal_cdf(x) - p
            };
            x -= err / pdf;
        }
    }
    x
}
