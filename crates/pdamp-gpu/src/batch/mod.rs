//! A batch of independent DEM worlds advanced together on the GPU.

mod laws;
mod setup;

use crate::GpuError;
use pdamp_dem::{EnergyLedger, Motion, RigidBody, Vec3};

pub use self::laws::check_world;

/// Steps encoded per submission (the body-state table holds this many rows per body).
const CHUNK_STEPS: usize = 256;
/// Threads per workgroup of the particle and cell kernels (`WG` in dem.wgsl).
const WG: u32 = 256;
/// f64 parameters per contact law (`LAW_F` in dem.wgsl).
const LAW_F: usize = 16;
/// Number of storage bindings of the kernels.
const BINDINGS: u32 = 26;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    n_mat: u32,
    max_nb: u32,
    max_c: u32,
    max_wc: u32,
    n_cells: u32,
    cell_cap: u32,
    n_bodies: u32,
    off_wall_f: u32,
    off_law_f: u32,
    off_body: u32,
    off_world_u: u32,
    off_wall_u: u32,
    off_law_u: u32,
    n_worlds: u32,
    off_wstep: u32,
    skin: f64,
    pad: f64,
}

/// How far a world goes in the next `GpuBatch` run.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Target {
    /// This many steps of the nominal time step.
    Steps(u64),
    /// Until this time, the last step shortened to end on it (as `World::run_until`).
    Until(f64),
}

/// The single-bin DFT of a body's load over a time window [D Eq. 3.12–3.17].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sampling {
    body: usize,
    omega: f64,
    t_start: f64,
    t_end: f64,
}

/// Device memory a batch needs, computed before anything is allocated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryEstimate {
    /// All buffers together, bytes.
    pub total_bytes: u64,
    /// The largest single buffer, bytes.
    pub largest_buffer_bytes: u64,
    /// `total_bytes` per particle, bytes.
    pub bytes_per_particle: f64,
    /// Particle–particle contacts kept per particle.
    pub contacts_per_particle: u32,
    /// Neighbour-list entries per particle.
    pub neighbors_per_particle: u32,
}

/// State of one world read back from the device.
#[derive(Debug, Clone)]
pub struct GpuSnapshot {
    /// Simulated time, s.
    pub time_s: f64,
    /// Particle centres, m.
    pub position: Vec<Vec3>,
    /// Velocities, m/s.
    pub velocity: Vec<Vec3>,
    /// Angular velocities, rad/s.
    pub angular_velocity: Vec<Vec3>,
    /// Forces of the last evaluation, N.
    pub force: Vec<Vec3>,
    /// Torques of the last evaluation, N·m.
    pub torque: Vec<Vec3>,
    /// Energy ledger: the CPU world's at hand-over plus everything booked on the device.
    pub ledger: EnergyLedger,
    /// Force of the particles on all bodies of the world together (last evaluation), N.
    pub body_force_n: Vec3,
    /// Torque of the particles on all bodies about each body's position, summed, N·m.
    pub body_torque_nm: Vec3,
}

struct WorldMeta {
    first: usize,
    n: usize,
    bodies: Vec<RigidBody>,
    body_offset: usize,
    time_s: f64,
    dt_s: f64,
    target: Target,
    sampling: Option<Sampling>,
    sample_times: Vec<f64>,
    steps: u64,
    ledger0: EnergyLedger,
    stepped: bool,
    gravity: Vec3,
}

struct Pipes {
    drift: wgpu::ComputePipeline,
    decide: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    bin: wgpu::ComputePipeline,
    sort: wgpu::ComputePipeline,
    neighbors: wgpu::ComputePipeline,
    forces: wgpu::ComputePipeline,
    kick: wgpu::ComputePipeline,
}

/// Independent worlds on one device (see the crate docs).
pub struct GpuBatch {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipes: Pipes,
    groups: [wgpu::BindGroup; 2],
    args_group: wgpu::BindGroup,
    pos: wgpu::Buffer,
    vel: wgpu::Buffer,
    omg: wgpu::Buffer,
    frc: wgpu::Buffer,
    trq: wgpu::Buffer,
    ledger: wgpu::Buffer,
    ctrl: wgpu::Buffer,
    args: wgpu::Buffer,
    tab_f: wgpu::Buffer,
    off_body: u64,
    off_wstep: u64,
    worlds: Vec<WorldMeta>,
    n: usize,
    n_bodies: usize,
    parity: usize,
    memory: MemoryEstimate,
    caps: (u32, u32, u32, u32),
    failed: Option<String>,
    builds: u64,
}

impl std::fmt::Debug for GpuBatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuBatch")
            .field("worlds", &self.worlds.len())
            .field("particles", &self.n)
            .finish()
    }
}

fn v4(a: &Vec3, w: f64) -> [f64; 4] {
    [a.x, a.y, a.z, w]
}

impl GpuBatch {
    /// Memory the batch uses on the device.
    pub fn memory(&self) -> MemoryEstimate {
        self.memory
    }

    /// Particles of all worlds.
    pub fn num_particles(&self) -> usize {
        self.n
    }

    /// Worlds in the batch.
    pub fn num_worlds(&self) -> usize {
        self.worlds.len()
    }

    /// Neighbour-list builds so far (all worlds rebuild together).
    pub fn neighbor_builds(&self) -> u64 {
        self.builds
    }

    /// Simulated time of world `w`, s.
    pub fn time_s(&self, w: usize) -> f64 {
        self.worlds[w].time_s
    }

    /// Gives body `body` of world `w` a new motion law (e.g. the excitation after settling in a
    /// container at rest); it takes effect from the next step, relative to the body's reference
    /// pose.
    pub fn set_motion(&mut self, w: usize, body: usize, motion: Motion) -> Result<(), GpuError> {
        let b = self.worlds[w]
            .bodies
            .get_mut(body)
            .ok_or_else(|| GpuError::Body {
                world: w,
                body: format!("#{body}"),
                what: "no such body".into(),
            })?;
        if matches!(motion, Motion::Driven) {
            return Err(GpuError::Unsupported {
                world: w,
                what: format!("body '{}' driven from outside (coupling)", b.name),
            });
        }
        b.motion = motion;
        Ok(())
    }

    /// Sets the clock of world `w` back to 0 and puts its bodies at their pose of t = 0 (the
    /// particles stay where they are), as `World::restart_clock` does after settling.
    pub fn restart_clock(&mut self, w: usize) {
        let meta = &mut self.worlds[w];
        meta.time_s = 0.0;
        for b in meta.bodies.iter_mut() {
            let s = b.prescribed_state(0.0);
            b.state = s;
            b.previous = s;
        }
    }

    /// Advances every world by `steps` velocity-Verlet steps of its own time step, then checks
    /// the device's error flags (non-finite states, exceeded capacities).
    pub fn step(&mut self, steps: u64) -> Result<(), GpuError> {
        for w in &mut self.worlds {
            w.target = Target::Steps(steps);
        }
        self.advance()
    }

    /// Advances every world `w` until its clock reaches `t_end_s[w]`, with its own time step and
    /// the last step shortened to end on the time, as `World::run_until` does (worlds that are
    /// already there do not move); then checks the error flags.
    pub fn run_until(&mut self, t_end_s: &[f64]) -> Result<(), GpuError> {
        assert_eq!(t_end_s.len(), self.worlds.len(), "one end time per world");
        for (w, &t) in self.worlds.iter_mut().zip(t_end_s) {
            w.target = Target::Until(t);
        }
        self.advance()
    }

    /// Sets the nominal time step of world `w`, s.
    pub fn set_time_step(&mut self, w: usize, dt_s: f64) {
        self.worlds[w].dt_s = dt_s;
    }

    /// Nominal time step of world `w`, s.
    pub fn time_step_s(&self, w: usize) -> f64 {
        self.worlds[w].dt_s
    }

    /// Steps world `w` has taken on the device.
    pub fn steps(&self, w: usize) -> u64 {
        self.worlds[w].steps
    }

    /// From now on only body `body` of world `w` counts in the loads read back, and its load
    /// (the force of the particles on it) is transformed into the single-bin DFT at angular
    /// frequency `omega_rad_s` over the samples from `t_start_s` to `t_end_s`, trapezoidal over
    /// the steps — the sums `harmonic_amplitude` of the complex power method [D Eq. 3.12] forms,
    /// accumulated on the device per particle (see [`GpuBatch::load_dft`]).
    pub fn set_load_sampling(
        &mut self,
        w: usize,
        body: usize,
        omega_rad_s: f64,
        t_start_s: f64,
        t_end_s: f64,
    ) {
        let m = &mut self.worlds[w];
        assert!(body < m.bodies.len(), "world {w} has no body {body}");
        m.sampling = Some(Sampling {
            body,
            omega: omega_rad_s,
            t_start: t_start_s,
            t_end: t_end_s,
        });
        m.sample_times.clear();
    }

    /// The load DFT of world `w` (see [`GpuBatch::set_load_sampling`]): the sample times and
    /// the sums Σ ½h (F₀ cos Ωt₀ + F₁ cos Ωt₁) and −Σ ½h (F₀ sin Ωt₀ + F₁ sin Ωt₁) of the force F of
    /// the particles on the body, N·s. `2 / (t_last − t_first)` times these is the complex
    /// amplitude of the body's load.
    pub fn load_dft(&self, w: usize) -> Result<(Vec<f64>, Vec3, Vec3), GpuError> {
        let meta = &self.worlds[w];
        let led: Vec<[f64; 4]> = self.read(
            &self.ledger,
            meta.first as u64 * 192,
            (meta.n as u64 * 192).max(32),
        )?;
        let (mut re, mut im) = (Vec3::zeros(), Vec3::zeros());
        for i in 0..meta.n {
            let (a, b) = (&led[6 * i + 4], &led[6 * i + 5]);
            // rows hold the force on the particles: the body receives the opposite
            re -= Vec3::new(a[0], a[1], a[2]);
            im -= Vec3::new(b[0], b[1], b[2]);
        }
        Ok((meta.sample_times.clone(), re, im))
    }

    fn advance(&mut self) -> Result<(), GpuError> {
        if let Some(e) = &self.failed {
            return Err(GpuError::Device(format!("the batch failed earlier: {e}")));
        }
        let before: Vec<f64> = self.worlds.iter().map(|w| w.time_s).collect();
        loop {
            let k = self.fill_tables()?;
            if k == 0 {
                break;
            }
            self.queue
                .write_buffer(&self.ctrl, 4, bytemuck::bytes_of(&0u32));
            let mut enc = self.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                let pw = (self.n as u32).div_ceil(WG);
                for _ in 0..k {
                    pass.set_bind_group(0, &self.groups[self.parity], &[]);
                    pass.set_pipeline(&self.pipes.drift);
                    pass.dispatch_workgroups(pw, 1, 1);
                    pass.set_pipeline(&self.pipes.decide);
                    pass.set_bind_group(1, &self.args_group, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                    pass.set_pipeline(&self.pipes.clear);
                    pass.dispatch_workgroups_indirect(&self.args, 0);
                    pass.set_pipeline(&self.pipes.bin);
                    pass.dispatch_workgroups_indirect(&self.args, 12);
                    pass.set_pipeline(&self.pipes.sort);
                    pass.dispatch_workgroups_indirect(&self.args, 0);
                    pass.set_pipeline(&self.pipes.neighbors);
                    pass.dispatch_workgroups_indirect(&self.args, 12);
                    pass.set_pipeline(&self.pipes.forces);
                    pass.dispatch_workgroups(pw, 1, 1);
                    pass.set_pipeline(&self.pipes.kick);
                    pass.dispatch_workgroups(pw, 1, 1);
                    self.parity ^= 1;
                }
            }
            self.queue.submit([enc.finish()]);
        }
        let ctrl: Vec<u32> = self.read(&self.ctrl, 0, 32)?;
        self.builds = ctrl[2] as u64;
        if ctrl[3] != 0 {
            let g = ctrl[4] as usize;
            let k = self
                .worlds
                .iter()
                .position(|w| g >= w.first && g < w.first + w.n)
                .unwrap_or(0);
            let (world, particle, time_s) = (
                k,
                g.saturating_sub(self.worlds[k].first),
                self.worlds[k].time_s,
            );
            let (max_c, max_nb, max_wc, cell_cap) = self.caps;
            let flags = ctrl[3];
            let err = if flags & 4 != 0 {
                GpuError::NonFinite {
                    world,
                    particle,
                    time_s,
                    last_good_s: before[k],
                }
            } else {
                let (what, capacity) = if flags & 1 != 0 {
                    ("particles in one neighbour cell", cell_cap)
                } else if flags & 2 != 0 {
                    ("neighbour-list entries", max_nb)
                } else if flags & 8 != 0 {
                    ("particle contacts", max_c)
                } else {
                    ("wall contacts", max_wc)
                };
                GpuError::Capacity {
                    world,
                    particle,
                    time_s,
                    what,
                    capacity,
                }
            };
            self.failed = Some(err.to_string());
            return Err(err);
        }
        Ok(())
    }

    /// The per-step tables of the next launch (up to `CHUNK_STEPS` steps): every world's time
    /// step and whether it steps, its bodies' poses and step velocities (the CPU engine's own
    /// motion laws evaluated here: the rows `World::step` would use), and the DFT weights of
    /// its load. Returns the number of steps in which some world moves (0: all are done).
    fn fill_tables(&mut self) -> Result<usize, GpuError> {
        let nw = self.worlds.len();
        let mut body = vec![[0.0f64; 4]; 2 * CHUNK_STEPS * self.n_bodies];
        let mut wstep = vec![[0.0f64; 4]; 2 * CHUNK_STEPS * nw];
        let mut used = 0usize;
        for (wk, w) in self.worlds.iter_mut().enumerate() {
            for s in 0..CHUNK_STEPS {
                let h = match &mut w.target {
                    Target::Steps(0) => None,
                    Target::Steps(r) => {
                        *r -= 1;
                        Some(w.dt_s)
                    }
                    Target::Until(t_end) => {
                        let tol = 1e-12 * t_end.abs().max(1e-300);
                        (w.time_s < *t_end - tol).then(|| w.dt_s.min(*t_end - w.time_s))
                    }
                };
                let Some(h) = h else {
                    wstep[2 * (s * nw + wk)] = [w.dt_s, 0.0, 0.0, 0.0];
                    continue;
                };
                used = used.max(s + 1);
                w.stepped = true;
                w.steps += 1;
                let (t0, t1) = (w.time_s, w.time_s + h);
                for (bi, b) in w.bodies.iter_mut().enumerate() {
                    b.previous = b.state;
                    b.state = b.prescribed_state(t1);
                    if b.state.orientation != pdamp_dem::math::Rotation::identity()
                        || b.state.angular_velocity_rad_s != Vec3::zeros()
                    {
                        return Err(GpuError::Body {
                            world: wk,
                            body: b.name.clone(),
                            what: format!(
                                "rotates at t = {t1} s; the GPU kernels take translating bodies only"
                            ),
                        });
                    }
                    let st = b.step_state(h);
                    let flag = match w.sampling {
                        Some(sm) if sm.body != bi => 0.0,
                        _ => 1.0,
                    };
                    let row = s * self.n_bodies + w.body_offset + bi;
                    body[2 * row] = v4(&st.position_m, 0.0);
                    body[2 * row + 1] = v4(&st.velocity_m_s, flag);
                }
                wstep[2 * (s * nw + wk)] = [h, 1.0, 0.0, 0.0];
                if let Some(sm) = w.sampling {
                    let tol = 1e-9 * h;
                    if t0 >= sm.t_start - tol && t1 <= sm.t_end + tol {
                        let (s0, c0) = (sm.omega * t0).sin_cos();
                        let (s1, c1) = (sm.omega * t1).sin_cos();
                        wstep[2 * (s * nw + wk) + 1] =
                            [0.5 * h * c0, -0.5 * h * s0, 0.5 * h * c1, -0.5 * h * s1];
                        if w.sample_times.is_empty() {
                            w.sample_times.push(t0);
                        }
                        w.sample_times.push(t1);
                    }
                }
                w.time_s = t1;
            }
        }
        if used > 0 {
            let nb = 2 * used * self.n_bodies;
            self.queue.write_buffer(
                &self.tab_f,
                self.off_body * 32,
                bytemuck::cast_slice(&body[..nb]),
            );
            // (rows of steps past `used` are never read)
            self.queue.write_buffer(
                &self.tab_f,
                self.off_wstep * 32,
                bytemuck::cast_slice(&wstep[..2 * used * nw]),
            );
        }
        Ok(used)
    }

    fn read<T: bytemuck::Pod>(
        &self,
        buf: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> Result<Vec<T>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buf, offset, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(format!("waiting for the device: {e}")))?;
        let view = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Device(format!("reading back: {e}")))?;
        let out = bytemuck::cast_slice::<u8, T>(&view).to_vec();
        Ok(out)
    }

    fn read_vec3(&self, buf: &wgpu::Buffer, w: &WorldMeta) -> Result<Vec<[f64; 4]>, GpuError> {
        self.read(buf, w.first as u64 * 32, (w.n as u64 * 32).max(32))
            .map(|mut v: Vec<[f64; 4]>| {
                v.truncate(w.n);
                v
            })
    }

    /// Reads world `w` back from the device.
    pub fn snapshot(&self, w: usize) -> Result<GpuSnapshot, GpuError> {
        let meta = &self.worlds[w];
        let to3 = |v: &[f64; 4]| Vec3::new(v[0], v[1], v[2]);
        let pos = self.read_vec3(&self.pos, meta)?;
        let vel = self.read_vec3(&self.vel, meta)?;
        let omg = self.read_vec3(&self.omg, meta)?;
        let frc = self.read_vec3(&self.frc, meta)?;
        let trq = self.read_vec3(&self.trq, meta)?;
        let led: Vec<[f64; 4]> = self.read(
            &self.ledger,
            meta.first as u64 * 192,
            (meta.n as u64 * 192).max(32),
        )?;
        let mut ledger = meta.ledger0;
        let mut sums = [0.0f64; 6];
        for i in 0..meta.n {
            for (k, s) in sums.iter_mut().enumerate() {
                *s += led[6 * i + k / 4][k % 4];
            }
        }
        ledger.dissipated_normal_pp_j += sums[0];
        ledger.dissipated_tangential_pp_j += sums[1];
        ledger.dissipated_normal_pw_j += sums[2];
        ledger.dissipated_tangential_pw_j += sums[3];
        ledger.wall_work_j += sums[4];
        if meta.stepped {
            ledger.elastic_j = sums[5];
        }
        let (mut kin, mut pot) = (0.0, 0.0);
        let g = meta.gravity;
        let (mut bf, mut bt) = (Vec3::zeros(), Vec3::zeros());
        for i in 0..meta.n {
            let (m, jinv) = (vel[i][3], omg[i][3]);
            let (v, om, x) = (to3(&vel[i]), to3(&omg[i]), to3(&pos[i]));
            kin += 0.5 * m * v.norm_squared() + 0.5 * om.norm_squared() / jinv;
            pot += m * g.dot(&x);
            bf -= to3(&led[6 * i + 2]);
            bt += to3(&led[6 * i + 3]);
        }
        ledger.kinetic_j = kin;
        ledger.potential_j = -pot;
        Ok(GpuSnapshot {
            time_s: meta.time_s,
            position: pos.iter().map(to3).collect(),
            velocity: vel.iter().map(to3).collect(),
            angular_velocity: omg.iter().map(to3).collect(),
            force: frc.iter().map(to3).collect(),
            torque: trq.iter().map(to3).collect(),
            ledger,
            body_force_n: bf,
            body_torque_nm: bt,
        })
    }
}
