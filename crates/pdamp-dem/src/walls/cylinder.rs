//! Finite cylinders: the closed cylindrical container and the solid rod
//! [D Eq. 2.28–2.33, 2.74–2.75].
//!
//! Both are described by the centre of the bottom end disc `base_center_m`, the unit `axis`
//! (pointing from the bottom to the top disc), the radius and the length. For a point $\mathbf x$
//! the axial coordinate is $a = \boldsymbol\ell\cdot(\mathbf x - \mathbf c)$ and the radial
//! vector $\boldsymbol\rho = (\mathbf x - \mathbf c) - a\boldsymbol\ell$, so that
//! $\|\boldsymbol\rho\| = \|\boldsymbol\ell\times\mathbf r_{CP}\|$ of [D Eq. 2.30] and the
//! normal of [D Eq. 2.32–2.33] is $\mp\boldsymbol\rho/\|\boldsymbol\rho\|$.

use super::WallContact;
use super::plane::unit;
use crate::math::Vec3;
use serde::{Deserialize, Serialize};

/// Axial coordinate, radial vector and radial distance of `x` relative to the axis.
#[inline]
fn axial_radial(base: &Vec3, axis: &Vec3, x: &Vec3) -> (f64, Vec3, f64) {
    let rel = x - base;
    let a = axis.dot(&rel);
    let rho = rel - axis * a;
    let rn = rho.norm();
    (a, rho, rn)
}

/// Unit radial direction; an arbitrary perpendicular of `axis` when `x` lies on the axis.
#[inline]
fn radial_dir(axis: &Vec3, rho: &Vec3, rn: f64) -> Vec3 {
    if rn > 0.0 {
        rho / rn
    } else {
        let t = if axis.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        (t - axis * axis.dot(&t)).normalize()
    }
}

/// Bounding box of a finite cylinder (both end discs).
fn cylinder_aabb(base: &Vec3, axis: &Vec3, radius: f64, length: f64) -> (Vec3, Vec3) {
    let top = base + axis * length;
    let mut lo = Vec3::zeros();
    let mut hi = Vec3::zeros();
    for k in 0..3 {
        let e = radius * (1.0 - axis[k] * axis[k]).max(0.0).sqrt();
        lo[k] = base[k].min(top[k]) - e;
        hi[k] = base[k].max(top[k]) + e;
    }
    (lo, hi)
}

/// Raw serialised form of both cylinder types, validated on conversion.
#[derive(Deserialize)]
struct CylSpec {
    base_center_m: Vec3,
    axis: Vec3,
    radius_m: f64,
    length_m: f64,
    #[serde(default = "default_true")]
    capped: bool,
}

fn default_true() -> bool {
    true
}

impl CylSpec {
    fn check(&self) -> Result<Vec3, crate::ParameterError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(self.base_center_m.iter().all(|c| c.is_finite())
            && positive(self.radius_m)
            && positive(self.length_m))
        {
            return Err(crate::ParameterError::invalid(
                "cylinder",
                format!(
                    "cylinder needs a finite base centre and positive radius/length, got {:?}, {}, {}",
                    self.base_center_m, self.radius_m, self.length_m
                ),
            ));
        }
        unit(self.axis, "cylinder axis")
    }
}

/// A closed cylindrical container (lateral surface + two flat end discs), particles inside
/// [D Eq. 2.28–2.33].
///
/// Lateral surface: gap $d = r_{cyl} - \|\boldsymbol\rho\|$ [D Eq. 2.30], overlap $r - d$
/// [D Eq. 2.31], normal $-\boldsymbol\rho/\|\boldsymbol\rho\|$ (towards the axis, [D Eq. 2.32–2.33]
/// with our wall-to-sphere sign), curvature radius $-2r_{cyl}$ [D Eq. 2.75], feature 0. End caps
/// are one-sided planes [D Eq. 2.17–2.18] with inward normals and infinite curvature radius
/// [D Eq. 2.73]: feature 1 = bottom ($a = 0$), 2 = top ($a = L$). Every surface within reach
/// contributes its own contact (a sphere in the inner rim touches lateral surface and cap).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CylSpec")]
pub struct CylinderInside {
    /// Centre of the bottom end disc, m.
    pub base_center_m: Vec3,
    /// Unit axis from the bottom to the top disc.
    pub axis: Vec3,
    /// Inner radius $r_{cyl}$, m.
    pub radius_m: f64,
    /// Inner length between the end discs, m.
    pub length_m: f64,
}

impl TryFrom<CylSpec> for CylinderInside {
    type Error = crate::ParameterError;
    fn try_from(s: CylSpec) -> Result<Self, crate::ParameterError> {
        let axis = s.check()?;
        Ok(CylinderInside {
            base_center_m: s.base_center_m,
            axis,
            radius_m: s.radius_m,
            length_m: s.length_m,
        })
    }
}

impl CylinderInside {
    /// Container with bottom disc centre `base_center_m`, axis direction `axis` (normalised
    /// here), radius and length in m.
    ///
    /// # Panics
    /// If `axis` is zero or not finite.
    pub fn new(base_center_m: Vec3, axis: Vec3, radius_m: f64, length_m: f64) -> Self {
        let axis = unit(axis, "cylinder axis").unwrap_or_else(|e| panic!("{e}"));
        CylinderInside {
            base_center_m,
            axis,
            radius_m,
            length_m,
        }
    }

    /// Axis-aligned bounding box `(min, max)` in the body frame.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        cylinder_aabb(
            &self.base_center_m,
            &self.axis,
            self.radius_m,
            self.length_m,
        )
    }

    /// Appends the lateral-surface and end-cap contacts of a sphere inside the container
    /// [D Eq. 2.28–2.33, 2.75].
    pub fn sphere_contacts(&self, x: &Vec3, r: f64, margin: f64, out: &mut Vec<WallContact>) {
        let (a, rho, rn) = axial_radial(&self.base_center_m, &self.axis, x);
        let reach = r + margin;
        // Lateral surface [D Eq. 2.30–2.33].
        let d = self.radius_m - rn;
        if d < reach {
            let u = radial_dir(&self.axis, &rho, rn);
            let ac = a.clamp(0.0, self.length_m);
            out.push(WallContact {
                overlap_m: r - d,
                normal: -u,
                point: self.base_center_m + self.axis * ac + u * self.radius_m,
                curvature_radius_m: -2.0 * self.radius_m,
                feature: 0,
            });
        }
        // End caps: one-sided planes [D Eq. 2.17–2.18].
        let rho_c = if rn > self.radius_m {
            rho * (self.radius_m / rn)
        } else {
            rho
        };
        if a < reach {
            out.push(WallContact {
                overlap_m: r - a,
                normal: self.axis,
                point: self.base_center_m + rho_c,
                curvature_radius_m: f64::INFINITY,
                feature: 1,
            });
        }
        let dt = self.length_m - a;
        if dt < reach {
            out.push(WallContact {
                overlap_m: r - dt,
                normal: -self.axis,
                point: self.base_center_m + self.axis * self.length_m + rho_c,
                curvature_radius_m: f64::INFINITY,
                feature: 2,
            });
        }
    }
}

/// A solid finite cylinder (rod), particles outside [D Eq. 2.28–2.33, 2.74].
///
/// The contact is with the closest point of the solid:
/// * lateral surface (feature 0) for $0 \le a \le L$: gap $\|\boldsymbol\rho\| - r_{cyl}$
///   [D Eq. 2.30], normal $+\boldsymbol\rho/\|\boldsymbol\rho\|$ [D Eq. 2.32–2.33], curvature
///   radius $+2r_{cyl}$ [D Eq. 2.74];
/// * end discs (feature 1 bottom, 2 top) for $\|\boldsymbol\rho\| \le r_{cyl}$ beyond the ends:
///   planes, curvature radius ∞ [D Eq. 2.73];
/// * circular rim edges (feature 3 bottom, 4 top) beyond the ends and outside the radius: the
///   closest rim point $\mathbf q$, normal $(\mathbf x - \mathbf q)/\|\mathbf x - \mathbf q\|$,
///   curvature radius ∞ (a proper edge contact, continuous with both neighbours).
///
/// A centre inside the solid uses the nearest of lateral surface and the two discs (penetration
/// depth added to $r$). With `capped = false` the end discs are not contact surfaces (e.g. the rod
/// ends are embedded in the container walls): beyond the ends only the rims act.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CylSpec")]
pub struct CylinderOutside {
    /// Centre of the bottom end disc, m.
    pub base_center_m: Vec3,
    /// Unit axis from the bottom to the top disc.
    pub axis: Vec3,
    /// Rod radius $r_{cyl}$, m.
    pub radius_m: f64,
    /// Rod length, m.
    pub length_m: f64,
    /// Whether the flat end discs are contact surfaces.
    pub capped: bool,
}

impl TryFrom<CylSpec> for CylinderOutside {
    type Error = crate::ParameterError;
    fn try_from(s: CylSpec) -> Result<Self, crate::ParameterError> {
        let axis = s.check()?;
        Ok(CylinderOutside {
            base_center_m: s.base_center_m,
            axis,
            radius_m: s.radius_m,
            length_m: s.length_m,
            capped: s.capped,
        })
    }
}

impl CylinderOutside {
    /// Rod with bottom disc centre `base_center_m`, axis direction `axis` (normalised here),
    /// radius and length in m.
    ///
    /// # Panics
    /// If `axis` is zero or not finite.
    pub fn new(
        base_center_m: Vec3,
        axis: Vec3,
        radius_m: f64,
        length_m: f64,
        capped: bool,
    ) -> Self {
        let axis = unit(axis, "cylinder axis").unwrap_or_else(|e| panic!("{e}"));
        CylinderOutside {
            base_center_m,
            axis,
            radius_m,
            length_m,
            capped,
        }
    }

    /// Axis-aligned bounding box `(min, max)` in the body frame.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        cylinder_aabb(
            &self.base_center_m,
            &self.axis,
            self.radius_m,
            self.length_m,
        )
    }

    /// Appends the contact of a sphere with the closest point of the rod
    /// [D Eq. 2.28–2.33, 2.74]; at most one contact.
    pub fn sphere_contacts(&self, x: &Vec3, r: f64, margin: f64, out: &mut Vec<WallContact>) {
        let (a, rho, rn) = axial_radial(&self.base_center_m, &self.axis, x);
        let (rc, len, c) = (self.radius_m, self.length_m, &self.base_center_m);
        let u = radial_dir(&self.axis, &rho, rn);
        let lateral = |gap: f64| WallContact {
            overlap_m: r - gap,
            normal: u,
            point: c + self.axis * a.clamp(0.0, len) + u * rc,
            curvature_radius_m: 2.0 * rc,
            feature: 0,
        };
        let disc = |top: bool, gap: f64| WallContact {
            overlap_m: r - gap,
            normal: if top { self.axis } else { -self.axis },
            point: c + self.axis * if top { len } else { 0.0 } + rho,
            curvature_radius_m: f64::INFINITY,
            feature: if top { 2 } else { 1 },
        };
        let contact = if (0.0..=len).contains(&a) {
            if rn >= rc {
                lateral(rn - rc)
            } else {
                // Centre inside the solid: nearest surface.
                let depth_lat = rc - rn;
                let (depth_cap, top) = if a <= len - a {
                    (a, false)
                } else {
                    (len - a, true)
                };
                if self.capped && depth_cap < depth_lat {
                    disc(top, -depth_cap)
                } else {
                    lateral(-depth_lat)
                }
            }
        } else if self.capped && rn <= rc {
            let top = a > len;
            disc(top, if top { a - len } else { -a })
        } else {
            // Rim edge: closest point on the circle at the nearer end.
            let top = a > len;
            let q = c + self.axis * if top { len } else { 0.0 } + u * rc;
            let v = x - q;
            let d = v.norm();
            let normal = if d > 0.0 {
                v / d
            } else if top {
                self.axis
            } else {
                -self.axis
            };
            WallContact {
                overlap_m: r - d,
                normal,
                point: q,
                curvature_radius_m: f64::INFINITY,
                feature: if top { 4 } else { 3 },
            }
        };
        if contact.overlap_m > -margin {
            out.push(contact);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: f64 = 1e-12;

    fn tilted() -> (Vec3, Vec3) {
        (
            Vec3::new(0.1, -0.2, 0.3),
            Vec3::new(1.0, 2.0, 2.0) / 3.0, // unit
        )
    }

    /// Orthonormal frame (axis, e1, e2) for building test positions.
    fn frame(axis: &Vec3) -> (Vec3, Vec3) {
        let e1 = radial_dir(axis, &Vec3::zeros(), 0.0);
        (e1, axis.cross(&e1))
    }

    #[test]
    fn walls_cylinder_inside_lateral_and_caps() {
        let (c, ax) = tilted();
        let cyl = CylinderInside::new(c, ax * 5.0, 0.05, 0.2);
        assert!((cyl.axis - ax).norm() < TOL);
        let (e1, e2) = frame(&ax);
        let r = 0.004;
        let mut out = Vec::new();
        // Radial distance R - 0.9 r from the wall, mid-height: overlap 0.1 r.
        let dir = (e1 * 0.6 + e2 * 0.8).normalize();
        let x = c + ax * 0.1 + dir * (0.05 - 0.9 * r);
        cyl.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        let k = out[0];
        assert_eq!(k.feature, 0);
        assert!((k.overlap_m - 0.1 * r).abs() < TOL);
        assert!((k.normal + dir).norm() < TOL);
        assert!((k.point - (c + ax * 0.1 + dir * 0.05)).norm() < TOL);
        assert!((k.curvature_radius_m + 0.1).abs() < TOL);
        // Inner rim at the top: lateral gap 0.5 r, top cap distance 0.7 r.
        out.clear();
        let x = c + ax * (0.2 - 0.7 * r) + dir * (0.05 - 0.5 * r);
        cyl.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 2);
        let top = out.iter().find(|k| k.feature == 2).unwrap();
        assert!((top.overlap_m - 0.3 * r).abs() < TOL);
        assert!((top.normal + ax).norm() < TOL);
        assert_eq!(top.curvature_radius_m, f64::INFINITY);
        assert!((top.point - (c + ax * 0.2 + dir * (0.05 - 0.5 * r))).norm() < TOL);
        let lat = out.iter().find(|k| k.feature == 0).unwrap();
        assert!((lat.overlap_m - 0.5 * r).abs() < TOL);
        // Bottom cap only, with a margin.
        out.clear();
        let x = c + ax * (1.1 * r) + dir * 0.01;
        cyl.sphere_contacts(&x, r, 0.0, &mut out);
        assert!(out.is_empty());
        cyl.sphere_contacts(&x, r, 0.2 * r, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].feature, 1);
        assert!((out[0].overlap_m + 0.1 * r).abs() < TOL);
        assert!((out[0].normal - ax).norm() < TOL);
    }

    #[test]
    fn walls_cylinder_outside_lateral_cap_rim() {
        let (c, ax) = tilted();
        let rod = CylinderOutside::new(c, ax, 0.02, 0.1, true);
        let (e1, e2) = frame(&ax);
        let dir = (e1 * 0.8 - e2 * 0.6).normalize();
        let r = 0.005;
        let mut out = Vec::new();
        // Lateral: radial distance R + 0.9 r.
        let x = c + ax * 0.04 + dir * (0.02 + 0.9 * r);
        rod.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].feature, 0);
        assert!((out[0].overlap_m - 0.1 * r).abs() < TOL);
        assert!((out[0].normal - dir).norm() < TOL);
        assert!((out[0].curvature_radius_m - 0.04).abs() < TOL);
        assert!((out[0].point - (c + ax * 0.04 + dir * 0.02)).norm() < TOL);
        // Top cap: 0.6 r above the top disc, inside the radius.
        out.clear();
        let x = c + ax * (0.1 + 0.6 * r) + dir * 0.01;
        rod.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].feature, 2);
        assert!((out[0].overlap_m - 0.4 * r).abs() < TOL);
        assert!((out[0].normal - ax).norm() < TOL);
        assert_eq!(out[0].curvature_radius_m, f64::INFINITY);
        // Bottom rim: offset (−0.3 r axially, +0.4 r radially) from the rim: distance 0.5 r.
        out.clear();
        let x = c - ax * (0.3 * r) + dir * (0.02 + 0.4 * r);
        rod.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        let k = out[0];
        assert_eq!(k.feature, 3);
        assert!((k.overlap_m - 0.5 * r).abs() < TOL);
        let n_expected = (dir * 0.4 - ax * 0.3) / 0.5;
        assert!((k.normal - n_expected).norm() < TOL);
        assert!((k.point - (c + dir * 0.02)).norm() < TOL);
        assert_eq!(k.curvature_radius_m, f64::INFINITY);
        // Top rim, uncapped rod: same geometry.
        let open = CylinderOutside::new(c, ax, 0.02, 0.1, false);
        out.clear();
        let x = c + ax * (0.1 + 0.3 * r) + dir * (0.02 + 0.4 * r);
        open.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].feature, 4);
        assert!((out[0].overlap_m - 0.5 * r).abs() < TOL);
        assert!((out[0].normal - (dir * 0.4 + ax * 0.3) / 0.5).norm() < TOL);
    }

    #[test]
    fn walls_cylinder_outside_rim_continuity() {
        // Walking around the top rim at constant distance 0.5 r: overlap constant, normal turns
        // continuously from the lateral direction to the axis, features 0 → 4 → 2.
        let rod = CylinderOutside::new(Vec3::zeros(), Vec3::z(), 0.02, 0.1, true);
        let r = 0.005;
        let rim = Vec3::new(0.02, 0.0, 0.1);
        let mut out = Vec::new();
        let mut features = Vec::new();
        let n = 200;
        for i in 0..=n {
            let phi = -0.3 + (std::f64::consts::FRAC_PI_2 + 0.6) * i as f64 / n as f64;
            let dir = Vec3::new(phi.cos(), 0.0, phi.sin());
            let x = rim + dir * (0.5 * r);
            out.clear();
            rod.sphere_contacts(&x, r, 0.0, &mut out);
            assert_eq!(out.len(), 1);
            let k = out[0];
            let expect_n = if phi < 0.0 {
                Vec3::x()
            } else if phi > std::f64::consts::FRAC_PI_2 {
                Vec3::z()
            } else {
                dir
            };
            let expect_overlap = if phi < 0.0 {
                r - 0.5 * r * phi.cos()
            } else if phi > std::f64::consts::FRAC_PI_2 {
                r - 0.5 * r * phi.sin()
            } else {
                0.5 * r
            };
            assert!((k.overlap_m - expect_overlap).abs() < TOL, "phi {phi}");
            assert!((k.normal - expect_n).norm() < TOL, "phi {phi}");
            if features.last() != Some(&k.feature) {
                features.push(k.feature);
            }
        }
        assert_eq!(features, vec![0, 4, 2]);
    }

    #[test]
    fn walls_cylinder_bounding_boxes() {
        let rod = CylinderOutside::new(Vec3::new(1.0, 0.0, 0.0), Vec3::z(), 0.5, 2.0, true);
        let (lo, hi) = rod.bounding_box();
        assert!((lo - Vec3::new(0.5, -0.5, 0.0)).norm() < TOL);
        assert!((hi - Vec3::new(1.5, 0.5, 2.0)).norm() < TOL);
        let can = CylinderInside::new(Vec3::zeros(), -Vec3::x(), 1.0, 3.0);
        let (lo, hi) = can.bounding_box();
        assert!((lo - Vec3::new(-3.0, -1.0, -1.0)).norm() < TOL);
        assert!((hi - Vec3::new(0.0, 1.0, 1.0)).norm() < TOL);
    }
}
