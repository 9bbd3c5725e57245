//! Force evaluation: contact kinematics [D Eq. 2.12–2.27], contact laws, torques [D Eq. 2.86–2.89],
//! gravity, loads on rigid bodies, and the per-contact work that feeds the energy ledger.

use crate::body::BodyState;
use crate::contact::{ContactForce, ContactHistory, ContactKinematics, PairProps};
use crate::energy::EnergyIncrements;
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
    slab: Vec<PpContact>,
    free: Vec<u32>,
    /// Contacts that are not in the neighbour list (any more): closed by the next evaluation.
    orphans: Vec<PpContact>,
    sums: (f64, f64, f64),
}

impl PpChunk {
    fn alloc(&mut self, k: PpContact) -> u32 {
        match self.free.pop() {
            Some(s) => {
                self.slab[s as usize] = k;
                s
            }
            None => {
                self.slab.push(k);
                (self.slab.len() - 1) as u32
            }
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.slab.len() - self.free.len() + self.orphans.len()
    }
}

impl World {
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
                        out.push(chunk.slab[s as usize]);
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
const PREFETCH_AHEAD: usize = 6;

/// Hints the processor to load the cache line of `x` (no effect on other targets).
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint; it never faults, whatever the address.
    #[allow(unused_unsafe)]
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
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

/// [`evaluate_pair`] for a touching pair (`dist < r_i + r_j`) with LIGGGHTS' `hertz` +
/// `tangential history` law (no rolling resistance, no adhesion), fused into one pass: contact
/// kinematics [D Eq. 2.12–2.27], the law (the same operations as `hertz_mindlin_history`:
/// $k_n = \tfrac43\bar E a$, $S_n = 2\bar E a$, $k_t = 8\bar G a$, $a = \sqrt{\bar R\delta}$,
/// $\gamma = -2\sqrt{5/6}\,\beta\sqrt{S\bar M}$, spring $\xi$ projected on the tangent plane and
/// cut at $\mu|F_n|$), and the trapezoidal work of the ledger.
#[inline]
#[allow(clippy::too_many_arguments)]
fn hm_pair_fast(
    c: &crate::interaction::HmConstants,
    (ri, rj): (f64, f64),
    ki: &Kin,
    kj: &Kin,
    d: Vec3,
    dist: f64,
    st: &mut PairState,
    dt: f64,
) -> (PairEval, f64, f64, f64) {
    let delta = ri + rj - dist;
    let n = d * (1.0 / dist);
    let rb_i = ri - 0.5 * delta;
    let rb_j = rj - 0.5 * delta;
    let dv = Vec3::from(ki.v) - Vec3::from(kj.v);
    // v_rel = Δv + ω_i × (−r_b,i n) − ω_j × (r_b,j n) = Δv − (r_b,i ω_i + r_b,j ω_j) × n
    let v_rel = dv - (Vec3::from(ki.w) * rb_i + Vec3::from(kj.w) * rb_j).cross(&n);
    let rate = -n.dot(&dv);
    let h = &mut st.history;
    if h.impact_velocity_m_s == 0.0 {
        h.impact_velocity_m_s = rate.max(crate::contact::default_min_impact_velocity());
    }
    let (mi, mj) = (ki.m, kj.m);
    let r_eff = ri * rj / (ri + rj);
    let m_eff = mi * mj / (mi + mj);
    let a = (r_eff * delta).sqrt();
    let sn = 2.0 * c.e_eff_pa * a;
    let kn = 4.0 / 3.0 * c.e_eff_pa * a;
    let gamma_n = c.damping * (sn * m_eff).sqrt();
    let elastic = kn * delta;
    let mut dissipative = gamma_n * rate;
    if c.clip_attractive {
        dissipative = dissipative.max(-elastic);
    }
    let vt = v_rel - n * n.dot(&v_rel);
    let kt = 8.0 * c.g_eff_pa * a;
    let gamma_t = c.damping * (kt * m_eff).sqrt();
    let mut xi = h.spring_m + vt * dt;
    xi -= n * xi.dot(&n);
    let shear2 = xi.norm_squared();
    let ft_friction = c.mu * (elastic + dissipative).abs();
    let ft = if kt * kt * shear2 > ft_friction * ft_friction {
        let shear_len = shear2.sqrt();
        let f = -xi * (ft_friction / shear_len);
        xi = -f / kt;
        f
    } else {
        -kt * xi - gamma_t * vt
    };
    h.spring_m = xi;
    let fn_vec = n * (elastic + dissipative);
    let e_n = 0.4 * kn * delta * delta;
    let e_t = 0.5 * kt * xi.norm_squared();
    // Ledger (no rolling torque): trapezoidal work minus the change of stored energy.
    let w_n = -0.5 * (st.normal_force_prev + fn_vec).dot(&v_rel) * dt;
    let w_t = -0.5 * (st.tangential_force_prev + ft).dot(&v_rel) * dt;
    let d_n = w_n - (e_n - st.normal_energy_prev);
    let d_t = w_t - (e_t - st.tangential_energy_prev);
    st.normal_force_prev = fn_vec;
    st.tangential_force_prev = ft;
    st.normal_energy_prev = e_n;
    st.tangential_energy_prev = e_t;
    st.active = true;
    let cr = n.cross(&ft);
    (
        PairEval {
            force: fn_vec + ft,
            torque_first: -rb_i * cr,
            torque_second: -rb_j * cr,
        },
        d_n,
        d_t,
        e_n + e_t,
    )
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
        let t_pairs = self.tick();
        let World {
            particles: p,
            interactions,
            neighbors,
            pair_out,
            out_count,
            second_start,
            second_list,
            scratch_fill: fill,
            row_force,
            row_torque,
            pair_contact,
            pp_chunks,
            wall_slots,
            bodies,
            gravity_m_s2,
            wall_candidate,
            wall_ref,
            wall_ref_builds,
            wall_skip,
            scratch_xr: xr,
            scratch_kin: kin,
            ..
        } = self;
        let p = &*p;
        let interactions = &*interactions;
        let nl = &*neighbors;
        let n = p.len();

        // 1. Particle–particle contacts, in parallel over chunks of particles (rows of the half
        //    neighbour list). A pair without a contact that does not touch costs one
        //    squared-distance test on positions and radii; a contact keeps its slot in the
        //    chunk's slab (history updated in place); a contact that ended closes its work
        //    integral and frees its slot. The first partner's force and torque are summed here;
        //    the second partner's share goes to the chunk's output list (`pair_out`, written
        //    sequentially), which a counting sort by second partner then indexes for the gather
        //    (fixed order, the first partner ascending: thread-count independent).
        let nchunks = n.div_ceil(PP_CHUNK);
        let m = nl.num_pairs();
        if pp_chunks.len() != nchunks || pair_contact.len() != m {
            // Particle count changed without a rebuild: start from the orphans only.
            let mut all = Vec::new();
            for c in pp_chunks.iter() {
                all.extend(
                    c.slab
                        .iter()
                        .copied()
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
        // Every chunk writes the outputs of its contacts densely from the start of its pair range.
        pair_out.resize(m, SecondOutput::default());
        out_count.resize(nchunks, 0);
        row_force.resize(n, Vec3::zeros());
        row_torque.resize(n, Vec3::zeros());
        let reach = nl.extra_range_m;
        // Positions and radii packed together: one load per partner in the pair loop.
        // Velocities, masses and spins packed likewise: one cache line per contact partner.
        xr.resize(n, [0.0; 4]);
        kin.resize(n, Kin::default());
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
        let xr = &*xr;
        let kin = &*kin;
        let uniform = interactions.hm_uniform();
        {
            // Disjoint slices per chunk: pairs of its rows, and its particles.
            let mut pcs: Vec<(&mut [u32], &mut [SecondOutput])> = Vec::with_capacity(nchunks);
            let (mut rest_c, mut rest_o): (&mut [u32], &mut [SecondOutput]) =
                (pair_contact, pair_out);
            for c in 0..nchunks {
                let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
                let len = (nl.row_start[hi] - nl.row_start[lo]) as usize;
                let (a, b) = rest_c.split_at_mut(len);
                let (x, y) = rest_o.split_at_mut(len);
                pcs.push((a, x));
                rest_c = b;
                rest_o = y;
            }
            pp_chunks
                .par_iter_mut()
                .zip(pcs.into_par_iter())
                .zip(row_force.par_chunks_mut(PP_CHUNK))
                .zip(row_torque.par_chunks_mut(PP_CHUNK))
                .zip(out_count.par_iter_mut())
                .enumerate()
                .for_each(|(c, ((((chunk, (pc, po)), rf), rt), count))| {
                    let mut outs = 0usize;
                    let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
                    let (mut dn, mut dtan, mut el) = (0.0, 0.0, 0.0);
                    let q0 = nl.row_start[lo] as usize;
                    let second_c = &nl.second[q0..nl.row_start[hi] as usize];
                    for i in lo..hi {
                        let [xi0, xi1, xi2, ri0] = xr[i];
                        let ri = ri0 + reach;
                        let mat_i = p.material[i];
                        let (mut fi, mut ti) = (Vec3::zeros(), Vec3::zeros());
                        let row = nl.row_start[i] as usize..nl.row_start[i + 1] as usize;
                        let (a, b) = (row.start - q0, row.end - q0);
                        for qq in a..b {
                            // Look ahead: fetch the partner of a later pair (and its velocities
                            // and contact state if it is in contact) while this one computes.
                            if let Some(&jn) = second_c.get(qq + PREFETCH_AHEAD) {
                                prefetch(&xr[jn as usize]);
                                let sn = pc[qq + PREFETCH_AHEAD];
                                if sn != NO_CONTACT {
                                    prefetch(&kin[jn as usize]);
                                    if let Some(k) = chunk.slab.get(sn as usize) {
                                        prefetch(k);
                                    }
                                }
                            }
                            let j = second_c[qq] as usize;
                            let slot = pc[qq];
                            let slot_ref = &mut pc[qq];
                            let [xj0, xj1, xj2, rj] = xr[j];
                            let d = Vec3::new(xi0 - xj0, xi1 - xj1, xi2 - xj2);
                            let dist2 = d.norm_squared();
                            let cut = ri + rj;
                            if dist2 >= cut * cut && slot == NO_CONTACT {
                                continue;
                            }
                            let dist = dist2.sqrt();
                            if reach <= 0.0
                                && dist2 < cut * cut
                                && dist > 0.0
                                && let Some(hm) =
                                    uniform.or_else(|| interactions.hm_fast(mat_i, p.material[j]))
                            {
                                let s = if slot == NO_CONTACT {
                                    let s = chunk.alloc(PpContact {
                                        i: i as u32,
                                        j: j as u32,
                                        state: PairState::default(),
                                    });
                                    *slot_ref = s;
                                    s
                                } else {
                                    slot
                                };
                                let st = &mut chunk.slab[s as usize].state;
                                let (out, x, y, e) =
                                    hm_pair_fast(hm, (ri0, rj), &kin[i], &kin[j], d, dist, st, dt);
                                dn += x;
                                dtan += y;
                                el += e;
                                fi += out.force;
                                ti += out.torque_first;
                                po[outs] = SecondOutput {
                                    force: out.force,
                                    torque: out.torque_second,
                                    second: j as u32,
                                };
                                outs += 1;
                                continue;
                            }
                            let touching = interacts(p, interactions, reach, i, j, dist);
                            if !touching && slot == NO_CONTACT {
                                continue;
                            }
                            let s = if slot == NO_CONTACT {
                                chunk.alloc(PpContact {
                                    i: i as u32,
                                    j: j as u32,
                                    state: PairState::default(),
                                })
                            } else {
                                slot
                            };
                            let st = &mut chunk.slab[s as usize].state;
                            let (out, x, y, e) =
                                evaluate_pair(p, interactions, i, j, d, dist, touching, st, dt);
                            dn += x;
                            dtan += y;
                            el += e;
                            if touching {
                                *slot_ref = s;
                                fi += out.force;
                                ti += out.torque_first;
                                po[outs] = SecondOutput {
                                    force: out.force,
                                    torque: out.torque_second,
                                    second: j as u32,
                                };
                                outs += 1;
                            } else {
                                *slot_ref = NO_CONTACT;
                                chunk.free.push(s);
                            }
                        }
                        rf[i - lo] = fi;
                        rt[i - lo] = ti;
                    }
                    // Contacts that left the neighbour list: close their work integral.
                    for k in chunk.orphans.drain(..) {
                        let (i, j) = (k.i as usize, k.j as usize);
                        let d = p.position[i] - p.position[j];
                        let mut st = k.state;
                        let (_, x, y, _) =
                            evaluate_pair(p, interactions, i, j, d, d.norm(), false, &mut st, dt);
                        dn += x;
                        dtan += y;
                    }
                    chunk.sums = (dn, dtan, el);
                    *count = outs as u32;
                });
        }
        // Counting sort of the outputs by second partner. For one particle its entries follow
        // the chunks and, within a chunk, the pair loop: the first partner ascending (the order
        // of the transposed neighbour index), whatever the thread count.
        second_start.clear();
        second_start.resize(n + 1, 0);
        for (c, &cnt) in out_count.iter().enumerate() {
            let base = nl.row_start[(c * PP_CHUNK).min(n)] as usize;
            for o in &pair_out[base..base + cnt as usize] {
                second_start[o.second as usize + 1] += 1;
            }
        }
        for k in 0..n {
            second_start[k + 1] += second_start[k];
        }
        let total = second_start[n] as usize;
        second_list.resize(total, 0);
        fill.clear();
        fill.extend_from_slice(&second_start[..n]);
        for (c, &cnt) in out_count.iter().enumerate() {
            let base = nl.row_start[(c * PP_CHUNK).min(n)] as usize;
            for (k, o) in pair_out[base..base + cnt as usize].iter().enumerate() {
                let f = &mut fill[o.second as usize];
                second_list[*f as usize] = (base + k) as u32;
                *f += 1;
            }
        }
        let pp: Vec<(f64, f64, f64)> = pp_chunks.iter().map(|c| c.sums).collect();

        let t_particles = self.profile.map(|_| std::time::Instant::now());
        if let (Some(pr), Some(t)) = (self.profile.as_mut(), t_pairs) {
            pr.pair_forces_s += t.elapsed().as_secs_f64();
        }
        // 2. Per particle: gather pair forces, walls, gravity, external.
        let body_step: Vec<BodyState> = bodies.iter().map(|b| b.step_state(dt)).collect();
        refresh_wall_candidates(
            p,
            interactions,
            nl,
            bodies,
            &body_step,
            wall_candidate,
            wall_ref,
            wall_ref_builds,
            *wall_skip,
        );
        let wall_candidate = &*wall_candidate;
        let bodies_ref = &*bodies;
        let pair_out = &*pair_out;
        let second_start = &*second_start;
        let second_list = &*second_list;
        let rows_f = &*row_force;
        let rows_t = &*row_torque;
        let g = *gravity_m_s2;
        let mut force = std::mem::take(&mut self.scratch_force);
        let mut torque = std::mem::take(&mut self.scratch_torque);
        force.resize(n, Vec3::zeros());
        torque.resize(n, Vec3::zeros());
        let pw: Vec<EnergyIncrements> = force
            .par_chunks_mut(CHUNK)
            .zip(torque.par_chunks_mut(CHUNK))
            .zip(wall_slots.par_chunks_mut(CHUNK))
            .enumerate()
            .map_init(
                || {
                    (
                        Vec::<WallContact>::with_capacity(16),
                        Vec::<WallSlot>::with_capacity(16),
                    )
                },
                |(contacts, fresh), (c, ((fs, ts), slots))| {
                    let mut inc = EnergyIncrements::default();
                    for (k, ((f_out, t_out), slot_list)) in fs
                        .iter_mut()
                        .zip(ts.iter_mut())
                        .zip(slots.iter_mut())
                        .enumerate()
                    {
                        let i = c * CHUNK + k;
                        let mut f = g * p.mass[i] + p.external_force[i] + rows_f[i];
                        let mut t = rows_t[i];
                        inc.external_work_j += p.external_force[i].dot(&p.velocity[i]) * dt;
                        // Contacts where `i` is the second partner, in neighbour-list order.
                        let range = second_start[i] as usize..second_start[i + 1] as usize;
                        for &g in &second_list[range] {
                            let o = &pair_out[g as usize];
                            f -= o.force;
                            t += o.torque;
                        }
                        if !wall_candidate[i] && slot_list.is_empty() {
                            *f_out = f;
                            *t_out = t;
                            continue;
                        }
                        wall_contacts_of(
                            i,
                            p,
                            interactions,
                            bodies_ref,
                            &body_step,
                            dt,
                            slot_list,
                            contacts,
                            fresh,
                            &mut f,
                            &mut t,
                            &mut inc,
                        );
                        *f_out = f;
                        *t_out = t;
                    }
                    inc
                },
            )
            .collect();

        std::mem::swap(&mut self.particles.force, &mut force);
        std::mem::swap(&mut self.particles.torque, &mut torque);
        self.scratch_force = force;
        self.scratch_torque = torque;

        self.tock(t_particles, |p| &mut p.particle_forces_s);
        let t_loads = self.tick();
        // 3. Loads on rigid bodies, summed in particle order (deterministic).
        for b in self.bodies.iter_mut() {
            b.contact_force_n = Vec3::zeros();
            b.contact_torque_nm = Vec3::zeros();
        }
        for slots in &self.wall_slots {
            for s in slots {
                let b = &mut self.bodies[s.body as usize];
                b.contact_force_n -= s.force;
                b.contact_torque_nm +=
                    (s.point - b.state.position_m).cross(&(-s.force)) - s.rolling_torque;
            }
        }

        let mut inc = EnergyIncrements::default();
        for (dn, dtan, el) in pp {
            inc.dissipated_normal_pp_j += dn;
            inc.dissipated_tangential_pp_j += dtan;
            inc.elastic_j += el;
        }
        for w in pw {
            inc += w;
        }
        self.tock(t_loads, |p| &mut p.energies_s);
        inc
    }
}

/// Marks the particles that may touch a wall before the next refresh: those that touch a wall
/// with their radius and interaction range both grown by `3 × skin`. A particle moves less than one skin
/// between neighbour-list rebuilds [D Eq. 2.11], so less than two skins since any refresh after
/// the last rebuild; the refresh is repeated at every rebuild and whenever a body has translated
/// by one skin since, or rotated at all. Skipping the others therefore changes no result.
#[allow(clippy::too_many_arguments)]
fn refresh_wall_candidates(
    p: &crate::particles::ParticleSet,
    interactions: &crate::interaction::InteractionTable,
    nl: &crate::neighbor::NeighborList,
    bodies: &[crate::body::RigidBody],
    body_step: &[BodyState],
    candidate: &mut Vec<bool>,
    reference: &mut Vec<(Vec3, crate::math::Rotation, usize)>,
    ref_builds: &mut u64,
    enabled: bool,
) {
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
        });
    if fresh {
        return;
    }
    candidate.resize(n, true);
    reference.clear();
    reference.extend(
        bodies
            .iter()
            .map(|b| (b.state.position_m, b.state.orientation, b.walls.len())),
    );
    *ref_builds = nl.builds;
    if !enabled || skin <= 0.0 {
        candidate.iter_mut().for_each(|c| *c = true);
        return;
    }
    let margin = 3.0 * skin;
    candidate.par_chunks_mut(CHUNK).enumerate().for_each_init(
        || Vec::<WallContact>::with_capacity(16),
        |contacts, (c, cs)| {
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
        },
    );
}

/// Contacts of particle `i` with all walls: finds them, matches them to the previous slots
/// (same feature, or the same wall with a nearly parallel normal, so that history survives a
/// sphere sliding from a face onto an edge), evaluates the laws and accumulates force, torque
/// and energy.
#[allow(clippy::too_many_arguments)]
#[inline]
fn wall_contacts_of(
    i: usize,
    p: &crate::particles::ParticleSet,
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
    let x = p.position[i];
    let r = p.radius[i];
    for (bi, body) in bodies.iter().enumerate() {
        let bs = &body_step[bi];
        let xb = bs.to_body(&x);
        for (wi, wall) in body.walls.iter().enumerate() {
            let (model, el_pair) = interactions.get(p.material[i], wall.material);
            let props0 = PairProps {
                e_eff_pa: el_pair.e_eff_pa,
                g_eff_pa: el_pair.g_eff_pa,
                poisson_mean: el_pair.poisson_mean,
                r_eff_m: r,
                m_eff_kg: p.mass[i],
            };
            let gap = model.max_interaction_gap_m(&props0);
            contacts.clear();
            wall.geometry.sphere_contacts(&xb, r, gap, contacts);
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
                let v_wall = bs.point_velocity(&point);
                let rb = r - 0.5 * c.overlap_m.max(0.0);
                let v_p = p.velocity[i] + p.angular_velocity[i].cross(&(-rb * normal));
                let v_rel = v_p - v_wall;
                let w_rel = p.angular_velocity[i] - bs.angular_velocity_rad_s;
                let kin = ContactKinematics {
                    overlap_m: c.overlap_m,
                    overlap_rate_m_s: -normal.dot(&(p.velocity[i] - v_wall)),
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
                let dv_wall = bs.point_velocity(&prev_point) - v_wall;
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
        let v_wall = bs.point_velocity(&s.point);
        let rb = r;
        let v_rel = p.velocity[i] + p.angular_velocity[i].cross(&(-rb * s.normal)) - v_wall;
        let w_rel = p.angular_velocity[i] - bs.angular_velocity_rad_s;
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
    std::mem::swap(slots, fresh);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
    use crate::interaction::InteractionTable;
    use crate::material::Material;
    use crate::particles::ParticleSet;
    use rand::{RngExt, SeedableRng};

    /// The fused Hertz–Mindlin kernel gives the forces, torques, history, dissipation and
    /// stored energy of the general pipeline (kinematics + `ContactModel::evaluate` + ledger)
    /// within 1e-12 relative, over sequences of random sticking and sliding contacts, for
    /// unequal sizes and materials.
    #[test]
    fn fused_hertz_mindlin_equals_general_pipeline() {
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
                let (a, dn_a, dt_a, e_a) =
                    hm_pair_fast(&hm, radii, &k0, &k1, d, dist, &mut s_fast, dt);
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
