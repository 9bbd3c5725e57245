//! The particle–wall pass: which particles may touch a wall before the next refresh, their
//! wall contacts with history kept per slot [D Eq. 2.17–2.33], and the loads on the bodies.

use super::state::{CHUNK, Kin, PairState, WallSlot, account};
use crate::body::BodyState;
use crate::contact::{ContactForce, ContactKinematics, PairProps};
use crate::energy::EnergyIncrements;
use crate::material::effective_radius;
use crate::math::{Vec3, tangential_part};
use crate::walls::WallContact;
use rayon::prelude::*;

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
pub(super) fn deformation_m(b: &crate::body::RigidBody) -> f64 {
    b.walls.iter().map(|w| w.geometry.deformation_m()).sum()
}

/// Wall contacts a particle has room for once it is a wall candidate (more grow the buffer).
pub(super) const WALL_SLOTS_RESERVED: usize = 2;

thread_local! {
    /// Contacts found by the candidate test of one particle (scratch of a rayon worker).
    pub(super) static CANDIDATE_CONTACTS: std::cell::RefCell<Vec<WallContact>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The candidate flags of [`refresh_wall_candidates`].
pub(super) fn refresh_candidate_flags(
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
pub(super) fn deforming_mesh(geometry: &crate::walls::Geometry) -> Option<&crate::walls::TriMesh> {
    match geometry {
        crate::walls::Geometry::Mesh(m) if !m.vertex_velocities().is_empty() => Some(m),
        _ => None,
    }
}

/// Velocity of a deformable mesh's surface at contact point `point_world` of `feature`, on top
/// of its body's rigid motion (world frame), m/s. Kept out of line: rigid walls never call it.
#[inline(never)]
#[cold]
pub(super) fn deforming_surface_velocity(
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
                let (state, prev_point) =
                    inherit_wall_history(slots, (bi, wi), c.feature, &normal, point);
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
    close_ended_wall_contacts(slots, bodies, body_step, (r, &v, &w), dt, inc);
    // Copied back rather than swapped: every particle keeps its own buffer (allocated once),
    // so the wall pass reads the same memory step after step.
    slots.clear();
    slots.extend_from_slice(fresh);
}

/// The history a new wall contact inherits from the contacts of the last evaluation on the
/// same wall (`(body, wall)`): that of the same feature first, otherwise that of the closest
/// normal (cosine above 0.9), which is consumed; with the previous contact point (`point` for
/// a fresh contact).
#[inline]
fn inherit_wall_history(
    slots: &mut [WallSlot],
    (bi, wi): (usize, usize),
    feature: u32,
    normal: &Vec3,
    point: Vec3,
) -> (PairState, Vec3) {
    let mut state = PairState::default();
    let mut prev_point = point;
    let mut best: Option<(usize, f64)> = None;
    for (k, s) in slots.iter().enumerate() {
        if s.body as usize == bi && s.wall as usize == wi && s.state.active {
            let score = if s.feature == feature {
                2.0
            } else {
                s.normal.dot(normal)
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
    (state, prev_point)
}

/// Contacts of the particle (radius `r`, velocity `v`, spin `w`) that ended during this step:
/// their work integral is closed (the force falls to zero).
fn close_ended_wall_contacts(
    slots: &mut [WallSlot],
    bodies: &[crate::body::RigidBody],
    body_step: &[BodyState],
    (r, v, w): (f64, &Vec3, &Vec3),
    dt: f64,
    inc: &mut EnergyIncrements,
) {
    let (v, w) = (*v, *w);
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
}
