//! The particle state (structure of arrays) and the velocity-Verlet step of paper eq. 1:
//! $m\ddot{\mathbf r}_G = m\mathbf g + \sum(\mathbf f_{CN}+\mathbf f_{CT}+\mathbf f_{AN})$,
//! $I_G\dot{\boldsymbol\omega} = \sum \mathbf r_{CG}\times\mathbf f_{CT}$, $I_G = 0.4mr^2$.
//!
//! A step is split so that wall forces can be iterated by a partitioned coupling:
//! [`Powder::predict`] (half kick + drift), [`Powder::pair_forces`] (particle–particle forces at
//! the new positions with the half-step velocities), wall forces written by the caller into
//! `wall_force`/`wall_torque`, then [`Powder::finish`] (second half kick).
//! Pair forces are computed per pair in parallel and gathered per particle in a fixed order,
//! so results do not depend on the thread count.

use rayon::prelude::*;

use super::law::{self, PowderLaw};
use super::neighbor::NeighborList;

/// Energy bookkeeping of the particles \[J\].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PowderLedger {
    /// Dissipated in particle–particle contacts.
    pub dissipated_pp_j: f64,
    /// Dissipated in particle–wall contacts.
    pub dissipated_pw_j: f64,
}

/// Particles and their contacts.
///
/// Serializable for checkpoints: every field that carries state from one step to the next
/// (positions, velocities, spins, forces, accelerations, the pair list with its tangential
/// springs and reference positions, energies) is written; the per-pair scratch buffers are
/// skipped because [`Powder::pair_forces`] overwrites every entry before reading it.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct Powder {
    /// Contact law.
    pub law: PowderLaw,
    /// Gravity [m/s²].
    pub gravity: [f64; 3],
    /// Time step \[s\].
    pub dt: f64,
    /// Time \[s\].
    pub t: f64,
    /// Positions \[m\].
    pub pos: Vec<[f64; 3]>,
    /// Velocities [m/s] (half-step values between `predict` and `finish`).
    pub vel: Vec<[f64; 3]>,
    /// Angular velocities [rad/s].
    pub omega: Vec<[f64; 3]>,
    /// Radii \[m\].
    pub radius: Vec<f64>,
    /// Masses \[kg\].
    pub mass: Vec<f64>,
    /// Moments of inertia [kg m²].
    pub inertia: Vec<f64>,
    /// Particle–particle force + gravity of the current step \[N\].
    pub force: Vec<[f64; 3]>,
    /// Particle–particle torque [N m].
    pub torque: Vec<[f64; 3]>,
    /// Wall forces of the current step, written by the caller \[N\].
    pub wall_force: Vec<[f64; 3]>,
    /// Wall torques [N m].
    pub wall_torque: Vec<[f64; 3]>,
    /// Total acceleration of the last finished step [m/s²].
    pub acc: Vec<[f64; 3]>,
    /// Angular acceleration [rad/s²].
    pub alpha: Vec<[f64; 3]>,
    /// Pair list.
    pub nl: NeighborList,
    /// Elastic energy stored in particle–particle springs after the last force pass \[J\].
    pub elastic_pp_j: f64,
    /// Energy ledger.
    pub ledger: PowderLedger,
    /// Sliding pp contacts in the last force pass.
    pub sliding_pp: usize,
    /// Touching pp contacts in the last force pass.
    pub touching_pp: usize,
    #[serde(skip)]
    pf: Vec<[f64; 3]>,
    #[serde(skip)]
    ti: Vec<[f64; 3]>,
    #[serde(skip)]
    tj: Vec<[f64; 3]>,
    #[serde(skip)]
    e_el: Vec<f64>,
    #[serde(skip)]
    e_diss: Vec<f64>,
    #[serde(skip)]
    state: Vec<u8>,
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Powder {
    /// Particles at rest at `pos` with radii `radius` and density [kg/m³].
    ///
    /// # Panics
    /// If the lengths differ or a radius is not positive.
    #[track_caller]
    pub fn new(
        law: PowderLaw,
        pos: Vec<[f64; 3]>,
        radius: Vec<f64>,
        density_kg_m3: f64,
        gravity: [f64; 3],
        dt: f64,
    ) -> Self {
        assert_eq!(pos.len(), radius.len());
        assert!(radius.iter().all(|&r| r > 0.0), "radii must be positive");
        let n = pos.len();
        let mass: Vec<f64> = radius
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * density_kg_m3 * r.powi(3))
            .collect();
        let inertia = mass
            .iter()
            .zip(&radius)
            .map(|(m, r)| 0.4 * m * r * r)
            .collect();
        let rmin = radius.iter().fold(f64::INFINITY, |m, &r| m.min(r));
        let acc = vec![gravity; n];
        Self {
            law,
            gravity,
            dt,
            t: 0.0,
            pos,
            vel: vec![[0.0; 3]; n],
            omega: vec![[0.0; 3]; n],
            radius,
            mass,
            inertia,
            force: vec![[0.0; 3]; n],
            torque: vec![[0.0; 3]; n],
            wall_force: vec![[0.0; 3]; n],
            wall_torque: vec![[0.0; 3]; n],
            acc,
            alpha: vec![[0.0; 3]; n],
            nl: NeighborList::new(0.2 * rmin),
            elastic_pp_j: 0.0,
            ledger: PowderLedger::default(),
            sliding_pp: 0,
            touching_pp: 0,
            pf: Vec::new(),
            ti: Vec::new(),
            tj: Vec::new(),
            e_el: Vec::new(),
            e_diss: Vec::new(),
            state: Vec::new(),
        }
    }

    /// Checks that a deserialized state is self-consistent (array lengths, pair indices), so
    /// that a damaged checkpoint is refused with a message instead of a panic later.
    pub fn check_consistency(&self) -> Result<(), String> {
        let n = self.pos.len();
        for (k, len) in [
            ("vel", self.vel.len()),
            ("omega", self.omega.len()),
            ("radius", self.radius.len()),
            ("mass", self.mass.len()),
            ("inertia", self.inertia.len()),
            ("force", self.force.len()),
            ("torque", self.torque.len()),
            ("wall_force", self.wall_force.len()),
            ("wall_torque", self.wall_torque.len()),
            ("acc", self.acc.len()),
            ("alpha", self.alpha.len()),
        ] {
            if len != n {
                return Err(format!("powder state: {k} has {len} entries, expected {n}"));
            }
        }
        let pos_fin = |v: &[f64]| v.iter().all(|&x| x > 0.0 && x.is_finite());
        if !(pos_fin(&self.radius) && pos_fin(&self.mass) && pos_fin(&self.inertia)) {
            return Err(
                "powder state: radii, masses and inertias must be finite and positive".into(),
            );
        }
        if !(self.dt > 0.0 && self.dt.is_finite() && self.t.is_finite())
            || self.gravity.iter().any(|g| !g.is_finite())
            || !(self.nl.skin >= 0.0 && self.nl.skin.is_finite())
        {
            return Err("powder state: time step, time, gravity or skin not finite".into());
        }
        self.law.validate("powder state: law.")?;
        self.nl.check_consistency(n)
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// First half kick and drift: $\mathbf v_{n+1/2} = \mathbf v_n + \tfrac{\Delta t}{2}\mathbf a_n$,
    /// $\mathbf x_{n+1} = \mathbf x_n + \Delta t\,\mathbf v_{n+1/2}$.
    pub fn predict(&mut self) {
        let dt = self.dt;
        let h = 0.5 * dt;
        self.pos
            .par_iter_mut()
            .zip(self.vel.par_iter_mut())
            .zip(self.acc.par_iter())
            .with_min_len(1024)
            .for_each(|((x, v), a)| {
                for k in 0..3 {
                    v[k] += h * a[k];
                    x[k] += dt * v[k];
                }
            });
        self.omega
            .par_iter_mut()
            .zip(self.alpha.par_iter())
            .with_min_len(1024)
            .for_each(|(w, a)| {
                for k in 0..3 {
                    w[k] += h * a[k];
                }
            });
        self.t += dt;
    }

    /// Velocity of the surface point of particle `i` in direction `n` [m/s].
    #[inline]
    pub fn surface_velocity(&self, i: usize, n: [f64; 3]) -> [f64; 3] {
        let w = cross(
            self.omega[i],
            [
                self.radius[i] * n[0],
                self.radius[i] * n[1],
                self.radius[i] * n[2],
            ],
        );
        [
            self.vel[i][0] + w[0],
            self.vel[i][1] + w[1],
            self.vel[i][2] + w[2],
        ]
    }

    /// Particle–particle forces (paper eq. 2–7) and gravity at the current positions.
    pub fn pair_forces(&mut self) {
        let extra = self
            .law
            .adhesion_range(self.radius.iter().fold(0.0f64, |m, &r| m.max(r)));
        if self.nl.needs_rebuild(&self.pos) {
            self.nl.rebuild(&self.pos, &self.radius, extra);
        }
        let ne = self.nl.pj.len();
        self.pf.resize(ne, [0.0; 3]);
        self.ti.resize(ne, [0.0; 3]);
        self.tj.resize(ne, [0.0; 3]);
        self.e_el.resize(ne, 0.0);
        self.e_diss.resize(ne, 0.0);
        self.state.resize(ne, 0);
        let (pos, vel, omega, radius, mass) =
            (&self.pos, &self.vel, &self.omega, &self.radius, &self.mass);
        let law = self.law;
        let dt = self.dt;
        let (pi, pj) = (&self.nl.pi, &self.nl.pj);
        self.nl
            .gt
            .par_iter_mut()
            .zip(self.pf.par_iter_mut())
            .zip(self.ti.par_iter_mut())
            .zip(self.tj.par_iter_mut())
            .zip(self.e_el.par_iter_mut())
            .zip(self.e_diss.par_iter_mut())
            .zip(self.state.par_iter_mut())
            .enumerate()
            .with_min_len(512)
            .for_each(|(e, ((((((gt, pf), ti), tj), eel), ediss), st))| {
                let (i, j) = (pi[e] as usize, pj[e] as usize);
                let d = [
                    pos[j][0] - pos[i][0],
                    pos[j][1] - pos[i][1],
                    pos[j][2] - pos[i][2],
                ];
                let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let gap = dist - radius[i] - radius[j];
                if gap > 0.0 && law.surface_energy_j_m2 == 0.0 {
                    *gt = [0.0; 3];
                    *pf = [0.0; 3];
                    *ti = [0.0; 3];
                    *tj = [0.0; 3];
                    *eel = 0.0;
                    *ediss = 0.0;
                    *st = 0;
                    return;
                }
                let n = [d[0] / dist, d[1] / dist, d[2] / dist];
                let wi = cross(
                    omega[i],
                    [radius[i] * n[0], radius[i] * n[1], radius[i] * n[2]],
                );
                let wj = cross(
                    omega[j],
                    [-radius[j] * n[0], -radius[j] * n[1], -radius[j] * n[2]],
                );
                let vrel = [
                    vel[i][0] + wi[0] - vel[j][0] - wj[0],
                    vel[i][1] + wi[1] - vel[j][1] - wj[1],
                    vel[i][2] + wi[2] - vel[j][2] - wj[2],
                ];
                let r_eff = radius[i] * radius[j] / (radius[i] + radius[j]);
                let m_eff = mass[i] * mass[j] / (mass[i] + mass[j]);
                let r = law::evaluate(&law, n, gap, vrel, r_eff, m_eff, gt, dt);
                *pf = r.force;
                *ti = cross(
                    [radius[i] * n[0], radius[i] * n[1], radius[i] * n[2]],
                    r.force,
                );
                *tj = cross(
                    [radius[j] * n[0], radius[j] * n[1], radius[j] * n[2]],
                    r.force,
                );
                *eel = r.elastic_j;
                *ediss = r.dissipated_j;
                *st = if gap <= 0.0 { 1 + r.sliding as u8 } else { 0 };
            });
        let nl = &self.nl;
        let (pf, ti, tj) = (&self.pf, &self.ti, &self.tj);
        let g = self.gravity;
        self.force
            .par_iter_mut()
            .zip(self.torque.par_iter_mut())
            .enumerate()
            .with_min_len(512)
            .for_each(|(p, (f, t))| {
                let m = mass[p];
                let mut fs = [m * g[0], m * g[1], m * g[2]];
                let mut ts = [0.0; 3];
                for e in nl.start[p]..nl.start[p + 1] {
                    for k in 0..3 {
                        fs[k] += pf[e][k];
                        ts[k] += ti[e][k];
                    }
                }
                for &e in &nl.rev[nl.rev_start[p]..nl.rev_start[p + 1]] {
                    let e = e as usize;
                    for k in 0..3 {
                        fs[k] -= pf[e][k];
                        ts[k] += tj[e][k];
                    }
                }
                *f = fs;
                *t = ts;
            });
        // fixed-order sums (deterministic)
        self.elastic_pp_j = self.e_el.iter().sum();
        self.ledger.dissipated_pp_j += self.e_diss.iter().sum::<f64>();
        self.touching_pp = self.state.iter().filter(|&&s| s > 0).count();
        self.sliding_pp = self.state.iter().filter(|&&s| s == 2).count();
    }

    /// Second half kick with the total (pair + gravity + wall) forces.
    pub fn finish(&mut self) {
        let h = 0.5 * self.dt;
        let (force, torque, wf, wt, mass, inertia) = (
            &self.force,
            &self.torque,
            &self.wall_force,
            &self.wall_torque,
            &self.mass,
            &self.inertia,
        );
        self.vel
            .par_iter_mut()
            .zip(self.acc.par_iter_mut())
            .zip(self.omega.par_iter_mut())
            .zip(self.alpha.par_iter_mut())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(p, (((v, a), w), al))| {
                for k in 0..3 {
                    a[k] = (force[p][k] + wf[p][k]) / mass[p];
                    v[k] += h * a[k];
                    al[k] = (torque[p][k] + wt[p][k]) / inertia[p];
                    w[k] += h * al[k];
                }
            });
    }

    /// Translational + rotational kinetic energy \[J\].
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for p in 0..self.len() {
            let v = self.vel[p];
            let w = self.omega[p];
            e += 0.5 * self.mass[p] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                + 0.5 * self.inertia[p] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
        e
    }

    /// Gravitational potential energy $-\sum m\,\mathbf g\cdot\mathbf x$ \[J\].
    pub fn potential_energy(&self) -> f64 {
        let g = self.gravity;
        self.pos
            .iter()
            .zip(&self.mass)
            .map(|(x, m)| -m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]))
            .sum()
    }

    /// Total particle volume \[m³\].
    pub fn volume(&self) -> f64 {
        self.radius
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
            .sum()
    }

    /// Largest overlap relative to the diameter of the smaller particle, over touching pairs.
    pub fn max_relative_overlap(&self) -> f64 {
        let mut m = 0.0f64;
        for e in 0..self.nl.pj.len() {
            let (i, j) = (self.nl.pi[e] as usize, self.nl.pj[e] as usize);
            let d = ((0..3)
                .map(|k| (self.pos[j][k] - self.pos[i][k]).powi(2))
                .sum::<f64>())
            .sqrt();
            let gap = d - self.radius[i] - self.radius[j];
            if gap < 0.0 {
                m = m.max(-gap / (2.0 * self.radius[i].min(self.radius[j])));
            }
        }
        m
    }
}
