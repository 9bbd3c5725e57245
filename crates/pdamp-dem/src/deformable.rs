//! Deformable walls: a triangle-mesh wall whose vertices are set from outside every step — the
//! wetted surface of a finite-element structure (P Sect. 2.3, the two-way DEM–FEM coupling), a
//! flexible container — and the contact forces handed back to its vertices as nodal loads.
//!
//! Per step: [`World::move_wall_vertices`] with the surface at the end of the step (the DEM
//! then uses the mean vertex velocity over the step, so the wall work matches the particles'
//! kinematics and the energy ledger closes), [`World::step`], then [`World::wall_nodal_forces`]
//! for the loads on the structure. Feature ids, and so the contact history, survive the moves;
//! the wall candidates are refreshed when the surface has moved by a skin.

use crate::math::Vec3;
use crate::walls::{Geometry, MeshError, TriMesh};
use crate::world::World;

impl World {
    /// Moves the vertices of mesh wall `wall` of body `body` to `positions` (body frame, m) at
    /// the end of the next step: the contacts of that step see the mean vertex velocity
    /// `(new − old)/dt` ([`crate::walls::TriMesh::move_vertices`]).
    pub fn move_wall_vertices(
        &mut self,
        body: usize,
        wall: usize,
        positions: &[Vec3],
    ) -> Result<(), MeshError> {
        let dt = self.dt_s;
        self.mesh_wall_mut(body, wall)?.move_vertices(positions, dt)
    }

    /// Replaces the last [`World::move_wall_vertices`] of mesh wall `wall` of body `body` by a
    /// move from the same start to `positions` (a coupling iteration; then
    /// [`World::repeat_wall_pass`]), see [`crate::walls::TriMesh::replace_last_move`].
    pub fn move_wall_vertices_again(
        &mut self,
        body: usize,
        wall: usize,
        positions: &[Vec3],
    ) -> Result<(), MeshError> {
        let dt = self.dt_s;
        self.mesh_wall_mut(body, wall)?
            .replace_last_move(positions, dt)
    }

    /// The triangle mesh of wall `wall` of body `body`.
    fn mesh_wall_mut(&mut self, body: usize, wall: usize) -> Result<&mut TriMesh, MeshError> {
        let w = self
            .bodies
            .get_mut(body)
            .and_then(|b| b.walls.get_mut(wall))
            .ok_or(MeshError::NoSuchWall { body, wall })?;
        match &mut w.geometry {
            Geometry::Mesh(m) => Ok(m),
            _ => Err(MeshError::NotAMesh {
                wall: w.name.clone(),
            }),
        }
    }

    /// The loads the particles exert on the vertices of mesh wall `wall` of body `body` in the
    /// last force evaluation, N (world frame; one per vertex, written into `out`): every
    /// contact's force on the wall split onto the vertices of its feature with the barycentric
    /// weights of the contact point ([`crate::walls::TriMesh::vertex_weights`]) — their sum is
    /// the wall's total contact force and their first moment the contact points'. Rolling
    /// torques (if a rolling law is used) are not distributed.
    pub fn wall_nodal_forces(
        &self,
        body: usize,
        wall: usize,
        out: &mut Vec<Vec3>,
    ) -> Result<(), MeshError> {
        let b = self
            .bodies
            .get(body)
            .ok_or(MeshError::NoSuchWall { body, wall })?;
        let w = b
            .walls
            .get(wall)
            .ok_or(MeshError::NoSuchWall { body, wall })?;
        let Geometry::Mesh(m) = &w.geometry else {
            return Err(MeshError::NotAMesh {
                wall: w.name.clone(),
            });
        };
        out.clear();
        out.resize(m.num_vertices(), Vec3::zeros());
        for slots in &self.pass.wall_slots {
            for s in slots
                .iter()
                .filter(|s| s.body as usize == body && s.wall as usize == wall)
            {
                let f = -s.force;
                if f == Vec3::zeros() {
                    continue;
                }
                for (v, weight) in m.vertex_weights(s.feature, &b.state.to_body(&s.point)) {
                    if weight > 0.0 {
                        out[v as usize] += f * weight;
                    }
                }
            }
        }
        Ok(())
    }
}
