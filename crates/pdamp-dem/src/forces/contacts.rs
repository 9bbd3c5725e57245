//! Where particle–particle contacts live between steps: per chunk of particles, a slab of
//! 128-byte contact states addressed from the pair list, plus orphans carried over a rebuild
//! of the neighbour list; collecting and restoring them for checkpoints.

use super::ForcePass;
use super::state::{NO_CONTACT, PP_CHUNK, PairState};
use crate::neighbor::NeighborList;

/// A particle–particle contact that was active (touching, or within the adhesion range) at the
/// last force evaluation: the partners `i < j` and the contact state.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PpContact {
    /// First partner.
    pub i: u32,
    /// Second partner (`j > i`).
    pub j: u32,
    /// Contact state.
    pub state: PairState,
}

/// The particle–particle contacts whose first partner lies in one chunk of [`PP_CHUNK`]
/// particles. They live in a slab: a contact keeps its slot while it lasts (the neighbour pair
/// points to it through `pair_contact`), so the laws update the history in place; slots of
/// ended contacts are reused. At every neighbour-list rebuild the slab is rewritten in `(i, j)`
/// order (compact, in the order the pair loop visits it).
#[derive(Debug, Clone, Default)]
pub(crate) struct PpChunk {
    /// Contact states by slot, each in two cache lines of its own.
    pub(super) slab: Vec<SlabState>,
    /// Partners `(i, j)` of each slot (read only when contacts are collected).
    pub(super) slab_ij: Vec<(u32, u32)>,
    pub(super) free: Vec<u32>,
    /// Contacts that are not in the neighbour list (any more): closed by the next evaluation.
    pub(super) orphans: Vec<PpContact>,
    pub(super) sums: (f64, f64, f64),
}

/// The state of one contact in a slab: 128 bytes aligned to a cache line, so that the pair loop
/// touches exactly two lines per contact.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub(crate) struct SlabState {
    pub(super) state: PairState,
}

/// Puts a contact into a free slot of the slab (or a new one); returns the slot.
pub(super) fn slab_alloc(
    slab: &mut Vec<SlabState>,
    slab_ij: &mut Vec<(u32, u32)>,
    free: &mut Vec<u32>,
    k: PpContact,
) -> u32 {
    let e = SlabState { state: k.state };
    match free.pop() {
        Some(s) => {
            slab[s as usize] = e;
            slab_ij[s as usize] = (k.i, k.j);
            s
        }
        None => {
            slab.push(e);
            slab_ij.push((k.i, k.j));
            (slab.len() - 1) as u32
        }
    }
}

impl PpChunk {
    pub(super) fn alloc(&mut self, k: PpContact) -> u32 {
        slab_alloc(&mut self.slab, &mut self.slab_ij, &mut self.free, k)
    }

    /// The contact in slot `s`.
    pub(super) fn contact(&self, s: u32) -> PpContact {
        let (i, j) = self.slab_ij[s as usize];
        PpContact {
            i,
            j,
            state: self.slab[s as usize].state,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.slab.len() - self.free.len() + self.orphans.len()
    }
}

impl ForcePass {
    /// Adds the particles that hold wall contacts but are missing from the wall pass's list
    /// (after wall contacts were restored from a backup); keeps the list ascending.
    pub(crate) fn include_wall_holders(&mut self) {
        let list = &self.wall_list;
        let mut k = 0;
        let mut missing = Vec::new();
        for (i, s) in self.wall_slots.iter().enumerate() {
            while k < list.len() && (list[k] as usize) < i {
                k += 1;
            }
            if !s.is_empty() && list.get(k) != Some(&(i as u32)) {
                missing.push(i as u32);
            }
        }
        if !missing.is_empty() {
            self.wall_list.extend(missing);
            self.wall_list.sort_unstable();
        }
    }

    /// All active particle–particle contacts, sorted by `(i, j)`, appended to `out` (those of
    /// partners that no longer exist are dropped).
    pub(crate) fn collect_pp_contacts(
        &self,
        nl: &NeighborList,
        n: usize,
        out: &mut Vec<PpContact>,
    ) {
        // The particles the list and the slabs were built for.
        let n_list = nl.row_start.len().saturating_sub(1);
        let start = out.len();
        let mut orphans = false;
        let attached = self.pair_contact.len() == nl.num_pairs()
            && self.pp_chunks.len() >= n_list.div_ceil(PP_CHUNK);
        for (c, chunk) in self.pp_chunks.iter().enumerate() {
            let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n_list));
            if attached && lo < hi {
                for q in nl.row_start[lo] as usize..nl.row_start[hi] as usize {
                    let s = self.pair_contact[q];
                    if s != NO_CONTACT {
                        out.push(chunk.contact(s));
                    }
                }
            }
            orphans |= !chunk.orphans.is_empty();
            out.extend_from_slice(&chunk.orphans);
        }
        if n_list != n {
            let mut k = start;
            for r in start..out.len() {
                if (out[r].i as usize) < n && (out[r].j as usize) < n {
                    out[k] = out[r];
                    k += 1;
                }
            }
            out.truncate(k);
        }
        if orphans {
            out[start..].sort_by_key(|k| (k.i, k.j));
        }
    }

    /// Replaces the active particle–particle contacts (sorted by `(i, j)`) and attaches them to
    /// the pairs of the current neighbour list; contacts whose pair is not in the list (or whose
    /// partners no longer exist) are closed by the next force evaluation.
    pub(crate) fn set_pp_contacts(&mut self, nl: &NeighborList, n: usize, contacts: &[PpContact]) {
        let nchunks = n.div_ceil(PP_CHUNK);
        self.pp_chunks.resize_with(nchunks, PpChunk::default);
        for c in self.pp_chunks.iter_mut() {
            c.slab.clear();
            c.slab_ij.clear();
            c.free.clear();
            c.orphans.clear();
        }
        let list_ok = nl.row_start.len() == n + 1;
        self.pair_contact.clear();
        self.pair_contact
            .resize(if list_ok { nl.num_pairs() } else { 0 }, NO_CONTACT);
        for k in contacts {
            let (i, j) = (k.i as usize, k.j as usize);
            if i >= n || j >= n {
                continue;
            }
            let chunk = &mut self.pp_chunks[i / PP_CHUNK];
            let q = if list_ok {
                let row = nl.row_start[i] as usize..nl.row_start[i + 1] as usize;
                nl.second[row.clone()]
                    .binary_search(&k.j)
                    .ok()
                    .map(|o| row.start + o)
            } else {
                None
            };
            match q {
                Some(q) => self.pair_contact[q] = chunk.alloc(*k),
                None => chunk.orphans.push(*k),
            }
        }
    }
}

/// Fits the contact store to `n` particles and `m` pairs of the neighbour list. When the
/// particle count changed without a rebuild, the chunks start again from their active contacts
/// and orphans, all as orphans (the next pair pass finds their pairs again).
pub(super) fn fit_contact_store(
    pp_chunks: &mut Vec<PpChunk>,
    pair_contact: &mut Vec<u32>,
    n: usize,
    m: usize,
) {
    let nchunks = n.div_ceil(PP_CHUNK);
    if pp_chunks.len() != nchunks || pair_contact.len() != m {
        // Particle count changed without a rebuild: start from the orphans only.
        let mut all = Vec::new();
        for c in pp_chunks.iter() {
            all.extend(
                (0..c.slab.len() as u32)
                    .map(|s| c.contact(s))
                    .filter(|k| (k.j as usize) < n && k.state.active),
            );
            all.extend(c.orphans.iter().copied().filter(|k| (k.j as usize) < n));
        }
        pp_chunks.clear();
        pp_chunks.resize_with(nchunks, PpChunk::default);
        pair_contact.clear();
        pair_contact.resize(m, NO_CONTACT);
        for k in all {
            pp_chunks[k.i as usize / PP_CHUNK].orphans.push(k);
        }
    }
}
