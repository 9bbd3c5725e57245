//! What a repetition of a step's particle–wall pass needs, and the repetition itself (see
//! [`crate::wall_repeat`]).

use super::{
    ForcePass, PAIR_SCRATCH, PP_CHUNK, WallSlot, add_wall_loads, refresh_wall_candidates,
    wall_contacts_of,
};
use crate::body::RigidBody;
use crate::energy::{EnergyIncrements, EnergyLedger};
use crate::interaction::InteractionTable;
use crate::math::Vec3;
use crate::neighbor::NeighborList;
use crate::particles::ParticleSet;

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
    /// The step's pass is the latest and was a velocity-Verlet step's.
    pub(crate) fn repeatable(&self) -> bool {
        self.repeatable
    }

    /// The ledger before the step.
    pub(crate) fn ledger_before(&self) -> &EnergyLedger {
        &self.ledger_before
    }

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

impl ForcePass {
    /// The particle–wall contacts of the step of `dt` just evaluated, again with the walls
    /// where they are now: every particle of the latest pass and every candidate starts from
    /// its wall slots at the start of the step and from its force and torque before its wall
    /// contacts; the bodies' loads are summed again. Returns the energy increments of the
    /// evaluation with the new wall terms.
    pub(crate) fn repeat_walls(
        &mut self,
        r: &mut WallRepeat,
        particles: &mut ParticleSet,
        interactions: &InteractionTable,
        neighbors: &NeighborList,
        bodies: &mut [RigidBody],
        dt: f64,
    ) -> EnergyIncrements {
        self.scratch_body_step.clear();
        self.scratch_body_step
            .extend(bodies.iter().map(|b| b.step_state(dt)));
        // The candidates again, as the pass does. Candidates refreshed in the latest pass were
        // found for walls that have moved since (by a replaced move the deformation count does
        // not see): refreshed once more.
        if r.refreshed {
            self.wall_ref.clear();
        }
        if refresh_wall_candidates(
            particles,
            interactions,
            neighbors,
            bodies,
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
            self.block_loads[b].resize(bodies.len(), (Vec3::zeros(), Vec3::zeros()));
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
                    .unwrap_or((particles.force[iu], particles.torque[iu]));
                let (mut f, mut t) = before;
                wall_contacts_of(
                    (
                        particles.material[iu],
                        &self.scratch_xr[iu],
                        &self.scratch_kin[iu],
                    ),
                    interactions,
                    bodies,
                    &self.scratch_body_step,
                    dt,
                    slots,
                    &mut scratch.wall_contacts,
                    &mut scratch.wall_fresh,
                    &mut f,
                    &mut t,
                    &mut self.scratch_block_out[b].1,
                );
                add_wall_loads(slots, bodies, &mut self.block_loads[b]);
                particles.force[iu] = f;
                particles.torque[iu] = t;
                next.push(before);
            }
        });
        std::mem::swap(&mut r.latest_particles, &mut next_p);
        std::mem::swap(&mut r.latest, &mut next);
        r.next_particles = next_p;
        r.next = next;
        self.sum_body_loads(bodies, nblocks);
        self.sum_increments()
    }
}
