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

use crate::energy::{EnergyIncrements, EnergyLedger};
use crate::forces::{
    PAIR_SCRATCH, PP_CHUNK, WallSlot, add_wall_loads, refresh_wall_candidates, wall_contacts_of,
};
use crate::integrate::Integrator;
use crate::math::Vec3;
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

/// What a repetition of the last step's wall pass needs: the wall slots at the start of the
/// pass, each particle's force and torque before its wall contacts, and the ledger before the
/// step.
#[derive(Debug, Clone, Default)]
pub(crate) struct WallRepeat {
    /// Particles of the wall list at the start of the step's pass, ascending.
    saved_particles: Vec<u32>,
    /// Their wall slots then (`saved[saved_start[k]..saved_start[k + 1]]` for particle `k`).
    saved_start: Vec<u32>,
    saved: Vec<WallSlot>,
    /// Particles of the latest pass, ascending, and the force and torque each had before its
    /// wall contacts were added (the same in every repetition).
    latest_particles: Vec<u32>,
    latest: Vec<(Vec3, Vec3)>,
    /// Scratch of a repetition (the next `latest_*`).
    next_particles: Vec<u32>,
    next: Vec<(Vec3, Vec3)>,
    /// The ledger before the step.
    ledger_before: EnergyLedger,
    /// A velocity-Verlet step's pass is the latest (reset by every force evaluation).
    repeatable: bool,
    /// The wall candidates were refreshed in the latest pass, i.e. for walls that a
    /// repetition moves again: the repetition refreshes them once more.
    refreshed: bool,
}

impl WallRepeat {
    /// Called by the force evaluation before its wall pass (`refreshed`: the candidates were
    /// just refreshed): keeps the slots of the wall-list particles and returns the record of
    /// the forces before the wall contacts that the pass fills (aligned with `list`).
    pub(crate) fn start_pass<'a>(
        &'a mut self,
        list: &[u32],
        slots: &[Vec<WallSlot>],
        refreshed: bool,
    ) -> &'a mut [(Vec3, Vec3)] {
        self.repeatable = false;
        self.refreshed = refreshed;
        self.saved_particles.clear();
        self.saved_particles.extend_from_slice(list);
        self.saved_start.clear();
        self.saved.clear();
        for &i in list {
            self.saved_start.push(self.saved.len() as u32);
            self.saved.extend_from_slice(&slots[i as usize]);
        }
        self.saved_start.push(self.saved.len() as u32);
        self.latest_particles.clear();
        self.latest_particles.extend_from_slice(list);
        self.latest.clear();
        self.latest
            .resize(list.len(), (Vec3::zeros(), Vec3::zeros()));
        &mut self.latest
    }

    /// Called after a step's force evaluation, before its increments enter the ledger.
    pub(crate) fn step_taken(&mut self, ledger: &EnergyLedger, velocity_verlet: bool) {
        self.ledger_before = *ledger;
        self.repeatable = velocity_verlet;
    }

    /// The wall slots particle `i` had at the start of the step.
    fn saved_slots(&self, i: u32) -> &[WallSlot] {
        match self.saved_particles.binary_search(&i) {
            Ok(k) => &self.saved[self.saved_start[k] as usize..self.saved_start[k + 1] as usize],
            Err(_) => &[],
        }
    }

    /// The force and torque particle `i` had before its wall contacts in the latest pass.
    fn before_walls(&self, i: u32) -> Option<(Vec3, Vec3)> {
        self.latest_particles
            .binary_search(&i)
            .ok()
            .map(|k| self.latest[k])
    }
}

/// The ascending union of two ascending lists, into `out`.
fn union_sorted(a: &[u32], b: &[u32], out: &mut Vec<u32>) {
    out.clear();
    let (mut ia, mut ib) = (0, 0);
    while ia < a.len() && ib < b.len() {
        let (x, y) = (a[ia], b[ib]);
        out.push(x.min(y));
        ia += usize::from(x <= y);
        ib += usize::from(y <= x);
    }
    out.extend_from_slice(&a[ia..]);
    out.extend_from_slice(&b[ib..]);
}

impl World {
    /// Keeps (or stops keeping) what [`World::repeat_wall_pass`] needs: the wall contact slots
    /// of the particles near walls at the start of every force evaluation (a copy per step).
    pub fn set_wall_pass_repeatable(&mut self, on: bool) {
        self.wall_repeat = on.then(Box::default);
    }

    /// Repeats the particle–wall contacts of the step just taken by [`World::step_deferred`]
    /// with the walls where they are now (after [`World::move_wall_vertices_again`]): see the
    /// module documentation. The particle–particle forces, positions and half-step velocities
    /// are those of the step; the wall histories restart from the start of the step.
    pub fn repeat_wall_pass(&mut self) -> Result<(), WallRepeatError> {
        let mut r = self
            .wall_repeat
            .take()
            .ok_or(WallRepeatError::NotRepeatable)?;
        let result = self.repeat_with(&mut r);
        self.wall_repeat = Some(r);
        result
    }

    fn repeat_with(&mut self, r: &mut WallRepeat) -> Result<(), WallRepeatError> {
        let half = match self.pending_half_kick_s {
            Some(h) if r.repeatable && matches!(self.integrator, Integrator::VelocityVerlet) => h,
            _ => return Err(WallRepeatError::NoPendingStep),
        };
        let dt = 2.0 * half;
        self.scratch_body_step.clear();
        self.scratch_body_step
            .extend(self.bodies.iter().map(|b| b.step_state(dt)));
        // The candidates again, as the pass does. Candidates refreshed in the latest pass were
        // found for walls that have moved since (by a replaced move the deformation count does
        // not see): refreshed once more.
        if r.refreshed {
            self.wall_ref.clear();
        }
        if refresh_wall_candidates(
            &self.particles,
            &self.interactions,
            &self.neighbors,
            &self.bodies,
            &self.scratch_body_step,
            &mut self.wall_candidate,
            &mut self.wall_ref,
            &mut self.wall_ref_builds,
            self.wall_skip,
            &mut self.wall_slots,
            &mut self.wall_list,
        ) {
            self.wall_refreshes += 1;
        }
        // Every particle of the latest pass (its contacts must be undone, one that ended must
        // close its work) and every candidate now, ascending: particles without wall contacts
        // add nothing, so the sums below are those of a pass over the candidates alone.
        let (mut next_p, mut next) = (
            std::mem::take(&mut r.next_particles),
            std::mem::take(&mut r.next),
        );
        union_sorted(&r.latest_particles, &self.wall_list, &mut next_p);
        next.clear();
        let nblocks = self.scratch_block_out.len();
        for (b, out) in self.scratch_block_out.iter_mut().enumerate() {
            out.1 = EnergyIncrements::default();
            self.block_loads[b].clear();
            self.block_loads[b].resize(self.bodies.len(), (Vec3::zeros(), Vec3::zeros()));
        }
        PAIR_SCRATCH.with_borrow_mut(|scratch| {
            for &i in &next_p {
                let iu = i as usize;
                let b = self.chunk_block[iu / PP_CHUNK] as usize;
                let slots = &mut self.wall_slots[iu];
                slots.clear();
                slots.extend_from_slice(r.saved_slots(i));
                let before = r
                    .before_walls(i)
                    .unwrap_or((self.particles.force[iu], self.particles.torque[iu]));
                let (mut f, mut t) = before;
                wall_contacts_of(
                    (
                        self.particles.material[iu],
                        &self.scratch_xr[iu],
                        &self.scratch_kin[iu],
                    ),
                    &self.interactions,
                    &self.bodies,
                    &self.scratch_body_step,
                    dt,
                    slots,
                    &mut scratch.wall_contacts,
                    &mut scratch.wall_fresh,
                    &mut f,
                    &mut t,
                    &mut self.scratch_block_out[b].1,
                );
                add_wall_loads(slots, &self.bodies, &mut self.block_loads[b]);
                self.particles.force[iu] = f;
                self.particles.torque[iu] = t;
                next.push(before);
            }
        });
        std::mem::swap(&mut r.latest_particles, &mut next_p);
        std::mem::swap(&mut r.latest, &mut next);
        r.next_particles = next_p;
        r.next = next;
        self.sum_body_loads(nblocks);
        let inc = self.sum_increments();
        self.ledger = r.ledger_before;
        self.ledger.add(&inc);
        Ok(())
    }
}
