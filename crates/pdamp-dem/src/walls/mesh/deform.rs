//! Deformable triangle meshes: a wall whose vertices are set from outside every step (the
//! surface of a finite-element model, a flexible container), refitted without rebuilding its
//! topology; the velocity of the surface at a contact point and the distribution of a contact
//! force onto the vertices, both with the barycentric weights of the contact point in its
//! feature (face, edge or vertex), so that the loads handed to the structure are consistent with
//! the surface velocity used for the wall work (P Sect. 2.3: the DEM wall forces are the FE
//! surface's nodal loads).

use super::{Derived, FEATURE_TOL, MeshError, TriMesh, bbox_of};
use crate::math::Vec3;
use std::sync::Arc;

/// Weights of the vertices carrying a contact point: up to three `(vertex, weight)` pairs with
/// non-negative weights summing to 1 (unused entries have weight 0).
pub type VertexWeights = [(u32, f64); 3];

impl TriMesh {
    /// Moves the vertices to `positions` (body frame, m; same count and order as
    /// [`TriMesh::vertices`]) over a step of `dt_s`: the surface velocity used by contacts
    /// during that step is the mean vertex velocity `(new − old)/dt` (as for rigid bodies, so
    /// that the wall work matches the particles' kinematics). Topology, feature ids and so the
    /// contact history are kept; normals, barycentric data, the bounding box and the grid are
    /// refitted. A triangle that degenerates (zero area) is refused and the mesh left as it was.
    pub fn move_vertices(&mut self, positions: &[Vec3], dt_s: f64) -> Result<(), MeshError> {
        self.check_move(positions, dt_s)?;
        self.before_move.0.clear();
        self.before_move.0.extend_from_slice(&self.vertices);
        self.before_move.1 = self.deformation_m;
        self.apply_move(positions, dt_s);
        Ok(())
    }

    /// Replaces the last [`TriMesh::move_vertices`] by a move from the same start to
    /// `positions` (the repeated wall pass of a coupling iteration, P Algorithm 1): the result
    /// is that of calling `move_vertices(positions, dt_s)` instead of the last move, to the bit.
    pub fn replace_last_move(&mut self, positions: &[Vec3], dt_s: f64) -> Result<(), MeshError> {
        if self.before_move.0.len() != self.vertices.len() {
            return Err(MeshError::NoMoveToReplace);
        }
        self.check_move(positions, dt_s)?;
        self.vertices.copy_from_slice(&self.before_move.0);
        self.deformation_m = self.before_move.1;
        self.apply_move(positions, dt_s);
        Ok(())
    }

    /// The checks of a move, on the new positions, before anything changes.
    fn check_move(&self, positions: &[Vec3], dt_s: f64) -> Result<(), MeshError> {
        if positions.len() != self.vertices.len() {
            return Err(MeshError::VertexCount {
                expected: self.vertices.len(),
                got: positions.len(),
            });
        }
        if let Some(i) = positions
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex: i });
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(MeshError::BadTimeStep(dt_s));
        }
        for (t, f) in self.faces.iter().enumerate() {
            let p = f.map(|i| positions[i as usize]);
            let area2 = (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            let lmax2 = (p[1] - p[0])
                .norm_squared()
                .max((p[2] - p[1]).norm_squared())
                .max((p[0] - p[2]).norm_squared());
            if area2.partial_cmp(&(1e-14 * lmax2)) != Some(std::cmp::Ordering::Greater) {
                return Err(MeshError::Degenerate { triangle: t });
            }
        }
        Ok(())
    }

    /// Moves the (checked) vertices from the current ones to `positions`.
    fn apply_move(&mut self, positions: &[Vec3], dt_s: f64) {
        // In place when no clone shares the derived data (the usual case: a world's wall).
        let d: &mut Derived = Arc::make_mut(&mut self.d);
        for (t, f) in self.faces.iter().enumerate() {
            let p = f.map(|i| positions[i as usize]);
            let c = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let area2 = c.norm();
            let n = c / area2;
            let tri = &mut d.tris[t];
            tri.n = n;
            for i in 0..3 {
                tri.g[i] = n.cross(&(p[(i + 1) % 3] - p[i])) / area2;
            }
        }
        for e in d.edges.iter_mut() {
            e.inv_len2 = 1.0 / (positions[e.b as usize] - positions[e.a as usize]).norm_squared();
        }
        d.bbox = bbox_of(positions);
        d.grid = super::Grid::build(positions, &self.faces, d.bbox);
        self.velocity.clear();
        let mut largest = 0.0f64;
        for (old, new) in self.vertices.iter().zip(positions) {
            let u = new - old;
            largest = largest.max(u.norm());
            self.velocity.push(u / dt_s);
        }
        self.deformation_m += largest;
        self.vertices.clear();
        self.vertices.extend_from_slice(positions);
    }

    /// Sets the vertex velocities (body frame, m/s) without moving the vertices — for a mesh
    /// whose positions are handed over with exact velocities; [`TriMesh::move_vertices`] sets
    /// the mean velocity of the step itself.
    pub fn set_vertex_velocities(&mut self, velocities: &[Vec3]) -> Result<(), MeshError> {
        if velocities.len() != self.vertices.len() {
            return Err(MeshError::VertexCount {
                expected: self.vertices.len(),
                got: velocities.len(),
            });
        }
        self.velocity.clear();
        self.velocity.extend_from_slice(velocities);
        Ok(())
    }

    /// Vertex velocities of a deformable mesh (empty for a rigid one), m/s.
    pub fn vertex_velocities(&self) -> &[Vec3] {
        &self.velocity
    }

    /// Sum of the largest vertex displacement of every move, m (0 for a rigid mesh).
    pub fn deformation_m(&self) -> f64 {
        self.deformation_m
    }

    /// The vertices carrying point `x` (body frame) of contact feature `feature` (as in
    /// [`super::super::WallContact::feature`]) and their barycentric weights: a face's three
    /// vertices, an edge's two, a vertex alone. Weights are clamped to [0, 1] and normalised
    /// (a point within the feature tolerance outside its face).
    pub fn vertex_weights(&self, feature: u32, x: &Vec3) -> VertexWeights {
        let (nf, ne) = (self.faces.len() as u32, self.d.edges.len() as u32);
        let mut w: VertexWeights = [(0, 0.0); 3];
        if feature < nf {
            let t = feature as usize;
            // bary(t, i) is the coordinate of vertex (i + 2) % 3.
            for i in 0..3 {
                w[(i + 2) % 3] = (self.faces[t][(i + 2) % 3], self.bary(t, i, x).max(0.0));
            }
        } else if feature < nf + ne {
            let e = (feature - nf) as usize;
            let s = self.edge_t(e, x).clamp(0.0, 1.0);
            let ed = &self.d.edges[e];
            w[0] = (ed.a, 1.0 - s);
            w[1] = (ed.b, s);
        } else {
            w[0] = (feature - nf - ne, 1.0);
        }
        let sum: f64 = w.iter().map(|p| p.1).sum();
        if sum > FEATURE_TOL {
            w.iter_mut().for_each(|p| p.1 /= sum);
        } else {
            w = [(w[0].0, 1.0), (w[1].0, 0.0), (w[2].0, 0.0)];
        }
        w
    }

    /// Velocity of the surface at point `x` (body frame) of contact feature `feature`, m/s:
    /// the vertex velocities interpolated with [`TriMesh::vertex_weights`]; zero for a rigid
    /// mesh.
    #[inline]
    pub fn surface_velocity(&self, feature: u32, x: &Vec3) -> Vec3 {
        if self.velocity.is_empty() {
            return Vec3::zeros();
        }
        self.vertex_weights(feature, x)
            .iter()
            .map(|&(v, w)| self.velocity[v as usize] * w)
            .sum()
    }
}
