//! Dirichlet–Neumann partitioned DEM–FEM coupling (paper Sect. 2.3, Algorithm 1).
//!
//! The particles are the Dirichlet partition: for given interface displacements
//! $\mathbf d^{ps}$ (and the velocities the generalized-α relations imply) the particle
//! operator $\mathcal P$ returns the contact forces. The structure is the Neumann partition:
//! $\mathcal S^{-1}$ solves the generalized-α step under those forces. Contacts are found by
//! closest-point projection onto the bilinear interface quads; the reaction on the structure is
//! distributed to the nodes with the shape functions (eq. 15,
//! $\mathbf f^{ps}_j = \sum_e\sum_i N^e_j(\xi_i)\mathbf f^e_i$). Fixed-point iterations with
//! Aitken relaxation (Küttler & Wall 2008, paper ref. \[34\]) run until eq. 16,
//! $|\Delta\mathbf d^{ps}_{n+1,k+1}|/(\Delta t\sqrt{n^{ps}_{dof}}) < \epsilon$, with the increment
//! between successive iterates as in Algorithm 1.
//!
//! Within one step, particle–particle forces do not depend on $\mathbf d^{ps}$ (velocity
//! Verlet positions are explicit), so an iteration re-evaluates only particle–wall contacts
//! and the structural solve.
//!
//! Contacts with several faces: closest points strictly inside a face are always used; a
//! closest point on a face boundary (edge/corner) is used only if no interior contact of the
//! particle has a nearly parallel face normal and no accepted contact shares the point — this
//! avoids double counting on coplanar neighbours and keeps both walls in concave corners.

use rayon::prelude::*;

use crate::dem::Powder;
use crate::dem::wall::{self, EMPTY_SLOTS, WallSlots};
use crate::fe::{Aabb, Dynamics, DynamicsError, DynamicsState, Face, Structure};
use crate::health::{self, HealthError, Symptom};

/// Steps between the overlap checks of the coupled run (positions, velocities and the
/// container are checked every step).
pub const OVERLAP_CHECK_EVERY: u64 = 100;

/// The interface $\Gamma^{ps}$: boundary faces of the structure in contact with the powder.
#[derive(Debug, Clone)]
pub struct Interface {
    /// Interface faces (normals pointing into the cavity).
    pub faces: Vec<Face>,
    /// Unique interface nodes, ascending.
    pub nodes: Vec<usize>,
}

impl Interface {
    /// Builds the interface from faces; collects their nodes.
    pub fn new(faces: Vec<Face>) -> Self {
        let mut nodes: Vec<usize> = faces.iter().flat_map(|f| f.nodes).collect();
        nodes.sort_unstable();
        nodes.dedup();
        Self { faces, nodes }
    }
    /// $n^{ps}_{dof}$.
    pub fn n_dof(&self) -> usize {
        3 * self.nodes.len()
    }
}

/// Closest point on a bilinear quad with corner positions `x` to `p`: returns (s, t, point,
/// interior, unit normal of the quad at the point (right-hand rule of the node order)).
pub fn closest_point(x: &[[f64; 3]; 4], p: [f64; 3]) -> (f64, f64, [f64; 3], bool, [f64; 3]) {
    let (mut s, mut t) = (0.0f64, 0.0f64);
    let mut interior = true;
    for _ in 0..8 {
        let qp = crate::fe::quad::point(x, s, t);
        let (c, a, b) = (qp.x, qp.dxds, qp.dxdt);
        let r = [c[0] - p[0], c[1] - p[1], c[2] - p[2]];
        let (aa, ab, bb) = (dot(a, a), dot(a, b), dot(b, b));
        let (ra, rb) = (dot(r, a), dot(r, b));
        let det = aa * bb - ab * ab;
        let ds_ = -(bb * ra - ab * rb) / det;
        let dt_ = -(aa * rb - ab * ra) / det;
        let (s1, t1) = (s + ds_, t + dt_);
        let (sc, tc) = (s1.clamp(-1.0, 1.0), t1.clamp(-1.0, 1.0));
        interior = sc == s1 && tc == t1;
        let done = (sc - s).abs() < 1e-13 && (tc - t).abs() < 1e-13;
        s = sc;
        t = tc;
        if done {
            break;
        }
    }
    let qp = crate::fe::quad::point(x, s, t);
    let (c, a, b) = (qp.x, qp.dxds, qp.dxdt);
    let nn = crate::fe::quad::cross(a, b);
    let l = dot(nn, nn).sqrt();
    (
        s,
        t,
        c,
        interior && s.abs() < 1.0 && t.abs() < 1.0,
        [nn[0] / l, nn[1] / l, nn[2] / l],
    )
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Geometric candidate: (face, s, t, closest point, interior, face normal, gap, contact normal).
type GeoHit = (u32, f64, f64, [f64; 3], bool, [f64; 3], f64, [f64; 3]);

/// One particle–face contact of an evaluation.
#[derive(Debug, Clone, Copy, Default)]
struct Hit {
    face: u32,
    s: f64,
    t: f64,
    force: [f64; 3],
}

/// Per-particle result of the particle operator.
#[derive(Debug, Clone, Copy)]
struct WallResult {
    force: [f64; 3],
    torque: [f64; 3],
    hist: WallSlots,
    hits: [Hit; 4],
    nhits: u8,
    elastic: f64,
    dissipated: f64,
}

impl Default for WallResult {
    fn default() -> Self {
        Self {
            force: [0.0; 3],
            torque: [0.0; 3],
            hist: EMPTY_SLOTS,
            hits: [Hit::default(); 4],
            nhits: 0,
            elastic: 0.0,
            dissipated: 0.0,
        }
    }
}

/// Coupling settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSettings {
    /// ε of eq. 16 [m/s] (paper: 1e-3).
    pub tolerance: f64,
    /// Maximum fixed-point iterations per step.
    pub max_iterations: usize,
    /// Aitken relaxation (otherwise fixed relaxation `initial_relaxation`).
    pub aitken: bool,
    /// First relaxation factor of each step.
    pub initial_relaxation: f64,
}

impl Default for CouplingSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-3,
            max_iterations: 50,
            aitken: true,
            initial_relaxation: 1.0,
        }
    }
}

/// Errors of the coupled step.
#[derive(Debug, thiserror::Error)]
pub enum CoupleError {
    /// Structural solve failed.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// A health check failed (non-finite state, a particle outside the cavity, a runaway
    /// overlap), see [`crate::health`].
    #[error(transparent)]
    Health(#[from] Box<HealthError>),
    /// Fixed point did not converge.
    #[error(
        "coupling did not converge at t = {t_s} s: eq. 16 measure {measure:e} after {iterations} iterations"
    )]
    NotConverged {
        /// Time \[s\].
        t_s: f64,
        /// Final value of the eq. 16 measure [m/s].
        measure: f64,
        /// Iterations.
        iterations: usize,
    },
}

/// Energies of the coupled system \[J\].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledEnergy {
    /// Structure kinetic energy.
    pub structure_kinetic_j: f64,
    /// Structure strain energy.
    pub structure_strain_j: f64,
    /// Particle kinetic (translational + rotational).
    pub particle_kinetic_j: f64,
    /// Particle gravitational potential.
    pub particle_potential_j: f64,
    /// Elastic energy of particle–particle and particle–wall springs.
    pub contact_elastic_j: f64,
    /// Dissipated in contacts (dashpots, sliding).
    pub dissipated_j: f64,
    /// Work of the structural loads and body forces (not the interface forces).
    pub load_work_j: f64,
    /// Stored + dissipated − load work (constant for an exact scheme).
    pub balance_j: f64,
}

/// The dynamic state of a [`Coupled`] system between steps, for checkpoints: the structure's
/// time integration, the particles (with their pair list and spring history), the
/// particle–wall spring history, the interface force and work, the contact candidates and the
/// fixed-point work vectors, and the iteration counters. The mesh, the interface and the
/// factorization are rebuilt from the scenario.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct CoupledState {
    /// Structure.
    pub dynamics: DynamicsState,
    /// Particles.
    pub powder: Powder,
    counters: [u64; 4],
    f_ps: Vec<f64>,
    elastic_pw_j: f64,
    interface_work_j: f64,
    hist: Vec<WallSlots>,
    cand_start: Vec<usize>,
    cand: Vec<u32>,
    cand_pos: Vec<[f64; 3]>,
    cand_disp: f64,
    dk: Vec<f64>,
    f_trial: Vec<f64>,
    r_prev: Vec<f64>,
    r_cur: Vec<f64>,
    omega: f64,
    xcur: Vec<[f64; 3]>,
    vcur: Vec<[f64; 3]>,
}

/// The coupled particle–structure system.
pub struct Coupled {
    /// Structure.
    pub structure: Structure,
    /// Its time integration.
    pub dynamics: Dynamics,
    /// The particles.
    pub powder: Powder,
    /// The interface.
    pub interface: Interface,
    /// Settings.
    pub settings: CouplingSettings,
    /// Fixed-point iterations of the last step.
    pub last_iterations: usize,
    /// Sum of iterations over all steps.
    pub total_iterations: u64,
    /// Largest iteration count of a step.
    pub max_iterations_seen: usize,
    /// Steps done.
    pub steps: u64,
    /// Interface force on the structure at the committed state (all dofs) \[N\].
    pub f_ps: Vec<f64>,
    /// Elastic energy of the particle–wall springs (committed) \[J\].
    pub elastic_pw_j: f64,
    /// Work of the interface forces on the structure \[J\].
    pub interface_work_j: f64,
    /// The closed container of the particles in the reference configuration (the cavity);
    /// when set, a particle centre outside it (enlarged by the largest interface displacement)
    /// stops the run with [`Symptom::Escaped`]. `None` (default): open interfaces such as a
    /// plate.
    pub container: Option<Aabb>,
    hist: Vec<WallSlots>,
    results: Vec<WallResult>,
    cand_start: Vec<usize>,
    cand: Vec<u32>,
    cand_pos: Vec<[f64; 3]>,
    cand_disp: f64,
    margin: f64,
    dk: Vec<f64>,
    f_trial: Vec<f64>,
    r_prev: Vec<f64>,
    r_cur: Vec<f64>,
    omega: f64,
    xcur: Vec<[f64; 3]>,
    vcur: Vec<[f64; 3]>,
}

impl Coupled {
    /// Couples `powder` (positions inside the cavity) with the structure over `interface`.
    pub fn new(
        structure: Structure,
        dynamics: Dynamics,
        powder: Powder,
        interface: Interface,
        settings: CouplingSettings,
    ) -> Self {
        let n = powder.len();
        let ndof = structure.n_dof();
        let nn = structure.mesh.nodes.len();
        let rmin = powder.radius.iter().fold(f64::INFINITY, |m, &r| m.min(r));
        Self {
            structure,
            dynamics,
            interface,
            settings,
            last_iterations: 0,
            total_iterations: 0,
            max_iterations_seen: 0,
            steps: 0,
            f_ps: vec![0.0; ndof],
            elastic_pw_j: 0.0,
            interface_work_j: 0.0,
            container: None,
            hist: vec![EMPTY_SLOTS; n],
            results: vec![WallResult::default(); n],
            cand_start: Vec::new(),
            cand: Vec::new(),
            cand_pos: Vec::new(),
            cand_disp: 0.0,
            margin: 0.5 * rmin.min(1.0),
            dk: vec![0.0; ndof],
            f_trial: vec![0.0; ndof],
            r_prev: Vec::new(),
            r_cur: Vec::new(),
            omega: 1.0,
            xcur: vec![[0.0; 3]; nn],
            vcur: vec![[0.0; 3]; nn],
            powder,
        }
    }

    /// The state for a checkpoint (see [`CoupledState`]).
    pub fn save_state(&self) -> CoupledState {
        CoupledState {
            dynamics: self.dynamics.save_state(),
            powder: self.powder.clone(),
            counters: [
                self.last_iterations as u64,
                self.total_iterations,
                self.max_iterations_seen as u64,
                self.steps,
            ],
            f_ps: self.f_ps.clone(),
            elastic_pw_j: self.elastic_pw_j,
            interface_work_j: self.interface_work_j,
            hist: self.hist.clone(),
            cand_start: self.cand_start.clone(),
            cand: self.cand.clone(),
            cand_pos: self.cand_pos.clone(),
            cand_disp: self.cand_disp,
            dk: self.dk.clone(),
            f_trial: self.f_trial.clone(),
            r_prev: self.r_prev.clone(),
            r_cur: self.r_cur.clone(),
            omega: self.omega,
            xcur: self.xcur.clone(),
            vcur: self.vcur.clone(),
        }
    }

    /// The system of [`Coupled::new`] continued from `st` (saved by [`Coupled::save_state`]
    /// for the same structure, interface and settings): the following steps are bit for bit
    /// those of the saved run. `dynamics` is a fresh [`Dynamics`] of `structure`.
    pub fn from_state(
        structure: Structure,
        mut dynamics: Dynamics,
        interface: Interface,
        settings: CouplingSettings,
        st: CoupledState,
    ) -> Result<Self, String> {
        st.powder.check_consistency()?;
        dynamics.restore_state(st.dynamics)?;
        let (n, ndof) = (st.powder.len(), structure.n_dof());
        let nn = structure.mesh.nodes.len();
        let nf = interface.faces.len();
        let cand_ok = (st.cand_start.is_empty() && st.cand.is_empty())
            || (st.cand_start.len() == n + 1
                && st.cand_start[0] == 0
                && st.cand_start[n] == st.cand.len()
                && st.cand_start.windows(2).all(|w| w[0] <= w[1])
                && st.cand.iter().all(|&f| (f as usize) < nf));
        if st.hist.len() != n
            || !cand_ok
            || st.cand_pos.is_empty() != st.cand_start.is_empty()
            || !(st.cand_pos.is_empty() || st.cand_pos.len() == n)
            || [&st.f_ps, &st.dk, &st.f_trial]
                .iter()
                .any(|v| v.len() != ndof)
            || st.xcur.len() != nn
            || st.vcur.len() != nn
        {
            return Err("coupling state does not match the structure and the particles".into());
        }
        let mut c = Self::new(structure, dynamics, st.powder, interface, settings);
        let [last, total, max, steps] = st.counters;
        c.last_iterations = last as usize;
        c.total_iterations = total;
        c.max_iterations_seen = max as usize;
        c.steps = steps;
        c.f_ps = st.f_ps;
        c.elastic_pw_j = st.elastic_pw_j;
        c.interface_work_j = st.interface_work_j;
        c.hist = st.hist;
        c.cand_start = st.cand_start;
        c.cand = st.cand;
        c.cand_pos = st.cand_pos;
        c.cand_disp = st.cand_disp;
        c.dk = st.dk;
        c.f_trial = st.f_trial;
        c.r_prev = st.r_prev;
        c.r_cur = st.r_cur;
        c.omega = st.omega;
        c.xcur = st.xcur;
        c.vcur = st.vcur;
        Ok(c)
    }

    /// Candidate faces per particle: faces whose current bounding box, enlarged by the particle
    /// radius plus a margin, contains the particle centre. Rebuilt when particles or the
    /// structure moved more than a quarter of the margin.
    fn update_candidates(&mut self) {
        let dmax = self
            .interface
            .nodes
            .iter()
            .map(|&a| (0..3).map(|k| self.dk[3 * a + k].abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        let moved = self.cand_pos.len() != self.powder.len()
            || (dmax - self.cand_disp).abs() > 0.25 * self.margin
            || self
                .powder
                .pos
                .iter()
                .zip(&self.cand_pos)
                .any(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 0.25 * self.margin));
        if !moved {
            return;
        }
        let nodes = &self.structure.mesh.nodes;
        let faces = &self.interface.faces;
        // face boxes and a uniform grid over them
        let boxes: Vec<([f64; 3], [f64; 3])> = faces
            .iter()
            .map(|f| {
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                for &a in &f.nodes {
                    for k in 0..3 {
                        let x = nodes[a][k] + self.dk[3 * a + k];
                        lo[k] = lo[k].min(x);
                        hi[k] = hi[k].max(x);
                    }
                }
                (lo, hi)
            })
            .collect();
        let rmax = self.powder.radius.iter().fold(0.0f64, |m, &r| m.max(r));
        let reach = rmax + self.margin + self.powder.law.adhesion_range(rmax);
        let mut glo = [f64::INFINITY; 3];
        let mut ghi = [f64::NEG_INFINITY; 3];
        let mut hmax = 0.0f64;
        for (lo, hi) in &boxes {
            for k in 0..3 {
                glo[k] = glo[k].min(lo[k] - reach);
                ghi[k] = ghi[k].max(hi[k] + reach);
                hmax = hmax.max(hi[k] - lo[k]);
            }
        }
        let cell0 = (hmax + 2.0 * reach).max(1e-9);
        let mut nc: Vec<usize> = (0..3)
            .map(|k| (((ghi[k] - glo[k]) / cell0).ceil() as usize).clamp(1, 512))
            .collect();
        // at most 8 cells per face (a structure blown apart must not allocate 512³ cells);
        // cells grow instead, per axis, so that they still cover the whole range
        let limit = (8 * faces.len()).max(4096);
        while nc[0] * nc[1] * nc[2] > limit {
            let k = (0..3).max_by_key(|&k| nc[k]).unwrap_or(0);
            nc[k] = nc[k].div_ceil(2);
        }
        let cellk: Vec<f64> = (0..3)
            .map(|k| {
                let c = cell0.max((ghi[k] - glo[k]) / nc[k] as f64);
                if c.is_finite() { c } else { f64::MAX }
            })
            .collect();
        let idx = |p: [f64; 3]| -> Option<usize> {
            let mut c = [0usize; 3];
            for k in 0..3 {
                let f = (p[k] - glo[k]) / cellk[k];
                if f < 0.0 || f >= nc[k] as f64 {
                    return None;
                }
                c[k] = f as usize;
            }
            Some(c[0] + nc[0] * (c[1] + nc[1] * c[2]))
        };
        let ncell = nc[0] * nc[1] * nc[2];
        let mut cell_faces: Vec<Vec<u32>> = vec![Vec::new(); ncell];
        for (fi, (lo, hi)) in boxes.iter().enumerate() {
            let c0: Vec<usize> = (0..3)
                .map(|k| (((lo[k] - reach - glo[k]) / cellk[k]).max(0.0) as usize).min(nc[k] - 1))
                .collect();
            let c1: Vec<usize> = (0..3)
                .map(|k| (((hi[k] + reach - glo[k]) / cellk[k]).max(0.0) as usize).min(nc[k] - 1))
                .collect();
            for z in c0[2]..=c1[2] {
                for y in c0[1]..=c1[1] {
                    for x in c0[0]..=c1[0] {
                        cell_faces[x + nc[0] * (y + nc[1] * z)].push(fi as u32);
                    }
                }
            }
        }
        self.cand_start.clear();
        self.cand.clear();
        for (i, p) in self.powder.pos.iter().enumerate() {
            self.cand_start.push(self.cand.len());
            if let Some(c) = idx(*p) {
                let r = self.powder.radius[i] + self.margin;
                for &fi in &cell_faces[c] {
                    let (lo, hi) = boxes[fi as usize];
                    if (0..3).all(|k| p[k] >= lo[k] - r && p[k] <= hi[k] + r) {
                        self.cand.push(fi);
                    }
                }
            }
        }
        self.cand_start.push(self.cand.len());
        self.cand_pos.clear();
        self.cand_pos.extend_from_slice(&self.powder.pos);
        self.cand_disp = dmax;
    }

    /// The particle operator $\mathcal P$: wall forces for interface displacement `self.dk`;
    /// writes the particle wall forces and the nodal reaction (eq. 15) into `f_trial`.
    fn particle_operator(&mut self) {
        let p = &self.dynamics.params;
        let dt = self.dynamics.dt;
        let (beta, gamma) = (p.beta, p.gamma);
        for &a in &self.interface.nodes {
            for k in 0..3 {
                let g = 3 * a + k;
                let d = &self.dynamics;
                let acc = (self.dk[g] - d.d[g] - dt * d.v[g] - dt * dt * (0.5 - beta) * d.a[g])
                    / (beta * dt * dt);
                self.xcur[a][k] = self.structure.mesh.nodes[a][k] + self.dk[g];
                self.vcur[a][k] = d.v[g] + dt * ((1.0 - gamma) * d.a[g] + gamma * acc);
            }
        }
        self.update_candidates();
        let powder = &self.powder;
        let faces = &self.interface.faces;
        let (xcur, vcur) = (&self.xcur, &self.vcur);
        let (cs, cand, hist) = (&self.cand_start, &self.cand, &self.hist);
        let range_max = powder
            .law
            .adhesion_range(powder.radius.iter().fold(0.0f64, |m, &r| m.max(r)));
        self.results
            .par_iter_mut()
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, res)| {
                *res = WallResult::default();
                let list = &cand[cs[i]..cs[i + 1]];
                if list.is_empty() {
                    return;
                }
                let pos = powder.pos[i];
                let r = powder.radius[i];
                // gather geometric contacts
                let mut geo: [GeoHit; 8] =
                    [(0, 0.0, 0.0, [0.0; 3], false, [0.0; 3], 0.0, [0.0; 3]); 8];
                let mut ng = 0;
                for &fi in list {
                    let f = &faces[fi as usize];
                    let x = [
                        xcur[f.nodes[0]],
                        xcur[f.nodes[1]],
                        xcur[f.nodes[2]],
                        xcur[f.nodes[3]],
                    ];
                    let (s, t, c, interior, fnrm) = closest_point(&x, pos);
                    let (n, gap) = if interior {
                        // particle → wall direction is against the face normal (which points into the cavity)
                        let dist = dot([pos[0] - c[0], pos[1] - c[1], pos[2] - c[2]], fnrm);
                        ([-fnrm[0], -fnrm[1], -fnrm[2]], dist - r)
                    } else {
                        let v = [c[0] - pos[0], c[1] - pos[1], c[2] - pos[2]];
                        let l = dot(v, v).sqrt();
                        if l == 0.0 {
                            continue;
                        }
                        ([v[0] / l, v[1] / l, v[2] / l], l - r)
                    };
                    if gap > range_max || (gap > 0.0 && range_max == 0.0) {
                        continue;
                    }
                    if ng < 8 {
                        geo[ng] = (fi, s, t, c, interior, fnrm, gap, n);
                        ng += 1;
                    }
                }
                // selection (module docs)
                let mut keep = [false; 8];
                for a in 0..ng {
                    if geo[a].4 {
                        keep[a] = true;
                    }
                }
                for a in 0..ng {
                    if geo[a].4 {
                        continue;
                    }
                    let covered = (0..ng)
                        .any(|b| b != a && geo[b].4 && dot(geo[b].5, geo[a].5) > 0.99)
                        || (0..a).any(|b| {
                            keep[b]
                                && !geo[b].4
                                && (0..3).all(|k| (geo[b].3[k] - geo[a].3[k]).abs() < 1e-9 * r)
                        });
                    keep[a] = !covered;
                }
                for a in 0..ng {
                    if !keep[a] || res.nhits as usize >= 4 {
                        continue;
                    }
                    let (fi, s, t, _, _, _, gap, n) = geo[a];
                    let f = &faces[fi as usize];
                    let nsh = crate::fe::quad::shape(s, t);
                    let mut vw = [0.0; 3];
                    for q in 0..4 {
                        for k in 0..3 {
                            vw[k] += nsh[q] * vcur[f.nodes[q]][k];
                        }
                    }
                    let mut gt = wall::slot_get(&hist[i], fi);
                    let (cr, tq) = wall::particle_wall(powder, i, n, gap, vw, &mut gt);
                    wall::slot_put(&mut res.hist, fi, gt);
                    for k in 0..3 {
                        res.force[k] += cr.force[k];
                        res.torque[k] += tq[k];
                    }
                    res.elastic += cr.elastic_j;
                    res.dissipated += cr.dissipated_j;
                    res.hits[res.nhits as usize] = Hit {
                        face: fi,
                        s,
                        t,
                        force: cr.force,
                    };
                    res.nhits += 1;
                }
            });
        // eq. 15, gathered in particle order (deterministic)
        for &a in &self.interface.nodes {
            for k in 0..3 {
                self.f_trial[3 * a + k] = 0.0;
            }
        }
        for res in &self.results {
            for h in &res.hits[..res.nhits as usize] {
                let f = &self.interface.faces[h.face as usize];
                let nsh = crate::fe::quad::shape(h.s, h.t);
                for q in 0..4 {
                    for k in 0..3 {
                        self.f_trial[3 * f.nodes[q] + k] -= nsh[q] * h.force[k];
                    }
                }
            }
        }
    }

    /// Sum of the particle wall forces and of the nodal interface forces of the committed step
    /// (interface equilibrium: their sum vanishes since $\sum_j N_j = 1$) \[N\].
    pub fn interface_force_sums(&self) -> ([f64; 3], [f64; 3]) {
        let mut fp = [0.0; 3];
        for f in &self.powder.wall_force {
            for k in 0..3 {
                fp[k] += f[k];
            }
        }
        let mut fs = [0.0; 3];
        for &a in &self.interface.nodes {
            for k in 0..3 {
                fs[k] += self.f_ps[3 * a + k];
            }
        }
        (fp, fs)
    }

    /// One coupled time step (Algorithm 1); returns the number of fixed-point iterations.
    pub fn step(&mut self) -> Result<usize, CoupleError> {
        self.powder.predict();
        self.check_particles()?;
        self.powder.pair_forces();
        if self.steps.is_multiple_of(OVERLAP_CHECK_EVERY) {
            let p = &self.powder;
            health::check_overlaps(p)
                .map_err(|s| Box::new(HealthError::new(p.t, "coupled run", s, p)))?;
        }
        let dt = self.dynamics.dt;
        let nps = self.interface.n_dof();
        // predictor of the interface displacements
        {
            let d = &self.dynamics;
            for &a in &self.interface.nodes {
                for k in 0..3 {
                    let g = 3 * a + k;
                    self.dk[g] = d.d[g] + dt * d.v[g];
                }
            }
        }
        self.r_prev.resize(nps, 0.0);
        self.r_cur.resize(nps, 0.0);
        let mut omega = self.settings.initial_relaxation;
        let mut k = 0;
        loop {
            self.particle_operator();
            if let Err(e) = self
                .dynamics
                .solve(&mut self.structure, Some(&self.f_trial), k == 0)
            {
                // a diverged structure (or particles) is a health failure, not a solver one
                if self.dynamics.d1.iter().any(|x| !x.is_finite())
                    || self.f_trial.iter().any(|x| !x.is_finite())
                {
                    return Err(self.structure_failure().into());
                }
                return Err(e.into());
            }
            k += 1;
            let mut norm2 = 0.0;
            for (q, &a) in self.interface.nodes.iter().enumerate() {
                for c in 0..3 {
                    let g = 3 * a + c;
                    let r = self.dynamics.d1[g] - self.dk[g];
                    self.r_cur[3 * q + c] = r;
                    norm2 += r * r;
                }
            }
            let measure = norm2.sqrt() / (dt * (nps.max(1) as f64).sqrt());
            if !measure.is_finite() {
                return Err(self.structure_failure().into());
            }
            if measure < self.settings.tolerance {
                break;
            }
            if k >= self.settings.max_iterations {
                return Err(CoupleError::NotConverged {
                    t_s: self.dynamics.t + dt,
                    measure,
                    iterations: k,
                });
            }
            if self.settings.aitken && k > 1 {
                let mut num = 0.0;
                let mut den = 0.0;
                for q in 0..nps {
                    let dr = self.r_cur[q] - self.r_prev[q];
                    num += self.r_prev[q] * dr;
                    den += dr * dr;
                }
                if den > 0.0 {
                    omega = -omega * num / den;
                }
            }
            for (q, &a) in self.interface.nodes.iter().enumerate() {
                for c in 0..3 {
                    self.dk[3 * a + c] += omega * self.r_cur[3 * q + c];
                }
            }
            std::mem::swap(&mut self.r_prev, &mut self.r_cur);
        }
        self.omega = omega;
        // commit: interface work (trapezoidal), structure, particle wall forces and history
        let mut w = 0.0;
        for &a in &self.interface.nodes {
            for c in 0..3 {
                let g = 3 * a + c;
                w += 0.5
                    * (self.dynamics.d1[g] - self.dynamics.d[g])
                    * (self.f_trial[g] + self.f_ps[g]);
            }
        }
        self.interface_work_j += w;
        self.dynamics.commit();
        std::mem::swap(&mut self.f_ps, &mut self.f_trial);
        let mut el = 0.0;
        let mut diss = 0.0;
        for (i, r) in self.results.iter().enumerate() {
            self.powder.wall_force[i] = r.force;
            self.powder.wall_torque[i] = r.torque;
            self.hist[i] = r.hist;
            el += r.elastic;
            diss += r.dissipated;
        }
        self.elastic_pw_j = el;
        self.powder.ledger.dissipated_pw_j += diss;
        self.powder.finish();
        self.last_iterations = k;
        self.total_iterations += k as u64;
        self.max_iterations_seen = self.max_iterations_seen.max(k);
        self.steps += 1;
        Ok(k)
    }

    /// Health of the particles after the drift of a step: finite states and centres inside
    /// the container (if set); the overlaps are checked after the force pass, every
    /// [`OVERLAP_CHECK_EVERY`] steps.
    fn check_particles(&self) -> Result<(), Box<HealthError>> {
        let p = &self.powder;
        let fail = |symptom| Box::new(HealthError::new(p.t, "coupled run", symptom, p));
        let margin = self.container.map(|b| {
            let dmax = self
                .interface
                .nodes
                .iter()
                .flat_map(|&a| (0..3).map(move |k| 3 * a + k))
                .map(|g| self.dynamics.d[g].abs())
                .fold(0.0, f64::max);
            let size = (0..3).map(|k| b.max[k] - b.min[k]).fold(0.0, f64::max);
            (b, dmax + 1e-9 * size)
        });
        health::check_particles(p, margin.as_ref().map(|(b, m)| (b, *m)))
            .map_err(|(_, s)| fail(s))?;
        Ok(())
    }

    /// The health error of a non-finite structural state (first non-finite trial dof).
    fn structure_failure(&self) -> Box<HealthError> {
        let p = &self.powder;
        if let Err((_, s)) = health::check_particles(p, None) {
            return Box::new(HealthError::new(p.t, "coupled run", s, p));
        }
        let node = self
            .dynamics
            .d1
            .iter()
            .position(|x| !x.is_finite())
            .map_or(0, |g| g / 3);
        let element = self
            .structure
            .mesh
            .elements
            .iter()
            .position(|el| el.contains(&node));
        Box::new(HealthError::new(
            p.t,
            "coupled run",
            Symptom::NonFiniteStructure { node, element },
            p,
        ))
    }

    /// Energies of the committed state.
    pub fn energy(&self) -> CoupledEnergy {
        let mut e = CoupledEnergy {
            structure_kinetic_j: self.dynamics.kinetic_energy(&self.structure),
            structure_strain_j: self.dynamics.strain_energy,
            particle_kinetic_j: self.powder.kinetic_energy(),
            particle_potential_j: self.powder.potential_energy(),
            contact_elastic_j: self.powder.elastic_pp_j + self.elastic_pw_j,
            dissipated_j: self.powder.ledger.dissipated_pp_j + self.powder.ledger.dissipated_pw_j,
            load_work_j: self.dynamics.external_work - self.interface_work_j,
            balance_j: 0.0,
        };
        e.balance_j = e.structure_kinetic_j
            + e.structure_strain_j
            + e.particle_kinetic_j
            + e.particle_potential_j
            + e.contact_elastic_j
            + e.dissipated_j
            - e.load_work_j;
        e
    }
}
