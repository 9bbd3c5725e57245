//! The particle–particle pass over one chunk of the half neighbour list: the overlap test, the
//! contact law through the general pipeline [D Eq. 2.12–2.27] or the Hertz–Mindlin block kernel
//! (`hm_block`), and the contact's work for the energy ledger.

use super::blocks::BlockAcc;
use super::contacts::{PpChunk, PpContact, SlabState, slab_alloc};
use super::prefetch::{prefetch, prefetch_at};
use super::state::{Kin, NO_CONTACT, PairState, WallSlot, account};
use crate::contact::{ContactForce, ContactHistory, ContactKinematics, PairProps};
use crate::hm_block::{HmInput, HmOutput, HmState, LANES};
use crate::interaction::InteractionTable;
use crate::material::{effective_mass, effective_radius};
use crate::math::{Vec3, tangential_part};
use crate::particles::ParticleSet;
use crate::walls::WallContact;

/// Scratch of the pair loop, one per worker thread (kept between steps: no allocation once
/// grown, and it stays in that core's cache).
#[derive(Debug, Default)]
pub(crate) struct PairScratch {
    /// The pairs of a chunk that touch or had a contact (index within the chunk's pair range)
    /// and their first partners.
    pub(super) scan_pair: Vec<u32>,
    pub(super) scan_first: Vec<u32>,
    /// Hertz–Mindlin contacts gathered for block evaluation.
    pub(super) batch: HmBatch,
    /// Wall contacts found for one particle, and its new wall slots.
    pub(crate) wall_contacts: Vec<WallContact>,
    pub(crate) wall_fresh: Vec<WallSlot>,
}

thread_local! {
    pub(crate) static PAIR_SCRATCH: std::cell::RefCell<PairScratch> =
        std::cell::RefCell::new(PairScratch::default());
}

/// How many pairs ahead the pair loop prefetches partner data.
pub(super) const PREFETCH_AHEAD: usize = 8;

/// Hertz–Mindlin contacts gathered before a block evaluation (a multiple of [`LANES`]; the
/// gathered lanes stay in the L1 cache until the kernel and the hand-out read them).
pub(super) const BATCH_FLUSH: usize = 2 * LANES;

/// Evaluates the contact of the pair (`i`, `j`) at distance vector `d = x_i − x_j`: the law if the
/// partners interact (`touching`), or the closing of the work integral of a contact that ended.
/// Returns the output, the dissipated normal and tangential energy and the stored energy.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(super) fn evaluate_pair(
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
pub(super) struct PairRows<'a> {
    /// First partners `lo..hi`.
    pub(super) lo: usize,
    pub(super) hi: usize,
    /// Index of the chunk's first pair in the list.
    pub(super) q0: usize,
    pub(super) row_start: &'a [u32],
    pub(super) second: &'a [u32],
}

/// What the pair loop reads, shared by all chunks.
pub(super) struct PairContext<'a> {
    pub(super) p: &'a crate::particles::ParticleSet,
    pub(super) interactions: &'a crate::interaction::InteractionTable,
    /// Positions and radii `[x, y, z, r]`.
    pub(super) xr: &'a [[f64; 4]],
    /// Velocities, masses and spins.
    pub(super) kin: &'a [Kin],
    /// Adhesion range added to the contact distance, m.
    pub(super) reach: f64,
    /// Hertz–Mindlin constants shared by every pair, if they are.
    pub(super) uniform: Option<&'a crate::interaction::HmConstants>,
    pub(super) dt: f64,
    pub(super) kernel: crate::hm_block::Kernel,
}

/// Hertz–Mindlin contacts collected for evaluation in blocks (see [`crate::hm_block`]):
/// [`BATCH_FLUSH`] contacts are gathered first, then evaluated block by block, then handed out,
/// so that the kernel reads lanes written a while before (no stalled store-to-load forwarding),
/// the gather loop keeps many independent loads in flight, and the lanes stay in the L1 cache.
/// Scratch of a chunk; grows, never shrinks.
#[derive(Debug, Clone, Default)]
pub(crate) struct HmBatch {
    pub(super) inp: Vec<HmInput>,
    pub(super) st: Vec<HmState>,
    pub(super) out: Vec<HmOutput>,
    /// First partner, second partner and slab slot of each contact.
    pub(super) lane: Vec<(u32, u32, u32)>,
    pub(super) len: usize,
}

impl HmBatch {
    /// Adds the touching pair (`i`, `j`) at distance vector `d`, its contact in `slot`.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push(
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
    pub(super) fn flush(
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
pub(super) fn copy_lane(b: &mut HmInput, s: &mut HmState, from: usize, to: usize) {
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
    pub(super) fn chunk_pairs(
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
        let (hi, q0) = (rows.hi, rows.q0);
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
        let na = scan_pairs(rows, second_c, xr, reach, pc, scan_pair, scan_first);
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
        close_orphans(p, interactions, orphans, dt, &mut sum);
        *sums = sum;
    }
}

/// The scan of the pair pass: tests every pair of the rows for contact (squared distance
/// against the sum of the radii plus the adhesion range `reach`) without branching and keeps
/// the pairs that touch or had a contact (`scan_pair`: index into `second_c`, `scan_first`:
/// first partner); returns how many.
#[inline(always)]
fn scan_pairs(
    rows: &PairRows,
    second_c: &[u32],
    xr: &[[f64; 4]],
    reach: f64,
    pc: &[u32],
    scan_pair: &mut Vec<u32>,
    scan_first: &mut Vec<u32>,
) -> usize {
    let (lo, hi, q0) = (rows.lo, rows.hi, rows.q0);
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
    na
}

/// Closes the work integral of the contacts that left the neighbour list (`orphans`, emptied):
/// their force falls to zero; the dissipated work goes to `sum`.
fn close_orphans(
    p: &ParticleSet,
    interactions: &InteractionTable,
    orphans: &mut Vec<PpContact>,
    dt: f64,
    sum: &mut (f64, f64, f64),
) {
    for k in orphans.drain(..) {
        let (i, j) = (k.i as usize, k.j as usize);
        let d = p.position[i] - p.position[j];
        let mut st = k.state;
        let (_, x, y, _) = evaluate_pair(p, interactions, i, j, d, d.norm(), false, &mut st, dt);
        sum.0 += x;
        sum.1 += y;
    }
}

/// Forces and torques of one pair evaluation.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairEval {
    pub(super) force: Vec3,
    pub(super) torque_first: Vec3,
    pub(super) torque_second: Vec3,
}

/// True if the pair interacts: overlap, or a gap within the law's adhesion range.
#[inline]
pub(super) fn interacts(
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
