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

/// Output of one pair evaluation: force on the first partner, torques on both.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairOutput {
    /// Force on the first partner (the second gets the opposite), N.
    pub force: Vec3,
    /// Torque on the first partner, N·m.
    pub torque_first: Vec3,
    /// Torque on the second partner, N·m.
    pub torque_second: Vec3,
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
/// last force evaluation: the partners `i < j` and the contact state. The world keeps these
/// sorted by `(i, j)` in one dense array, separate from the neighbour list, so that the contact
/// laws stream through contiguous memory and the history survives neighbour-list rebuilds.
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
/// particles, sorted by `(i, j)`, with the scratch of the pair loop (reused between steps).
#[derive(Debug, Clone, Default)]
pub(crate) struct PpChunk {
    pub(crate) contacts: Vec<PpContact>,
    next: Vec<PpContact>,
    outputs: Vec<PairOutput>,
    sums: (f64, f64, f64),
}

impl World {
    /// All active particle–particle contacts, sorted by `(i, j)`.
    pub(crate) fn pp_contacts(&self) -> impl Iterator<Item = &PpContact> {
        self.pp_chunks.iter().flat_map(|c| c.contacts.iter())
    }

    /// Replaces the active particle–particle contacts (sorted by `(i, j)`).
    pub(crate) fn set_pp_contacts(&mut self, contacts: &[PpContact]) {
        let n = self.particles.len();
        self.pp_chunks
            .resize_with(n.div_ceil(PP_CHUNK), PpChunk::default);
        for c in self.pp_chunks.iter_mut() {
            c.contacts.clear();
        }
        for k in contacts {
            self.pp_chunks[k.i as usize / PP_CHUNK].contacts.push(*k);
        }
    }
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
) -> (PairOutput, f64, f64, f64) {
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
    let out = PairOutput {
        force: fn_vec + ft,
        torque_first: (-rb_i * n).cross(&ft) + f.rolling_torque_nm,
        torque_second: (rb_j * n).cross(&(-ft)) - f.rolling_torque_nm,
    };
    (out, a, b, f.normal_energy_j + f.tangential_energy_j)
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
            contact_output,
            pair_contact,
            pp_chunks,
            wall_slots,
            bodies,
            gravity_m_s2,
            ..
        } = self;
        let p = &*p;
        let interactions = &*interactions;
        let nl = &*neighbors;
        let n = p.len();

        // 1. Particle–particle contacts, in parallel over chunks of particles (rows of the half
        //    neighbour list). Each chunk merges its rows with the previous contacts of its
        //    particles (both sorted by (i, j)): a pair that neither interacts now nor did before is
        //    skipped after a squared-distance test; a previous contact that no longer interacts
        //    closes its work integral. New contacts go to the chunk's scratch, in (i, j) order.
        let nchunks = n.div_ceil(PP_CHUNK);
        if pp_chunks.len() != nchunks {
            // Particle count changed: redistribute the contacts over the new chunks.
            let all: Vec<PpContact> = pp_chunks
                .iter()
                .flat_map(|c| c.contacts.iter().copied())
                .filter(|k| (k.j as usize) < n)
                .collect();
            pp_chunks.clear();
            pp_chunks.resize_with(nchunks, PpChunk::default);
            for k in all {
                pp_chunks[k.i as usize / PP_CHUNK].contacts.push(k);
            }
        }
        pair_contact.resize(nl.num_pairs(), NO_CONTACT);
        let reach = nl.extra_range_m;
        {
            // Disjoint slices of `pair_contact`, one per chunk.
            let mut slices: Vec<&mut [u32]> = Vec::with_capacity(nchunks);
            let mut rest: &mut [u32] = pair_contact;
            for c in 0..nchunks {
                let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
                let len = (nl.row_start[hi] - nl.row_start[lo]) as usize;
                let (a, b) = rest.split_at_mut(len);
                slices.push(a);
                rest = b;
            }
            pp_chunks
                .par_iter_mut()
                .zip(slices.into_par_iter())
                .enumerate()
                .for_each(|(c, (chunk, pc))| {
                    let (lo, hi) = (c * PP_CHUNK, ((c + 1) * PP_CHUNK).min(n));
                    let PpChunk {
                        contacts: old,
                        next,
                        outputs,
                        sums,
                    } = chunk;
                    next.clear();
                    outputs.clear();
                    let (mut dn, mut dtan, mut el) = (0.0, 0.0, 0.0);
                    let mut a = 0usize;
                    let q0 = nl.row_start[lo] as usize;
                    // Closes a previous contact that is not in the neighbour list any more.
                    let close = |k: &PpContact, dn: &mut f64, dtan: &mut f64| {
                        let (i, j) = (k.i as usize, k.j as usize);
                        let d = p.position[i] - p.position[j];
                        let mut st = k.state;
                        let (_, x, y, _) =
                            evaluate_pair(p, interactions, i, j, d, d.norm(), false, &mut st, dt);
                        *dn += x;
                        *dtan += y;
                    };
                    for i in lo..hi {
                        let xi = p.position[i];
                        let ri = p.radius[i] + reach;
                        for q in nl.row_start[i] as usize..nl.row_start[i + 1] as usize {
                            let j = nl.second[q] as usize;
                            while a < old.len()
                                && ((old[a].i as usize) < i
                                    || (old[a].i as usize == i && (old[a].j as usize) < j))
                            {
                                close(&old[a], &mut dn, &mut dtan);
                                a += 1;
                            }
                            let was =
                                a < old.len() && old[a].i as usize == i && old[a].j as usize == j;
                            let d = xi - p.position[j];
                            let dist2 = d.norm_squared();
                            let cut = ri + p.radius[j];
                            if dist2 >= cut * cut && !was {
                                pc[q - q0] = NO_CONTACT;
                                continue;
                            }
                            let dist = dist2.sqrt();
                            let touching = interacts(p, interactions, reach, i, j, dist);
                            if !touching && !was {
                                pc[q - q0] = NO_CONTACT;
                                continue;
                            }
                            let mut st = if was {
                                a += 1;
                                old[a - 1].state
                            } else {
                                PairState::default()
                            };
                            let (out, x, y, e) = evaluate_pair(
                                p,
                                interactions,
                                i,
                                j,
                                d,
                                dist,
                                touching,
                                &mut st,
                                dt,
                            );
                            dn += x;
                            dtan += y;
                            el += e;
                            if touching {
                                pc[q - q0] = next.len() as u32;
                                next.push(PpContact {
                                    i: i as u32,
                                    j: j as u32,
                                    state: st,
                                });
                                outputs.push(out);
                            } else {
                                pc[q - q0] = NO_CONTACT;
                            }
                        }
                    }
                    while a < old.len() {
                        close(&old[a], &mut dn, &mut dtan);
                        a += 1;
                    }
                    *sums = (dn, dtan, el);
                    std::mem::swap(old, next);
                });
        }
        // Gather the chunks into the dense contact arrays and make `pair_contact` global.
        let mut offsets = Vec::with_capacity(nchunks + 1);
        offsets.push(0usize);
        for ch in pp_chunks.iter() {
            offsets.push(offsets.last().unwrap() + ch.contacts.len());
        }
        contact_output.clear();
        for ch in pp_chunks.iter() {
            contact_output.extend_from_slice(&ch.outputs);
        }
        {
            let offs = &offsets;
            pair_contact
                .par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, pcs)| {
                    for (k, v) in pcs.iter_mut().enumerate() {
                        if *v != NO_CONTACT {
                            let q = c * CHUNK + k;
                            *v += offs[nl.first[q] as usize / PP_CHUNK] as u32;
                        }
                    }
                });
        }
        let pp: Vec<(f64, f64, f64)> = pp_chunks.iter().map(|c| c.sums).collect();

        let t_particles = self.profile.map(|_| std::time::Instant::now());
        if let (Some(pr), Some(t)) = (self.profile.as_mut(), t_pairs) {
            pr.pair_forces_s += t.elapsed().as_secs_f64();
        }
        // 2. Per particle: gather pair forces, walls, gravity, external.
        let body_step: Vec<BodyState> = bodies.iter().map(|b| b.step_state(dt)).collect();
        let bodies_ref = &*bodies;
        let outs = &*contact_output;
        let pair_contact = &*pair_contact;
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
                        let mut f = g * p.mass[i] + p.external_force[i];
                        let mut t = Vec3::zeros();
                        inc.external_work_j += p.external_force[i].dot(&p.velocity[i]) * dt;
                        // Forces of the active contacts, in neighbour-list order.
                        let row = nl.row_start[i] as usize..nl.row_start[i + 1] as usize;
                        for &k in &pair_contact[row] {
                            if k != NO_CONTACT {
                                let o = &outs[k as usize];
                                f += o.force;
                                t += o.torque_first;
                            }
                        }
                        for &q in
                            &nl.col_pairs[nl.col_start[i] as usize..nl.col_start[i + 1] as usize]
                        {
                            let k = pair_contact[q as usize];
                            if k != NO_CONTACT {
                                let o = &outs[k as usize];
                                f -= o.force;
                                t += o.torque_second;
                            }
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
                let (dn, dtan) = account(&mut s.state, &f, fn_vec, ft, &v_rel, &w_rel, dt, true);
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
