//! Bounding geometry (walls) in the body-fixed frame of a rigid body [D Sect. 2.2.2].
//!
//! A geometry only answers "where does a sphere touch me": it returns [`WallContact`]s in its own
//! (body) frame. Rigid-body pose, velocity, forces and contact history live in the pipeline.

use crate::math::Vec3;
use serde::{Deserialize, Serialize};

mod cylinder;
mod mesh;
mod plane;

pub use cylinder::{CylinderInside, CylinderOutside};
pub use mesh::{MeshError, TriMesh, VertexWeights};
pub use plane::{BoxInside, Plane};

/// One contact of a sphere with a wall, expressed in the wall's body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallContact {
    /// Overlap $\delta = r - d$ in m (negative: a gap, reported only within the requested margin).
    pub overlap_m: f64,
    /// Unit normal pointing from the wall surface towards the sphere centre.
    pub normal: Vec3,
    /// Closest point on the wall surface (the contact point), m.
    pub point: Vec3,
    /// Radius of curvature used for the Hertz effective radius, m: `f64::INFINITY` for planes and
    /// triangles [D Eq. 2.73], $2 r_{cyl}$ outside a cylinder [D Eq. 2.74], $-2 r_{cyl}$ inside
    /// [D Eq. 2.75]; edges and vertices of meshes use `f64::INFINITY` too.
    pub curvature_radius_m: f64,
    /// Identifier of the touched feature, unique within this geometry and stable over time
    /// (plane index, triangle face, mesh edge or vertex); used to keep contact history.
    pub feature: u32,
}

/// A wall geometry attached to a rigid body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Geometry {
    /// Infinite plane (one- or two-sided).
    Plane(Plane),
    /// Closed cuboid container; particles are inside.
    BoxInside(BoxInside),
    /// Closed cylindrical container with end caps; particles are inside.
    CylinderInside(CylinderInside),
    /// Solid finite cylinder (rod) with end caps; particles are outside.
    CylinderOutside(CylinderOutside),
    /// Triangle mesh (e.g. from STL).
    Mesh(TriMesh),
}

impl Geometry {
    /// Appends to `out` every contact of the sphere (centre `x` in the body frame, radius `r`)
    /// whose gap is smaller than `margin` (i.e. `overlap_m > -margin`); `margin = 0` returns
    /// touching contacts only. Must not allocate once `out` has capacity (meshes may keep an
    /// internal scratch).
    pub fn sphere_contacts(&self, x: &Vec3, r: f64, margin: f64, out: &mut Vec<WallContact>) {
        match self {
            Geometry::Plane(g) => g.sphere_contacts(x, r, margin, out),
            Geometry::BoxInside(g) => g.sphere_contacts(x, r, margin, out),
            Geometry::CylinderInside(g) => g.sphere_contacts(x, r, margin, out),
            Geometry::CylinderOutside(g) => g.sphere_contacts(x, r, margin, out),
            Geometry::Mesh(g) => g.sphere_contacts(x, r, margin, out),
        }
    }

    /// How far a sphere (centre `x` in the body frame, radius `r`) would start inside this wall:
    /// the largest overlap of its contacts, or `f64::INFINITY` when the centre lies behind a
    /// closed mesh (inside an obstacle, outside a container) where the one-sided triangles
    /// report nothing; `None` when the sphere is clear (touching allowed up to `tolerance_m`).
    /// Used to place particles without overlap with any wall or inner structure.
    pub fn sphere_overlap(
        &self,
        x: &Vec3,
        r: f64,
        tolerance_m: f64,
        scratch: &mut Vec<WallContact>,
    ) -> Option<f64> {
        scratch.clear();
        self.sphere_contacts(x, r, 0.0, scratch);
        let deepest = scratch
            .iter()
            .map(|c| c.overlap_m)
            .fold(f64::NEG_INFINITY, f64::max);
        if deepest > tolerance_m {
            return Some(deepest);
        }
        if let Geometry::Mesh(m) = self
            && !m.in_particle_region(x)
        {
            return Some(f64::INFINITY);
        }
        None
    }

    /// Velocity of the wall surface itself at contact point `x` (body frame) of `feature`, on
    /// top of the body's rigid motion: non-zero only for a deformable mesh
    /// ([`TriMesh::move_vertices`]), m/s.
    #[inline]
    pub fn surface_velocity(&self, feature: u32, x: &Vec3) -> Vec3 {
        match self {
            Geometry::Mesh(m) => m.surface_velocity(feature, x),
            _ => Vec3::zeros(),
        }
    }

    /// How far the surface has deformed in all (sum of the largest vertex displacement of
    /// every move), m; 0 for rigid geometry.
    pub fn deformation_m(&self) -> f64 {
        match self {
            Geometry::Mesh(m) => m.deformation_m(),
            _ => 0.0,
        }
    }

    /// Axis-aligned bounding box in the body frame, if finite.
    pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> {
        match self {
            Geometry::Plane(_) => None,
            Geometry::BoxInside(g) => Some(g.bounding_box()),
            Geometry::CylinderInside(g) => Some(g.bounding_box()),
            Geometry::CylinderOutside(g) => Some(g.bounding_box()),
            Geometry::Mesh(g) => g.bounding_box(),
        }
    }
}
