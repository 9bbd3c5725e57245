//! Particle generation: size distributions, container regions and initial placements
//! ([D sec. 2.1, Fig. 2.2]).
//!
//! * [`SizeDistribution`] — monodisperse, uniform in radius, or (truncated) log-normal in diameter
//!   as in [P Table A.2] (D50 = 1.0 mm, σ = 0.2707, r ∈ [0.353414, 0.707385] mm).
//! * [`Region`] — the volume to fill (axis-aligned box or arbitrary cylinder).
//! * Placements: [`grid_packing`] (simple cubic) and [`tight_packing`] (hexagonal close packing)
//!   filled layer by layer from the bottom ([D Fig. 2.2a]); [`random_insertion`] over the whole
//!   volume ([D Fig. 2.2c]) or layer by layer ([D Fig. 2.2d], via [`Layering`]).
//!
//! Drop-down settling ([D Fig. 2.2b]) is done by the simulation pipeline, not here.
//! All generators are deterministic: the same inputs (and seed) give bit-identical output.

use crate::ParameterError;
use crate::math::Vec3;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

// ------------------------------------------------------------------------------------------------
// Size distributions
// ------------------------------------------------------------------------------------------------

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

// ------------------------------------------------------------------------------------------------
// Regions
// ------------------------------------------------------------------------------------------------

/// A volume to fill with particles (usually the inner volume of the container).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// Axis-aligned box `[min_m, max_m]`.
    Box {
        /// Lower corner in m.
        min_m: Vec3,
        /// Upper corner in m.
        max_m: Vec3,
    },
    /// Solid cylinder from `base_center_m` along `axis` (any length, normalized internally).
    Cylinder {
        /// Centre of the base disc in m.
        base_center_m: Vec3,
        /// Axis direction (need not be unit).
        axis: Vec3,
        /// Cylinder radius in m.
        radius_m: f64,
        /// Cylinder length along the axis in m.
        length_m: f64,
    },
}

impl Region {
    /// Checks ranges; returns a message naming the offending field.
    pub fn validate(&self) -> Result<(), ParameterError> {
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        match self {
            Region::Box { min_m, max_m } => {
                if !finite(min_m) || !finite(max_m) {
                    return Err(ParameterError::invalid(
                        "min_m",
                        "min_m and max_m must be finite",
                    ));
                }
                if (0..3).any(|i| min_m[i] >= max_m[i]) {
                    return Err(ParameterError::invalid(
                        "min_m",
                        format!(
                            "min_m {:?} must be below max_m {:?} in every component",
                            min_m.as_slice(),
                            max_m.as_slice()
                        ),
                    ));
                }
                Ok(())
            }
            Region::Cylinder {
                base_center_m,
                axis,
                radius_m,
                length_m,
            } => {
                if !finite(base_center_m) {
                    return Err(ParameterError::invalid(
                        "base_center_m",
                        "base_center_m must be finite",
                    ));
                }
                if !finite(axis) || axis.norm() == 0.0 {
                    return Err(ParameterError::invalid(
                        "axis",
                        "axis must be finite and non-zero",
                    ));
                }
                let (r, l) = (*radius_m, *length_m);
                ParameterError::check(
                    r.is_finite() && r > 0.0,
                    "radius_m",
                    "be finite and > 0",
                    r,
                )?;
                ParameterError::check(l.is_finite() && l > 0.0, "length_m", "be finite and > 0", l)
            }
        }
    }

    /// Whether the sphere of radius `r` at `x` lies completely inside (touching allowed).
    pub fn contains_sphere(&self, x: &Vec3, r: f64) -> bool {
        match self {
            Region::Box { min_m, max_m } => {
                (0..3).all(|i| x[i] - r >= min_m[i] && x[i] + r <= max_m[i])
            }
            Region::Cylinder {
                base_center_m,
                axis,
                radius_m,
                length_m,
            } => {
                let a = axis.normalize();
                let d = x - base_center_m;
                let t = d.dot(&a);
                if t < r || t > length_m - r {
                    return false;
                }
                let rho2 = (d - a * t).norm_squared();
                let free = radius_m - r;
                free >= 0.0 && rho2 <= free * free
            }
        }
    }

    /// Volume in m³.
    pub fn volume_m3(&self) -> f64 {
        match self {
            Region::Box { min_m, max_m } => (max_m - min_m).product(),
            Region::Cylinder {
                radius_m, length_m, ..
            } => PI * radius_m * radius_m * length_m,
        }
    }

    /// Range `(min, max)` of `x·u` over the region, for a unit vector `u`.
    pub fn extent_along(&self, u: &Vec3) -> (f64, f64) {
        match self {
            Region::Box { min_m, max_m } => {
                let c = 0.5 * (min_m + max_m);
                let h = 0.5 * (max_m - min_m);
                let half = h.x * u.x.abs() + h.y * u.y.abs() + h.z * u.z.abs();
                (c.dot(u) - half, c.dot(u) + half)
            }
            Region::Cylinder {
                base_center_m,
                axis,
                radius_m,
                length_m,
            } => {
                let a = axis.normalize();
                let p0 = base_center_m.dot(u);
                let p1 = (base_center_m + a * *length_m).dot(u);
                let lateral = radius_m * (1.0 - a.dot(u).powi(2)).max(0.0).sqrt();
                (p0.min(p1) - lateral, p0.max(p1) + lateral)
            }
        }
    }

    /// The region extended by `h` beyond its top along the unit vector `up`: a box with an edge
    /// along `up`, a cylinder with its axis along `up`; `None` for other orientations.
    pub fn raised(&self, up: &Vec3, h: f64) -> Option<Region> {
        let aligned = |c: f64| c.abs() > 1.0 - 1e-9;
        match self {
            Region::Box { min_m, max_m } => {
                let k = (0..3).find(|&k| aligned(up[k]))?;
                let (mut lo, mut hi) = (*min_m, *max_m);
                if up[k] > 0.0 {
                    hi[k] += h;
                } else {
                    lo[k] -= h;
                }
                Some(Region::Box {
                    min_m: lo,
                    max_m: hi,
                })
            }
            Region::Cylinder {
                base_center_m,
                axis,
                radius_m,
                length_m,
            } => {
                let c = axis.normalize().dot(up);
                if !aligned(c) {
                    return None;
                }
                Some(Region::Cylinder {
                    base_center_m: if c > 0.0 {
                        *base_center_m
                    } else {
                        base_center_m + up * h
                    },
                    axis: *axis,
                    radius_m: *radius_m,
                    length_m: length_m + h,
                })
            }
        }
    }

    /// Axis-aligned bounding box `(min, max)` in m.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::zeros();
        let mut hi = Vec3::zeros();
        for i in 0..3 {
            let (a, b) = self.extent_along(&Vec3::ith(i, 1.0));
            lo[i] = a;
            hi[i] = b;
        }
        (lo, hi)
    }

    /// Uniform random centre for a sphere of radius `r` inside the region; `None` if it cannot fit.
    pub(crate) fn sample_center<R: Rng + ?Sized>(&self, r: f64, rng: &mut R) -> Option<Vec3> {
        match self {
            Region::Box { min_m, max_m } => {
                let mut x = Vec3::zeros();
                for i in 0..3 {
                    let (lo, hi) = (min_m[i] + r, max_m[i] - r);
                    if lo > hi {
                        return None;
                    }
                    let u: f64 = rng.random();
                    x[i] = (lo + (hi - lo) * u).min(hi);
                }
                Some(x)
            }
            Region::Cylinder {
                base_center_m,
                axis,
                radius_m,
                length_m,
            } => {
                let free = radius_m - r;
                if free < 0.0 || length_m - r < r {
                    return None;
                }
                let (e1, e2, a) = orthonormal_frame(axis)?;
                let (u, v, w): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
                let rho = free * u.sqrt();
                let phi = 2.0 * PI * v;
                let t = r + (length_m - 2.0 * r) * w;
                Some(base_center_m + a * t + (e1 * phi.cos() + e2 * phi.sin()) * rho)
            }
        }
    }
}

/// Orthonormal right-handed frame `(e1, e2, e3)` with `e3 = up / |up|`; `None` for a zero or
/// non-finite `up`.
pub fn orthonormal_frame(up: &Vec3) -> Option<(Vec3, Vec3, Vec3)> {
    let n = up.norm();
    if !(n.is_finite() && n > 0.0) {
        return None;
    }
    let e3 = up / n;
    let helper = if e3.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let e1 = (helper - e3 * helper.dot(&e3)).normalize();
    let e2 = e3.cross(&e1);
    Some((e1, e2, e3))
}

// ------------------------------------------------------------------------------------------------
// Lattice packings
// ------------------------------------------------------------------------------------------------

/// Errors of the packing generators ([`grid_packing`], [`tight_packing`], [`random_insertion`],
/// [`lattice_sites`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PackingError {
    /// A region, radius, spacing, gap or layering parameter out of range.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The lattice would need more candidate sites than 5e7.
    #[error(
        "lattice packing would need about {sites:.3e} candidate sites (spacing {spacing_m} m too small for the region)"
    )]
    TooManySites {
        /// Estimated number of candidate sites.
        sites: f64,
        /// Lattice spacing in m.
        spacing_m: f64,
    },
    /// The region holds fewer lattice sites than particles.
    #[error(
        "region holds only {fitted} of {requested} particles on a {lattice:?} lattice with spacing {spacing_m:.6e} m (2 r_max + gap)"
    )]
    RegionTooSmall {
        /// Sites that fit.
        fitted: usize,
        /// Particles to place.
        requested: usize,
        /// The lattice.
        lattice: Lattice,
        /// Nearest-neighbour spacing in m.
        spacing_m: f64,
    },
    /// More particles than the insertion grid can index.
    #[error("too many particles ({count})")]
    TooManyParticles {
        /// Particles requested.
        count: usize,
    },
    /// Random insertion found no free position for a particle.
    #[error(
        "random insertion placed only {placed} of {requested} particles: particle {particle} (radius {radius_m:.6e} m) found no free position in {attempts} attempts{}",
        if *in_top_layer { " in the top layer" } else { "" }
    )]
    NoFreePosition {
        /// Particles placed before.
        placed: usize,
        /// Particles to place.
        requested: usize,
        /// Index of the particle that found no place.
        particle: usize,
        /// Its radius in m.
        radius_m: f64,
        /// Attempts per particle.
        attempts: usize,
        /// Whether layered insertion had reached its top layer.
        in_top_layer: bool,
    },
}

/// Transitional: lets callers that still return `Result<_, String>` use `?` (issue 30).
impl From<PackingError> for String {
    fn from(e: PackingError) -> String {
        e.to_string()
    }
}

/// Lattice of a regular packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lattice {
    /// Simple cubic grid (solid fraction π/6 ≈ 0.524 for equal spheres).
    SimpleCubic,
    /// Hexagonal close packing, triangular layers stacked ABAB (π/(3√2) ≈ 0.740).
    Hcp,
    /// Face-centred cubic, triangular layers stacked ABC (π/(3√2) ≈ 0.740).
    Fcc,
}

/// Relative tolerance (of the spacing) for lattice sites touching the region boundary.
const LATTICE_TOL: f64 = 1e-9;
/// Refuse to enumerate more candidate lattice sites than this.
const MAX_LATTICE_SITES: f64 = 5.0e7;

/// All sites of `lattice` with nearest-neighbour distance `spacing_m` at which a sphere of radius
/// `clearance_m` lies inside `region` (to within 1e-9 · spacing), ordered layer by layer along
/// `up` from the bottom and, within a layer, from the lateral centre outwards (so a partial top
/// layer is centred). Layers start `clearance_m` above the lowest point of the region and are
/// centred laterally on the region's extent.
pub fn lattice_sites(
    region: &Region,
    spacing_m: f64,
    clearance_m: f64,
    up: &Vec3,
    lattice: Lattice,
) -> Result<Vec<Vec3>, PackingError> {
    lattice_sites_limited(region, spacing_m, clearance_m, up, lattice, usize::MAX)
}

/// As [`lattice_sites`] but stops after the first complete layer that brings the count to `limit`.
fn lattice_sites_limited(
    region: &Region,
    d: f64,
    c: f64,
    up: &Vec3,
    lattice: Lattice,
    limit: usize,
) -> Result<Vec<Vec3>, PackingError> {
    region.validate()?;
    if !(d.is_finite() && d > 0.0) {
        return Err(ParameterError::out_of_range("lattice spacing", "be finite and > 0", d).into());
    }
    if !(c.is_finite() && c >= 0.0) {
        return Err(
            ParameterError::out_of_range("lattice clearance", "be finite and >= 0", c).into(),
        );
    }
    let (e1, e2, e3) = orthonormal_frame(up).ok_or(ParameterError::invalid(
        "up",
        "up direction must be finite and non-zero",
    ))?;
    let (lo1, hi1) = region.extent_along(&e1);
    let (lo2, hi2) = region.extent_along(&e2);
    let (lo3, hi3) = region.extent_along(&e3);
    let tol = LATTICE_TOL * d;
    let (row, layer) = match lattice {
        Lattice::SimpleCubic => (d, d),
        Lattice::Hcp | Lattice::Fcc => (d * 3f64.sqrt() / 2.0, d * (2.0f64 / 3.0).sqrt()),
    };
    let count = |w: f64, s: f64| ((w - 2.0 * c + tol) / s).floor() + 1.0;
    let (n1, n2, n3) = (
        count(hi1 - lo1, d),
        count(hi2 - lo2, row),
        count(hi3 - lo3, layer),
    );
    if n1 < 1.0 || n2 < 1.0 || n3 < 1.0 {
        return Ok(Vec::new());
    }
    if (n1 + 2.0) * (n2 + 2.0) * n3 > MAX_LATTICE_SITES {
        return Err(PackingError::TooManySites {
            sites: n1 * n2 * n3,
            spacing_m: d,
        });
    }
    let (n1, n2, n3) = (n1 as i64, n2 as i64, n3 as i64);
    let x0 = lo1 + 0.5 * (hi1 - lo1 - (n1 - 1) as f64 * d);
    let y0 = lo2 + 0.5 * (hi2 - lo2 - (n2 - 1) as f64 * row);
    let (xc, yc) = (0.5 * (lo1 + hi1), 0.5 * (lo2 + hi2));
    let mut out = Vec::new();
    let mut layer_sites: Vec<(f64, i64, i64, Vec3)> = Vec::new();
    for k in 0..n3 {
        let z = lo3 + c + k as f64 * layer;
        // Lateral shift of the layer (B and C positions of the close-packed stacking).
        let m = match lattice {
            Lattice::SimpleCubic => 0,
            Lattice::Hcp => k % 2,
            Lattice::Fcc => k % 3,
        } as f64;
        let (sx, sy) = (m * 0.5 * d, m * d / (2.0 * 3f64.sqrt()));
        layer_sites.clear();
        for j in -1..=n2 {
            let odd = lattice != Lattice::SimpleCubic && j.rem_euclid(2) == 1;
            let y = y0 + j as f64 * row + sy;
            for i in -2..=n1 {
                let x = x0 + i as f64 * d + if odd { 0.5 * d } else { 0.0 } + sx;
                let p = e1 * x + e2 * y + e3 * z;
                if region.contains_sphere(&p, (c - tol).max(0.0)) {
                    let r2 = (x - xc).powi(2) + (y - yc).powi(2);
                    layer_sites.push((r2, j, i, p));
                }
            }
        }
        layer_sites.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        out.extend(layer_sites.iter().map(|s| s.3));
        if out.len() >= limit {
            break;
        }
    }
    Ok(out)
}

fn check_radii(radii: &[f64]) -> Result<f64, ParameterError> {
    let mut r_max = 0.0f64;
    for (i, &r) in radii.iter().enumerate() {
        if !(r.is_finite() && r > 0.0) {
            let key = format!("radius of particle {i}");
            return Err(ParameterError::out_of_range(key, "be finite and > 0", r));
        }
        r_max = r_max.max(r);
    }
    Ok(r_max)
}

fn lattice_packing(
    region: &Region,
    radii: &[f64],
    gap_m: f64,
    up: &Vec3,
    lattice: Lattice,
) -> Result<Vec<Vec3>, PackingError> {
    let r_max = check_radii(radii)?;
    if radii.is_empty() {
        return Ok(Vec::new());
    }
    if !(gap_m.is_finite() && gap_m >= 0.0) {
        return Err(ParameterError::out_of_range("gap_m", "be finite and >= 0", gap_m).into());
    }
    let spacing = 2.0 * r_max + gap_m;
    let mut sites = lattice_sites_limited(
        region,
        spacing,
        r_max + 0.5 * gap_m,
        up,
        lattice,
        radii.len(),
    )?;
    if sites.len() < radii.len() {
        return Err(PackingError::RegionTooSmall {
            fitted: sites.len(),
            requested: radii.len(),
            lattice,
            spacing_m: spacing,
        });
    }
    sites.truncate(radii.len());
    Ok(sites)
}

/// Simple cubic packing with spacing `2 r_max + gap_m`, filled layer by layer from the bottom
/// (bottom = lowest point along `up`, i.e. opposite to gravity). Particle `i` gets position `i`;
/// sphere surfaces keep at least `gap_m` from each other and `gap_m / 2` from the region boundary.
/// Errors if the region cannot hold all particles (the message states how many fit).
pub fn grid_packing(
    region: &Region,
    radii: &[f64],
    gap_m: f64,
    up: &Vec3,
) -> Result<Vec<Vec3>, PackingError> {
    lattice_packing(region, radii, gap_m, up, Lattice::SimpleCubic)
}

/// Tight packing ([D Fig. 2.2a]): hexagonal close packing (triangular layers, ABAB stacking)
/// with nearest-neighbour spacing `2 r_max + gap_m`, otherwise as [`grid_packing`]. Solid
/// fraction for equal spheres and gap 0 is 0.740 in the bulk, less near walls.
pub fn tight_packing(
    region: &Region,
    radii: &[f64],
    gap_m: f64,
    up: &Vec3,
) -> Result<Vec<Vec3>, PackingError> {
    lattice_packing(region, radii, gap_m, up, Lattice::Hcp)
}

// ------------------------------------------------------------------------------------------------
// Random insertion
// ------------------------------------------------------------------------------------------------

/// Layer-by-layer random insertion ([D Fig. 2.2d]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layering {
    /// Upward direction (opposite to gravity); need not be unit.
    pub up: Vec3,
    /// Height of one layer (range of centre heights) in m.
    pub layer_height_m: f64,
}

/// Uniform cell grid over a box with linked lists of particle indices (O(1) overlap checks).
pub(crate) struct CellGrid {
    lo: Vec3,
    cell: f64,
    dims: [usize; 3],
    head: Vec<u32>,
    next: Vec<u32>,
}

pub(crate) const EMPTY: u32 = u32::MAX;

impl CellGrid {
    pub(crate) fn new(lo: Vec3, hi: Vec3, min_cell: f64, n: usize) -> Self {
        let ext = hi - lo;
        // Keep the cell count bounded (≤ ~4M cells) for huge regions with tiny particles.
        let cell = min_cell.max((ext.product() / 4.0e6).cbrt());
        let dim = |e: f64| ((e / cell).ceil() as usize).max(1);
        let dims = [dim(ext.x), dim(ext.y), dim(ext.z)];
        CellGrid {
            lo,
            cell,
            dims,
            head: vec![EMPTY; dims[0] * dims[1] * dims[2]],
            next: Vec::with_capacity(n),
        }
    }

    fn coord(&self, x: &Vec3) -> [usize; 3] {
        let mut c = [0usize; 3];
        for i in 0..3 {
            let f = ((x[i] - self.lo[i]) / self.cell).floor();
            c[i] = if f <= 0.0 {
                0
            } else {
                (f as usize).min(self.dims[i] - 1)
            };
        }
        c
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Adds particle `id` (ids must be added in order 0, 1, 2, …).
    pub(crate) fn insert(&mut self, id: u32, x: &Vec3) {
        let k = self.index(self.coord(x));
        debug_assert_eq!(self.next.len(), id as usize);
        self.next.push(self.head[k]);
        self.head[k] = id;
    }

    /// Whether a sphere (x, r) overlaps any stored particle; valid while r + r_j ≤ cell size.
    pub(crate) fn overlaps(&self, x: &Vec3, r: f64, pos: &[Vec3], radii: &[f64]) -> bool {
        let c = self.coord(x);
        let range = |i: usize| c[i].saturating_sub(1)..=(c[i] + 1).min(self.dims[i] - 1);
        for iz in range(2) {
            for iy in range(1) {
                for ix in range(0) {
                    let mut j = self.head[self.index([ix, iy, iz])];
                    while j != EMPTY {
                        let ju = j as usize;
                        let s = r + radii[ju];
                        if (pos[ju] - x).norm_squared() < s * s {
                            return true;
                        }
                        j = self.next[ju];
                    }
                }
            }
        }
        false
    }
}

impl CellGrid {
    /// Calls `f(j)` for every stored particle in the cells around `x` (the 27 cells).
    pub(crate) fn for_each_near(&self, x: &Vec3, mut f: impl FnMut(usize)) {
        let c = self.coord(x);
        let range = |i: usize| c[i].saturating_sub(1)..=(c[i] + 1).min(self.dims[i] - 1);
        for iz in range(2) {
            for iy in range(1) {
                for ix in range(0) {
                    let mut j = self.head[self.index([ix, iy, iz])];
                    while j != EMPTY {
                        f(j as usize);
                        j = self.next[j as usize];
                    }
                }
            }
        }
    }

    /// Whether the point `x` lies inside any stored particle (valid for points within one cell
    /// of the stored centres' box).
    pub(crate) fn contains_point(&self, x: &Vec3, pos: &[Vec3], radii: &[f64]) -> bool {
        let mut inside = false;
        self.for_each_near(x, |j| {
            if !inside && (pos[j] - x).norm_squared() < radii[j] * radii[j] {
                inside = true;
            }
        });
        inside
    }
}

/// Random placement without overlaps ([D Fig. 2.2c/d]), deterministic for a `seed`
/// (`ChaCha8Rng::seed_from_u64`). Whole-volume insertion places the particles in order of
/// decreasing radius, layered insertion in the given order; position `i` always belongs to
/// `radii[i]`. Each particle gets up to
/// `max_attempts_per_particle` uniformly drawn trial centres (every draw counts as an attempt).
/// Spheres may touch but not overlap each other or the region boundary. Overlap checks use a cell
/// grid with cells ≥ 2 r_max, so each trial costs O(1).
///
/// * `layering = None`: trial centres are uniform over the whole region.
/// * `layering = Some(l)`: the region is cut into slabs of centre heights
///   `[k h, (k+1) h)` above its lowest point along `l.up`; particles go into slab 0 until one fails
///   `max_attempts_per_particle` times, then into slab 1, and so on.
///
/// Errors (naming how many were placed) if a particle finds no free position.
pub fn random_insertion(
    region: &Region,
    radii: &[f64],
    seed: u64,
    max_attempts_per_particle: usize,
    layering: Option<&Layering>,
) -> Result<Vec<Vec3>, PackingError> {
    random_insertion_clear_of(
        region,
        radii,
        seed,
        max_attempts_per_particle,
        layering,
        &|_, _| false,
    )
}

/// [`random_insertion`] that also rejects every trial centre for which `blocked(x, r)` is true —
/// e.g. a sphere that would start inside or across a wall or an inner structure of the
/// container ([`crate::World::wall_overlap`]). A rejected trial counts as an attempt.
pub fn random_insertion_clear_of(
    region: &Region,
    radii: &[f64],
    seed: u64,
    max_attempts_per_particle: usize,
    layering: Option<&Layering>,
    blocked: &dyn Fn(&Vec3, f64) -> bool,
) -> Result<Vec<Vec3>, PackingError> {
    region.validate()?;
    let r_max = check_radii(radii)?;
    if radii.is_empty() {
        return Ok(Vec::new());
    }
    if max_attempts_per_particle == 0 {
        return Err(ParameterError::invalid(
            "max_attempts_per_particle",
            "max_attempts_per_particle must be > 0",
        )
        .into());
    }
    if radii.len() >= EMPTY as usize {
        return Err(PackingError::TooManyParticles { count: radii.len() });
    }
    let (lo, hi) = region.bounding_box();
    let mut grid = CellGrid::new(lo, hi, 2.0 * r_max, radii.len());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Whole-volume insertion tries the largest particles first (they are the hardest to place
    // late); layered insertion keeps the given order so sizes are not segregated by height.
    let mut order: Vec<usize> = (0..radii.len()).collect();
    if layering.is_none() {
        order.sort_by(|&a, &b| radii[b].total_cmp(&radii[a]).then(a.cmp(&b)));
    }
    let ins_radii: Vec<f64> = order.iter().map(|&i| radii[i]).collect();
    let mut pos: Vec<Vec3> = Vec::with_capacity(radii.len());

    let layers = match layering {
        None => None,
        Some(l) => {
            if !(l.layer_height_m.is_finite() && l.layer_height_m > 0.0) {
                let h = l.layer_height_m;
                return Err(
                    ParameterError::out_of_range("layer_height_m", "be finite and > 0", h).into(),
                );
            }
            let (e1, e2, e3) = orthonormal_frame(&l.up).ok_or(ParameterError::invalid(
                "layering.up",
                "layering: up must be finite and non-zero",
            ))?;
            let ext = [
                region.extent_along(&e1),
                region.extent_along(&e2),
                region.extent_along(&e3),
            ];
            let n_layers = (((ext[2].1 - ext[2].0) / l.layer_height_m).ceil() as usize).max(1);
            Some(([e1, e2, e3], ext, l.layer_height_m, n_layers))
        }
    };
    let mut layer = 0usize;

    for (n_placed, (&i, &r)) in order.iter().zip(&ins_radii).enumerate() {
        let placed = loop {
            let mut found = None;
            for _ in 0..max_attempts_per_particle {
                let trial = match &layers {
                    None => region.sample_center(r, &mut rng),
                    Some((e, ext, h, _)) => {
                        let z_lo = (ext[2].0 + layer as f64 * h).max(ext[2].0 + r);
                        let z_hi = (ext[2].0 + (layer + 1) as f64 * h).min(ext[2].1 - r);
                        let (x_lo, x_hi) = (ext[0].0 + r, ext[0].1 - r);
                        let (y_lo, y_hi) = (ext[1].0 + r, ext[1].1 - r);
                        if z_lo > z_hi || x_lo > x_hi || y_lo > y_hi {
                            None
                        } else {
                            let (u, v, w): (f64, f64, f64) =
                                (rng.random(), rng.random(), rng.random());
                            let p = e[0] * (x_lo + (x_hi - x_lo) * u)
                                + e[1] * (y_lo + (y_hi - y_lo) * v)
                                + e[2] * (z_lo + (z_hi - z_lo) * w);
                            region.contains_sphere(&p, r).then_some(p)
                        }
                    }
                };
                let Some(p) = trial else {
                    if layers.is_none() {
                        break; // cannot fit at all
                    }
                    continue;
                };
                if !region.contains_sphere(&p, r) {
                    continue;
                }
                if !grid.overlaps(&p, r, &pos, &ins_radii) && !blocked(&p, r) {
                    found = Some(p);
                    break;
                }
            }
            match (found, &layers) {
                (Some(p), _) => break Some(p),
                (None, Some((_, _, _, n_layers))) if layer + 1 < *n_layers => layer += 1,
                (None, _) => break None,
            }
        };
        let Some(p) = placed else {
            return Err(PackingError::NoFreePosition {
                placed: n_placed,
                requested: radii.len(),
                particle: i,
                radius_m: r,
                attempts: max_attempts_per_particle,
                in_top_layer: layers.is_some(),
            });
        };
        grid.insert(n_placed as u32, &p);
        pos.push(p);
    }
    let mut out = vec![Vec3::zeros(); radii.len()];
    for (&i, p) in order.iter().zip(pos) {
        out[i] = p;
    }
    Ok(out)
}

// ------------------------------------------------------------------------------------------------
// Tests
// ------------------------------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    fn median(v: &mut [f64]) -> f64 {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    }

    fn quantile_sorted(v: &[f64], p: f64) -> f64 {
        let x = p * (v.len() - 1) as f64;
        let i = x.floor() as usize;
        let f = x - i as f64;
        if i + 1 < v.len() {
            v[i] * (1.0 - f) + v[i + 1] * f
        } else {
            v[i]
        }
    }

    fn no_overlaps(pos: &[Vec3], radii: &[f64], gap: f64) {
        let r_max = radii.iter().cloned().fold(0.0, f64::max);
        let (mut lo, mut hi) = (pos[0], pos[0]);
        for p in pos {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let mut grid = CellGrid::new(lo, hi, 2.0 * r_max + gap, pos.len());
        // Reuse the grid with inflated radii: overlap iff d < r_i + r_j + gap (tolerance 1e-12).
        let inflated: Vec<f64> = radii.iter().map(|r| r + 0.5 * gap - 1e-12).collect();
        for (i, p) in pos.iter().enumerate() {
            assert!(
                !grid.overlaps(p, inflated[i], &pos[..i], &inflated[..i]),
                "particle {i} overlaps"
            );
            grid.insert(i as u32, p);
        }
    }

    fn all_inside(region: &Region, pos: &[Vec3], radii: &[f64]) {
        for (i, (p, r)) in pos.iter().zip(radii).enumerate() {
            assert!(
                region.contains_sphere(p, r - 1e-12),
                "particle {i} at {p:?} outside"
            );
        }
    }

    #[test]
    fn normal_cdf_and_quantile() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-15);
        assert!((normal_cdf(1.0) - 0.841_344_746_068_542_9).abs() < 1e-14);
        assert!((normal_cdf(-3.5) / 2.326_290_790_355_250_4e-4 - 1.0).abs() < 1e-12);
        assert!((normal_cdf(-5.0) / 2.866_515_718_791_939e-7 - 1.0).abs() < 1e-10);
        assert!((normal_quantile(0.9) - 1.281_551_565_544_600_5).abs() < 1e-12);
        assert!((normal_quantile(0.025) + 1.959_963_984_540_054).abs() < 1e-12);
        for &p in &[1e-10, 1e-4, 0.01, 0.3, 0.5, 0.77, 0.99, 1.0 - 1e-6] {
            assert!(
                (normal_cdf(normal_quantile(p)) / p - 1.0).abs() < 1e-10,
                "p = {p}"
            );
        }
    }

    #[test]
    fn lognormal_reproduces_median_and_sigma() {
        let d = SizeDistribution::LogNormal {
            median_diameter_m: 1.0e-3,
            sigma: 0.2707,
            min_radius_m: None,
            max_radius_m: None,
        };
        d.validate().unwrap();
        let mut r = d.sample_n(20_000, 42);
        let med_d = 2.0 * median(&mut r);
        assert!((med_d / 1.0e-3 - 1.0).abs() < 0.02, "median {med_d}");
        let ln: Vec<f64> = r.iter().map(|r| (2.0 * r).ln()).collect();
        let mean = ln.iter().sum::<f64>() / ln.len() as f64;
        let std =
            (ln.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (ln.len() - 1) as f64).sqrt();
        assert!((std / 0.2707 - 1.0).abs() < 0.03, "sigma {std}");
        // Mean volume: closed form vs. sample mean.
        let vs = r.iter().map(|r| 4.0 / 3.0 * PI * r.powi(3)).sum::<f64>() / r.len() as f64;
        assert!((vs / d.mean_volume_m3() - 1.0).abs() < 0.02);
        assert_eq!(d.max_radius_m(), f64::INFINITY);
    }

    #[test]
    fn lognormal_table_a2_cutoffs() {
        let d = SizeDistribution::paper_table_a2();
        d.validate().unwrap();
        let (lo, hi) = (0.353414e-3, 0.707385e-3);
        assert_eq!((d.min_radius_m(), d.max_radius_m()), (lo, hi));
        let r = d.sample_n(20_000, 7);
        assert!(r.iter().all(|&x| (lo..=hi).contains(&x)));
        // Truncated moments: closed form vs. sampling.
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        assert!(
            (mean / d.mean_radius_m() - 1.0).abs() < 0.005,
            "{mean} vs {}",
            d.mean_radius_m()
        );
        let vs = r.iter().map(|r| 4.0 / 3.0 * PI * r.powi(3)).sum::<f64>() / r.len() as f64;
        assert!((vs / d.mean_volume_m3() - 1.0).abs() < 0.01);
        // The cut-offs are D10 and D90 of the untruncated distribution: 80 % mass kept, and the
        // truncated median equals the untruncated one.
        assert!((d.quantile_radius_m(0.5) / 0.5e-3 - 1.0).abs() < 1e-6);
        assert!(
            (d.quantile_radius_m(0.0) - lo).abs() < 1e-12
                && (d.quantile_radius_m(1.0) - hi).abs() < 1e-12
        );
        // Deterministic.
        assert_eq!(r, d.sample_n(20_000, 7));
        assert_ne!(r, d.sample_n(20_000, 8));
    }

    #[test]
    fn lognormal_paper_original_d10_d90() {
        let d50 = 26.5646e-6;
        let d = SizeDistribution::LogNormal {
            median_diameter_m: d50,
            sigma: 0.2707,
            min_radius_m: None,
            max_radius_m: None,
        };
        // Analytic, as in the brief: exp(ln D50 ± 1.2816 σ).
        let d10 = (d50.ln() - 1.2816 * 0.2707).exp();
        let d90 = (d50.ln() + 1.2816 * 0.2707).exp();
        assert!((d10 / 18.7766e-6 - 1.0).abs() < 0.02, "D10 {d10}");
        assert!((d90 / 37.5828e-6 - 1.0).abs() < 0.02, "D90 {d90}");
        // Quantile function.
        assert!((2.0 * d.quantile_radius_m(0.1) / 18.7766e-6 - 1.0).abs() < 0.002);
        assert!((2.0 * d.quantile_radius_m(0.9) / 37.5828e-6 - 1.0).abs() < 0.002);
        // Sampling.
        let mut r = d.sample_n(20_000, 3);
        r.sort_by(f64::total_cmp);
        let (s10, s90) = (
            2.0 * quantile_sorted(&r, 0.1),
            2.0 * quantile_sorted(&r, 0.9),
        );
        assert!((s10 / 18.7766e-6 - 1.0).abs() < 0.02, "sampled D10 {s10}");
        assert!((s90 / 37.5828e-6 - 1.0).abs() < 0.02, "sampled D90 {s90}");
    }

    #[test]
    fn uniform_and_monodisperse() {
        let d = SizeDistribution::Uniform {
            min_radius_m: 1e-3,
            max_radius_m: 2e-3,
        };
        d.validate().unwrap();
        let r = d.sample_n(20_000, 1);
        assert!(r.iter().all(|&x| (1e-3..=2e-3).contains(&x)));
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        assert!((mean / 1.5e-3 - 1.0).abs() < 0.005);
        assert!((d.mean_radius_m() - 1.5e-3).abs() < 1e-15);
        let v_exact = 4.0 / 3.0 * PI * (2e-3f64.powi(4) - 1e-3f64.powi(4)) / (4.0 * 1e-3);
        assert!((d.mean_volume_m3() / v_exact - 1.0).abs() < 1e-12);
        let m = SizeDistribution::Monodisperse { radius_m: 5e-4 };
        assert_eq!(m.sample_n(3, 0), vec![5e-4; 3]);
        assert!((m.mean_volume_m3() - 4.0 / 3.0 * PI * 1.25e-10).abs() < 1e-20);
    }

    #[test]
    fn validation_messages_name_fields() {
        let e = SizeDistribution::Uniform {
            min_radius_m: 2.0,
            max_radius_m: 1.0,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key(), "min_radius_m", "{e}");
        let e = SizeDistribution::Monodisperse { radius_m: -1.0 }
            .validate()
            .unwrap_err();
        assert_eq!(e.key(), "radius_m", "{e}");
        let e = SizeDistribution::LogNormal {
            median_diameter_m: 1e-3,
            sigma: -0.1,
            min_radius_m: None,
            max_radius_m: None,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key(), "sigma", "{e}");
        let narrow = SizeDistribution::LogNormal {
            median_diameter_m: 1e-3,
            sigma: 0.1,
            min_radius_m: Some(1.0e-3),
            max_radius_m: Some(1.1e-3),
        };
        assert!(
            narrow
                .validate()
                .unwrap_err()
                .to_string()
                .contains("probability mass")
        );
        let e = Region::Cylinder {
            base_center_m: Vec3::zeros(),
            axis: Vec3::zeros(),
            radius_m: 1.0,
            length_m: 1.0,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key(), "axis", "{e}");
    }

    #[test]
    fn narrow_truncation_terminates_and_stays_inside() {
        // Window far in the tail (mass ≈ 3e-5): the inverse-CDF fallback keeps samples inside.
        let d = SizeDistribution::LogNormal {
            median_diameter_m: 1e-3,
            sigma: 0.2,
            min_radius_m: Some(1.0e-3),
            max_radius_m: Some(1.2e-3),
        };
        d.validate().unwrap();
        let r = d.sample_n(2000, 5);
        assert!(r.iter().all(|&x| (1.0e-3..=1.2e-3).contains(&x)));
    }

    #[test]
    fn region_containment_and_volume() {
        let b = Region::Box {
            min_m: Vec3::zeros(),
            max_m: Vec3::new(1.0, 2.0, 3.0),
        };
        assert!((b.volume_m3() - 6.0).abs() < 1e-15);
        assert!(b.contains_sphere(&Vec3::new(0.5, 0.5, 0.5), 0.5));
        assert!(!b.contains_sphere(&Vec3::new(0.5, 0.5, 0.5), 0.50001));
        let c = Region::Cylinder {
            base_center_m: Vec3::new(1.0, 0.0, 0.0),
            axis: Vec3::new(2.0, 0.0, 0.0),
            radius_m: 1.0,
            length_m: 4.0,
        };
        assert!((c.volume_m3() - 4.0 * PI).abs() < 1e-12);
        assert!(c.contains_sphere(&Vec3::new(3.0, 0.5, 0.0), 0.5));
        assert!(!c.contains_sphere(&Vec3::new(3.0, 0.5, 0.1), 0.5));
        assert!(!c.contains_sphere(&Vec3::new(1.4, 0.0, 0.0), 0.5));
        let (lo, hi) = c.bounding_box();
        assert!(
            (lo - Vec3::new(1.0, -1.0, -1.0)).norm() < 1e-12
                && (hi - Vec3::new(5.0, 1.0, 1.0)).norm() < 1e-12
        );
    }

    #[test]
    fn grid_packing_fills_from_bottom() {
        let region = Region::Box {
            min_m: Vec3::zeros(),
            max_m: Vec3::new(0.01, 0.01, 0.02),
        };
        let radii = SizeDistribution::paper_table_a2().sample_n(500, 1);
        let up = Vec3::z();
        let pos = grid_packing(&region, &radii, 1e-5, &up).unwrap();
        assert_eq!(pos.len(), 500);
        no_overlaps(&pos, &radii, 1e-5);
        all_inside(&region, &pos, &radii);
        // Layer by layer: heights never decrease.
        assert!(pos.windows(2).all(|w| w[1].z >= w[0].z - 1e-12));
        // Error states how many fit.
        let many = vec![0.5e-3; 100_000];
        let e = grid_packing(&region, &many, 0.0, &up).unwrap_err();
        assert!(e.to_string().contains("holds only 2000 of 100000"), "{e}");
        assert!(
            matches!(
                e,
                PackingError::RegionTooSmall {
                    fitted: 2000,
                    requested: 100_000,
                    ..
                }
            ),
            "{e:?}"
        );
        // Gravity along −x: bottom is the x = 0 face.
        let pos = grid_packing(&region, &radii, 1e-5, &Vec3::x()).unwrap();
        assert!(pos.windows(2).all(|w| w[1].x >= w[0].x - 1e-12));
        all_inside(&region, &pos, &radii);
    }

    #[test]
    fn tight_packing_box_and_cylinder() {
        let d = 1.0e-3;
        let region = Region::Box {
            min_m: Vec3::zeros(),
            max_m: Vec3::repeat(20.0 * d),
        };
        let sites = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::Hcp).unwrap();
        let radii = vec![0.5 * d; sites.len()];
        let pos = tight_packing(&region, &radii, 0.0, &Vec3::z()).unwrap();
        assert_eq!(pos, sites);
        no_overlaps(&pos, &radii, 0.0);
        all_inside(&region, &pos, &radii);
        let phi = pos.len() as f64 * PI / 6.0 * d.powi(3) / region.volume_m3();
        println!(
            "HCP in 20^3 d box: {} spheres, solid fraction {phi:.4}",
            pos.len()
        );
        assert!(phi > 0.6, "solid fraction {phi}");
        let fcc = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::Fcc).unwrap();
        no_overlaps(&fcc, &radii[..fcc.len().min(radii.len())], 0.0);
        let cubic = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::SimpleCubic).unwrap();
        assert_eq!(cubic.len(), 8000);
        // Nearest-neighbour distance is exactly d in the bulk.
        let mut min_d = f64::INFINITY;
        for i in 0..200 {
            for j in 0..pos.len() {
                if i != j {
                    min_d = min_d.min((pos[i] - pos[j]).norm());
                }
            }
        }
        assert!((min_d / d - 1.0).abs() < 1e-9);

        // Cylinder along y (gravity −y), polydisperse, with gap.
        let cyl = Region::Cylinder {
            base_center_m: Vec3::new(0.0, -0.01, 0.0),
            axis: Vec3::y(),
            radius_m: 0.008,
            length_m: 0.03,
        };
        let radii = SizeDistribution::paper_table_a2().sample_n(2000, 9);
        let pos = tight_packing(&cyl, &radii, 2e-5, &Vec3::y()).unwrap();
        no_overlaps(&pos, &radii, 2e-5);
        all_inside(&cyl, &pos, &radii);
        assert!(pos.windows(2).all(|w| w[1].y >= w[0].y - 1e-12));
        // Top partial layer is centred on the axis.
        let top_y = pos.last().unwrap().y;
        let top: Vec<&Vec3> = pos.iter().filter(|p| (p.y - top_y).abs() < 1e-9).collect();
        let cx = top.iter().map(|p| p.x).sum::<f64>() / top.len() as f64;
        let cz = top.iter().map(|p| p.z).sum::<f64>() / top.len() as f64;
        assert!(cx.hypot(cz) < 0.003, "top layer centre ({cx}, {cz})");
    }

    #[test]
    fn random_insertion_no_overlap_and_deterministic() {
        let region = Region::Cylinder {
            base_center_m: Vec3::zeros(),
            axis: Vec3::z(),
            radius_m: 0.01,
            length_m: 0.02,
        };
        let radii = SizeDistribution::paper_table_a2().sample_n(2000, 2);
        let a = random_insertion(&region, &radii, 11, 1000, None).unwrap();
        no_overlaps(&a, &radii, 0.0);
        all_inside(&region, &a, &radii);
        let b = random_insertion(&region, &radii, 11, 1000, None).unwrap();
        assert_eq!(a, b);
        let c = random_insertion(&region, &radii, 12, 1000, None).unwrap();
        assert_ne!(a, c);
        // Too many particles: error names how many were placed.
        let many = vec![0.7e-3; 20_000];
        let e = random_insertion(&region, &many, 1, 50, None).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("placed only") && msg.contains("of 20000"),
            "{e}"
        );
        assert!(
            matches!(
                e,
                PackingError::NoFreePosition {
                    requested: 20000,
                    ..
                }
            ),
            "{e:?}"
        );
    }

    #[test]
    fn random_insertion_30000_fast() {
        let region = Region::Box {
            min_m: Vec3::zeros(),
            max_m: Vec3::repeat(0.038),
        };
        let radii = SizeDistribution::paper_table_a2().sample_n(30_000, 4);
        let phi = radii
            .iter()
            .map(|r| 4.0 / 3.0 * PI * r.powi(3))
            .sum::<f64>()
            / region.volume_m3();
        let t = Instant::now();
        let pos = random_insertion(&region, &radii, 5, 1000, None).unwrap();
        let dt = t.elapsed().as_secs_f64();
        println!("random insertion: 30000 particles, solid fraction {phi:.3}, {dt:.3} s");
        no_overlaps(&pos, &radii, 0.0);
        all_inside(&region, &pos, &radii);
        assert!(dt < 5.0, "{dt} s");
    }

    #[test]
    fn random_insertion_layered() {
        let region = Region::Box {
            min_m: Vec3::zeros(),
            max_m: Vec3::new(0.01, 0.01, 0.03),
        };
        let radii = SizeDistribution::paper_table_a2().sample_n(800, 6);
        let layering = Layering {
            up: Vec3::z(),
            layer_height_m: 2e-3,
        };
        let t = Instant::now();
        let pos = random_insertion(&region, &radii, 3, 200, Some(&layering)).unwrap();
        println!(
            "layered insertion of 800: {:.3} s, top z {:.4}",
            t.elapsed().as_secs_f64(),
            pos.iter().map(|p| p.z).fold(0.0, f64::max)
        );
        no_overlaps(&pos, &radii, 0.0);
        all_inside(&region, &pos, &radii);
        // Layer index (by centre height) never decreases along the insertion order.
        let layer = |p: &Vec3| (p.z / 2e-3).floor() as i64;
        assert!(pos.windows(2).all(|w| layer(&w[1]) >= layer(&w[0])));
        // The bottom is filled first: the upper part of the box stays empty.
        assert!(pos.iter().all(|p| p.z < 0.025));
        assert_eq!(
            pos,
            random_insertion(&region, &radii, 3, 200, Some(&layering)).unwrap()
        );
    }
}

/// Cells per layer of one tile in [`layer_order`] (two layers of a tile, with the data the pair
/// loop reads per particle, stay well inside a 1 MB L2 cache).
pub const LAYER_TILE_CELLS: u64 = 1600;

/// Order of `points` by layers of cubic cells of size `cell_m`: the axis with the fewest cells
/// counts slowest, then the next, the axis with the most cells fastest (ties: z before y
/// before x); ties keep their order. Where a layer has more than [`LAYER_TILE_CELLS`] cells, the
/// layer plane is first cut into tiles of about that many cells (columns through the bed,
/// numbered one after the other). Numbering particles this way puts a particle's neighbours
/// within the next one or two layers of its column, so the pair loop sweeps a window that stays
/// in cache and reads it in a few sequential streams (LIGGGHTS sorts its atoms spatially for the
/// same reason). Measured on the 32 000-sphere shaken box: about 17 % more particle-steps per
/// second than the Morton order of [`morton_order`] (docs/dev/performance-log.md).
pub fn layer_order(points: &[Vec3], cell_m: f64) -> Vec<usize> {
    let finite = |x: &&Vec3| x.iter().all(|c| c.is_finite());
    let lo = points
        .iter()
        .filter(finite)
        .fold(Vec3::repeat(f64::INFINITY), |a, x| a.inf(x));
    if !lo.iter().all(|c| c.is_finite()) || cell_m.is_nan() || cell_m <= 0.0 {
        return (0..points.len()).collect();
    }
    const MAX_CELL: u64 = 0x1f_ffff;
    let cell = |x: &Vec3| [0, 1, 2].map(|k| (((x[k] - lo[k]) / cell_m) as u64).min(MAX_CELL));
    let mut extent = [1u64; 3];
    for x in points.iter().filter(finite) {
        let c = cell(x);
        for k in 0..3 {
            extent[k] = extent[k].max(c[k] + 1);
        }
    }
    // Axes from slowest to fastest: fewest cells first, ties z, y, x.
    let mut axes = [2usize, 1, 0];
    axes.sort_by_key(|&k| extent[k]);
    let [slow, mid, fast] = axes;
    // Tiles of the layer plane.
    let tile = |e: u64, max: u64| -> u64 {
        let n = e.div_ceil(max.max(1));
        e.div_ceil(n)
    };
    let side = (LAYER_TILE_CELLS as f64).sqrt() as u64;
    let (t_fast, t_mid) = if extent[mid] * extent[fast] <= LAYER_TILE_CELLS {
        (extent[fast], extent[mid])
    } else {
        let t_fast = tile(extent[fast], side.max(LAYER_TILE_CELLS / extent[mid]));
        (t_fast, tile(extent[mid], LAYER_TILE_CELLS / t_fast))
    };
    let tiles_fast = extent[fast].div_ceil(t_fast);
    let key = |x: &Vec3| -> (u64, u64, u64, u64) {
        if !x.iter().all(|c| c.is_finite()) {
            return (u64::MAX, 0, 0, 0);
        }
        let c = cell(x);
        let t = (c[mid] / t_mid) * tiles_fast + c[fast] / t_fast;
        (t, c[slow], c[mid], c[fast])
    };
    let mut order: Vec<((u64, u64, u64, u64), usize)> = points
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x), i))
        .collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| i).collect()
}

/// Order of `points` along a Morton (Z-order) curve through cubic cells of size `cell_m`:
/// indices sorted by the interleaved bits of their cell coordinates (ties keep their order).
/// Numbering particles in this order puts spatial neighbours close in memory, so the pair loop
/// finds its partners' data in cache (LIGGGHTS sorts its atoms spatially for the same reason).
pub fn morton_order(points: &[Vec3], cell_m: f64) -> Vec<usize> {
    fn spread(v: u64) -> u64 {
        // 21 bits → every third bit.
        let mut x = v & 0x1f_ffff;
        x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
        x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
        x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
        x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
        x = (x | (x << 2)) & 0x1249_2492_4924_9249;
        x
    }
    let finite = |x: &&Vec3| x.iter().all(|c| c.is_finite());
    let lo = points
        .iter()
        .filter(finite)
        .fold(Vec3::repeat(f64::INFINITY), |a, x| a.inf(x));
    if !lo.iter().all(|c| c.is_finite()) || cell_m.is_nan() || cell_m <= 0.0 {
        return (0..points.len()).collect();
    }
    let key = |x: &Vec3| -> u64 {
        if !x.iter().all(|c| c.is_finite()) {
            return u64::MAX;
        }
        let c = [0, 1, 2].map(|k| (((x[k] - lo[k]) / cell_m) as u64).min(0x1f_ffff));
        spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
    };
    let mut order: Vec<(u64, usize)> = points
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x), i))
        .collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod morton_tests {
    use super::*;

    /// Layer order: on a small lattice the ranks are z-layer, then y-row, then x; a wide layer
    /// is cut into tiles of at most `LAYER_TILE_CELLS` cells; non-finite points go last.
    #[test]
    fn layer_order_numbers_layers_then_rows() {
        // A 10 × 6 × 3 lattice: z (3 cells) slowest, then y (6), x (10) fastest.
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..6 {
                for k in 0..3 {
                    pts.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
                }
            }
        }
        let order = layer_order(&pts, 1.0);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..pts.len()).collect::<Vec<_>>());
        for (rank, &k) in order.iter().enumerate() {
            let p = pts[k];
            let expect = (p.z as usize) * 60 + (p.y as usize) * 10 + p.x as usize;
            assert_eq!(rank, expect, "point {p:?}");
        }
        // A wide layer (100 × 100 cells) is cut into tiles: the first 2 × 100 ranks stay in
        // one tile of at most LAYER_TILE_CELLS cells per layer.
        let mut wide = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                for k in 0..2 {
                    wide.push(Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5));
                }
            }
        }
        let order = layer_order(&wide, 1.0);
        let first: Vec<Vec3> = order[..200].iter().map(|&k| wide[k]).collect();
        let span = |f: fn(&Vec3) -> f64| {
            let (a, b) = first
                .iter()
                .map(f)
                .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
            (b - a + 1.0) as u64
        };
        assert!(span(|p| p.x) * span(|p| p.y) <= LAYER_TILE_CELLS);
        assert_eq!(span(|p| p.z), 1, "a tile's first layer comes first");
        let bad = vec![
            Vec3::new(f64::NAN, 0.0, 0.0),
            Vec3::zeros(),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        assert_eq!(*layer_order(&bad, 1.0).last().unwrap(), 0);
    }

    /// The Morton order of a 16×16×16 lattice is a permutation in which every aligned block of
    /// 2×2×2, 4×4×4 and 8×8×8 sites occupies consecutive ranks (the property that keeps
    /// neighbours close in memory); non-finite points go last instead of panicking.
    #[test]
    fn morton_order_keeps_aligned_blocks_contiguous() {
        let mut pts = Vec::new();
        for i in 0..16 {
            for j in 0..16 {
                for k in 0..16 {
                    pts.push(Vec3::new(i as f64, j as f64, k as f64));
                }
            }
        }
        let order = morton_order(&pts, 1.0);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..4096).collect::<Vec<_>>());
        for b in [2usize, 4, 8] {
            let size = b * b * b;
            for chunk in order.chunks(size) {
                let block = |o: usize| {
                    let x = pts[o];
                    [x.x, x.y, x.z].map(|c| c as usize / b)
                };
                let first = block(chunk[0]);
                assert!(chunk.iter().all(|&o| block(o) == first), "block size {b}");
            }
        }
        let mut bad = pts.clone();
        bad[3] = Vec3::new(f64::NAN, 0.0, 0.0);
        assert_eq!(*morton_order(&bad, 1.0).last().unwrap(), 3);
    }
}
