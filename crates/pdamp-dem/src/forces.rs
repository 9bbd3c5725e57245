//! Force evaluation: contact kinematics [D Eq. 2.12–2.27], contact laws, torques [D Eq. 2.86–2.89],
//! gravity, loads on rigid bodies, and the per-contact work that feeds the energy ledger.

use crate::body::BodyState;
use crate::contact::{ContactForce, ContactHistory, ContactKinematics, PairProps};
use crate::energy::EnergyIncrements;
use crate::hm_block::{HmInput, HmOutput, HmState, LANES};
use crate::material::{effective_mass, effective_radius};
use crate::math::{Vec3, tangential_part};
use crate::walls::WallContact;
use crate::world::World;
use rayon::prelude::*;

/// State of one contact carried from step to step: the law's history plus the forces and stored
/// energies of the previous evaluation (for trapezoidal work integration).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairState {
    /// History owned by the contact law.
    pub history: ContactHistory,
    /// Normal force on the first partner at the previous evaluation, N.
    pub normal_force_prev: Vec3,
    /// Tangential force on the first partner at the previous evaluation, N.
    pub tangential_force_prev: Vec3,
    /// Rolling torque on the first partner at the previous evaluation, N·m.
    pub rolling_torque_prev: Vec3,
    /// Stored normal energy at the previous evaluation, J.
    pub normal_energy_prev: f64,
    /// Stored tangential energy at the previous evaluation, J.
    pub tangential_energy_prev: f64,
    /// The partners interacted at the previous evaluation.
    pub active: bool,
}

/// A particle–wall contact slot of one particle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallSlot {
    /// Body index.
    pub body: u16,
    /// Wall index within the body.
    pub wall: u16,
    /// Feature of the wall geometry.
    pub feature: u32,
    /// Contact normal (world frame) at the last evaluation.
    pub normal: Vec3,
    /// Contact point (world frame) at the last evaluation, m.
    pub point: Vec3,
    /// Force on the particle at the last evaluation, N.
    pub force: Vec3,
    /// Rolling torque on the particle at the last evaluation, N·m.
    pub rolling_torque: Vec3,
    /// Contact state.
    pub state: PairState,
}

/// What the second partner of a contact gathers from one pair evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct SecondOutput {
    /// Force on the first partner (the second gets the opposite), N.
    force: Vec3,
    /// Torque on the second partner, N·m.
    torque: Vec3,
    /// Second partner.
    second: u32,
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

/// Work bookkeeping of one contact evaluation; returns (dissipated normal, dissipated tangential).
#[inline]
#[allow(clippy::too_many_arguments)]
fn account(
    st: &mut PairState,
    f: &ContactForce,
    fn_vec: Vec3,
    ft: Vec3,
    v_rel: &Vec3,
    w_rel: &Vec3,
    dt: f64,
    active: bool,
) -> (f64, f64) {
    let w_n = -0.5 * (st.normal_force_prev + fn_vec).dot(v_rel) * dt;
    let w_t = -0.5 * (st.tangential_force_prev + ft).dot(v_rel) * dt
        - 0.5 * (st.rolling_torque_prev + f.rolling_torque_nm).dot(w_rel) * dt;
    let d_n = w_n - (f.normal_energy_j - st.normal_energy_prev);
    let d_t = w_t - (f.tangential_energy_j - st.tangential_energy_prev);
    st.normal_force_prev = fn_vec;
    st.tangential_force_prev = ft;
    st.rolling_torque_prev = f.rolling_torque_nm;
    st.normal_energy_prev = f.normal_energy_j;
    st.tangential_energy_prev = f.tangential_energy_j;
    st.active = active;
    (d_n, d_t)
}

const CHUNK: usize = 1024;

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
    slab: Vec<SlabState>,
    /// Partners `(i, j)` of each slot (read only when contacts are collected).
    slab_ij: Vec<(u32, u32)>,
    free: Vec<u32>,
    /// Contacts that are not in the neighbour list (any more): closed by the next evaluation.
    orphans: Vec<PpContact>,
    sums: (f64, f64, f64),
}

/// Scratch of the pair loop, one per worker thread (kept between steps: no allocation once
/// grown, and it stays in that core's cache).
#[derive(Debug, Default)]
pub(crate) struct PairScratch {
    /// The pairs of a chunk that touch or had a contact (index within the chunk's pair range)
    /// and their first partners.
    scan_pair: Vec<u32>,
    scan_first: Vec<u32>,
    /// Hertz–Mindlin contacts gathered for block evaluation.
    batch: HmBatch,
    /// Wall contacts found for one particle, and its new wall slots.
    pub(crate) wall_contacts: Vec<WallContact>,
    pub(crate) wall_fresh: Vec<WallSlot>,
}

thread_local! {
    pub(crate) static PAIR_SCRATCH: std::cell::RefCell<PairScratch> =
        std::cell::RefCell::new(PairScratch::default());
}

/// The state of one contact in a slab: 128 bytes aligned to a cache line, so that the pair loop
/// touches exactly two lines per contact.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub(crate) struct SlabState {
    state: PairState,
}

/// Puts a contact into a free slot of the slab (or a new one); returns the slot.
fn slab_alloc(
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
    fn alloc(&mut self, k: PpContact) -> u32 {
        slab_alloc(&mut self.slab, &mut self.slab_ij, &mut self.free, k)
    }

    /// The contact in slot `s`.
    fn contact(&self, s: u32) -> PpContact {
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

impl World {
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
    pub(crate) fn collect_pp_contacts(&self, out: &mut Vec<PpContact>) {
        let nl = &self.neighbors;
        let n = self.particles.len();
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

    /// All active particle–particle contacts, sorted by `(i, j)`.
    pub(crate) fn pp_contacts(&self) -> Vec<PpContact> {
        let mut v = Vec::new();
        self.collect_pp_contacts(&mut v);
        v
    }

    /// Replaces the active particle–particle contacts (sorted by `(i, j)`) and attaches them to
    /// the pairs of the current neighbour list; contacts whose pair is not in the list (or whose
    /// partners no longer exist) are closed by the next force evaluation.
    pub(crate) fn set_pp_contacts(&mut self, contacts: &[PpContact]) {
        let n = self.particles.len();
        let nchunks = n.div_ceil(PP_CHUNK);
        self.pp_chunks.resize_with(nchunks, PpChunk::default);
        for c in self.pp_chunks.iter_mut() {
            c.slab.clear();
            c.slab_ij.clear();
            c.free.clear();
            c.orphans.clear();
        }
        let nl = &self.neighbors;
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

/// How many pairs ahead the pair loop prefetches partner data.
const PREFETCH_AHEAD: usize = 8;

/// Hertz–Mindlin contacts gathered before a block evaluation (a multiple of [`LANES`]; the
/// gathered lanes stay in the L1 cache until the kernel and the hand-out read them).
const BATCH_FLUSH: usize = 2 * LANES;

/// Hints the processor to load the cache line of `x` (no effect on other targets).
#[inline(always)]
fn prefetch<T>(x: &T) {
    prefetch_at((x as *const T).cast::<u8>());
}

/// Hints the processor to load the cache line at `p` (never dereferenced).
#[inline(always)]
fn prefetch_at(p: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint; it never faults, whatever the address.
    #[allow(unused_unsafe)]
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Marks a neighbour pair without an active contact in `pair_contact`.
pub(crate) const NO_CONTACT: u32 = u32::MAX;

/// Particles per chunk of the particle–particle pass.
pub(crate) const PP_CHUNK: usize = 256;

/// Evaluates the contact of the pair (`i`, `j`) at distance vector `d = x_i − x_j`: the law if the
/// partners interact (`touching`), or the closing of the work integral of a contact that ended.
/// Returns the output, the dissipated normal and tangential energy and the stored energy.
#[inline]
#[allow(clippy::too_many_arguments)]
fn evaluate_pair(
    p: &crate::particles::ParticleSet,
    interactions: &crate::interaction::InteractionTable,
    i: usize,
    j: usize,
    d: Vec3,
    dist: f64,
    touching: bool,
    st: &mut PairState,
    dt: f64,
) -> (PairEval, f64, f64, f64) {
    let overlap = p.radius[i] + p.radius[j] - dist;
    let n = if dist > 0.0 { d / dist } else { Vec3::z() };
    let rb_i = p.radius[i] - 0.5 * overlap.max(0.0);
    let rb_j = p.radius[j] - 0.5 * overlap.max(0.0);
    let dv = p.velocity[i] - p.velocity[j];
    let v_rel =
        dv + p.angular_velocity[i].cross(&(-rb_i * n)) - p.angular_velocity[j].cross(&(rb_j * n));
    let w_rel = p.angular_velocity[i] - p.angular_velocity[j];
    let f = if touching {
        let (model, el_pair) = interactions.get(p.material[i], p.material[j]);
        let props = PairProps {
            e_eff_pa: el_pair.e_eff_pa,
            g_eff_pa: el_pair.g_eff_pa,
            poisson_mean: el_pair.poisson_mean,
            r_eff_m: effective_radius(p.radius[i], p.radius[j]),
            m_eff_kg: effective_mass(p.mass[i], p.mass[j]),
        };
        let kin = ContactKinematics {
            overlap_m: overlap,
            overlap_rate_m_s: -n.dot(&dv),
            normal: n,
            tangential_velocity_m_s: tangential_part(&v_rel, &n),
            relative_angular_velocity_rad_s: w_rel,
            dt_s: dt,
        };
        model.evaluate(&props, &kin, &mut st.history)
    } else {
        st.history = ContactHistory::default();
        ContactForce::default()
    };
    let fn_vec = n * f.normal_total_n();
    let ft = f.tangential_n;
    let (a, b) = account(st, &f, fn_vec, ft, &v_rel, &w_rel, dt, touching);
    // Torques (−r_b,i n) × F_t and (r_b,j n) × (−F_t) share the vector n × F_t.
    let c = n.cross(&ft);
    let out = PairEval {
        force: fn_vec + ft,
        torque_first: -rb_i * c + f.rolling_torque_nm,
        torque_second: -rb_j * c - f.rolling_torque_nm,
    };
    (out, a, b, f.normal_energy_j + f.tangential_energy_j)
}

/// The rows of the half neighbour list that belong to one chunk of first partners.
struct PairRows<'a> {
    /// First partners `lo..hi`.
    lo: usize,
    hi: usize,
    /// Index of the chunk's first pair in the list.
    q0: usize,
    row_start: &'a [u32],
    second: &'a [u32],
}

/// What the pair loop reads, shared by all chunks.
struct PairContext<'a> {
    p: &'a crate::particles::ParticleSet,
    interactions: &'a crate::interaction::InteractionTable,
    /// Positions and radii `[x, y, z, r]`.
    xr: &'a [[f64; 4]],
    /// Velocities, masses and spins.
    kin: &'a [Kin],
    /// Adhesion range added to the contact distance, m.
    reach: f64,
    /// Hertz–Mindlin constants shared by every pair, if they are.
    uniform: Option<&'a crate::interaction::HmConstants>,
    dt: f64,
    kernel: crate::hm_block::Kernel,
}

/// Hertz–Mindlin contacts collected for evaluation in blocks (see [`crate::hm_block`]):
/// [`BATCH_FLUSH`] contacts are gathered first, then evaluated block by block, then handed out,
/// so that the kernel reads lanes written a while before (no stalled store-to-load forwarding),
/// the gather loop keeps many independent loads in flight, and the lanes stay in the L1 cache.
/// Scratch of a chunk; grows, never shrinks.
#[derive(Debug, Clone, Default)]
pub(crate) struct HmBatch {
    inp: Vec<HmInput>,
    st: Vec<HmState>,
    out: Vec<HmOutput>,
    /// First partner, second partner and slab slot of each contact.
    lane: Vec<(u32, u32, u32)>,
    len: usize,
}

impl HmBatch {
    /// Adds the touching pair (`i`, `j`) at distance vector `d`, its contact in `slot`.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        hm: &crate::interaction::HmConstants,
        (i, j): (usize, usize),
        (ri, rj): (f64, f64),
        (ki, kj): (&Kin, &Kin),
        d: Vec3,
        state: &PairState,
        slot: u32,
    ) {
        let (blk, k) = (self.len / LANES, self.len % LANES);
        if blk == self.inp.len() {
            self.inp.push(HmInput::default());
            self.st.push(HmState::default());
            self.out.push(HmOutput::default());
        }
        let (b, s) = (&mut self.inp[blk], &mut self.st[blk]);
        (b.dx[k], b.dy[k], b.dz[k]) = (d.x, d.y, d.z);
        (b.ri[k], b.rj[k]) = (ri, rj);
        b.vx[k] = ki.v[0] - kj.v[0];
        b.vy[k] = ki.v[1] - kj.v[1];
        b.vz[k] = ki.v[2] - kj.v[2];
        (b.wix[k], b.wiy[k], b.wiz[k]) = (ki.w[0], ki.w[1], ki.w[2]);
        (b.wjx[k], b.wjy[k], b.wjz[k]) = (kj.w[0], kj.w[1], kj.w[2]);
        (b.mi[k], b.mj[k]) = (ki.m, kj.m);
        b.e_eff[k] = hm.e_eff_pa;
        b.g_eff[k] = hm.g_eff_pa;
        b.damping[k] = hm.damping;
        b.mu[k] = hm.mu;
        b.clip[k] = hm.clip_attractive;
        let xi = state.history.spring_m;
        (s.sx[k], s.sy[k], s.sz[k]) = (xi.x, xi.y, xi.z);
        let f = state.normal_force_prev;
        (s.fnx[k], s.fny[k], s.fnz[k]) = (f.x, f.y, f.z);
        let f = state.tangential_force_prev;
        (s.ftx[k], s.fty[k], s.ftz[k]) = (f.x, f.y, f.z);
        s.en[k] = state.normal_energy_prev;
        s.et[k] = state.tangential_energy_prev;
        if self.len == self.lane.len() {
            self.lane.push((0, 0, 0));
        }
        self.lane[self.len] = (i as u32, j as u32, slot);
        self.len += 1;
    }

    /// Evaluates the collected contacts and hands out their results in the order they were
    /// added: contact states into the slab, forces and torques to both partners through `acc`,
    /// energies added to `sums` (normal and tangential dissipation, stored energy).
    #[allow(clippy::too_many_arguments)]
    fn flush(
        &mut self,
        kernel: crate::hm_block::Kernel,
        dt: f64,
        slab: &mut [SlabState],
        acc: &mut BlockAcc,
        sums: &mut (f64, f64, f64),
    ) {
        let m = self.len;
        if m == 0 {
            return;
        }
        let nblk = m.div_ceil(LANES);
        // Unused lanes of the last block repeat its first contact (finite numbers; dropped).
        let used = m - (nblk - 1) * LANES;
        for k in used..LANES {
            copy_lane(&mut self.inp[nblk - 1], &mut self.st[nblk - 1], 0, k);
        }
        for ((b, s), o) in self.inp[..nblk]
            .iter()
            .zip(&mut self.st[..nblk])
            .zip(&mut self.out[..nblk])
        {
            kernel.eval(b, s, o, dt);
        }
        for (e, &(i, j, slot)) in self.lane[..m].iter().enumerate() {
            let (s, o, k) = (&self.st[e / LANES], &self.out[e / LANES], e % LANES);
            let st = &mut slab[slot as usize].state;
            let h = &mut st.history;
            if h.impact_velocity_m_s == 0.0 {
                h.impact_velocity_m_s =
                    o.rate[k].max(crate::contact::default_min_impact_velocity());
            }
            h.spring_m = Vec3::new(s.sx[k], s.sy[k], s.sz[k]);
            st.normal_force_prev = Vec3::new(s.fnx[k], s.fny[k], s.fnz[k]);
            st.tangential_force_prev = Vec3::new(s.ftx[k], s.fty[k], s.ftz[k]);
            st.normal_energy_prev = s.en[k];
            st.tangential_energy_prev = s.et[k];
            st.active = true;
            sums.0 += o.dn[k];
            sums.1 += o.dt[k];
            sums.2 += o.el[k];
            let force = Vec3::new(o.fx[k], o.fy[k], o.fz[k]);
            acc.first(i as usize, force, Vec3::new(o.tix[k], o.tiy[k], o.tiz[k]));
            acc.second(j as usize, force, Vec3::new(o.tjx[k], o.tjy[k], o.tjz[k]));
        }
        self.len = 0;
    }
}

/// Copies lane `from` of a block's inputs and state to lane `to`.
fn copy_lane(b: &mut HmInput, s: &mut HmState, from: usize, to: usize) {
    for a in [
        &mut b.dx,
        &mut b.dy,
        &mut b.dz,
        &mut b.ri,
        &mut b.rj,
        &mut b.vx,
        &mut b.vy,
        &mut b.vz,
        &mut b.wix,
        &mut b.wiy,
        &mut b.wiz,
        &mut b.wjx,
        &mut b.wjy,
        &mut b.wjz,
        &mut b.mi,
        &mut b.mj,
        &mut b.e_eff,
        &mut b.g_eff,
        &mut b.damping,
        &mut b.mu,
        &mut s.sx,
        &mut s.sy,
        &mut s.sz,
        &mut s.fnx,
        &mut s.fny,
        &mut s.fnz,
        &mut s.ftx,
        &mut s.fty,
        &mut s.ftz,
        &mut s.en,
        &mut s.et,
    ] {
        a[to] = a[from];
    }
    b.clip[to] = b.clip[from];
}

impl PairContext<'_> {
    /// The particle–particle contacts of one chunk of first partners: returns the number of
    /// second-partner outputs written to `po`; the first partners' forces and torques go to
    /// `rf`/`rt`, the energies to `chunk.sums`.
    ///
    /// Two passes. The scan tests every pair of the rows for contact (squared distance against
    /// the sum of the radii plus the adhesion range) without branching and keeps the pairs that
    /// touch or had a contact. The second pass evaluates those in list order: touching pairs
    /// with the Hertz–Mindlin law go into blocks of [`LANES`] evaluated together
    /// ([`crate::hm_block`]); other laws and contacts that ended are evaluated one by one (a
    /// pending block is evaluated first, so that every first partner sums its forces in list
    /// order). A contact keeps its slot in the chunk's slab while it lasts.
    #[inline(never)]
    fn chunk_pairs(
        &self,
        rows: &PairRows,
        chunk: &mut PpChunk,
        pc: &mut [u32],
        acc: &mut BlockAcc,
        scratch: &mut PairScratch,
    ) {
        let (p, interactions, xr, kin, reach, dt) = (
            self.p,
            self.interactions,
            self.xr,
            self.kin,
            self.reach,
            self.dt,
        );
        let (lo, hi, q0) = (rows.lo, rows.hi, rows.q0);
        let second_c = &rows.second[q0..rows.row_start[hi] as usize];
        let PpChunk {
            slab,
            slab_ij,
            free,
            orphans,
            sums,
        } = chunk;
        let PairScratch {
            scan_pair,
            scan_first,
            batch,
            ..
        } = scratch;
        // 1. Scan.
        if scan_pair.len() < second_c.len() {
            scan_pair.resize(second_c.len(), 0);
            scan_first.resize(second_c.len(), 0);
        }
        // (slices taken once: the loop keeps their bounds in registers instead of reloading
        // the vectors' headers after every store, 1.5–2 % of a step)
        let np = second_c.len();
        let (sp, sf, pcs) = (&mut scan_pair[..np], &mut scan_first[..np], &pc[..np]);
        let mut na = 0usize;
        for (i, w) in (lo..hi).zip(rows.row_start[lo..=hi].windows(2)) {
            let [xi0, xi1, xi2, ri0] = xr[i];
            let ri = ri0 + reach;
            let (a, b) = (w[0] as usize - q0, w[1] as usize - q0);
            for (qq, (&j, &slot)) in (a..b).zip(second_c[a..b].iter().zip(&pcs[a..b])) {
                let [xj0, xj1, xj2, rj] = xr[j as usize];
                let (d0, d1, d2) = (xi0 - xj0, xi1 - xj1, xi2 - xj2);
                let dist2 = (d0 * d0 + d1 * d1) + d2 * d2;
                let cut = ri + rj;
                sp[na] = qq as u32;
                sf[na] = i as u32;
                na += ((dist2 < cut * cut) | (slot != NO_CONTACT)) as usize;
            }
        }
        // 2. Contacts, in list order.
        let mut sum = (0.0, 0.0, 0.0);
        let mut alloc = |slab: &mut Vec<SlabState>, free: &mut Vec<u32>, i: usize, j: usize| {
            let k = PpContact {
                i: i as u32,
                j: j as u32,
                state: PairState::default(),
            };
            slab_alloc(slab, slab_ij, free, k)
        };
        for e in 0..na {
            // Look ahead: fetch the partner data and contact state of a later contact while this
            // one is gathered (the slab and the partners' velocities are mostly not in L1).
            if e + PREFETCH_AHEAD < na {
                let qn = scan_pair[e + PREFETCH_AHEAD] as usize;
                prefetch(&kin[second_c[qn] as usize]);
                let sn = pc[qn];
                if let Some(k) = slab.get(sn as usize) {
                    // both cache lines of the slot
                    let p = (k as *const SlabState).cast::<u8>();
                    prefetch_at(p);
                    prefetch_at(p.wrapping_add(64));
                }
            }
            let qq = scan_pair[e] as usize;
            let i = scan_first[e] as usize;
            let j = second_c[qq] as usize;
            let slot = pc[qq];
            let ([xi0, xi1, xi2, ri0], [xj0, xj1, xj2, rj]) = (xr[i], xr[j]);
            let d = Vec3::new(xi0 - xj0, xi1 - xj1, xi2 - xj2);
            let dist2 = d.norm_squared();
            let cut = ri0 + rj;
            if reach <= 0.0
                && dist2 < cut * cut
                && dist2 > 0.0
                && let Some(hm) = self
                    .uniform
                    .or_else(|| interactions.hm_fast(p.material[i], p.material[j]))
            {
                let s = if slot == NO_CONTACT {
                    let s = alloc(slab, free, i, j);
                    pc[qq] = s;
                    s
                } else {
                    slot
                };
                acc.prefetch_second(j);
                batch.push(
                    hm,
                    (i, j),
                    (ri0, rj),
                    (&kin[i], &kin[j]),
                    d,
                    &slab[s as usize].state,
                    s,
                );
                if batch.len == BATCH_FLUSH {
                    batch.flush(self.kernel, dt, slab, acc, &mut sum);
                }
                continue;
            }
            let dist = dist2.sqrt();
            let touching = interacts(p, interactions, reach, i, j, dist);
            if !touching && slot == NO_CONTACT {
                continue;
            }
            if touching {
                batch.flush(self.kernel, dt, slab, acc, &mut sum);
            }
            let s = if slot == NO_CONTACT {
                alloc(slab, free, i, j)
            } else {
                slot
            };
            let st = &mut slab[s as usize].state;
            let (out, x, y, en) = evaluate_pair(p, interactions, i, j, d, dist, touching, st, dt);
            sum.0 += x;
            sum.1 += y;
            sum.2 += en;
            if touching {
                pc[qq] = s;
                acc.first(i, out.force, out.torque_first);
                acc.second(j, out.force, out.torque_second);
            } else {
                pc[qq] = NO_CONTACT;
                free.push(s);
            }
        }
        batch.flush(self.kernel, dt, slab, acc, &mut sum);
        // Contacts that left the neighbour list: close their work integral.
        for k in orphans.drain(..) {
            let (i, j) = (k.i as usize, k.j as usize);
            let d = p.position[i] - p.position[j];
            let mut st = k.state;
            let (_, x, y, _) =
                evaluate_pair(p, interactions, i, j, d, d.norm(), false, &mut st, dt);
            sum.0 += x;
            sum.1 += y;
        }
        *sums = sum;
    }
}

/// Where the pair pass of one block sums forces and torques: directly into the block's own
/// particles `lo..hi`, and for a second partner in a later block into that block's list.
pub(crate) struct BlockAcc<'a> {
    lo: usize,
    hi: usize,
    force: &'a mut [Vec3],
    torque: &'a mut [Vec3],
    /// Outgoing lists of this block, by target chunk.
    cross: &'a mut [Vec<SecondOutput>],
}

impl BlockAcc<'_> {
    /// Adds the force and torque on the first partner `i` (always in this block).
    #[inline(always)]
    fn first(&mut self, i: usize, force: Vec3, torque: Vec3) {
        let a = i - self.lo;
        self.force[a] += force;
        self.torque[a] += torque;
    }

    /// Starts loading the force and torque sums of the second partner `j` (added to by a later
    /// flush of the batch; they are mostly not in L1).
    #[inline(always)]
    fn prefetch_second(&self, j: usize) {
        if j < self.hi {
            prefetch(&self.force[j - self.lo]);
            prefetch(&self.torque[j - self.lo]);
        }
    }

    /// Adds the share of the second partner `j`: the opposite force, and its torque.
    #[inline(always)]
    fn second(&mut self, j: usize, force: Vec3, torque: Vec3) {
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
const BLOCK_PARTICLES: usize = 8192;

/// Most blocks of the pair pass (see [`force_blocks`]).
const MAX_BLOCKS: usize = 16;

/// Cuts the chunks of first partners into blocks for the pair pass: `K` = the largest power of
/// two not above `n / BLOCK_PARTICLES`, or up to 4 blocks of at least `BLOCK_PARTICLES / 4`
/// particles for small beds (at least 1, at most 16, at most the number of chunks),
/// contiguous runs of chunks of about equal work (neighbour pairs, plus six per contact of the
/// last evaluation and 25 per particle of the wall list `walls`: the costs relative to a pair
/// test, measured on the shaken box, where the blocks then take equal times within 1 %).
/// Depends on the state only, never on the thread count. Writes the first chunk of every block
/// (and the end) to `block_start`, the block of every chunk to `chunk_block`; returns `K`.
fn force_blocks(
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

/// Velocity, mass and angular velocity of one particle, packed into one cache line for the
/// contact laws of the pair loop (scratch, refreshed every evaluation).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub(crate) struct Kin {
    v: [f64; 3],
    m: f64,
    w: [f64; 3],
    _pad: f64,
}

impl Kin {
    /// Packs velocity `v`, mass `m` and angular velocity `w`.
    #[inline]
    pub(crate) fn new(v: &Vec3, m: f64, w: &Vec3) -> Self {
        Kin {
            v: [v.x, v.y, v.z],
            m,
            w: [w.x, w.y, w.z],
            _pad: 0.0,
        }
    }

    /// The packed state of particle `i`.
    #[inline]
    fn of(p: &crate::particles::ParticleSet, i: usize) -> Self {
        let (u, w) = (p.velocity[i], p.angular_velocity[i]);
        Kin {
            v: [u.x, u.y, u.z],
            m: p.mass[i],
            w: [w.x, w.y, w.z],
            _pad: 0.0,
        }
    }
}

/// Forces and torques of one pair evaluation.
#[derive(Debug, Clone, Copy)]
struct PairEval {
    force: Vec3,
    torque_first: Vec3,
    torque_second: Vec3,
}

/// True if the pair interacts: overlap, or a gap within the law's adhesion range.
#[inline]
fn interacts(
    p: &crate::particles::ParticleSet,
    interactions: &crate::interaction::InteractionTable,
    reach: f64,
    i: usize,
    j: usize,
    dist: f64,
) -> bool {
    let overlap = p.radius[i] + p.radius[j] - dist;
    if dist <= 0.0 {
        return false;
    }
    if reach <= 0.0 {
        return overlap > 0.0;
    }
    let (model, el_pair) = interactions.get(p.material[i], p.material[j]);
    let props = PairProps {
        e_eff_pa: el_pair.e_eff_pa,
        g_eff_pa: el_pair.g_eff_pa,
        poisson_mean: el_pair.poisson_mean,
        r_eff_m: effective_radius(p.radius[i], p.radius[j]),
        m_eff_kg: effective_mass(p.mass[i], p.mass[j]),
    };
    overlap > -model.max_interaction_gap_m(&props)
}

impl World {
    /// Evaluates all forces and torques at the current state. `dt` is the step that led to this
    /// state (0 for the initial evaluation): it integrates history variables and contact work.
    /// Returns the energy increments of this evaluation.
    pub(crate) fn evaluate_forces(&mut self, dt: f64) -> EnergyIncrements {
        self.evaluate_forces_with(dt, false)
    }

    /// [`World::evaluate_forces`]; with `defer_shares`, the forces and torques that second
    /// partners receive from earlier blocks of the pair pass are left for the caller to add,
    /// chunk by chunk, with [`SecondShares`] (before anything reads the forces): the second
    /// half-kick of velocity Verlet does, one parallel loop less.
    pub(crate) fn evaluate_forces_with(&mut self, dt: f64, defer_shares: bool) -> EnergyIncrements {
        let t_pairs = self.tick();
        let World {
            particles: p,
            interactions,
            neighbors,
            cross_out,
            block_loads,
            block_start,
            chunk_block,
            wall_list,
            pair_contact,
            pp_chunks,
            wall_slots,
            bodies,
            gravity_m_s2,
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
            ..
        } = self;
        let p = &*p;
        let interactions = &*interactions;
        let nl = &*neighbors;
        let n = p.len();

        // 1. Particle–particle contacts, in parallel over blocks of chunks of particles (rows
        //    of the half neighbour list). A pair without a contact that does not touch costs
        //    one squared-distance test on positions and radii; a contact keeps its slot in the
        //    chunk's slab (history updated in place); a contact that ended closes its work
        //    integral and frees its slot. Both partners' forces and torques are summed in the
        //    block's own particles, in pair-loop order (see `BlockAcc` and `force_blocks`).
        let nchunks = n.div_ceil(PP_CHUNK);
        let m = nl.num_pairs();
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
            xr.par_chunks_mut(CHUNK)
                .zip(kin.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(|(c, (out, kout))| {
                    for (k, (v, kv)) in out.iter_mut().zip(kout.iter_mut()).enumerate() {
                        let i = c * CHUNK + k;
                        let x = p.position[i];
                        *v = [x.x, x.y, x.z, p.radius[i]];
                        *kv = Kin::of(p, i);
                    }
                });
        }
        let xr = &*xr;
        let kin = &*kin;
        let uniform = interactions.hm_uniform();
        let kernel = crate::hm_block::kernel();
        let g = *gravity_m_s2;
        let mut force = std::mem::take(&mut self.scratch_force);
        let mut torque = std::mem::take(&mut self.scratch_torque);
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
        let chunk_block = &*chunk_block;
        let bodies_ref = &*bodies;
        let wall_list_ref = &*wall_list;
        block_out.clear();
        block_out.resize(nblocks, (0.0, EnergyIncrements::default()));
        {
            // Disjoint slices per block: its chunks, their pairs' contact slots, its particles'
            // forces, torques and wall slots, its outgoing lists.
            struct BlockParts<'a> {
                chunks: &'a mut [PpChunk],
                pc: &'a mut [u32],
                force: &'a mut [Vec3],
                torque: &'a mut [Vec3],
                slots: &'a mut [Vec<WallSlot>],
                cross: &'a mut [Vec<SecondOutput>],
                loads: &'a mut Vec<(Vec3, Vec3)>,
                /// Force and torque of each of the block's wall-list particles before its wall
                /// contacts (only when the wall pass is repeatable; empty otherwise).
                record: &'a mut [(Vec3, Vec3)],
            }
            // (on the stack: no allocation per step; `force_blocks` cuts at most MAX_BLOCKS)
            let mut parts: [Option<BlockParts>; MAX_BLOCKS] = std::array::from_fn(|_| None);
            let (mut rest_k, mut rest_c, mut rest_f, mut rest_t, mut rest_s, mut rest_x) = (
                &mut pp_chunks[..],
                &mut pair_contact[..],
                &mut force[..],
                &mut torque[..],
                &mut wall_slots[..],
                &mut cross_out[..],
            );
            let (mut rest_r, mut w_prev) = (record, 0usize);
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
                (rest_k, rest_c, rest_f, rest_t, rest_s, rest_x, rest_r) =
                    (kr, cr, fr, tr, wr, xr_, rr);
            }
            parts[..nblocks]
                .par_iter_mut()
                .zip(block_out.par_iter_mut())
                .enumerate()
                .for_each(|(b, (part, result))| {
                    let part = part.as_mut().expect("every block has its parts");
                    let (c0, c1) = (block_start[b], block_start[b + 1]);
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
                        *f = g * p.mass[i] + p.external_force[i];
                        *t = Vec3::zeros();
                        ext += p.external_force[i].dot(&p.velocity[i]) * dt;
                    }
                    part.cross.iter_mut().for_each(Vec::clear);
                    part.loads.clear();
                    part.loads
                        .resize(bodies_ref.len(), (Vec3::zeros(), Vec3::zeros()));
                    let mut acc = BlockAcc {
                        lo,
                        hi,
                        force: &mut *part.force,
                        torque: &mut *part.torque,
                        cross: &mut *part.cross,
                    };
                    let ctx = PairContext {
                        p,
                        interactions,
                        xr,
                        kin,
                        reach,
                        uniform,
                        dt,
                        kernel,
                    };
                    let q_block = nl.row_start[lo] as usize;
                    let mut walls = EnergyIncrements::default();
                    let mut w = wall_list_ref.partition_point(|&i| (i as usize) < lo);
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
                            // The wall slots of the chunk's particles lie anywhere on the
                            // heap: fetched while the pairs are evaluated.
                            let w_end =
                                w + wall_list_ref[w..].partition_point(|&i| (i as usize) < chi);
                            for &i in &wall_list_ref[w..w_end] {
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
                            while let Some(&i) = wall_list_ref.get(w)
                                && (i as usize) < chi
                            {
                                let (i, a) = (i as usize, i as usize - lo);
                                if let Some(r) = part.record.get_mut(w - w_block) {
                                    *r = (acc.force[a], acc.torque[a]);
                                }
                                wall_contacts_of(
                                    (p.material[i], &xr[i], &kin[i]),
                                    interactions,
                                    bodies_ref,
                                    body_step,
                                    dt,
                                    &mut part.slots[a],
                                    &mut scratch.wall_contacts,
                                    &mut scratch.wall_fresh,
                                    &mut acc.force[a],
                                    &mut acc.torque[a],
                                    &mut walls,
                                );
                                // Loads on the bodies, in particle order.
                                add_wall_loads(&part.slots[a], bodies_ref, part.loads);
                                w += 1;
                            }
                        }
                    });
                    *result = (ext, walls);
                });
        }
        let t_particles = self.profile.map(|_| std::time::Instant::now());
        if let (Some(pr), Some(t)) = (self.profile.as_mut(), t_pairs) {
            pr.pair_forces_s += t.elapsed().as_secs_f64();
        }
        // Shares of second partners from earlier blocks, the earliest first (or, with
        // `defer_shares`, by the caller, see [`SecondShares`]).
        if !defer_shares {
            let shares = SecondShares {
                lists: cross_out,
                chunk_block,
            };
            force
                .par_chunks_mut(PP_CHUNK)
                .zip(torque.par_chunks_mut(PP_CHUNK))
                .enumerate()
                .for_each(|(c, (f, t))| shares.add_to_chunk(c, f, t));
        }
        std::mem::swap(&mut self.particles.force, &mut force);
        std::mem::swap(&mut self.particles.torque, &mut torque);
        self.scratch_force = force;
        self.scratch_torque = torque;

        self.tock(t_particles, |p| &mut p.particle_forces_s);
        let t_loads = self.tick();
        self.sum_body_loads(nblocks);
        let inc = self.sum_increments();
        self.tock(t_loads, |p| &mut p.energies_s);
        inc
    }

    /// The loads on the rigid bodies: the sums of the first `nblocks` blocks of the pair pass
    /// (each in particle order), in block order.
    pub(crate) fn sum_body_loads(&mut self, nblocks: usize) {
        for (k, b) in self.bodies.iter_mut().enumerate() {
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

/// Marks the particles that may touch a wall before the next refresh: those that touch a wall
/// with their radius and interaction range both grown by `3 × skin`. A particle moves less than one skin
/// between neighbour-list rebuilds [D Eq. 2.11], so less than two skins since any refresh after
/// the last rebuild; the refresh is repeated at every rebuild and whenever a body has translated
/// by one skin since, rotated at all, or its deformable walls moved by one skin. Skipping the others therefore changes no result.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refresh_wall_candidates(
    p: &crate::particles::ParticleSet,
    interactions: &crate::interaction::InteractionTable,
    nl: &crate::neighbor::NeighborList,
    bodies: &[crate::body::RigidBody],
    body_step: &[BodyState],
    candidate: &mut Vec<bool>,
    reference: &mut Vec<(Vec3, crate::math::Rotation, usize, f64)>,
    ref_builds: &mut u64,
    enabled: bool,
    slots: &mut [Vec<WallSlot>],
    list: &mut Vec<u32>,
) -> bool {
    let n = p.len();
    let skin = nl.skin_m;
    let fresh = enabled
        && skin > 0.0
        && candidate.len() == n
        && *ref_builds == nl.builds
        && reference.len() == bodies.len()
        && bodies.iter().zip(reference.iter()).all(|(b, r)| {
            (b.state.position_m - r.0).norm() < skin
                && b.state.orientation == r.1
                && b.walls.len() == r.2
                && deformation_m(b) - r.3 < skin
        });
    if fresh {
        return false;
    }
    reference.clear();
    reference.extend(bodies.iter().map(|b| {
        (
            b.state.position_m,
            b.state.orientation,
            b.walls.len(),
            deformation_m(b),
        )
    }));
    *ref_builds = nl.builds;
    refresh_candidate_flags(p, interactions, nl, bodies, body_step, candidate, enabled);
    list.clear();
    list.extend((0..n as u32).filter(|&i| candidate[i as usize] || !slots[i as usize].is_empty()));
    // Room for the wall contacts of every candidate now, so that the steps until the next
    // refresh allocate nothing when a candidate reaches a wall for the first time.
    for &i in list.iter() {
        let s = &mut slots[i as usize];
        if s.capacity() == 0 {
            s.reserve(WALL_SLOTS_RESERVED);
        }
    }
    true
}

/// How far the deformable walls of body `b` have moved in all, m (a refresh of the wall
/// candidates is due when it has grown by a skin, like a body's translation).
fn deformation_m(b: &crate::body::RigidBody) -> f64 {
    b.walls.iter().map(|w| w.geometry.deformation_m()).sum()
}

/// Wall contacts a particle has room for once it is a wall candidate (more grow the buffer).
const WALL_SLOTS_RESERVED: usize = 2;

thread_local! {
    /// Contacts found by the candidate test of one particle (scratch of a rayon worker).
    static CANDIDATE_CONTACTS: std::cell::RefCell<Vec<WallContact>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The candidate flags of [`refresh_wall_candidates`].
fn refresh_candidate_flags(
    p: &crate::particles::ParticleSet,
    interactions: &crate::interaction::InteractionTable,
    nl: &crate::neighbor::NeighborList,
    bodies: &[crate::body::RigidBody],
    body_step: &[BodyState],
    candidate: &mut Vec<bool>,
    enabled: bool,
) {
    let (n, skin) = (p.len(), nl.skin_m);
    candidate.resize(n, true);
    if !enabled || skin <= 0.0 {
        candidate.iter_mut().for_each(|c| *c = true);
        return;
    }
    let margin = 3.0 * skin;
    candidate
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, cs)| {
            CANDIDATE_CONTACTS.with_borrow_mut(|contacts| {
                for (k, cand) in cs.iter_mut().enumerate() {
                    let i = c * CHUNK + k;
                    let (x, r) = (p.position[i], p.radius[i]);
                    *cand = bodies.iter().zip(body_step).any(|(body, bs)| {
                        let xb = bs.to_body(&x);
                        body.walls.iter().any(|wall| {
                            let (model, el_pair) = interactions.get(p.material[i], wall.material);
                            let props = PairProps {
                                e_eff_pa: el_pair.e_eff_pa,
                                g_eff_pa: el_pair.g_eff_pa,
                                poisson_mean: el_pair.poisson_mean,
                                r_eff_m: r,
                                m_eff_kg: p.mass[i],
                            };
                            let gap = model.max_interaction_gap_m(&props);
                            contacts.clear();
                            // Radius and range both grown by the margin: also conservative
                            // for geometries that ignore spheres behind a face (centre deeper
                            // than one radius).
                            wall.geometry
                                .sphere_contacts(&xb, r + margin, gap + margin, contacts);
                            !contacts.is_empty()
                        })
                    });
                }
            });
        });
}

/// The wall as a deformable mesh (a mesh whose vertices have velocities), if it is one.
#[inline(always)]
fn deforming_mesh(geometry: &crate::walls::Geometry) -> Option<&crate::walls::TriMesh> {
    match geometry {
        crate::walls::Geometry::Mesh(m) if !m.vertex_velocities().is_empty() => Some(m),
        _ => None,
    }
}

/// Velocity of a deformable mesh's surface at contact point `point_world` of `feature`, on top
/// of its body's rigid motion (world frame), m/s. Kept out of line: rigid walls never call it.
#[inline(never)]
#[cold]
fn deforming_surface_velocity(
    mesh: &crate::walls::TriMesh,
    bs: &BodyState,
    feature: u32,
    point_world: &Vec3,
) -> Vec3 {
    bs.vector_to_world(&mesh.surface_velocity(feature, &bs.to_body(point_world)))
}

/// Adds the loads that one particle's wall contacts `slots` put on the bodies to `loads` (one
/// entry per body: force, torque about the body's position).
#[inline]
pub(crate) fn add_wall_loads(
    slots: &[WallSlot],
    bodies: &[crate::body::RigidBody],
    loads: &mut [(Vec3, Vec3)],
) {
    for s in slots {
        let b = &bodies[s.body as usize];
        let l = &mut loads[s.body as usize];
        l.0 -= s.force;
        l.1 += (s.point - b.state.position_m).cross(&(-s.force)) - s.rolling_torque;
    }
}

/// Contacts of particle `i` with all walls: finds them, matches them to the previous slots
/// (same feature, or the same wall with a nearly parallel normal, so that history survives a
/// sphere sliding from a face onto an edge), evaluates the laws and accumulates force, torque
/// and energy.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn wall_contacts_of(
    (material, xr, kin): (u16, &[f64; 4], &Kin),
    interactions: &crate::interaction::InteractionTable,
    bodies: &[crate::body::RigidBody],
    body_step: &[BodyState],
    dt: f64,
    slots: &mut Vec<WallSlot>,
    contacts: &mut Vec<WallContact>,
    fresh: &mut Vec<WallSlot>,
    f_acc: &mut Vec3,
    t_acc: &mut Vec3,
    inc: &mut EnergyIncrements,
) {
    fresh.clear();
    let x = Vec3::new(xr[0], xr[1], xr[2]);
    let r = xr[3];
    let (mass, v, w) = (kin.m, Vec3::from(kin.v), Vec3::from(kin.w));
    for (bi, body) in bodies.iter().enumerate() {
        let bs = &body_step[bi];
        let xb = bs.to_body(&x);
        for (wi, wall) in body.walls.iter().enumerate() {
            let (model, el_pair) = interactions.get(material, wall.material);
            let props0 = PairProps {
                e_eff_pa: el_pair.e_eff_pa,
                g_eff_pa: el_pair.g_eff_pa,
                poisson_mean: el_pair.poisson_mean,
                r_eff_m: r,
                m_eff_kg: mass,
            };
            let gap = model.max_interaction_gap_m(&props0);
            contacts.clear();
            wall.geometry.sphere_contacts(&xb, r, gap, contacts);
            let deforming = deforming_mesh(&wall.geometry);
            for c in contacts.iter() {
                let normal = bs.vector_to_world(&c.normal);
                let point = bs.point_to_world(&c.point);
                // Inherit history: same feature first, then the closest normal on the same wall.
                let mut state = PairState::default();
                let mut prev_point = point;
                let mut best: Option<(usize, f64)> = None;
                for (k, s) in slots.iter().enumerate() {
                    if s.body as usize == bi && s.wall as usize == wi && s.state.active {
                        let score = if s.feature == c.feature {
                            2.0
                        } else {
                            s.normal.dot(&normal)
                        };
                        if score > 0.9 && best.is_none_or(|(_, b)| score > b) {
                            best = Some((k, score));
                        }
                    }
                }
                if let Some((k, _)) = best {
                    state = slots[k].state;
                    prev_point = slots[k].point;
                    slots[k].state.active = false; // consumed
                }
                fresh.push(WallSlot {
                    body: bi as u16,
                    wall: wi as u16,
                    feature: c.feature,
                    normal,
                    point,
                    force: Vec3::zeros(),
                    rolling_torque: Vec3::zeros(),
                    state,
                });
                let s = fresh.last_mut().unwrap();
                let props = PairProps {
                    r_eff_m: effective_radius(r, c.curvature_radius_m),
                    ..props0
                };
                let mut v_wall = bs.point_velocity(&point);
                if let Some(m) = deforming {
                    v_wall += deforming_surface_velocity(m, bs, c.feature, &point);
                }
                let rb = r - 0.5 * c.overlap_m.max(0.0);
                let v_p = v + w.cross(&(-rb * normal));
                let v_rel = v_p - v_wall;
                let w_rel = w - bs.angular_velocity_rad_s;
                let kin = ContactKinematics {
                    overlap_m: c.overlap_m,
                    overlap_rate_m_s: -normal.dot(&(v - v_wall)),
                    normal,
                    tangential_velocity_m_s: tangential_part(&v_rel, &normal),
                    relative_angular_velocity_rad_s: w_rel,
                    dt_s: dt,
                };
                let f = model.evaluate(&props, &kin, &mut s.state.history);
                let fn_vec = normal * f.normal_total_n();
                let ft = f.tangential_n;
                let f_total = fn_vec + ft;
                inc.wall_work_j += 0.5
                    * (s.state.normal_force_prev + s.state.tangential_force_prev + f_total)
                        .dot(&v_wall)
                    * dt
                    + 0.5
                        * (s.state.rolling_torque_prev + f.rolling_torque_nm)
                            .dot(&bs.angular_velocity_rad_s)
                        * dt;
                // The previous force acted at the previous contact point: on a rotating wall
                // its half of the trapezoid uses the wall velocity there (exactly zero change
                // for walls that only translate).
                let mut dv_wall = bs.point_velocity(&prev_point) - v_wall;
                if let Some(m) = deforming {
                    // the surface velocity at the previous point, interpolated in the
                    // current contact's feature
                    dv_wall += deforming_surface_velocity(m, bs, c.feature, &prev_point);
                }
                let (fn_prev, ft_prev) = (s.state.normal_force_prev, s.state.tangential_force_prev);
                inc.wall_work_j += 0.5 * (fn_prev + ft_prev).dot(&dv_wall) * dt;
                let (mut dn, mut dtan) =
                    account(&mut s.state, &f, fn_vec, ft, &v_rel, &w_rel, dt, true);
                dn += 0.5 * fn_prev.dot(&dv_wall) * dt;
                dtan += 0.5 * ft_prev.dot(&dv_wall) * dt;
                inc.dissipated_normal_pw_j += dn;
                inc.dissipated_tangential_pw_j += dtan;
                inc.elastic_j += f.normal_energy_j + f.tangential_energy_j;
                s.force = f_total;
                s.rolling_torque = f.rolling_torque_nm;
                *f_acc += f_total;
                *t_acc += (-rb * normal).cross(&ft) + f.rolling_torque_nm;
            }
        }
    }
    // Contacts that ended during this step: close their work integral (force falls to zero).
    for s in slots.iter_mut().filter(|s| s.state.active) {
        let bs = &body_step[s.body as usize];
        let mut v_wall = bs.point_velocity(&s.point);
        if let Some(m) = deforming_mesh(&bodies[s.body as usize].walls[s.wall as usize].geometry) {
            v_wall += deforming_surface_velocity(m, bs, s.feature, &s.point);
        }
        let rb = r;
        let v_rel = v + w.cross(&(-rb * s.normal)) - v_wall;
        let w_rel = w - bs.angular_velocity_rad_s;
        let f = ContactForce::default();
        inc.wall_work_j +=
            0.5 * (s.state.normal_force_prev + s.state.tangential_force_prev).dot(&v_wall) * dt
                + 0.5 * s.state.rolling_torque_prev.dot(&bs.angular_velocity_rad_s) * dt;
        let (dn, dtan) = account(
            &mut s.state,
            &f,
            Vec3::zeros(),
            Vec3::zeros(),
            &v_rel,
            &w_rel,
            dt,
            false,
        );
        inc.dissipated_normal_pw_j += dn;
        inc.dissipated_tangential_pw_j += dtan;
    }
    // Copied back rather than swapped: every particle keeps its own buffer (allocated once),
    // so the wall pass reads the same memory step after step.
    slots.clear();
    slots.extend_from_slice(fresh);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
    use crate::interaction::InteractionTable;
    use crate::material::Material;
    use crate::particles::ParticleSet;
    use rand::{RngExt, SeedableRng};

    /// One contact through the block kernel ([`HmBatch`] with the baseline kernel): the
    /// outputs of the first partner, dissipation and stored energy, like `evaluate_pair`.
    fn block_one(
        hm: &crate::interaction::HmConstants,
        radii: (f64, f64),
        kin: (&Kin, &Kin),
        d: Vec3,
        st: &mut PairState,
        dt: f64,
    ) -> (PairEval, f64, f64, f64) {
        let mut slab = vec![SlabState { state: *st }];
        let mut batch = HmBatch::default();
        batch.push(hm, (0, 1), radii, kin, d, st, 0);
        let (mut rf, mut rt) = (vec![Vec3::zeros(); 2], vec![Vec3::zeros(); 2]);
        let mut sums = (0.0, 0.0, 0.0);
        let kernel = crate::hm_block::Kernel::SCALAR;
        let mut acc = BlockAcc {
            lo: 0,
            hi: 2,
            force: &mut rf,
            torque: &mut rt,
            cross: &mut [],
        };
        batch.flush(kernel, dt, &mut slab, &mut acc, &mut sums);
        *st = slab[0].state;
        let eval = PairEval {
            force: rf[0],
            torque_first: rt[0],
            torque_second: rt[1],
        };
        assert_eq!(-rf[1], rf[0]);
        (eval, sums.0, sums.1, sums.2)
    }

    /// The block Hertz–Mindlin kernel gives the forces, torques, history, dissipation and
    /// stored energy of the general pipeline (kinematics + `ContactModel::evaluate` + ledger)
    /// within 1e-12 relative, over sequences of random sticking and sliding contacts, for
    /// unequal sizes and materials.
    #[test]
    fn block_hertz_mindlin_equals_general_pipeline() {
        let mats = vec![
            Material::new("steel", 7850.0, 2.1e11, 0.3),
            Material::new("glass", 2500.0, 6.3e10, 0.22),
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for (e, mu) in [(0.7, 0.3), (0.3, 0.05), (0.95, 1.0)] {
            let model = ContactModel {
                normal: NormalLaw::HertzMindlin {
                    restitution: e,
                    clip_attractive: false,
                },
                friction: FrictionLaw::Mindlin {
                    friction_coefficient: mu,
                },
                rolling: None,
                adhesion: None,
            };
            let table = InteractionTable::new(&mats, model);
            let mut p = ParticleSet::default();
            p.push(Vec3::zeros(), 1e-3, 7850.0, 0);
            p.push(Vec3::new(1.9e-3, 0.1e-3, -0.05e-3), 0.8e-3, 2500.0, 1);
            let hm = *table.hm_fast(0, 1).expect("fast path applies");
            let (mut s_fast, mut s_gen) = (PairState::default(), PairState::default());
            let dt = 1e-7;
            let scale = |a: f64, b: f64| a.abs().max(b.abs()).max(1e-30);
            for _ in 0..200 {
                // Random walk of the relative motion (overlap stays positive).
                for k in 0..2 {
                    p.velocity[k] = Vec3::new(
                        rng.random::<f64>() - 0.5,
                        rng.random::<f64>() - 0.5,
                        rng.random::<f64>() - 0.5,
                    ) * 0.4;
                    p.angular_velocity[k] = Vec3::new(
                        rng.random::<f64>() - 0.5,
                        rng.random::<f64>() - 0.5,
                        rng.random::<f64>() - 0.5,
                    ) * 300.0;
                }
                let jitter = Vec3::new(
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                ) * 2e-6;
                p.position[1] = Vec3::new(1.75e-3, 0.1e-3, -0.05e-3) + jitter;
                let d = p.position[0] - p.position[1];
                let dist = d.norm();
                assert!(dist < 1.8e-3);
                let (k0, k1) = (Kin::of(&p, 0), Kin::of(&p, 1));
                let radii = (p.radius[0], p.radius[1]);
                let (a, dn_a, dt_a, e_a) = block_one(&hm, radii, (&k0, &k1), d, &mut s_fast, dt);
                let (b, dn_b, dt_b, e_b) =
                    evaluate_pair(&p, &table, 0, 1, d, dist, true, &mut s_gen, dt);
                for (x, y) in [
                    (a.force, b.force),
                    (a.torque_first, b.torque_first),
                    (a.torque_second, b.torque_second),
                    (s_fast.history.spring_m, s_gen.history.spring_m),
                ] {
                    assert!(
                        (x - y).norm() <= 1e-12 * scale(x.norm(), y.norm()),
                        "{x} vs {y}"
                    );
                }
                for (x, y) in [(dn_a, dn_b), (dt_a, dt_b), (e_a, e_b)] {
                    assert!((x - y).abs() <= 1e-9 * scale(x, y) + 1e-24, "{x} vs {y}");
                }
                let (x, y) = (
                    s_fast.history.impact_velocity_m_s,
                    s_gen.history.impact_velocity_m_s,
                );
                assert!((x - y).abs() <= 1e-12 * scale(x, y), "{x} vs {y}");
            }
        }
    }
}
