//! Motion modes of the bed [D Sect. 3.2.1]: phase-resolved velocity fields in the container frame
//! normalised by the container velocity amplitude V, trajectories of chosen particles, VTK
//! frames of the last cycle for animation, and the force–displacement record of every cycle
//! (bed force, driving force and container motion; its loops give the dissipated energy
//! [D Sect. 3.2.2]).

use crate::damper::{Damper, PointObserver};
use pdamp_dem::{Vec3, World};
use std::f64::consts::PI;
use std::path::PathBuf;

/// One phase-averaged velocity field on a grid in the plane (excitation direction, up).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PhaseField {
    /// Phase Ωt of the field, rad.
    pub phase_rad: f64,
    /// Sum of |v|/V per cell.
    pub speed_sum: Vec<f64>,
    /// Sum of the in-plane velocity components / V per cell.
    pub vel_sum: Vec<[f64; 2]>,
    /// Particle samples per cell.
    pub count: Vec<u64>,
}

/// Rows of the force–displacement record per cycle (plus the cycle's closing row, see
/// [`MotionRecorder::force_displacement`]).
pub const FD_SAMPLES_PER_CYCLE: u32 = 200;

/// Columns of [`MotionRecorder::force_displacement`] (and of `force_displacement.csv`).
pub const FORCE_DISPLACEMENT_COLUMNS: [&str; 7] = [
    "time_s",
    "cycle",
    "displacement_m",
    "velocity_m_s",
    "bed_force_n",
    "driving_force_n",
    "work_on_bed_j",
];

/// Records velocity fields, trajectories, VTK frames and the force–displacement record while
/// a point runs.
#[derive(Debug)]
pub struct MotionRecorder {
    /// Unit vectors of the field plane: excitation direction and the up direction (when
    /// gravity is along the excitation or zero: a direction perpendicular to it).
    pub axes: [Vec3; 2],
    /// +1 (−1) when the excitation points up (down), i.e. gravity is along it; 0 when the
    /// excitation is horizontal or there is no gravity. Plots of a vertical excitation draw
    /// the excitation axis upwards ([`crate::plots`]).
    pub excitation_up: f64,
    /// No gravity: `axes[1]` is only a direction perpendicular to the excitation.
    pub gravity_free: bool,
    /// Lower corner of the grid in (axis 0, axis 1), container frame, m.
    pub origin_m: [f64; 2],
    /// Cell size, m.
    pub cell_m: f64,
    /// Cells along both axes.
    pub cells: [usize; 2],
    /// Container velocity amplitude V, m/s.
    pub velocity_amplitude_m_s: f64,
    /// One field per recorded phase.
    pub fields: Vec<PhaseField>,
    /// Particles whose trajectories are recorded.
    pub trajectory_particles: Vec<usize>,
    /// Trajectory rows: particle, time, position in the container frame (x, y, z).
    pub trajectories: Vec<[f64; 5]>,
    /// VTK output folder and frames per cycle (last cycle only).
    pub vtk: Option<(PathBuf, u32)>,
    /// (time, file) of written VTK frames.
    pub vtk_frames: Vec<(f64, String)>,
    /// First error while writing VTK frames.
    pub error: Option<String>,
    /// Force–displacement record of all cycles, transient ones included, one row
    /// ([`FORCE_DISPLACEMENT_COLUMNS`]) at the first step at or after each of
    /// [`FD_SAMPLES_PER_CYCLE`] equally spaced instants per cycle, with the values of that
    /// step (its exact time; no interpolation): time t (s), cycle (from 0), container
    /// displacement x and velocity ẋ along the excitation (m, m/s), the force of the bed on
    /// the container along the excitation f_p (N; the particles' contact forces on its walls),
    /// the driving force m_con ẍ − f_p (N) the complex power method evaluates
    /// [D Sect. 3.2.2], and the work of the container on the bed since t = 0, ∫(−f_p) ẋ dt
    /// over every step by the trapezoidal rule (the first step by the rectangle rule), J: its
    /// increase over whole cycles is their dissipated energy Ẽ_diss of the complex power
    /// method [D Eq. 3.13] without the sampling error of the decimated rows. Each cycle's rows
    /// start and end at its boundaries (the boundary step is the last row of one cycle and,
    /// repeated, the first row of the next), so the rows of one cycle form a closed loop whose
    /// area ∮(−f_p) dx approximates the work on the bed in that cycle; the first cycle starts
    /// at its first sample instead of t = 0.
    pub force_displacement: Vec<[f64; 7]>,
    /// The container's extent in the field plane, `[[lo, hi] along axis 0, [lo, hi] along
    /// axis 1]` in the container frame, m (from the bounding boxes of its walls; `None` when
    /// they are unbounded).
    pub container_extent_m: Option<[[f64; 2]; 2]>,
    /// Angular excitation frequency Ω, rad/s.
    pub omega_rad_s: f64,
    prev_phase: f64,
    prev_theta: f64,
    /// Cycle whose VTK frames `vtk_frames` holds (with an early stop on convergence every
    /// evaluated cycle is written, each over the previous one, as any may be the last).
    vtk_cycle: u32,
    traj_every: u64,
    /// Last force–displacement sample slot, ⌊f t · FD_SAMPLES_PER_CYCLE⌋ (−1: none yet).
    fd_slot: i64,
    /// Work of the container on the bed so far, J, and the time and power −f_p ẋ of the
    /// previous step (for the trapezoidal rule).
    fd_work: (f64, Option<(f64, f64)>),
}

impl MotionRecorder {
    /// A recorder for `damper` excited at `frequency_hz` with velocity amplitude `v_amp`, with
    /// `phases` fields per cycle and `cells_along` cells along the excitation direction over the
    /// container's extent.
    pub fn new(
        damper: &Damper,
        frequency_hz: f64,
        v_amp: f64,
        phases: u32,
        cells_along: u32,
        trajectory_particles: Vec<usize>,
        steps_per_cycle: f64,
    ) -> Self {
        let w = &damper.settled;
        let e = damper.direction;
        let g = -w.gravity_m_s2;
        let mut up = g - e * g.dot(&e);
        if up.norm() < 1e-9 * g.norm().max(1e-300) || g.norm() == 0.0 {
            // Gravity along the excitation or zero: pick a perpendicular axis.
            let t = if e.z.abs() < 0.9 {
                Vec3::z()
            } else {
                Vec3::x()
            };
            up = t - e * t.dot(&e);
        }
        let up = up.normalize();
        let axes = [e, up];
        let excitation_up = if g.norm() > 0.0 && (g - e * g.dot(&e)).norm() < 1e-9 * g.norm() {
            g.dot(&e).signum()
        } else {
            0.0
        };
        // Extent: container walls (body frame) or, without bounded walls, the bed ± 50 %.
        let body = &w.bodies[damper.container];
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for wall in &body.walls {
            if let Some((a, b)) = wall.geometry.bounding_box() {
                for c in 0..8 {
                    let p = Vec3::new(
                        if c & 1 == 0 { a.x } else { b.x },
                        if c & 2 == 0 { a.y } else { b.y },
                        if c & 4 == 0 { a.z } else { b.z },
                    );
                    let p = body.reference.orientation.transform_vector(&p);
                    for k in 0..2 {
                        lo[k] = lo[k].min(p.dot(&axes[k]));
                        hi[k] = hi[k].max(p.dot(&axes[k]));
                    }
                }
            }
        }
        let container_extent_m =
            (lo[0].is_finite() && lo[1].is_finite()).then_some([[lo[0], hi[0]], [lo[1], hi[1]]]);
        if !lo[0].is_finite() || !lo[1].is_finite() {
            for (x, r) in w.particles.position.iter().zip(&w.particles.radius) {
                let rel = x - body.reference.position_m;
                for k in 0..2 {
                    lo[k] = lo[k].min(rel.dot(&axes[k]) - r);
                    hi[k] = hi[k].max(rel.dot(&axes[k]) + r);
                }
            }
            for k in 0..2 {
                let m = 0.5 * (hi[k] - lo[k]);
                lo[k] -= m;
                hi[k] += m;
            }
        }
        let cell = (hi[0] - lo[0]).max(1e-12) / cells_along.max(1) as f64;
        let cells = [
            cells_along.max(1) as usize,
            (((hi[1] - lo[1]) / cell).ceil() as usize).max(1),
        ];
        let nc = cells[0] * cells[1];
        let fields = (0..phases)
            .map(|k| PhaseField {
                phase_rad: 2.0 * PI * k as f64 / phases as f64,
                speed_sum: vec![0.0; nc],
                vel_sum: vec![[0.0; 2]; nc],
                count: vec![0; nc],
            })
            .collect();
        Self {
            axes,
            excitation_up,
            gravity_free: g.norm() == 0.0,
            origin_m: lo,
            cell_m: cell,
            cells,
            velocity_amplitude_m_s: v_amp,
            fields,
            trajectory_particles,
            trajectories: Vec::new(),
            vtk: None,
            vtk_frames: Vec::new(),
            error: None,
            force_displacement: Vec::new(),
            container_extent_m,
            omega_rad_s: 2.0 * PI * frequency_hz,
            prev_phase: 0.0,
            prev_theta: 0.0,
            vtk_cycle: u32::MAX,
            traj_every: ((steps_per_cycle / 200.0).floor() as u64).max(1),
            fd_slot: -1,
            fd_work: (0.0, None),
        }
    }

    /// Adds this step's work on the bed and appends the force–displacement row of this step
    /// when it is the first at or after a sample instant (see [`Self::force_displacement`]);
    /// no allocation beyond the growing record.
    fn record_force_displacement(&mut self, w: &World, cycle: u32, damper: &Damper) {
        let per_cycle = FD_SAMPLES_PER_CYCLE as i64;
        let b = &w.bodies[damper.container];
        let e = damper.direction;
        let x = (b.state.position_m - b.reference.position_m).dot(&e);
        let v = b.state.velocity_m_s.dot(&e);
        let f_p = b.contact_force_n.dot(&e);
        let power = -f_p * v;
        let (work, prev) = &mut self.fd_work;
        *work += match *prev {
            Some((t0, p0)) => 0.5 * (p0 + power) * (w.time_s - t0),
            None => power * w.time_s,
        };
        *prev = Some((w.time_s, power));
        // A new cycle opens with the closing row of the previous one.
        if self.fd_slot == cycle as i64 * per_cycle
            && let Some(last) = self.force_displacement.last()
            && last[1] < cycle as f64
        {
            let mut row = *last;
            row[1] = cycle as f64;
            self.force_displacement.push(row);
        }
        // Slot of this step; the 1e-6 puts the step that ends a cycle (t = kT up to rounding)
        // into the slot of the boundary.
        let slot =
            (self.omega_rad_s * w.time_s / (2.0 * PI) * per_cycle as f64 + 1e-6).floor() as i64;
        if slot <= self.fd_slot {
            return;
        }
        self.fd_slot = slot;
        // ẍ = −Ω² x for x = X sin Ωt [D Eq. 3.8–3.10].
        let a = -self.omega_rad_s * self.omega_rad_s * x;
        self.force_displacement.push([
            w.time_s,
            cycle as f64,
            x,
            v,
            f_p,
            damper.container_mass_kg * a - f_p,
            self.fd_work.0,
        ]);
    }

    /// Mean work of the container on the bed per cycle over the cycles `from_cycle..`,
    /// ∮(−f_p) dx by the trapezoidal rule over each cycle's rows of
    /// [`Self::force_displacement`], J: the area of the hysteresis loops, equal to the
    /// dissipated energy per cycle Ẽ_diss of the complex power method [D Eq. 3.13] up to the
    /// sampling (and to the ledger's dissipation in a steady state). Cycles without rows at
    /// both of their boundaries (the first one) are left out; `None` without a complete cycle.
    pub fn loop_work_per_cycle_j(&self, from_cycle: u32) -> Option<f64> {
        let rows = &self.force_displacement;
        let mut total = 0.0;
        let mut cycles = 0u32;
        let mut k = 0;
        while k < rows.len() {
            let c = rows[k][1];
            let end = k + rows[k..].iter().take_while(|r| r[1] == c).count();
            // Complete cycles only: rows at both of the cycle's boundaries.
            let at = |t: f64, n: f64| (self.omega_rad_s * t / (2.0 * PI) - n).abs() < 1e-6;
            let closed = at(rows[k][0], c) && at(rows[end - 1][0], c + 1.0);
            if c >= from_cycle as f64 && closed && end - k >= 2 {
                total += rows[k..end]
                    .windows(2)
                    .map(|w| -0.5 * (w[0][4] + w[1][4]) * (w[1][2] - w[0][2]))
                    .sum::<f64>();
                cycles += 1;
            }
            k = end;
        }
        (cycles > 0).then(|| total / cycles as f64)
    }

    fn accumulate(&mut self, w: &World, k: usize, container_pos: &Vec3) {
        let p = &w.particles;
        let v_amp = self.velocity_amplitude_m_s.max(1e-300);
        let f = &mut self.fields[k];
        for i in 0..p.len() {
            let rel = p.position[i] - container_pos;
            let c0 = ((rel.dot(&self.axes[0]) - self.origin_m[0]) / self.cell_m).floor();
            let c1 = ((rel.dot(&self.axes[1]) - self.origin_m[1]) / self.cell_m).floor();
            if c0 < 0.0 || c1 < 0.0 {
                continue;
            }
            let (c0, c1) = (c0 as usize, c1 as usize);
            if c0 >= self.cells[0] || c1 >= self.cells[1] {
                continue;
            }
            let c = c1 * self.cells[0] + c0;
            let v = p.velocity[i];
            f.speed_sum[c] += v.norm() / v_amp;
            f.vel_sum[c][0] += v.dot(&self.axes[0]) / v_amp;
            f.vel_sum[c][1] += v.dot(&self.axes[1]) / v_amp;
            f.count[c] += 1;
        }
    }

    /// Cell centre (axis 0, axis 1) of cell `c`, m.
    pub fn cell_center(&self, c: usize) -> [f64; 2] {
        let (c0, c1) = (c % self.cells[0], c / self.cells[0]);
        [
            self.origin_m[0] + (c0 as f64 + 0.5) * self.cell_m,
            self.origin_m[1] + (c1 as f64 + 0.5) * self.cell_m,
        ]
    }
}

/// What a [`MotionRecorder`] has gathered so far (kept in a damper point's checkpoint).
#[derive(serde::Serialize, serde::Deserialize)]
struct RecorderState {
    fields: Vec<PhaseField>,
    trajectories: Vec<[f64; 5]>,
    vtk_frames: Vec<(f64, String)>,
    error: Option<String>,
    prev_phase: f64,
    prev_theta: f64,
    vtk_cycle: u32,
    force_displacement: Vec<[f64; 7]>,
    fd_slot: i64,
    fd_work: (f64, Option<(f64, f64)>),
}

impl PointObserver for MotionRecorder {
    fn save_state(&self) -> Result<Vec<u8>, crate::DesignError> {
        pdamp_io::checkpoint::encode_part(&RecorderState {
            fields: self.fields.clone(),
            trajectories: self.trajectories.clone(),
            vtk_frames: self.vtk_frames.clone(),
            error: self.error.clone(),
            prev_phase: self.prev_phase,
            prev_theta: self.prev_theta,
            vtk_cycle: self.vtk_cycle,
            force_displacement: self.force_displacement.clone(),
            fd_slot: self.fd_slot,
            fd_work: self.fd_work,
        })
        .map_err(crate::DesignError::from)
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), crate::DesignError> {
        let s: RecorderState =
            pdamp_io::checkpoint::decode_part(bytes).map_err(crate::DesignError::from)?;
        if s.fields.len() != self.fields.len()
            || s.fields
                .iter()
                .zip(&self.fields)
                .any(|(a, b)| a.count.len() != b.count.len())
        {
            return Err(crate::DesignError::CheckpointFieldGrid);
        }
        self.fields = s.fields;
        self.trajectories = s.trajectories;
        self.vtk_frames = s.vtk_frames;
        self.error = s.error;
        self.prev_phase = s.prev_phase;
        self.prev_theta = s.prev_theta;
        self.vtk_cycle = s.vtk_cycle;
        self.force_displacement = s.force_displacement;
        self.fd_slot = s.fd_slot;
        self.fd_work = s.fd_work;
        Ok(())
    }

    fn on_step(&mut self, w: &World, cycle: u32, phase: f64, damper: &Damper) {
        self.record_force_displacement(w, cycle, damper);
        let prev = self.prev_phase;
        self.prev_phase = phase;
        if cycle < damper.transient_cycles {
            self.prev_theta = self.omega_rad_s * w.time_s;
            return;
        }
        let container_pos = w.bodies[damper.container].state.position_m;
        // Continuous phase θ = Ωt: phase k is crossed when ⌊(θ − φ_k)/2π⌋ grows (robust at the
        // exact cycle boundaries where θ mod 2π may read 0 or 2π).
        let theta = self.omega_rad_s * w.time_s;
        let theta_prev = std::mem::replace(&mut self.prev_theta, theta);
        for k in 0..self.fields.len() {
            let target = self.fields[k].phase_rad;
            let before = ((theta_prev - target) / (2.0 * PI) + 1e-9).floor();
            let after = ((theta - target) / (2.0 * PI) + 1e-9).floor();
            if after > before {
                self.accumulate(w, k, &container_pos);
            }
        }
        if !self.trajectory_particles.is_empty() && w.counters.steps.is_multiple_of(self.traj_every)
        {
            for &i in &self.trajectory_particles {
                if i < w.particles.len() {
                    let r = w.particles.position[i] - container_pos;
                    self.trajectories.push([i as f64, w.time_s, r.x, r.y, r.z]);
                }
            }
        }
        if let Some((dir, frames)) = &self.vtk
            && (cycle + 1 == damper.cycles || damper.convergence.is_some())
            && *frames > 0
        {
            if self.vtk_cycle != cycle {
                self.vtk_cycle = cycle;
                self.vtk_frames.clear();
            }
            let slot = (phase / (2.0 * PI) * *frames as f64).floor();
            let prev_slot = (prev / (2.0 * PI) * *frames as f64).floor();
            if slot != prev_slot || self.vtk_frames.is_empty() {
                let idx = self.vtk_frames.len();
                match pdamp_scenario::run::write_snapshot(w, dir, idx) {
                    Ok(f) => self
                        .vtk_frames
                        .push((w.time_s, f.to_string_lossy().into_owned())),
                    Err(e) => {
                        if self.error.is_none() {
                            self.error = Some(e.to_string());
                        }
                    }
                }
            }
        }
    }
}
