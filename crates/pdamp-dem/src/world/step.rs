//! The time step of a world: velocity Verlet (half kick, drift, forces, half kick) and Gear's
//! fifth-order predictor–corrector with step control [D Sect. 2.5, Eq. 2.95–2.106], and the force
//! evaluation that both call.

use super::{ENERGY_BLOCK, World, particle_energy};
use crate::energy::EnergyIncrements;
use crate::forces::{ForceInputs, Kin, SecondShares};
use crate::integrate::{GEAR5, GearParams, GearState, drift_and_pack, half_kick};
use crate::math::Vec3;
use rayon::prelude::*;

/// Particles per task of the drift pass (a whole number of energy blocks).
const PASS_CHUNK: usize = 1024;
const _: () = assert!(PASS_CHUNK.is_multiple_of(ENERGY_BLOCK));

/// Energy blocks per task of the second half-kick, at least.
const KICK_TASK_CHUNKS: usize = 8;

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
    /// half-kick of velocity Verlet does, one parallel loop less. The block pass, then the
    /// shares and the new forces swapped in, then the loads on the bodies and the energy
    /// increments summed in block order (see [`crate::forces::ForcePass`]).
    pub(crate) fn evaluate_forces_with(&mut self, dt: f64, defer_shares: bool) -> EnergyIncrements {
        let t_pairs = self.tick();
        let inputs = ForceInputs {
            particles: &self.particles,
            interactions: &self.interactions,
            neighbors: &self.neighbors,
            bodies: &self.bodies,
            gravity_m_s2: self.gravity_m_s2,
        };
        let nblocks = self.pass.run_blocks(&inputs, dt);
        let t_particles = self.profile.map(|_| std::time::Instant::now());
        if let (Some(pr), Some(t)) = (self.profile.as_mut(), t_pairs) {
            pr.pair_forces_s += t.elapsed().as_secs_f64();
        }
        self.pass.install_forces(&mut self.particles, defer_shares);
        self.tock(t_particles, |p| &mut p.particle_forces_s);
        let t_loads = self.tick();
        self.pass.sum_body_loads(&mut self.bodies, nblocks);
        let inc = self.pass.sum_increments();
        self.tock(t_loads, |p| &mut p.energies_s);
        inc
    }

    /// One velocity-Verlet step: half kick and drift, forces at the new positions, second half
    /// kick. With `defer_kick` the second half kick is left pending (see
    /// [`World::step_deferred`]); a pending half kick of the previous step is done here, in the
    /// same pass as this step's half kick and drift, with the same arithmetic (same bits).
    pub(crate) fn step_velocity_verlet(&mut self, defer_kick: bool) -> EnergyIncrements {
        let dt = self.dt_s;
        let t = self.tick();
        let half = 0.5 * dt;
        let n = self.particles.len();
        let pending = self.pending_half_kick_s.take();
        // Half kick and drift; the new positions and velocities are also packed for the pair
        // loop of the force evaluation (one pass over the particles less).
        self.pass.scratch_xr.resize(n, [0.0; 4]);
        self.pass.scratch_kin.resize(n, Kin::default());
        // The largest squared displacement since the last neighbour build is taken in the same
        // pass, per chunk: the list is sure to be valid while twice the largest displacement
        // stays below the skin (see `World::update_neighbors_given`).
        let check = self.neighbors.reference_position.len() == n && self.neighbors.builds > 0;
        self.scratch_top.clear();
        self.scratch_top.resize(n.div_ceil(PASS_CHUNK), 0.0);
        if let Some(half_prev) = pending {
            self.kick_pending_and_drift(half_prev, half, dt, check);
            self.ledger_energies_from_blocks();
        } else {
            self.kick_and_drift(half, dt, check);
        }
        let top = self.scratch_top.iter().fold(0.0f64, |a, &b| a.max(b));
        self.pass.packed = true;
        self.advance_bodies(dt);
        self.tock(t, |p| &mut p.integrate_s);
        self.update_neighbors_given(check.then_some(top));
        let inc = self.evaluate_forces_with(dt, true);
        self.counters.force_evaluations += 1;
        if defer_kick {
            self.pending_half_kick_s = Some(half);
        } else {
            let t = self.tick();
            self.second_half_kick(half);
            self.tock(t, |p| &mut p.integrate_s);
        }
        inc
    }

    /// The pending second half kick of the last step (`half_prev`), then this step's half kick
    /// (`half`) and drift by `dt`, particle by particle in one pass: the shares of the second
    /// partners, the kick, the kinetic and potential energy of the state it completes (in the
    /// blocks of `refresh_state_energies`, into `scratch_energy`), then the half kick and the
    /// drift, packed for the pair loop; the largest squared displacement per chunk goes to
    /// `scratch_top` (measured when `check`).
    fn kick_pending_and_drift(&mut self, half_prev: f64, half: f64, dt: f64, check: bool) {
        let n = self.particles.len();
        let reference = &self.neighbors.reference_position;
        let tops = &mut self.scratch_top;
        // The pending second half kick of the last step first, particle by particle: the
        // shares of its second partners, the kick, the kinetic and potential energy of the
        // state it completes (in the blocks of `refresh_state_energies`), then this step's
        // half kick and drift.
        let g = self.gravity_m_s2;
        let sums = &mut self.scratch_energy;
        sums.clear();
        sums.resize(n.div_ceil(ENERGY_BLOCK), [0.0; 2]);
        let shares = SecondShares {
            lists: &self.pass.cross_out,
            chunk_block: &self.pass.chunk_block,
        };
        let crate::particles::ParticleSet {
            position,
            velocity,
            angular_velocity,
            force,
            torque,
            radius,
            mass,
            inv_inertia,
            ..
        } = &mut self.particles;
        let (radius, mass, inv_inertia) = (&*radius, &*mass, &*inv_inertia);
        const BLOCKS: usize = PASS_CHUNK / ENERGY_BLOCK;
        position
            .par_chunks_mut(PASS_CHUNK)
            .zip(velocity.par_chunks_mut(PASS_CHUNK))
            .zip(angular_velocity.par_chunks_mut(PASS_CHUNK))
            .zip(force.par_chunks_mut(PASS_CHUNK))
            .zip(torque.par_chunks_mut(PASS_CHUNK))
            .zip(self.pass.scratch_xr.par_chunks_mut(PASS_CHUNK))
            .zip(self.pass.scratch_kin.par_chunks_mut(PASS_CHUNK))
            .zip(sums.par_chunks_mut(BLOCKS))
            .zip(tops.par_iter_mut())
            .enumerate()
            .for_each(
                |(c, ((((((((xs, vs), ws), fs), ts), xrs), ks), es), top))| {
                    let mut t = 0.0f64;
                    for (s, e) in es.iter_mut().enumerate() {
                        let b = c * BLOCKS + s;
                        let r = s * ENERGY_BLOCK..((s + 1) * ENERGY_BLOCK).min(xs.len());
                        let (fs, ts) = (&mut fs[r.clone()], &mut ts[r.clone()]);
                        shares.add_to_chunk(b, fs, ts);
                        let (mut kin, mut pot) = (0.0, 0.0);
                        for (k, ((((x, v), w), (f, tq)), (xr, kn))) in xs[r.clone()]
                            .iter_mut()
                            .zip(vs[r.clone()].iter_mut())
                            .zip(ws[r.clone()].iter_mut())
                            .zip(fs.iter().zip(ts.iter()))
                            .zip(xrs[r.clone()].iter_mut().zip(ks[r.clone()].iter_mut()))
                            .enumerate()
                        {
                            let i = b * ENERGY_BLOCK + k;
                            let (m, jinv) = (mass[i], inv_inertia[i]);
                            half_kick(v, w, f, tq, m, jinv, half_prev);
                            let (ek, ep) = particle_energy(m, jinv, v, w, x, &g);
                            kin += ek;
                            pot += ep;
                            half_kick(v, w, f, tq, m, jinv, half);
                            let d2 = drift_and_pack(
                                x,
                                v,
                                w,
                                m,
                                radius[i],
                                dt,
                                xr,
                                kn,
                                check.then(|| &reference[i]),
                            );
                            t = if d2 > t { d2 } else { t };
                        }
                        *e = [kin, pot];
                    }
                    *top = t;
                },
            );
    }

    /// This step's half kick (`half`) and drift by `dt` in one pass, packed for the pair loop;
    /// the largest squared displacement per chunk goes to `scratch_top` (measured when
    /// `check`).
    fn kick_and_drift(&mut self, half: f64, dt: f64, check: bool) {
        let reference = &self.neighbors.reference_position;
        let tops = &mut self.scratch_top;
        let crate::particles::ParticleSet {
            position,
            velocity,
            angular_velocity,
            force,
            torque,
            radius,
            mass,
            inv_inertia,
            ..
        } = &mut self.particles;
        let (force, torque, radius, mass, inv_inertia) =
            (&*force, &*torque, &*radius, &*mass, &*inv_inertia);
        position
            .par_chunks_mut(PASS_CHUNK)
            .zip(velocity.par_chunks_mut(PASS_CHUNK))
            .zip(angular_velocity.par_chunks_mut(PASS_CHUNK))
            .zip(self.pass.scratch_xr.par_chunks_mut(PASS_CHUNK))
            .zip(self.pass.scratch_kin.par_chunks_mut(PASS_CHUNK))
            .zip(tops.par_iter_mut())
            .enumerate()
            .for_each(|(c, (((((xs, vs), ws), xrs), ks), top))| {
                let mut t = 0.0f64;
                for (k, (((x, v), w), (xr, kin))) in xs
                    .iter_mut()
                    .zip(vs.iter_mut())
                    .zip(ws.iter_mut())
                    .zip(xrs.iter_mut().zip(ks.iter_mut()))
                    .enumerate()
                {
                    let i = c * PASS_CHUNK + k;
                    let m = mass[i];
                    half_kick(v, w, &force[i], &torque[i], m, inv_inertia[i], half);
                    let d2 = drift_and_pack(
                        x,
                        v,
                        w,
                        m,
                        radius[i],
                        dt,
                        xr,
                        kin,
                        check.then(|| &reference[i]),
                    );
                    t = if d2 > t { d2 } else { t };
                }
                *top = t;
            });
    }

    /// The second half kick of a velocity-Verlet step (`half` = half its time step), chunk by
    /// chunk after the chunk's shares from earlier blocks of the pair pass (left out by the
    /// force evaluation: one parallel loop less), with the kinetic and potential energy of the
    /// new state summed in the blocks of `refresh_state_energies` (the same numbers, one pass
    /// less again) and put into the ledger.
    pub(crate) fn second_half_kick(&mut self, half: f64) {
        let n = self.particles.len();
        let g = self.gravity_m_s2;
        let p = &mut self.particles;
        let sums = &mut self.scratch_energy;
        sums.clear();
        sums.resize(n.div_ceil(ENERGY_BLOCK), [0.0; 2]);
        let shares = SecondShares {
            lists: &self.pass.cross_out,
            chunk_block: &self.pass.chunk_block,
        };
        let (mass, inv_inertia, position) = (&p.mass, &p.inv_inertia, &p.position);
        p.velocity
            .par_chunks_mut(ENERGY_BLOCK)
            .zip(p.angular_velocity.par_chunks_mut(ENERGY_BLOCK))
            .zip(p.force.par_chunks_mut(ENERGY_BLOCK))
            .zip(p.torque.par_chunks_mut(ENERGY_BLOCK))
            .zip(sums.par_iter_mut())
            .enumerate()
            .with_min_len(KICK_TASK_CHUNKS)
            .for_each(|(b, ((((vs, ws), fs), ts), e))| {
                shares.add_to_chunk(b, fs, ts);
                let (mut kin, mut pot) = (0.0, 0.0);
                for (k, ((v, w), (f, t))) in vs
                    .iter_mut()
                    .zip(ws.iter_mut())
                    .zip(fs.iter().zip(ts.iter()))
                    .enumerate()
                {
                    let i = b * ENERGY_BLOCK + k;
                    half_kick(v, w, f, t, mass[i], inv_inertia[i], half);
                    let (k, u) = particle_energy(mass[i], inv_inertia[i], v, w, &position[i], &g);
                    kin += k;
                    pot += u;
                }
                *e = [kin, pot];
            });
        self.ledger_energies_from_blocks();
    }

    /// Moves prescribed bodies to `time + dt` and advances the clock.
    fn advance_bodies(&mut self, dt: f64) {
        let t1 = self.time_s + dt;
        for b in self.bodies.iter_mut() {
            b.previous = b.state;
            b.state = b.prescribed_state(t1);
        }
        self.time_s = t1;
    }

    pub(crate) fn step_gear(&mut self, params: &GearParams) -> EnergyIncrements {
        let n = self.particles.len();
        if self.gear.as_ref().is_none_or(|g| g.trans.len() != n) {
            let p = &self.particles;
            let mut g = GearState {
                trans: Vec::with_capacity(n),
                rot: Vec::with_capacity(n),
                ..Default::default()
            };
            for i in 0..n {
                let a = p.force[i] / p.mass[i];
                let al = p.torque[i] * p.inv_inertia[i];
                g.trans.push([
                    p.position[i],
                    p.velocity[i],
                    a,
                    Vec3::zeros(),
                    Vec3::zeros(),
                ]);
                g.rot.push([
                    Vec3::zeros(),
                    p.angular_velocity[i],
                    al,
                    Vec3::zeros(),
                    Vec3::zeros(),
                ]);
            }
            g.dt_max_s = params
                .dt_max_s
                .unwrap_or_else(|| self.gear_default_dt_max_s());
            self.gear = Some(g);
        }
        let mut gear = self.gear.take().unwrap();
        self.update_neighbors();
        gear.backup_pairs.clear();
        self.collect_pp_contacts(&mut gear.backup_pairs);
        gear.backup_walls.clone_from(&self.pass.wall_slots);
        let t0 = self.time_s;
        let body_backup: Vec<_> = self.bodies.iter().map(|b| (b.state, b.previous)).collect();
        let p_order = 5.0;
        loop {
            let dt = self.dt_s;
            // Predictor [D Eq. 2.95–2.99].
            let predict = |d: &[Vec3; 5]| -> [Vec3; 5] {
                let (h, h2, h3, h4) = (dt, dt * dt / 2.0, dt.powi(3) / 6.0, dt.powi(4) / 24.0);
                [
                    d[0] + d[1] * h + d[2] * h2 + d[3] * h3 + d[4] * h4,
                    d[1] + d[2] * h + d[3] * h2 + d[4] * h3,
                    d[2] + d[3] * h + d[4] * h2,
                    d[3] + d[4] * h,
                    d[4],
                ]
            };
            let mut tr = std::mem::take(&mut gear.pred_trans);
            let mut ro = std::mem::take(&mut gear.pred_rot);
            tr.resize(n, [Vec3::zeros(); 5]);
            ro.resize(n, [Vec3::zeros(); 5]);
            tr.par_iter_mut()
                .zip(gear.trans.par_iter())
                .for_each(|(t, d)| *t = predict(d));
            ro.par_iter_mut()
                .zip(gear.rot.par_iter())
                .for_each(|(t, d)| *t = predict(d));
            for (b, bk) in self.bodies.iter_mut().zip(&body_backup) {
                b.state = bk.0;
            }
            self.time_s = t0;
            self.advance_bodies(dt);
            let mut corrections = 0u32;
            let mut inc;
            let accepted = loop {
                corrections += 1;
                {
                    let p = &mut self.particles;
                    for i in 0..n {
                        p.position[i] = tr[i][0];
                        p.velocity[i] = tr[i][1];
                        p.angular_velocity[i] = ro[i][1];
                    }
                }
                self.set_pp_contacts(&gear.backup_pairs);
                self.pass.wall_slots.clone_from(&gear.backup_walls);
                self.include_wall_holders();
                inc = self.evaluate_forces(dt);
                self.counters.force_evaluations += 1;
                // Corrector [D Eq. 2.100–2.103].
                let p = &self.particles;
                let c = GEAR5;
                let k = [
                    c[0] * dt * dt / 2.0,
                    c[1] * dt / 2.0,
                    c[2],
                    c[3] * 3.0 / dt,
                    c[4] * 12.0 / (dt * dt),
                ];
                let err = tr
                    .par_iter_mut()
                    .zip(ro.par_iter_mut())
                    .enumerate()
                    .map(|(i, (t, r))| {
                        let a = p.force[i] / p.mass[i];
                        let al = p.torque[i] * p.inv_inertia[i];
                        let da = a - t[2];
                        let dal = al - r[2];
                        for l in 0..5 {
                            t[l] += da * k[l];
                            r[l] += dal * k[l];
                        }
                        let e1 =
                            da.norm() / (params.tolerance_abs + params.tolerance_rel * a.norm());
                        let e2 = dal.norm() * p.radius[i]
                            / (params.tolerance_abs
                                + params.tolerance_rel * al.norm() * p.radius[i]);
                        e1.max(e2)
                    })
                    .reduce(|| 0.0, f64::max);
                if err <= 1.0 {
                    break true;
                }
                if corrections >= params.max_corrections {
                    break false;
                }
            };
            if accepted || self.dt_s <= params.dt_min_s {
                let p = &mut self.particles;
                for i in 0..n {
                    p.position[i] = tr[i][0];
                    p.velocity[i] = tr[i][1];
                    p.angular_velocity[i] = ro[i][1];
                }
                // Accepted state becomes current; the old buffers are reused for the next prediction.
                gear.pred_trans = std::mem::replace(&mut gear.trans, tr);
                gear.pred_rot = std::mem::replace(&mut gear.rot, ro);
                gear.last_corrections = corrections;
                // Step-size controller [D Eq. 2.105/2.106].
                let f = params.safety_factor
                    * (params.max_corrections as f64 / (2.0 * corrections as f64))
                        .powf(1.0 / p_order);
                self.dt_s = (self.dt_s * f).clamp(params.dt_min_s, gear.dt_max_s);
                self.gear = Some(gear);
                return inc;
            }
            self.counters.rejected_steps += 1;
            gear.pred_trans = tr;
            gear.pred_rot = ro;
            let f = params.safety_factor * 0.5f64.powf(1.0 / p_order);
            self.dt_s = (self.dt_s * f).max(params.dt_min_s);
        }
    }
}
