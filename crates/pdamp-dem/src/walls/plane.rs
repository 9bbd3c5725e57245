//! Infinite planes and the axis-aligned box container [D Eq. 2.17–2.19, 2.73].
//!
//! Conventions shared by all walls: the contact normal points from the wall towards the sphere
//! centre (the dissertation's particle normal $\mathbf n_{ik}$ of [D Eq. 2.19] points the other
//! way, from the particle into the wall), the overlap is $\delta = r - d$ [D Eq. 2.18] with the
//! *signed* distance $d$ of the centre in front of the surface, and planes have an infinite
//! curvature radius [D Eq. 2.73].

use super::WallContact;
use crate::math::Vec3;
use serde::{Deserialize, Serialize};

/// Returns `v / |v|`, or an error message when `v` is zero or not finite. A vector that is a
/// unit vector to round-off (|v| within 4 ε of 1) is returned unchanged, so that normalising is
/// idempotent: a scenario written with its normalised vectors reads back to the same bits (and
/// the same digest).
pub(super) fn unit(v: Vec3, what: &str) -> Result<Vec3, crate::ParameterError> {
    let n = v.norm();
    if !(n.is_finite() && n > 0.0) {
        return Err(crate::ParameterError::invalid(
            what,
            format!("{what} must be a finite non-zero vector, got {v:?}"),
        ));
    }
    if (n - 1.0).abs() <= 4.0 * f64::EPSILON {
        return Ok(v);
    }
    Ok(v / n)
}

/// An infinite plane through `point_m` with unit `normal` [D Eq. 2.17–2.19].
///
/// * One-sided (`two_sided = false`): the half-space behind the plane (against `normal`) is solid.
///   A sphere touches when its signed distance $d = \mathbf n\cdot(\mathbf x - \mathbf p)$
///   satisfies $d < r$ (+ margin); the overlap is $r - d$ even after the centre has passed the
///   plane ($d < 0$), so a penetrating particle is always pushed back to the front side.
/// * Two-sided (`two_sided = true`): a thin sheet; the overlap is $r - |d|$ [D Eq. 2.18] and the
///   normal points towards the side of the centre, i.e. $\operatorname{sgn}(d)\,\mathbf n$
///   (the negative of the particle normal of [D Eq. 2.19]); $d = 0$ uses $+\mathbf n$.
///
/// Feature id: always 0. Construct with [`Plane::new`] (normalises the normal); deserialisation
/// normalises too and rejects a zero normal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PlaneSpec")]
pub struct Plane {
    /// A point on the plane (body frame), m.
    pub point_m: Vec3,
    /// Unit normal; for a one-sided plane it points into the free (particle) side.
    pub normal: Vec3,
    /// Whether particles may be on both sides [D Eq. 2.19].
    pub two_sided: bool,
}

/// Raw serialised form of [`Plane`], validated on conversion.
#[derive(Deserialize)]
struct PlaneSpec {
    point_m: Vec3,
    normal: Vec3,
    #[serde(default)]
    two_sided: bool,
}

impl TryFrom<PlaneSpec> for Plane {
    type Error = crate::ParameterError;
    fn try_from(s: PlaneSpec) -> Result<Self, crate::ParameterError> {
        if !s.point_m.iter().all(|c| c.is_finite()) {
            return Err(crate::ParameterError::invalid(
                "point_m",
                format!("plane point must be finite, got {:?}", s.point_m),
            ));
        }
        Ok(Plane {
            point_m: s.point_m,
            normal: unit(s.normal, "plane normal")?,
            two_sided: s.two_sided,
        })
    }
}

impl Plane {
    /// Plane through `point_m` with normal direction `normal` (normalised here).
    ///
    /// # Panics
    /// If `normal` is zero or not finite.
    pub fn new(point_m: Vec3, normal: Vec3, two_sided: bool) -> Self {
        let normal = unit(normal, "plane normal").unwrap_or_else(|e| panic!("{e}"));
        Plane {
            point_m,
            normal,
            two_sided,
        }
    }

    /// Signed distance of `x` in front of the plane [D Eq. 2.17].
    #[inline]
    pub fn signed_distance(&self, x: &Vec3) -> f64 {
        self.normal.dot(&(x - self.point_m))
    }

    /// Appends the contact of a sphere (centre `x`, radius `r`) if its gap is below `margin`
    /// [D Eq. 2.17–2.19]; see the type documentation for one- and two-sided rules.
    pub fn sphere_contacts(&self, x: &Vec3, r: f64, margin: f64, out: &mut Vec<WallContact>) {
        let d = self.signed_distance(x);
        let (dist, normal) = if self.two_sided && d < 0.0 {
            (-d, -self.normal)
        } else {
            (d, self.normal)
        };
        let overlap = r - dist;
        if overlap > -margin {
            out.push(WallContact {
                overlap_m: overlap,
                normal,
                point: x - self.normal * d,
                curvature_radius_m: f64::INFINITY,
                feature: 0,
            });
        }
    }
}

/// A closed axis-aligned cuboid container (in its body frame) with the particles inside.
///
/// Each of the six faces is a one-sided [`Plane`] [D Eq. 2.17–2.18] with the normal pointing
/// into the box; every face within reach produces its own contact (a sphere in a corner gets
/// three). Feature ids: 0 = −x face (normal +x), 1 = +x face, 2 = −y, 3 = +y, 4 = −z, 5 = +z.
/// The contact point is the projection of the centre onto the face plane, clamped to the face
/// rectangle (it only differs from the plain projection for a centre outside the box).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "BoxSpec")]
pub struct BoxInside {
    /// Centre of the box, m.
    pub center_m: Vec3,
    /// Half edge lengths along x, y, z, m (all positive).
    pub half_extents_m: Vec3,
}

/// Raw serialised form of [`BoxInside`], validated on conversion.
#[derive(Deserialize)]
struct BoxSpec {
    center_m: Vec3,
    half_extents_m: Vec3,
}

impl TryFrom<BoxSpec> for BoxInside {
    type Error = crate::ParameterError;
    fn try_from(s: BoxSpec) -> Result<Self, crate::ParameterError> {
        if !s.center_m.iter().all(|c| c.is_finite())
            || !s.half_extents_m.iter().all(|h| h.is_finite() && *h > 0.0)
        {
            return Err(crate::ParameterError::invalid(
                "box",
                format!(
                    "box needs a finite centre and positive half extents, got {:?} / {:?}",
                    s.center_m, s.half_extents_m
                ),
            ));
        }
        Ok(BoxInside {
            center_m: s.center_m,
            half_extents_m: s.half_extents_m,
        })
    }
}

impl BoxInside {
    /// Box with centre `center_m` and half edge lengths `half_extents_m` (m).
    pub fn new(center_m: Vec3, half_extents_m: Vec3) -> Self {
        BoxInside {
            center_m,
            half_extents_m,
        }
    }

    /// Appends one contact per face whose gap to the sphere is below `margin`
    /// (one-sided planes, [D Eq. 2.17–2.18]); normals point inward.
    pub fn sphere_contacts(&self, x: &Vec3, r: f64, margin: f64, out: &mut Vec<WallContact>) {
        let rel = x - self.center_m;
        let h = &self.half_extents_m;
        for axis in 0..3 {
            for (side, sign) in [(0u32, 1.0), (1u32, -1.0)] {
                // Face at rel[axis] = -sign * h[axis]; distance into the box.
                let d = h[axis] + sign * rel[axis];
                let overlap = r - d;
                if overlap > -margin {
                    let mut normal = Vec3::zeros();
                    normal[axis] = sign;
                    let mut p = Vec3::zeros();
                    for k in 0..3 {
                        p[k] = if k == axis {
                            -sign * h[axis]
                        } else {
                            rel[k].clamp(-h[k], h[k])
                        };
                    }
                    out.push(WallContact {
                        overlap_m: overlap,
                        normal,
                        point: self.center_m + p,
                        curvature_radius_m: f64::INFINITY,
                        feature: 2 * axis as u32 + side,
                    });
                }
            }
        }
    }

    /// Axis-aligned bounding box `(min, max)` in the body frame.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        (
            self.center_m - self.half_extents_m,
            self.center_m + self.half_extents_m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: f64 = 1e-12;

    #[test]
    fn walls_plane_one_sided_overlap() {
        let p = Plane::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, 2.0), false);
        assert!((p.normal - Vec3::z()).norm() < TOL);
        let r = 0.01;
        let mut out = Vec::new();
        // Distance 0.9 r in front: overlap 0.1 r.
        p.sphere_contacts(&Vec3::new(0.3, -0.2, 1.0 + 0.9 * r), r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        let c = out[0];
        assert!((c.overlap_m - 0.1 * r).abs() < TOL);
        assert!((c.normal - Vec3::z()).norm() < TOL);
        assert!((c.point - Vec3::new(0.3, -0.2, 1.0)).norm() < TOL);
        assert_eq!(c.curvature_radius_m, f64::INFINITY);
        // Behind the plane: overlap r - d with d < 0, same normal.
        out.clear();
        p.sphere_contacts(&Vec3::new(0.0, 0.0, 1.0 - 0.5 * r), r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert!((out[0].overlap_m - 1.5 * r).abs() < TOL);
        assert!((out[0].normal - Vec3::z()).norm() < TOL);
        // Gap 0.2 r: none without margin, one with margin 0.3 r.
        out.clear();
        let x = Vec3::new(0.0, 0.0, 1.0 + 1.2 * r);
        p.sphere_contacts(&x, r, 0.0, &mut out);
        assert!(out.is_empty());
        p.sphere_contacts(&x, r, 0.3 * r, &mut out);
        assert_eq!(out.len(), 1);
        assert!((out[0].overlap_m + 0.2 * r).abs() < TOL);
    }

    #[test]
    fn walls_plane_two_sided_normal_flips() {
        let n = Vec3::new(1.0, 1.0, 0.0);
        let p = Plane::new(Vec3::zeros(), n, true);
        let r = 0.5;
        let mut out = Vec::new();
        let x = -n.normalize() * 0.3;
        p.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert!((out[0].overlap_m - 0.2).abs() < TOL);
        assert!((out[0].normal + n.normalize()).norm() < TOL);
        assert!(out[0].point.norm() < TOL);
    }

    #[test]
    fn walls_box_inside_corner_and_faces() {
        let b = BoxInside::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 1.0, 2.0));
        let r = 0.1;
        let mut out = Vec::new();
        // Near the (-x, -y, +z) corner: distances 0.05, 0.08, 0.2 (z too far).
        let x = Vec3::new(0.5 + 0.05, 1.0 + 0.08, 5.0 - 0.2);
        b.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 2);
        let fx = out.iter().find(|c| c.feature == 0).unwrap();
        assert!((fx.overlap_m - 0.05).abs() < TOL);
        assert!((fx.normal - Vec3::x()).norm() < TOL);
        assert!((fx.point - Vec3::new(0.5, x.y, x.z)).norm() < TOL);
        let fy = out.iter().find(|c| c.feature == 2).unwrap();
        assert!((fy.overlap_m - 0.02).abs() < TOL);
        assert!((fy.normal - Vec3::y()).norm() < TOL);
        // With margin 0.15 the +z face (gap 0.1) is reported too, normal -z.
        out.clear();
        b.sphere_contacts(&x, r, 0.15, &mut out);
        assert_eq!(out.len(), 3);
        let fz = out.iter().find(|c| c.feature == 5).unwrap();
        assert!((fz.overlap_m + 0.1).abs() < TOL);
        assert!((fz.normal + Vec3::z()).norm() < TOL);
        let (lo, hi) = b.bounding_box();
        assert!((lo - Vec3::new(0.5, 1.0, 1.0)).norm() < TOL);
        assert!((hi - Vec3::new(1.5, 3.0, 5.0)).norm() < TOL);
    }
}
