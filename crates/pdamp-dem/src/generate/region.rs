//! The volume to fill with particles: an axis-aligned box or an arbitrary cylinder.

use crate::ParameterError;
use crate::math::Vec3;
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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
