//! Time integration: velocity Verlet and Gear's fifth-order predictor–corrector with the
//! step-size controller of Meyer & Seifried [D Sect. 2.5, Eq. 2.95–2.106, Tab. 2.2/2.3].

use crate::energy::EnergyIncrements;
use crate::forces::{Kin, PpContact, SecondShares, WallSlot};
use crate::math::Vec3;
use crate::world::{ENERGY_BLOCK, World, particle_energy};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Parameters of the Gear predictor–corrector with step control; defaults are [D Tab. 2.3].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GearParams {
    /// Smallest step $\Delta t_{min}$, s.
    pub dt_min_s: f64,
    /// Largest step $\Delta t_{max}$, s; `None` = $\pi / \max \omega_{con}$ [D Tab. 2.3, Eq. 2.83],
    /// see [`World::gear_default_dt_max_s`].
    pub dt_max_s: Option<f64>,
    /// Absolute tolerance $\tau_{abs}$ on the acceleration correction, m/s².
    pub tolerance_abs: f64,
    /// Relative tolerance $\tau_{rel}$.
    pub tolerance_rel: f64,
    /// Maximum number of corrector steps $n^c_{max}$.
    pub max_corrections: u32,
    /// Safety factor $\kappa_s$ of the controller [D Eq. 2.105].
    pub safety_factor: f64,
}

impl Default for GearParams {
    fn default() -> Self {
        Self {
            dt_min_s: 1e-16,
            dt_max_s: None,
            tolerance_abs: 1e-6,
            tolerance_rel: 1e-6,
            max_corrections: 10,
            safety_factor: 0.9,
        }
    }
}

impl GearParams {
    /// Checks the controller settings against the initial step `dt_s` (errors start with the
    /// key, e.g. `safety_factor must …`): Δt_min ≤ Δt ≤ Δt_max, positive finite tolerances,
    /// 1 to 100 corrector steps and a safety factor κ_s in (0, 1] [D Eq. 2.105].
    pub fn validate(&self, dt_s: f64) -> Result<(), crate::ParameterError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.dt_min_s) || self.dt_min_s > dt_s {
            return Err(crate::ParameterError::invalid(
                "dt_min_s",
                format!(
                    "dt_min_s must be > 0 and at most the time step {dt_s:e} s, got {}; e.g. 1e-16",
                    self.dt_min_s
                ),
            ));
        }
        if let Some(m) = self.dt_max_s
            && (!pos(m) || m < dt_s)
        {
            return Err(crate::ParameterError::invalid(
                "dt_max_s",
                format!(
                    "dt_max_s must be finite and at least the time step {dt_s:e} s, got {m}; leave it out for π/ω_max [D Eq. 2.83]"
                ),
            ));
        }
        if !pos(self.tolerance_abs) {
            return Err(crate::ParameterError::invalid(
                "tolerance_abs",
                format!(
                    "tolerance_abs must be > 0 (m/s²), got {}; e.g. 1e-6",
                    self.tolerance_abs
                ),
            ));
        }
        if !(self.tolerance_rel.is_finite() && (0.0..1.0).contains(&self.tolerance_rel)) {
            return Err(crate::ParameterError::invalid(
                "tolerance_rel",
                format!(
                    "tolerance_rel must lie in [0, 1), got {}; e.g. 1e-6",
                    self.tolerance_rel
                ),
            ));
        }
        if !(1..=100).contains(&self.max_corrections) {
            return Err(crate::ParameterError::invalid(
                "max_corrections",
                format!(
                    "max_corrections must lie in 1..=100, got {}; e.g. 10",
                    self.max_corrections
                ),
            ));
        }
        if !(self.safety_factor.is_finite()
            && self.safety_factor > 0.0
            && self.safety_factor <= 1.0)
        {
            return Err(crate::ParameterError::invalid(
                "safety_factor",
                format!(
                    "safety_factor must lie in (0, 1], got {}; e.g. 0.9 [D Eq. 2.105]",
                    self.safety_factor
                ),
            ));
        }
        Ok(())
    }
}

/// Time integration scheme.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "scheme", rename_all = "kebab-case")]
pub enum Integrator {
    /// Velocity Verlet with a fixed step; forces at $t+\Delta t$ use the half-step velocities.
    VelocityVerlet,
    /// Gear predictor–corrector of order 5 with step control.
    Gear(GearParams),
}

/// Particles per task of the drift pass (a whole number of energy blocks).
const PASS_CHUNK: usize = 1024;
const _: () = assert!(PASS_CHUNK.is_multiple_of(ENERGY_BLOCK));

/// Energy blocks per task of the second half-kick, at least.
const KICK_TASK_CHUNKS: usize = 8;

/// Gear corrector coefficients for order p = 5 [D Tab. 2.2].
const GEAR5: [f64; 5] = [19.0 / 90.0, 3.0 / 4.0, 1.0, 1.0 / 2.0, 1.0 / 12.0];

/// Time derivatives kept by the Gear scheme for every particle: translation (x, ẋ, ẍ, x⃛, x⁗) and
/// rotation (θ, ω, ω̇, ω̈, ω⃛).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GearState {
    trans: Vec<[Vec3; 5]>,
    rot: Vec<[Vec3; 5]>,
    dt_max_s: f64,
    backup_pairs: Vec<PpContact>,
    backup_walls: Vec<Vec<WallSlot>>,
    pred_trans: Vec<[Vec3; 5]>,
    pred_rot: Vec<[Vec3; 5]>,
    /// Corrector steps used by the last accepted step.
    pub last_corrections: u32,
}

/// Half kick of one particle: $v \mathrel{+}= F\,h/m$, $\omega \mathrel{+}= T\,h/J$ (`h` = half the
/// step).
#[inline(always)]
fn half_kick(v: &mut Vec3, w: &mut Vec3, f: &Vec3, t: &Vec3, m: f64, inv_inertia: f64, h: f64) {
    *v += *f * (h / m);
    *w += *t * (h * inv_inertia);
}

/// Drift of one particle by `dt`, packed for the pair loop (`[x, y, z, r]`, [`Kin`]); returns
/// its squared displacement from `reference` (0 without one).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn drift_and_pack(
    x: &mut Vec3,
    v: &Vec3,
    w: &Vec3,
    m: f64,
    radius: f64,
    dt: f64,
    xr: &mut [f64; 4],
    kin: &mut Kin,
    reference: Option<&Vec3>,
) -> f64 {
    *x += *v * dt;
    *xr = [x.x, x.y, x.z, radius];
    *kin = Kin::new(v, m, w);
    reference.map_or(0.0, |r| (*x - *r).norm_squared())
}

impl World {
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
        self.scratch_xr.resize(n, [0.0; 4]);
        self.scratch_kin.resize(n, Kin::default());
        // The largest squared displacement since the last neighbour build is taken in the same
        // pass, per chunk: the list is sure to be valid while twice the largest displacement
        // stays below the skin (see `World::update_neighbors_given`).
        let reference = &self.neighbors.reference_position;
        let check = reference.len() == n && self.neighbors.builds > 0;
        let tops = &mut self.scratch_top;
        tops.clear();
        tops.resize(n.div_ceil(PASS_CHUNK), 0.0);
        if let Some(half_prev) = pending {
            // The pending second half kick of the last step first, particle by particle: the
            // shares of its second partners, the kick, the kinetic and potential energy of the
            // state it completes (in the blocks of `refresh_state_energies`), then this step's
            // half kick and drift.
            let g = self.gravity_m_s2;
            let sums = &mut self.scratch_energy;
            sums.clear();
            sums.resize(n.div_ceil(ENERGY_BLOCK), [0.0; 2]);
            let shares = SecondShares {
                lists: &self.cross_out,
                chunk_block: &self.chunk_block,
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
                .zip(self.scratch_xr.par_chunks_mut(PASS_CHUNK))
                .zip(self.scratch_kin.par_chunks_mut(PASS_CHUNK))
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
            self.ledger_energies_from_blocks();
        } else {
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
                .zip(self.scratch_xr.par_chunks_mut(PASS_CHUNK))
                .zip(self.scratch_kin.par_chunks_mut(PASS_CHUNK))
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
        let top = self.scratch_top.iter().fold(0.0f64, |a, &b| a.max(b));
        self.packed = true;
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
            lists: &self.cross_out,
            chunk_block: &self.chunk_block,
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
        gear.backup_walls.clone_from(&self.wall_slots);
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
                self.wall_slots.clone_from(&gear.backup_walls);
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
