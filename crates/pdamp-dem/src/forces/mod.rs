//! Force evaluation: contact kinematics [D Eq. 2.12–2.27], contact laws, torques [D Eq. 2.86–2.89],
//! gravity, loads on rigid bodies, and the per-contact work that feeds the energy ledger.

use crate::body::{BodyState, RigidBody};
use crate::energy::EnergyIncrements;
use crate::interaction::InteractionTable;
use crate::math::{Rotation, Vec3};
use crate::neighbor::NeighborList;
use crate::particles::ParticleSet;
use blocks::{BlockAcc, BlockParts, BlockSlices, force_blocks, split_blocks};
use contacts::fit_contact_store;
use pair_pass::{PairContext, PairRows};
use prefetch::prefetch_at;
use rayon::prelude::*;
use state::pack_kinematics;
use wall_repeat::WallRepeat;

mod blocks;
mod contacts;
mod pair_pass;
mod prefetch;
mod state;
mod wall_pass;
pub(crate) mod wall_repeat;

pub(crate) use blocks::SecondShares;
pub(crate) use contacts::PpChunk;
pub use contacts::PpContact;
pub(crate) use pair_pass::PAIR_SCRATCH;
pub(crate) use state::{Kin, PP_CHUNK};
pub use state::{PairState, WallSlot};
pub(crate) use wall_pass::{add_wall_loads, refresh_wall_candidates, wall_contacts_of};

/// The force pass [D Sect. 2.2–2.4]: what it keeps from one evaluation to the next (the contact
/// history of particle pairs and walls, the block layout of the pair pass, the particles that
/// may touch a wall) and its scratch. The world owns one and hands it its particles, laws,
/// neighbour list and bodies ([`ForceInputs`]) at every evaluation.
#[derive(Debug, Clone)]
pub(crate) struct ForcePass {
    /// Active particle–particle contacts, by chunks of first partners, with the pair loop's
    /// scratch.
    pub(crate) pp_chunks: Vec<PpChunk>,
    /// For every neighbour pair: slot of its contact in the slab of the first partner's chunk,
    /// or `NO_CONTACT`.
    pub(crate) pair_contact: Vec<u32>,
    /// The particle–wall contacts of every particle.
    pub(crate) wall_slots: Vec<Vec<WallSlot>>,
    /// Outputs of the contacts whose second partner lies in a later block of the pair pass
    /// (see `force_blocks`): list `b × C + c` holds those of block `b` for chunk `c` (of `C`
    /// chunks of first partners), in pair-loop order.
    pub(crate) cross_out: Vec<Vec<blocks::SecondOutput>>,
    /// Contact force and torque on every rigid body from the wall contacts of each block of
    /// the pair pass (`K` lists of one entry per body), added in block order.
    pub(crate) block_loads: Vec<Vec<(Vec3, Vec3)>>,
    /// First chunk of every block of the pair pass, and the end (`K + 1` entries).
    pub(crate) block_start: Vec<usize>,
    /// Block of every chunk of first partners.
    pub(crate) chunk_block: Vec<u32>,
    /// Particles that may touch a wall or hold wall contacts, ascending (rebuilt with the
    /// candidates).
    pub(crate) wall_list: Vec<u32>,
    /// Particles that may touch a wall before the candidates are rebuilt (see
    /// `refresh_wall_candidates`); the others skip the wall search.
    pub(crate) wall_candidate: Vec<bool>,
    /// Body poses and neighbour-list build count when the candidates were computed.
    pub(crate) wall_ref: Vec<(Vec3, Rotation, usize, f64)>,
    pub(crate) wall_ref_builds: u64,
    /// Refreshes of the wall candidates since the world was built (diagnostic, not saved).
    pub(crate) wall_refreshes: u64,
    /// Use the wall candidates (switched off only by tests comparing both paths).
    pub(crate) wall_skip: bool,
    /// Scratch of the contact remap at neighbour-list rebuilds.
    pub(crate) remap_scratch: Vec<PpContact>,
    /// The forces and torques being summed (scratch; after [`ForcePass::install_forces`] the
    /// previous ones).
    pub(crate) scratch_force: Vec<Vec3>,
    pub(crate) scratch_torque: Vec<Vec3>,
    /// Positions and radii packed per particle for the pair loop (scratch).
    pub(crate) scratch_xr: Vec<[f64; 4]>,
    /// Velocities, masses and spins packed per particle for the pair loop (scratch).
    pub(crate) scratch_kin: Vec<Kin>,
    /// `scratch_xr`/`scratch_kin` hold the current state (packed by the drift of a
    /// velocity-Verlet step; consumed by the next force evaluation).
    pub(crate) packed: bool,
    /// Scratch: the bodies' states over the step being evaluated.
    pub(crate) scratch_body_step: Vec<BodyState>,
    /// Scratch: external work and wall energies of every block of the pair pass.
    pub(crate) scratch_block_out: Vec<(f64, EnergyIncrements)>,
    /// What a repetition of the last step's particle–wall pass needs (only when switched on
    /// with `World::set_wall_pass_repeatable`).
    pub(crate) wall_repeat: Option<Box<WallRepeat>>,
}

impl Default for ForcePass {
    fn default() -> Self {
        Self {
            pp_chunks: Vec::new(),
            pair_contact: Vec::new(),
            wall_slots: Vec::new(),
            cross_out: Vec::new(),
            block_loads: Vec::new(),
            block_start: Vec::new(),
            chunk_block: Vec::new(),
            wall_list: Vec::new(),
            wall_candidate: Vec::new(),
            wall_ref: Vec::new(),
            wall_ref_builds: 0,
            wall_refreshes: 0,
            wall_skip: true,
            remap_scratch: Vec::new(),
            scratch_force: Vec::new(),
            scratch_torque: Vec::new(),
            scratch_xr: Vec::new(),
            scratch_kin: Vec::new(),
            packed: false,
            scratch_body_step: Vec::new(),
            scratch_block_out: Vec::new(),
            wall_repeat: None,
        }
    }
}

/// What the force pass reads from the world.
pub(crate) struct ForceInputs<'a> {
    pub(crate) particles: &'a ParticleSet,
    pub(crate) interactions: &'a InteractionTable,
    pub(crate) neighbors: &'a NeighborList,
    pub(crate) bodies: &'a [RigidBody],
    /// Gravitational acceleration, m/s².
    pub(crate) gravity_m_s2: Vec3,
}

impl ForcePass {
    /// The block pass of a force evaluation at the current state: gravity, external loads,
    /// particle–particle and particle–wall contacts, in parallel over blocks. `dt` is the step
    /// that led to this state (0 for the initial evaluation): it integrates history variables
    /// and contact work. The new forces and torques are left in `scratch_force`/
    /// `scratch_torque` (without the shares of second partners from earlier blocks, see
    /// [`ForcePass::install_forces`]); returns the number of blocks.
    pub(crate) fn run_blocks(&mut self, inputs: &ForceInputs, dt: f64) -> usize {
        let ForceInputs {
            particles: p,
            interactions,
            neighbors: nl,
            bodies,
            gravity_m_s2: g,
        } = *inputs;
        let ForcePass {
            cross_out,
            block_loads,
            block_start,
            chunk_block,
            wall_list,
            pair_contact,
            pp_chunks,
            wall_slots,
            wall_candidate,
            wall_ref,
            wall_ref_builds,
            wall_refreshes,
            wall_skip,
            scratch_xr: xr,
            scratch_kin: kin,
            scratch_body_step: body_step,
            scratch_block_out: block_out,
            packed,
            wall_repeat,
            scratch_force: force,
            scratch_torque: torque,
            ..
        } = self;
        let n = p.len();

        // 1. Particle–particle contacts, in parallel over blocks of chunks of particles (rows
        //    of the half neighbour list). A pair without a contact that does not touch costs
        //    one squared-distance test on positions and radii; a contact keeps its slot in the
        //    chunk's slab (history updated in place); a contact that ended closes its work
        //    integral and frees its slot. Both partners' forces and torques are summed in the
        //    block's own particles, in pair-loop order (see `BlockAcc` and `force_blocks`).
        let nchunks = n.div_ceil(PP_CHUNK);
        fit_contact_store(pp_chunks, pair_contact, n, nl.num_pairs());
        // Blocks of chunks, one rayon task each. A block sums the forces of its own particles
        // directly (first and second partners, in pair-loop order); the share of a second
        // partner in a later block goes to that block's list and is added after the pass, the
        // earlier blocks first. Blocks are cut by the work of the chunks (pairs and contacts),
        // never by the thread count: results do not depend on it.
        let reach = nl.extra_range_m;
        // Positions and radii packed together: one load per partner in the pair loop.
        // Velocities, masses and spins packed likewise: one cache line per contact partner.
        // (Already packed by the drift of a velocity-Verlet step.)
        let packed = std::mem::take(packed) && xr.len() == n && kin.len() == n;
        xr.resize(n, [0.0; 4]);
        kin.resize(n, Kin::default());
        if !packed {
            pack_kinematics(p, xr, kin);
        }
        let xr = &*xr;
        let kin = &*kin;
        let uniform = interactions.hm_uniform();
        let kernel = crate::hm_block::kernel();
        force.resize(n, Vec3::zeros());
        torque.resize(n, Vec3::zeros());
        // Walls: the particles that may touch one (a sorted list), handled by the block task
        // right after the pairs of their chunk, while their data is in cache.
        body_step.clear();
        body_step.extend(bodies.iter().map(|b| b.step_state(dt)));
        let body_step = &*body_step;
        wall_slots.resize(n, Vec::new());
        let wall_list_stale = refresh_wall_candidates(
            p,
            interactions,
            nl,
            bodies,
            body_step,
            wall_candidate,
            wall_ref,
            wall_ref_builds,
            *wall_skip,
            wall_slots,
            wall_list,
        );
        if wall_list_stale {
            *wall_refreshes += 1;
        }
        // A repeatable wall pass keeps the wall slots it starts from (see `wall_repeat`).
        let mut no_record: [(Vec3, Vec3); 0] = [];
        let record: &mut [(Vec3, Vec3)] = match wall_repeat.as_deref_mut() {
            Some(r) => r.start_pass(wall_list, wall_slots, wall_list_stale),
            None => &mut no_record,
        };
        let nblocks = force_blocks(nl, pp_chunks, wall_list, n, block_start, chunk_block);
        cross_out.resize_with(nblocks * nchunks, Vec::new);
        block_loads.resize_with(nblocks, Vec::new);
        let block_start = &*block_start;
        let wall_list_ref = &*wall_list;
        block_out.clear();
        block_out.resize(nblocks, (0.0, EnergyIncrements::default()));
        {
            let mut parts = split_blocks(
                BlockSlices {
                    chunks: &mut pp_chunks[..],
                    pc: &mut pair_contact[..],
                    force: &mut force[..],
                    torque: &mut torque[..],
                    slots: &mut wall_slots[..],
                    cross: &mut cross_out[..],
                    record,
                },
                block_loads,
                nblocks,
                block_start,
                nl,
                wall_list,
                n,
            );
            let pass = BlockPass {
                ctx: PairContext {
                    p,
                    interactions,
                    xr,
                    kin,
                    reach,
                    uniform,
                    dt,
                    kernel,
                },
                nl,
                gravity: g,
                bodies,
                body_step,
                wall_list: wall_list_ref,
                block_start,
                n,
            };
            parts[..nblocks]
                .par_iter_mut()
                .zip(block_out.par_iter_mut())
                .enumerate()
                .for_each(|(b, (part, result))| {
                    let part = part.as_mut().expect("every block has its parts");
                    *result = pass.run(b, part);
                });
        }
        nblocks
    }

    /// After the block pass: the shares of second partners from earlier blocks, the earliest
    /// first (or, with `defer_shares`, by the caller, see [`SecondShares`]); the new forces and
    /// torques swapped into `particles` (the old ones kept as scratch).
    pub(crate) fn install_forces(&mut self, particles: &mut ParticleSet, defer_shares: bool) {
        let (force, torque) = (&mut self.scratch_force, &mut self.scratch_torque);
        if !defer_shares {
            let shares = SecondShares {
                lists: &self.cross_out,
                chunk_block: &self.chunk_block,
            };
            force
                .par_chunks_mut(PP_CHUNK)
                .zip(torque.par_chunks_mut(PP_CHUNK))
                .enumerate()
                .for_each(|(c, (f, t))| shares.add_to_chunk(c, f, t));
        }
        std::mem::swap(&mut particles.force, force);
        std::mem::swap(&mut particles.torque, torque);
    }

    /// The loads on the rigid bodies: the sums of the first `nblocks` blocks of the pair pass
    /// (each in particle order), in block order.
    pub(crate) fn sum_body_loads(&self, bodies: &mut [RigidBody], nblocks: usize) {
        for (k, b) in bodies.iter_mut().enumerate() {
            b.contact_force_n = Vec3::zeros();
            b.contact_torque_nm = Vec3::zeros();
            for l in &self.block_loads[..nblocks] {
                b.contact_force_n += l[k].0;
                b.contact_torque_nm += l[k].1;
            }
        }
    }

    /// The energy increments of the last force evaluation: the chunks' particle–particle
    /// sums, then every block's external work and wall terms, in block order.
    pub(crate) fn sum_increments(&self) -> EnergyIncrements {
        let mut inc = EnergyIncrements::default();
        for &(dn, dtan, el) in self.pp_chunks.iter().map(|c| &c.sums) {
            inc.dissipated_normal_pp_j += dn;
            inc.dissipated_tangential_pp_j += dtan;
            inc.elastic_j += el;
        }
        for &(e, w) in &self.scratch_block_out {
            inc.external_work_j += e;
            inc += w;
        }
        inc
    }
}

#[cfg(test)]
mod tests;

/// What every block task of a force evaluation reads.
struct BlockPass<'a> {
    /// Particles, laws and packed kinematics of the pair pass.
    ctx: PairContext<'a>,
    nl: &'a NeighborList,
    gravity: Vec3,
    bodies: &'a [RigidBody],
    /// The bodies' poses and velocities over the step.
    body_step: &'a [BodyState],
    /// The particles that may touch a wall, sorted.
    wall_list: &'a [u32],
    block_start: &'a [usize],
    n: usize,
}

impl BlockPass<'_> {
    /// The task of block `b`: gravity and external loads, then chunk by chunk the pairs and
    /// right after them the wall contacts of the chunk's wall-list particles (their data still
    /// in cache). Returns the external work and the wall terms of the ledger.
    fn run(&self, b: usize, part: &mut BlockParts) -> (f64, EnergyIncrements) {
        let (ctx, nl, n, wall_list) = (&self.ctx, self.nl, self.n, self.wall_list);
        let (p, dt) = (ctx.p, ctx.dt);
        let (c0, c1) = (self.block_start[b], self.block_start[b + 1]);
        let (lo, hi) = ((c0 * PP_CHUNK).min(n), (c1 * PP_CHUNK).min(n));
        // Gravity and external loads first.
        let mut ext = 0.0;
        for (k, (f, t)) in part
            .force
            .iter_mut()
            .zip(part.torque.iter_mut())
            .enumerate()
        {
            let i = lo + k;
            *f = self.gravity * p.mass[i] + p.external_force[i];
            *t = Vec3::zeros();
            ext += p.external_force[i].dot(&p.velocity[i]) * dt;
        }
        part.cross.iter_mut().for_each(Vec::clear);
        part.loads.clear();
        part.loads
            .resize(self.bodies.len(), (Vec3::zeros(), Vec3::zeros()));
        let mut acc = BlockAcc {
            lo,
            hi,
            force: &mut *part.force,
            torque: &mut *part.torque,
            cross: &mut *part.cross,
        };
        let q_block = nl.row_start[lo] as usize;
        let mut walls = EnergyIncrements::default();
        let mut w = wall_list.partition_point(|&i| (i as usize) < lo);
        let w_block = w;
        PAIR_SCRATCH.with_borrow_mut(|scratch| {
            for (ck, chunk) in part.chunks.iter_mut().enumerate() {
                let c = c0 + ck;
                let (clo, chi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
                let rows = PairRows {
                    lo: clo,
                    hi: chi,
                    q0: nl.row_start[clo] as usize,
                    row_start: &nl.row_start,
                    second: &nl.second,
                };
                let (qa, qb) = (
                    nl.row_start[clo] as usize - q_block,
                    nl.row_start[chi] as usize - q_block,
                );
                // The wall slots of the chunk's particles lie anywhere on the heap: fetched
                // while the pairs are evaluated.
                let w_end = w + wall_list[w..].partition_point(|&i| (i as usize) < chi);
                for &i in &wall_list[w..w_end] {
                    let s = &part.slots[i as usize - lo];
                    if !s.is_empty() {
                        let q = s.as_ptr().cast::<u8>();
                        for line in 0..std::mem::size_of::<WallSlot>().div_ceil(64) {
                            prefetch_at(q.wrapping_add(64 * line));
                        }
                    }
                }
                ctx.chunk_pairs(&rows, chunk, &mut part.pc[qa..qb], &mut acc, scratch);
                // The chunk's particles have all their pair forces from this block.
                while let Some(&i) = wall_list.get(w)
                    && (i as usize) < chi
                {
                    let (i, a) = (i as usize, i as usize - lo);
                    if let Some(r) = part.record.get_mut(w - w_block) {
                        *r = (acc.force[a], acc.torque[a]);
                    }
                    wall_contacts_of(
                        (p.material[i], &ctx.xr[i], &ctx.kin[i]),
                        ctx.interactions,
                        self.bodies,
                        self.body_step,
                        dt,
                        &mut part.slots[a],
                        &mut scratch.wall_contacts,
                        &mut scratch.wall_fresh,
                        &mut acc.force[a],
                        &mut acc.torque[a],
                        &mut walls,
                    );
                    // Loads on the bodies, in particle order.
                    add_wall_loads(&part.slots[a], self.bodies, part.loads);
                    w += 1;
                }
            }
        });
        (ext, walls)
    }
}
