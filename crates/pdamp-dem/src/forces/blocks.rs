//! Blocks of the pair pass: chunks of particles cut by their work (never by the thread count,
//! so results do not depend on it), each summing the forces of its own particles in pair-loop
//! order; the shares of second partners in later blocks are added after the pass.

use super::contacts::PpChunk;
use super::prefetch::prefetch;
use super::state::{PP_CHUNK, WallSlot};
use crate::math::Vec3;

/// What the second partner of a contact gathers from one pair evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct SecondOutput {
    /// Force on the first partner (the second gets the opposite), N.
    pub(super) force: Vec3,
    /// Torque on the second partner, N·m.
    pub(super) torque: Vec3,
    /// Second partner.
    pub(super) second: u32,
}

/// The forces and torques that second partners receive from earlier blocks of the pair pass:
/// the lists `cross_out` of the last evaluation (list `a × C + c`: those of block `a` for chunk
/// `c` of first partners), see `force_blocks`.
pub(crate) struct SecondShares<'a> {
    pub(crate) lists: &'a [Vec<SecondOutput>],
    /// Block of every chunk.
    pub(crate) chunk_block: &'a [u32],
}

impl SecondShares<'_> {
    /// Adds the shares of chunk `c` (particles `c × PP_CHUNK ..`) to its `force` and `torque`:
    /// those of the earliest block first, each list in pair-loop order.
    #[inline]
    pub(crate) fn add_to_chunk(&self, c: usize, force: &mut [Vec3], torque: &mut [Vec3]) {
        let (lo, nchunks) = (c * PP_CHUNK, self.chunk_block.len());
        for a in 0..self.chunk_block[c] as usize {
            for o in &self.lists[a * nchunks + c] {
                let k = o.second as usize - lo;
                force[k] -= o.force;
                torque[k] += o.torque;
            }
        }
    }
}

/// Where the pair pass of one block sums forces and torques: directly into the block's own
/// particles `lo..hi`, and for a second partner in a later block into that block's list.
pub(crate) struct BlockAcc<'a> {
    pub(super) lo: usize,
    pub(super) hi: usize,
    pub(super) force: &'a mut [Vec3],
    pub(super) torque: &'a mut [Vec3],
    /// Outgoing lists of this block, by target chunk.
    pub(super) cross: &'a mut [Vec<SecondOutput>],
}

impl BlockAcc<'_> {
    /// Adds the force and torque on the first partner `i` (always in this block).
    #[inline(always)]
    pub(super) fn first(&mut self, i: usize, force: Vec3, torque: Vec3) {
        let a = i - self.lo;
        self.force[a] += force;
        self.torque[a] += torque;
    }

    /// Starts loading the force and torque sums of the second partner `j` (added to by a later
    /// flush of the batch; they are mostly not in L1).
    #[inline(always)]
    pub(super) fn prefetch_second(&self, j: usize) {
        if j < self.hi {
            prefetch(&self.force[j - self.lo]);
            prefetch(&self.torque[j - self.lo]);
        }
    }

    /// Adds the share of the second partner `j`: the opposite force, and its torque.
    #[inline(always)]
    pub(super) fn second(&mut self, j: usize, force: Vec3, torque: Vec3) {
        if j < self.hi {
            let a = j - self.lo;
            self.force[a] -= force;
            self.torque[a] += torque;
        } else {
            self.cross[j / PP_CHUNK].push(SecondOutput {
                force,
                torque,
                second: j as u32,
            });
        }
    }
}

/// Particles per block of the pair pass, about (see [`force_blocks`]).
pub(super) const BLOCK_PARTICLES: usize = 8192;

/// Most blocks of the pair pass (see [`force_blocks`]).
pub(super) const MAX_BLOCKS: usize = 16;

/// Cuts the chunks of first partners into blocks for the pair pass: `K` = the largest power of
/// two not above `n / BLOCK_PARTICLES`, or up to 4 blocks of at least `BLOCK_PARTICLES / 4`
/// particles for small beds (at least 1, at most 16, at most the number of chunks),
/// contiguous runs of chunks of about equal work (neighbour pairs, plus six per contact of the
/// last evaluation and 25 per particle of the wall list `walls`: the costs relative to a pair
/// test, measured on the shaken box, where the blocks then take equal times within 1 %).
/// Depends on the state only, never on the thread count. Writes the first chunk of every block
/// (and the end) to `block_start`, the block of every chunk to `chunk_block`; returns `K`.
pub(super) fn force_blocks(
    nl: &crate::neighbor::NeighborList,
    chunks: &[PpChunk],
    walls: &[u32],
    n: usize,
    block_start: &mut Vec<usize>,
    chunk_block: &mut Vec<u32>,
) -> usize {
    let nchunks = n.div_ceil(PP_CHUNK);
    let mut k = 1usize;
    // (small beds: up to four blocks of at least a quarter of BLOCK_PARTICLES, so that two to
    // four threads still share one simulation)
    let target = (n / BLOCK_PARTICLES)
        .max((4 * n / BLOCK_PARTICLES).min(4))
        .min(MAX_BLOCKS);
    while k * 2 <= target {
        k *= 2;
    }
    let k = k.min(nchunks.max(1));
    block_start.clear();
    block_start.push(0);
    chunk_block.clear();
    chunk_block.resize(nchunks, 0);
    if k > 1 {
        // (`w` walks the sorted wall list along the chunks)
        let work = |c: usize, w: &mut usize| -> u64 {
            let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
            let pairs = u64::from(nl.row_start[hi] - nl.row_start[lo]);
            let ch = &chunks[c];
            let w0 = *w;
            while *w < walls.len() && (walls[*w] as usize) < hi {
                *w += 1;
            }
            pairs + 6 * (ch.slab.len() - ch.free.len()) as u64 + 25 * (*w - w0) as u64 + 1
        };
        let mut w = 0;
        let total: u64 = (0..nchunks).map(|c| work(c, &mut w)).sum();
        let (mut run, mut w) = (0u64, 0);
        for c in 0..nchunks {
            run += work(c, &mut w);
            let b = block_start.len();
            // Cut after this chunk once the run reaches the block's share, leaving at least one
            // chunk for each later block.
            let left = nchunks - (c + 1);
            if b < k && left >= k - b && (run * k as u64 >= total * b as u64 || left == k - b) {
                block_start.push(c + 1);
            }
        }
        while block_start.len() < k {
            // (only for fewer chunks than the shares could place)
            let last = *block_start.last().unwrap();
            block_start.push((last + 1).min(nchunks));
        }
    }
    block_start.push(nchunks);
    for b in 0..block_start.len() - 1 {
        chunk_block[block_start[b]..block_start[b + 1]].fill(b as u32);
    }
    block_start.len() - 1
}

/// The per-particle and per-pair storage of one force evaluation, whole (see [`split_blocks`]).
pub(super) struct BlockSlices<'a> {
    pub(super) chunks: &'a mut [PpChunk],
    pub(super) pc: &'a mut [u32],
    pub(super) force: &'a mut [Vec3],
    pub(super) torque: &'a mut [Vec3],
    pub(super) slots: &'a mut [Vec<WallSlot>],
    pub(super) cross: &'a mut [Vec<SecondOutput>],
    /// Force and torque of each wall-list particle before its wall contacts (only when the
    /// wall pass is repeatable; empty otherwise).
    pub(super) record: &'a mut [(Vec3, Vec3)],
}

/// Disjoint slices of one block: its chunks, their pairs' contact slots, its particles'
/// forces, torques and wall slots, its outgoing lists and its loads on the bodies.
pub(super) struct BlockParts<'a> {
    pub(super) chunks: &'a mut [PpChunk],
    pub(super) pc: &'a mut [u32],
    pub(super) force: &'a mut [Vec3],
    pub(super) torque: &'a mut [Vec3],
    pub(super) slots: &'a mut [Vec<WallSlot>],
    pub(super) cross: &'a mut [Vec<SecondOutput>],
    pub(super) loads: &'a mut Vec<(Vec3, Vec3)>,
    /// Force and torque of each of the block's wall-list particles before its wall
    /// contacts (only when the wall pass is repeatable; empty otherwise).
    pub(super) record: &'a mut [(Vec3, Vec3)],
}

/// Cuts `all` into the parts of the first `nblocks` blocks (chunks `block_start[b] ..
/// block_start[b + 1]`), on the stack: no allocation per step (`force_blocks` cuts at most
/// [`MAX_BLOCKS`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn split_blocks<'a>(
    all: BlockSlices<'a>,
    block_loads: &'a mut [Vec<(Vec3, Vec3)>],
    nblocks: usize,
    block_start: &[usize],
    nl: &crate::neighbor::NeighborList,
    wall_list: &[u32],
    n: usize,
) -> [Option<BlockParts<'a>>; MAX_BLOCKS] {
    let nchunks = n.div_ceil(PP_CHUNK);
    let mut parts: [Option<BlockParts>; MAX_BLOCKS] = std::array::from_fn(|_| None);
    let BlockSlices {
        chunks: mut rest_k,
        pc: mut rest_c,
        force: mut rest_f,
        torque: mut rest_t,
        slots: mut rest_s,
        cross: mut rest_x,
        record: mut rest_r,
    } = all;
    let mut w_prev = 0usize;
    for (b, loads) in block_loads.iter_mut().enumerate().take(nblocks) {
        let (c0, c1) = (block_start[b], block_start[b + 1]);
        let (lo, hi) = ((c0 * PP_CHUNK).min(n), (c1 * PP_CHUNK).min(n));
        let pairs = (nl.row_start[hi] - nl.row_start[lo]) as usize;
        let (k, kr) = rest_k.split_at_mut(c1 - c0);
        let (c, cr) = rest_c.split_at_mut(pairs);
        let (f, fr) = rest_f.split_at_mut(hi - lo);
        let (t, tr) = rest_t.split_at_mut(hi - lo);
        let (w, wr) = rest_s.split_at_mut(hi - lo);
        let (x, xr_) = rest_x.split_at_mut(nchunks);
        let w_hi = if rest_r.is_empty() {
            w_prev
        } else {
            wall_list.partition_point(|&i| (i as usize) < hi)
        };
        let (r, rr) = std::mem::take(&mut rest_r).split_at_mut(w_hi - w_prev);
        w_prev = w_hi;
        parts[b] = Some(BlockParts {
            chunks: k,
            pc: c,
            force: f,
            torque: t,
            slots: w,
            cross: x,
            loads,
            record: r,
        });
        (rest_k, rest_c, rest_f, rest_t, rest_s, rest_x, rest_r) = (kr, cr, fr, tr, wr, xr_, rr);
    }
    parts
}
