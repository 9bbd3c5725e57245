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

impl World {
    /// Evaluates all forces and torques at the current state. `dt` is the step that led to this
    /// state (0 for the initial evaluation): it integrates history variables and contact work.
    /// Returns the energy increments of this evaluation.
    pub(crate) fn evaluate_forces(&mut self, dt: f64) -> EnergyIncrements {
        let World {
            particles: p,
            interactions,
            neighbors,
            pair_state,
            pair_output,
            wall_slots,
            bodies,
            gravity_m_s2,
            ..
        } = self;
        let p = &*p;
        let interactions = &*interactions;
        let nl = &*neighbors;

        // 1. Particle–particle pairs, in parallel over fixed chunks.
        pair_output.resize(nl.num_pairs(), PairOutput::default());
        let pp: Vec<(f64, f64, f64)> = pair_state
            .par_chunks_mut(CHUNK)
            .zip(pair_output.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (states, outs))| {
                let (mut dn, mut dtan, mut el) = (0.0, 0.0, 0.0);
                for (k, (st, out)) in states.iter_mut().zip(outs.iter_mut()).enumerate() {
                    let pidx = c * CHUNK + k;
                    let i = nl.first[pidx] as usize;
                    let j = nl.second[pidx] as usize;
                    let d = p.position[i] - p.position[j];
                    let dist = d.norm();
                    let overlap = p.radius[i] + p.radius[j] - dist;
                    let (model, el_pair) = interactions.get(p.material[i], p.material[j]);
                    let props = PairProps {
                        e_eff_pa: el_pair.e_eff_pa,
                        g_eff_pa: el_pair.g_eff_pa,
                        poisson_mean: el_pair.poisson_mean,
                        r_eff_m: effective_radius(p.radius[i], p.radius[j]),
                        m_eff_kg: effective_mass(p.mass[i], p.mass[j]),
                    };
                    let gap = model.max_interaction_gap_m(&props);
                    let touching = overlap > -gap && dist > 0.0;
                    if !touching && !st.active {
                        *out = PairOutput::default();
                        continue;
                    }
                    let n = if dist > 0.0 { d / dist } else { Vec3::z() };
                    let rb_i = p.radius[i] - 0.5 * overlap.max(0.0);
                    let rb_j = p.radius[j] - 0.5 * overlap.max(0.0);
                    let v_rel = p.velocity[i] - p.velocity[j]
                        + p.angular_velocity[i].cross(&(-rb_i * n))
                        - p.angular_velocity[j].cross(&(rb_j * n));
                    let w_rel = p.angular_velocity[i] - p.angular_velocity[j];
                    let f = if touching {
                        let kin = ContactKinematics {
                            overlap_m: overlap,
                            overlap_rate_m_s: -n.dot(&(p.velocity[i] - p.velocity[j])),
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
                    dn += a;
                    dtan += b;
                    el += f.normal_energy_j + f.tangential_energy_j;
                    *out = PairOutput {
                        force: fn_vec + ft,
                        torque_first: (-rb_i * n).cross(&ft) + f.rolling_torque_nm,
                        torque_second: (rb_j * n).cross(&(-ft)) - f.rolling_torque_nm,
                    };
                }
                (dn, dtan, el)
            })
            .collect();

        // 2. Per particle: gather pair forces, walls, gravity, external.
        let body_step: Vec<BodyState> = bodies.iter().map(|b| b.step_state(dt)).collect();
        let bodies_ref = &*bodies;
        let outs = &*pair_output;
        let g = *gravity_m_s2;
        let n = p.len();
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
                        for q in nl.row_start[i]..nl.row_start[i + 1] {
                            let o = &outs[q as usize];
                            f += o.force;
                            t += o.torque_first;
                        }
                        for &q in
                            &nl.col_pairs[nl.col_start[i] as usize..nl.col_start[i + 1] as usize]
                        {
                            let o = &outs[q as usize];
                            f -= o.force;
                            t += o.torque_second;
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

        self.particles.force.copy_from_slice(&force);
        self.particles.torque.copy_from_slice(&torque);
        self.scratch_force = force;
        self.scratch_torque = torque;

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
