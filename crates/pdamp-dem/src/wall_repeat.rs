//! Repeating the particle–wall pass of a step: the inner loop of a partitioned DEM–structure
//! coupling (P Sect. 2.3, Algorithm 1, Dirichlet–Neumann fixed point with Aitken relaxation).
//!
//! Within a velocity-Verlet step the particle positions and the half-step velocities are
//! explicit, so the particle–particle forces do not depend on where the structure's surface
//! ends the step; only the particle–wall contacts do. A coupling iteration therefore moves the
//! deformable walls to the next iterate ([`World::move_wall_vertices_again`]) and calls
//! [`World::repeat_wall_pass`]: every particle that may touch a wall starts again from its
//! wall contact history at the start of the step, its old wall force and torque are taken off
//! and the new ones put on, the bodies' loads and the ledger's wall terms are replaced. The
//! result is that of a step taken with the final wall geometry from the start (the same
//! contacts, histories and energies; forces to round-off, since they are summed in another
//! order).
//!
//! Usage: [`World::set_wall_pass_repeatable`] once; per step [`World::move_wall_vertices`],
//! [`World::step_deferred`], read [`World::wall_nodal_forces`]; while the coupling has not
//! converged, [`World::move_wall_vertices_again`] + [`World::repeat_wall_pass`]; then
//! [`World::complete_step`] (or the next step) does the second half kick with the final forces.

use crate::forces::wall_repeat::WallRepeat;
use crate::integrate::Integrator;
use crate::world::World;

/// Why the wall pass cannot be repeated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WallRepeatError {
    /// The world does not keep what a repetition needs.
    #[error(
        "the wall pass is not repeatable: call World::set_wall_pass_repeatable(true) before the step"
    )]
    NotRepeatable,
    /// No step whose second half kick is still pending.
    #[error(
        "no step to repeat: the wall pass can be repeated only after World::step_deferred under \
         velocity Verlet and before World::complete_step"
    )]
    NoPendingStep,
}

impl World {
    /// Keeps (or stops keeping) what [`World::repeat_wall_pass`] needs: the wall contact slots
    /// of the particles near walls at the start of every force evaluation (a copy per step).
    pub fn set_wall_pass_repeatable(&mut self, on: bool) {
        self.pass.wall_repeat = on.then(Box::default);
    }

    /// Repeats the particle–wall contacts of the step just taken by [`World::step_deferred`]
    /// with the walls where they are now (after [`World::move_wall_vertices_again`]): see the
    /// module documentation. The particle–particle forces, positions and half-step velocities
    /// are those of the step; the wall histories restart from the start of the step.
    pub fn repeat_wall_pass(&mut self) -> Result<(), WallRepeatError> {
        let mut r = self
            .pass
            .wall_repeat
            .take()
            .ok_or(WallRepeatError::NotRepeatable)?;
        let result = self.repeat_with(&mut r);
        self.pass.wall_repeat = Some(r);
        result
    }

    fn repeat_with(&mut self, r: &mut WallRepeat) -> Result<(), WallRepeatError> {
        let half = match self.pending_half_kick_s {
            Some(h) if r.repeatable() && matches!(self.integrator, Integrator::VelocityVerlet) => h,
            _ => return Err(WallRepeatError::NoPendingStep),
        };
        let inc = self.pass.repeat_walls(
            r,
            &mut self.particles,
            &self.interactions,
            &self.neighbors,
            &mut self.bodies,
            2.0 * half,
        );
        self.ledger = *r.ledger_before();
        self.ledger.add(&inc);
        Ok(())
    }
}
