//! Explicit axisymmetric dynamic FE of a sphere hitting a wall [D Sect. 4.2.2].
//!
//! - Geometry and mesh: [`crate::mesh`] (sphere on a clamped cylinder of radius R_w = R and height
//!   H = 2R by default, as in D Fig. 4.5; refined contact zone, sizes scaled with the expected
//!   contact radius). An identical sphere as partner is modelled through symmetry: a sphere on a
//!   rigid frictionless plane hit at half the relative velocity.
//! - Elements: 4-node bilinear axisymmetric quads, 2×2 Gauss points, B-bar (mean dilatation,
//!   Hughes 1980) against volumetric locking; small-strain kinematics.
//! - Time integration: central differences with lumped (row-sum) mass; stable step from the
//!   smallest element ($\Delta t = s\,\min_e L_e/c_p$, $L_e$ = area / longest diagonal) and the
//!   contact penalty.
//! - Contact: frictionless node-to-segment penalty between the sphere surface nodes and the
//!   wall's top face: pressure $p = \varepsilon_N g$ on the node's tributary annulus area,
//!   $\varepsilon_N = \alpha\bar E/h_c$.
//! - Restitution: mass-averaged axial velocity of the sphere (its momentum / mass) after
//!   separation, over the impact velocity [D Eq. 3.5] — exact for a free vibrating body, so the
//!   "mean of the last time steps" of D L1775 is not needed.
//! - End: the contact force has been zero for 10 % of the contact duration and the sphere moves
//!   away [D L1777].

use std::time::Instant;

use crate::constitutive::Kernel;
use crate::hertz::{HertzPair, effective_modulus, sphere_mass};
use crate::material::{Material, MaterialModel};
use crate::mesh::{self, Mesh, MeshDensity, MeshParams};
use crate::viscoelastic::prony_complex_modulus;

mod setup;

use self::setup::{
    build_bodies, contact_slaves, element_geometry, element_time_step, penalty_time_step,
};

/// Impact partner.
#[derive(Debug, Clone, PartialEq)]
pub enum Partner {
    /// A clamped wall (cylinder) of this material.
    Wall(Material),
    /// An identical sphere (same material), head-on; modelled by symmetry.
    Sphere,
}

/// Options of the FE impact model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeOptions {
    /// Mesh size ratios.
    pub mesh: MeshParams,
    /// Wall cylinder radius / sphere radius (D: 1).
    pub wall_radius_over_radius: f64,
    /// Wall cylinder height / sphere radius (D: 2).
    pub wall_height_over_radius: f64,
    /// Penalty factor α in $\varepsilon_N = \alpha\bar E/h_c$.
    pub penalty_factor: f64,
    /// Safety factor on the stable time step.
    pub dt_safety: f64,
    /// Abort after this multiple of the Hertz contact time [D Eq. 4.8].
    pub max_time_over_contact_time: f64,
    /// Number of force-history samples per Hertz contact time.
    pub history_samples: usize,
}

impl Default for FeOptions {
    fn default() -> Self {
        Self::with_density(MeshDensity::Medium)
    }
}

impl FeOptions {
    /// Default options with a mesh preset.
    pub fn with_density(d: MeshDensity) -> Self {
        Self {
            mesh: d.params(),
            wall_radius_over_radius: 1.0,
            wall_height_over_radius: 2.0,
            penalty_factor: 4.0,
            dt_safety: 0.8,
            max_time_over_contact_time: 8.0,
            history_samples: 400,
        }
    }
}

/// Where the initial kinetic energy went, J.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergySplit {
    /// Initial energy (kinetic + stored at the start), J.
    pub initial_j: f64,
    /// Rigid-body kinetic energy of the sphere after the impact, ½Mv², J.
    pub sphere_rigid_kinetic_j: f64,
    /// Vibration of the sphere (kinetic minus rigid-body part, plus stored elastic energy), J.
    pub sphere_vibration_j: f64,
    /// Kinetic energy left in the wall (elastic waves), J.
    pub wall_kinetic_j: f64,
    /// Stored (recoverable + residual) strain energy of the wall, J.
    pub wall_stored_j: f64,
    /// Plastic dissipation in the sphere, J.
    pub plastic_sphere_j: f64,
    /// Plastic dissipation in the wall, J.
    pub plastic_wall_j: f64,
    /// Viscoelastic dissipation in the sphere, J.
    pub viscous_sphere_j: f64,
    /// Viscoelastic dissipation in the wall, J.
    pub viscous_wall_j: f64,
    /// Energy in the contact penalty springs, J.
    pub contact_j: f64,
    /// initial − (all of the above), J.
    pub balance_error_j: f64,
}

/// Result of one FE impact.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactResult {
    /// Impact velocity (relative), m/s.
    pub velocity_m_s: f64,
    /// Coefficient of restitution [D Eq. 3.5].
    pub restitution: f64,
    /// Contact duration (first to last instant with contact force), s.
    pub contact_time_s: f64,
    /// Maximum contact force, N.
    pub max_force_n: f64,
    /// Maximum approach of the sphere's centre of mass to the wall, m.
    pub max_overlap_m: f64,
    /// Force history `(t_s, force_n)`.
    pub force_history: Vec<(f64, f64)>,
    /// Energy split at the end.
    pub energy: EnergySplit,
    /// Whether separation was reached before the time limit.
    pub completed: bool,
    /// Elements.
    pub elements: usize,
    /// Nodes.
    pub nodes: usize,
    /// Element size in the contact zone, m.
    pub h_contact_m: f64,
    /// Time step, s.
    pub dt_s: f64,
    /// Time steps.
    pub steps: usize,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
    /// Numerical failure found by the health check (non-finite state, energy created), with
    /// the time, the node and the likely cause; `None` for a healthy run.
    pub failure: Option<String>,
}

/// Relative energy-balance error of an FE impact beyond which the run is reported as failed
/// (healthy runs close to below 1 %).
pub const MAX_BALANCE_ERROR: f64 = 0.05;

/// Geometry of one Gauss point: dN/dr, dN/dz, N/r (4 each) and weight 2πr·detJ.
#[derive(Debug, Clone, Copy)]
struct Gp {
    dndr: [f64; 4],
    dndz: [f64; 4],
    nr: [f64; 4],
    w: f64,
}

/// A body (sphere or wall) with one material.
struct Body {
    elems: std::ops::Range<usize>,
    kernel: Kernel,
    state: Vec<f64>,
    n_state: usize,
    plastic: bool,
    dissipated: f64,
}

/// Effective Hertz pair for mesh sizing and the penalty: moduli of Prony materials are taken at
/// the impact time scale (storage modulus at ω = π/t_c, fixed point).
pub fn effective_pair(
    sphere: &Material,
    partner: &Partner,
    radius: f64,
    v: f64,
) -> (HertzPair, f64) {
    let m = sphere_mass(radius, sphere.density_kg_m3);
    let (e2, nu2, m_eff, r_eff, v_eff) = match partner {
        Partner::Wall(w) => (w, w.poisson_ratio, m, radius, v),
        Partner::Sphere => (sphere, sphere.poisson_ratio, m, radius, 0.5 * v),
    };
    let rigid_partner = matches!(partner, Partner::Sphere);
    let modulus = |mat: &Material, tc: f64| -> f64 {
        match &mat.model {
            MaterialModel::ViscoelasticProny { prony, .. } => {
                let omega = std::f64::consts::PI / tc;
                let (gs, _) =
                    prony_complex_modulus(mat.instantaneous_shear_modulus(), prony, omega);
                2.0 * gs * (1.0 + mat.poisson_ratio)
            }
            _ => mat.youngs_modulus_pa,
        }
    };
    let mut pair = HertzPair {
        e_eff: 0.0,
        r_eff,
        m_eff,
    };
    let mut tc = 1e-4;
    for _ in 0..60 {
        let e1 = modulus(sphere, tc);
        let e2v = if rigid_partner {
            f64::INFINITY
        } else {
            modulus(e2, tc)
        };
        let e1_eff = e1; // on the symmetry plane only the sphere's own compliance counts
        pair.e_eff = effective_modulus(e1_eff, sphere.poisson_ratio, e2v, nu2);
        tc = pair.contact_time(v_eff);
    }
    (pair, v_eff)
}

/// A prepared FE impact model (mesh, materials, state). Repeated calls of [`FeImpact::run`] hit
/// the same spot with the material state (plastic strain, residual stress) carried over.
pub struct FeImpact {
    mesh: Mesh,
    gps: Vec<Gp>,
    bvbar: Vec<[f64; 8]>,
    inv_m: Vec<f64>,
    mass: Vec<f64>,
    ur: Vec<f64>,
    uz: Vec<f64>,
    vr: Vec<f64>,
    vz: Vec<f64>,
    fr: Vec<f64>,
    fz: Vec<f64>,
    sig: Vec<[f64; 4]>,
    bodies: Vec<Body>,
    slaves: Vec<u32>,
    slave_area: Vec<f64>,
    slave_seg: Vec<usize>,
    penalty: f64,
    dt: f64,
    rigid_plane: bool,
    sphere_mass: f64,
    hertz: HertzPair,
    opts: FeOptions,
}

impl FeImpact {
    /// Builds the model for a sphere of `radius` (m) of `sphere` against `partner`; `v_ref` (m/s)
    /// sets the expected contact radius used for the refinement.
    pub fn new(
        sphere: &Material,
        partner: &Partner,
        radius: f64,
        v_ref: f64,
        opts: &FeOptions,
    ) -> Self {
        let (hertz, v_eff) = effective_pair(sphere, partner, radius, v_ref);
        let a_ref = hertz.max_contact_radius(v_eff);
        let rigid_plane = matches!(partner, Partner::Sphere);
        let mesh = mesh::build(
            radius,
            !rigid_plane,
            opts.wall_radius_over_radius * radius,
            opts.wall_height_over_radius * radius,
            a_ref,
            &opts.mesh,
        );
        let n = mesh.r.len();
        let wall_mat = match partner {
            Partner::Wall(w) => w.clone(),
            Partner::Sphere => sphere.clone(),
        };
        // ---- geometry at the Gauss points, lumped mass ----
        let geo = element_geometry(&mesh, sphere, &wall_mat);
        let mass = geo.mass;
        let inv_m: Vec<f64> = (0..n).map(|i| 1.0 / mass[i]).collect();
        let sphere_mass: f64 = mesh.sphere_nodes.clone().map(|i| mass[i]).sum();
        // ---- contact slaves: sphere surface nodes in the lower third ----
        let (slaves, slave_area) = contact_slaves(&mesh, radius);
        let penalty = opts.penalty_factor * hertz.e_eff / mesh.h_contact;
        // ---- stable time step (elements, Prony algorithmic moduli, penalty) ----
        let wall = (!rigid_plane).then_some(&wall_mat);
        let wall_surface = (!rigid_plane).then_some(&mesh.wall_surface[..]);
        let mut dt = 1e-3;
        for _ in 0..30 {
            let dte = element_time_step(sphere, wall, geo.lmin_sphere, geo.lmin_wall, dt);
            let dtp = penalty_time_step(&slaves, &slave_area, penalty, &inv_m, wall_surface);
            let new = opts.dt_safety / (1.0 / (dte * dte) + 1.0 / (dtp * dtp)).sqrt();
            if (new - dt).abs() < 1e-6 * dt {
                dt = new;
                break;
            }
            dt = new;
        }
        // ---- bodies ----
        let bodies = build_bodies(&mesh, sphere, wall, dt);
        let nslaves = slaves.len();
        let ngp = geo.gps.len();
        Self {
            gps: geo.gps,
            bvbar: geo.bvbar,
            inv_m,
            mass,
            ur: vec![0.0; n],
            uz: vec![0.0; n],
            vr: vec![0.0; n],
            vz: vec![0.0; n],
            fr: vec![0.0; n],
            fz: vec![0.0; n],
            sig: vec![[0.0; 4]; ngp],
            bodies,
            slaves,
            slave_area,
            slave_seg: vec![0; nslaves],
            penalty,
            dt,
            rigid_plane,
            sphere_mass,
            hertz,
            opts: *opts,
            mesh,
        }
    }

    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.mesh.elems.len()
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Internal forces of all bodies into `fr`, `fz` for the velocity field (increment dt·v);
    /// updates stresses and dissipation.
    fn internal_forces(&mut self) {
        self.fr.iter_mut().for_each(|f| *f = 0.0);
        self.fz.iter_mut().for_each(|f| *f = 0.0);
        let dt = self.dt;
        for body in &mut self.bodies {
            let ns = body.n_state;
            let mut diss = 0.0;
            for e in body.elems.clone() {
                let q = self.mesh.elems[e];
                let mut dur = [0.0; 4];
                let mut duz = [0.0; 4];
                for a in 0..4 {
                    dur[a] = dt * self.vr[q[a] as usize];
                    duz[a] = dt * self.vz[q[a] as usize];
                }
                let bv = &self.bvbar[e];
                let mut dth = 0.0;
                for a in 0..4 {
                    dth += bv[2 * a] * dur[a] + bv[2 * a + 1] * duz[a];
                }
                let mut fe_r = [0.0; 4];
                let mut fe_z = [0.0; 4];
                for g in 0..4 {
                    let gi = 4 * e + g;
                    let gp = &self.gps[gi];
                    let mut de = [0.0; 4];
                    for a in 0..4 {
                        de[0] += gp.dndr[a] * dur[a];
                        de[1] += gp.dndz[a] * duz[a];
                        de[2] += gp.nr[a] * dur[a];
                        de[3] += 0.5 * (gp.dndz[a] * dur[a] + gp.dndr[a] * duz[a]);
                    }
                    let corr = (dth - (de[0] + de[1] + de[2])) / 3.0;
                    de[0] += corr;
                    de[1] += corr;
                    de[2] += corr;
                    let local = gi - 4 * body.elems.start;
                    let st = &mut body.state[local * ns..(local + 1) * ns];
                    let s = &mut self.sig[gi];
                    diss += gp.w * body.kernel.update(&de, s, st);
                    let p = (s[0] + s[1] + s[2]) / 3.0;
                    let w = gp.w;
                    for a in 0..4 {
                        fe_r[a] += w
                            * (gp.dndr[a] * s[0]
                                + gp.nr[a] * s[2]
                                + gp.dndz[a] * s[3]
                                + (bv[2 * a] - gp.dndr[a] - gp.nr[a]) * p);
                        fe_z[a] += w
                            * (gp.dndz[a] * s[1]
                                + gp.dndr[a] * s[3]
                                + (bv[2 * a + 1] - gp.dndz[a]) * p);
                    }
                }
                for a in 0..4 {
                    self.fr[q[a] as usize] -= fe_r[a];
                    self.fz[q[a] as usize] -= fe_z[a];
                }
            }
            body.dissipated += diss;
        }
    }

    /// Contact forces (added to `fr`, `fz`); returns (axial force on the sphere, penalty energy).
    fn contact_forces(&mut self) -> (f64, f64) {
        let mut ftot = 0.0;
        let mut epen = 0.0;
        let ws = &self.mesh.wall_surface;
        for (k, &s) in self.slaves.iter().enumerate() {
            let s = s as usize;
            let xs = self.mesh.r[s] + self.ur[s];
            let zs = self.mesh.z[s] + self.uz[s];
            let (g, nr, nz, seg) = if self.rigid_plane {
                (zs, 0.0, 1.0, None)
            } else {
                let xm = |j: usize| {
                    let m = ws[j] as usize;
                    (self.mesh.r[m] + self.ur[m], self.mesh.z[m] + self.uz[m])
                };
                let mut j = self.slave_seg[k];
                while j + 1 < ws.len() && xs >= xm(j + 1).0 {
                    j += 1;
                }
                while j > 0 && xs < xm(j).0 {
                    j -= 1;
                }
                self.slave_seg[k] = j;
                if j + 1 >= ws.len() {
                    continue;
                }
                let (ar, az) = xm(j);
                let (br, bz) = xm(j + 1);
                let (tr, tz) = (br - ar, bz - az);
                let l2 = tr * tr + tz * tz;
                let l = l2.sqrt();
                let (nr, nz) = (-tz / l, tr / l);
                let xi = ((xs - ar) * tr + (zs - az) * tz) / l2;
                ((xs - ar) * nr + (zs - az) * nz, nr, nz, Some((j, xi)))
            };
            if g >= 0.0 {
                continue;
            }
            let f = -self.penalty * g * self.slave_area[k];
            epen += 0.5 * self.penalty * g * g * self.slave_area[k];
            self.fr[s] += f * nr;
            self.fz[s] += f * nz;
            ftot += f * nz;
            if let Some((j, xi)) = seg {
                let (a, b) = (ws[j] as usize, ws[j + 1] as usize);
                self.fr[a] -= (1.0 - xi) * f * nr;
                self.fz[a] -= (1.0 - xi) * f * nz;
                self.fr[b] -= xi * f * nr;
                self.fz[b] -= xi * f * nz;
            }
        }
        (ftot, epen)
    }

    fn kinetic(&self, ar: &[f64], az: &[f64], nodes: std::ops::Range<usize>) -> (f64, f64) {
        // full-step velocity v^{n+1} = v^{n+1/2} + dt/2 a^{n+1}; returns (kinetic energy, momentum z)
        let mut ke = 0.0;
        let mut pz = 0.0;
        for i in nodes {
            let vr = self.vr[i] + 0.5 * self.dt * ar[i];
            let vz = self.vz[i] + 0.5 * self.dt * az[i];
            ke += 0.5 * self.mass[i] * (vr * vr + vz * vz);
            pz += self.mass[i] * vz;
        }
        (ke, pz)
    }

    fn stored(&self, b: usize) -> f64 {
        let body = &self.bodies[b];
        let ns = body.n_state;
        let mut e = 0.0;
        for (l, gi) in (4 * body.elems.start..4 * body.elems.end).enumerate() {
            e += self.gps[gi].w
                * body
                    .kernel
                    .stored_energy(&self.sig[gi], &body.state[l * ns..(l + 1) * ns]);
        }
        e
    }

    /// Hits the wall with relative impact velocity `v` (m/s) and runs to separation.
    pub fn run(&mut self, v: f64) -> ImpactResult {
        let start = Instant::now();
        let n = self.mesh.r.len();
        let v_s = if self.rigid_plane { 0.5 * v } else { v };
        let (mut ar, mut az, e0) = self.launch(v_s);
        let tr = self.integrate(v_s, &mut ar, &mut az);
        let mut failure = tr.failure;
        let dt = self.dt;
        // ---- results ----
        let (en, v_cm) = self.energy_split(e0, &ar, &az);
        if failure.is_none() && en.balance_error_j.abs() > MAX_BALANCE_ERROR * e0.abs() {
            failure = Some(balance_failure(&en, e0, dt));
        }
        ImpactResult {
            failure,
            velocity_m_s: v,
            restitution: v_cm / v_s,
            contact_time_s: if tr.t_first.is_nan() {
                0.0
            } else {
                tr.t_last - tr.t_first + dt
            },
            max_force_n: tr.fmax,
            max_overlap_m: tr.dmax,
            force_history: tr.history,
            energy: en,
            completed: tr.completed,
            elements: self.mesh.elems.len(),
            nodes: n,
            h_contact_m: self.mesh.h_contact,
            dt_s: dt,
            steps: tr.step,
            wall_time_s: start.elapsed().as_secs_f64(),
        }
    }

    /// Places the sphere just touching (rigid shift so that the lowest gap is zero), gives it
    /// the axial velocity `-v_s` and the accelerations of the current (possibly residually
    /// stressed) state; returns the accelerations (a_r, a_z) and the initial energy.
    fn launch(&mut self, v_s: f64) -> (Vec<f64>, Vec<f64>, f64) {
        let n = self.mesh.r.len();
        // place the sphere just touching: rigid shift so the lowest gap is zero
        let mut gmin = f64::INFINITY;
        for &s in &self.slaves {
            let s = s as usize;
            gmin = gmin.min(self.mesh.z[s] + self.uz[s]);
        }
        if gmin.is_finite() && gmin != 0.0 {
            // wall top is (close to) z = 0 near the axis; residual indentation is accounted by
            // the contact search itself
            for i in self.mesh.sphere_nodes.clone() {
                self.uz[i] -= gmin;
            }
        }
        for i in 0..n {
            self.vr[i] = 0.0;
            self.vz[i] = if self.mesh.sphere_nodes.contains(&i) {
                -v_s
            } else {
                0.0
            };
        }
        for b in &mut self.bodies {
            b.dissipated = 0.0;
        }
        // accelerations of the current (possibly residually stressed) state: forces with zero
        // increment
        let vz_save = std::mem::take(&mut self.vz);
        self.vz = vec![0.0; n];
        self.internal_forces();
        self.vz = vz_save;
        let (_, epen0) = self.contact_forces();
        let ar: Vec<f64> = (0..n)
            .map(|i| {
                if self.mesh.fix_r[i] {
                    0.0
                } else {
                    self.fr[i] * self.inv_m[i]
                }
            })
            .collect();
        let az: Vec<f64> = (0..n)
            .map(|i| {
                if self.mesh.fix_z[i] {
                    0.0
                } else {
                    self.fz[i] * self.inv_m[i]
                }
            })
            .collect();
        // treat the initial velocity as v^{n+1/2} - dt/2 a: start exactly with v at t = 0
        for i in 0..n {
            self.vr[i] -= 0.5 * self.dt * ar[i];
            self.vz[i] -= 0.5 * self.dt * az[i];
        }
        let e0 = {
            let (ke, _) = self.kinetic(&ar, &az, 0..n);
            let st: f64 = (0..self.bodies.len()).map(|b| self.stored(b)).sum();
            ke + st + epen0
        };
        (ar, az, e0)
    }

    /// Axial displacement of the sphere's centre of mass (mass-weighted mean of its nodes), m.
    fn sphere_cm_uz(&self) -> f64 {
        self.mesh
            .sphere_nodes
            .clone()
            .map(|i| self.mass[i] * self.uz[i])
            .sum::<f64>()
            / self.sphere_mass
    }

    /// Central-difference steps until the sphere has separated (contact force zero for 10 %
    /// of the contact duration and moving away [D L1777]), the time limit or a non-finite
    /// displacement; records the force history, contact times, peak force and approach.
    fn integrate(&mut self, v_s: f64, ar: &mut [f64], az: &mut [f64]) -> Trajectory {
        let n = self.mesh.r.len();
        let uz_cm0: f64 = self.sphere_cm_uz();
        let tc_est = self.hertz.contact_time(v_s.max(1e-9));
        let t_max = self.opts.max_time_over_contact_time * tc_est;
        let sample_every =
            ((tc_est / self.dt) / self.opts.history_samples as f64).max(1.0) as usize;
        let mut history = Vec::new();
        let (mut t, mut step) = (0.0, 0usize);
        let (mut t_first, mut t_last) = (f64::NAN, f64::NAN);
        let mut fmax = 0.0f64;
        let mut dmax = 0.0f64;
        let mut completed = false;
        let dt = self.dt;
        let mut failure = None;
        while t < t_max {
            // central differences: v^{n+1/2} = v^{n-1/2} + dt a^n; u^{n+1} = u^n + dt v^{n+1/2}
            for i in 0..n {
                self.vr[i] += dt * ar[i];
                self.vz[i] += dt * az[i];
                self.ur[i] += dt * self.vr[i];
                self.uz[i] += dt * self.vz[i];
            }
            self.internal_forces();
            let (fc, _) = self.contact_forces();
            for i in 0..n {
                ar[i] = if self.mesh.fix_r[i] {
                    0.0
                } else {
                    self.fr[i] * self.inv_m[i]
                };
                az[i] = if self.mesh.fix_z[i] {
                    0.0
                } else {
                    self.fz[i] * self.inv_m[i]
                };
            }
            t += dt;
            step += 1;
            // Health: every node's displacement finite (every 64 steps).
            if step % 64 == 0
                && let Some(i) =
                    (0..n).find(|&i| !(self.ur[i].is_finite() && self.uz[i].is_finite()))
            {
                failure = Some(format!(
                    "non-finite displacement at t = {t:.6e} s, node {i} at (r, z) = ({:.4e}, {:.4e}) m; \
                     likely cause: the explicit step {dt:.3e} s above the critical step of the mesh \
                     (contact element size {:.3e} m), or material data out of range",
                    self.mesh.r[i], self.mesh.z[i], self.mesh.h_contact
                ));
                break;
            }
            if fc > 0.0 {
                if t_first.is_nan() {
                    t_first = t;
                }
                t_last = t;
                fmax = fmax.max(fc);
            }
            if step % sample_every == 0 || fc > 0.0 && step % sample_every.div_ceil(4).max(1) == 0 {
                history.push((t, fc));
            }
            if step % 16 == 0 || fc > 0.0 {
                let uz_cm: f64 = self.sphere_cm_uz();
                dmax = dmax.max(uz_cm0 - uz_cm);
            }
            if !t_first.is_nan() && fc == 0.0 && step % 8 == 0 {
                let open = t - t_last;
                if open >= (0.1 * (t_last - t_first)).max(20.0 * dt) {
                    let (_, pz) = self.kinetic(ar, az, self.mesh.sphere_nodes.clone());
                    if pz > 0.0 {
                        completed = true;
                        break;
                    }
                }
            }
        }
        Trajectory {
            history,
            t_first,
            t_last,
            fmax,
            dmax,
            completed,
            step,
            failure,
        }
    }

    /// Where the initial energy `e0` went at the end (kinetic, stored, penalty, plastic and
    /// viscous dissipation by body) and the sphere's centre-of-mass velocity (its momentum /
    /// mass, [D Eq. 3.5]).
    fn energy_split(&mut self, e0: f64, ar: &[f64], az: &[f64]) -> (EnergySplit, f64) {
        let (ke_s, pz) = self.kinetic(ar, az, self.mesh.sphere_nodes.clone());
        let (ke_w, _) = self.kinetic(ar, az, self.mesh.wall_nodes.clone());
        let v_cm = pz / self.sphere_mass;
        let rigid = 0.5 * self.sphere_mass * v_cm * v_cm;
        let stored_s = self.stored(0);
        let stored_w = if self.bodies.len() > 1 {
            self.stored(1)
        } else {
            0.0
        };
        let (_, epen) = {
            // penalty energy at the end (forces are recomputed but not used)
            let (fr, fz) = (self.fr.clone(), self.fz.clone());
            let r = self.contact_forces();
            self.fr = fr;
            self.fz = fz;
            r
        };
        let mut en = EnergySplit {
            initial_j: e0,
            sphere_rigid_kinetic_j: rigid,
            sphere_vibration_j: ke_s - rigid + stored_s,
            wall_kinetic_j: ke_w,
            wall_stored_j: stored_w,
            contact_j: epen,
            ..Default::default()
        };
        for (b, body) in self.bodies.iter().enumerate() {
            let d = body.dissipated;
            match (b, body.plastic) {
                (0, true) => en.plastic_sphere_j += d,
                (0, false) => en.viscous_sphere_j += d,
                (_, true) => en.plastic_wall_j += d,
                (_, false) => en.viscous_wall_j += d,
            }
        }
        en.balance_error_j = e0
            - (ke_s
                + stored_s
                + ke_w
                + stored_w
                + epen
                + en.plastic_sphere_j
                + en.plastic_wall_j
                + en.viscous_sphere_j
                + en.viscous_wall_j);
        (en, v_cm)
    }
}

/// What the time loop of [`FeImpact::run`] recorded.
struct Trajectory {
    /// Force history `(t_s, force_n)`.
    history: Vec<(f64, f64)>,
    /// First and last instant with contact force (NaN without contact), s.
    t_first: f64,
    t_last: f64,
    /// Largest contact force, N.
    fmax: f64,
    /// Largest approach of the sphere's centre of mass, m.
    dmax: f64,
    /// Whether the sphere separated before the time limit.
    completed: bool,
    /// Steps taken.
    step: usize,
    /// A non-finite displacement, described.
    failure: Option<String>,
}

/// The failure message of a broken energy balance (error beyond [`MAX_BALANCE_ERROR`]).
fn balance_failure(en: &EnergySplit, e0: f64, dt: f64) -> String {
    format!(
        "energy balance broken: {:.3e} J of {:.3e} J ({:.1} %){}; likely cause: the \
         explicit step {dt:.3e} s too close to the critical step, or a penalty stiffness \
         out of range",
        en.balance_error_j,
        e0,
        100.0 * en.balance_error_j / e0,
        if en.balance_error_j < 0.0 {
            ", energy created"
        } else {
            ""
        }
    )
}

/// One FE impact of a sphere (`radius` m, material `sphere`) on `partner` at relative velocity
/// `v` (m/s), mesh refined for this velocity.
pub fn simulate_impact(
    sphere: &Material,
    partner: &Partner,
    radius: f64,
    v: f64,
    opts: &FeOptions,
) -> ImpactResult {
    FeImpact::new(sphere, partner, radius, v, opts).run(v)
}
