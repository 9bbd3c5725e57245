//! A batch of independent DEM worlds advanced together on the GPU.

use crate::{GpuDevice, GpuError, GpuFeature, GpuUnsupported};
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw, hertz::gonthier_damping};
use pdamp_dem::walls::Geometry;
use pdamp_dem::{EnergyLedger, Integrator, Motion, RigidBody, Vec3, World};
use wgpu::util::DeviceExt;

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

/// Parameters of one contact law for the kernels: `LAW_F` numbers and the kinds.
fn law_row_with_table(
    model: &ContactModel,
    el: &pdamp_dem::interaction::PairElastic,
    tables: &mut Vec<f64>,
) -> Result<([f64; LAW_F], [u32; 4]), GpuFeature> {
    if let NormalLaw::GonthierTable {
        impact_velocities_m_s,
        restitutions,
        ..
    } = &model.normal
    {
        // A plain Gonthier row, then the kind, the table's place (relative to the tables,
        // made absolute when the tables are laid out) and its length.
        let plain = ContactModel {
            normal: NormalLaw::Gonthier {
                restitution: model.normal.restitution(),
                min_impact_velocity_m_s: model.normal.min_impact_velocity_m_s(),
            },
            ..model.clone()
        };
        let (mut f, mut u) = law_row(&plain, el)?;
        u[0] = 2;
        f[14] = tables.len() as f64;
        f[15] = impact_velocities_m_s.len() as f64;
        for (v, e) in impact_velocities_m_s.iter().zip(restitutions) {
            tables.extend([*v, *e]);
        }
        return Ok((f, u));
    }
    law_row(model, el)
}

fn law_row(
    model: &ContactModel,
    el: &pdamp_dem::interaction::PairElastic,
) -> Result<([f64; LAW_F], [u32; 4]), GpuFeature> {
    if model.rolling.is_some() {
        return Err(GpuFeature::RollingResistance);
    }
    if model.adhesion.is_some() {
        return Err(GpuFeature::Adhesion);
    }
    let mut f = [0.0; LAW_F];
    let mut u = [0u32; 4];
    f[0] = el.e_eff_pa;
    f[1] = el.g_eff_pa;
    f[2] = el.poisson_mean;
    let e = model.normal.restitution();
    f[3] = e;
    let l = e.ln();
    let beta = l / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt();
    f[4] = -2.0 * (5.0_f64 / 6.0).sqrt() * beta;
    f[9] = model.normal.min_impact_velocity_m_s();
    match model.normal {
        NormalLaw::Hertz => u[0] = 0,
        NormalLaw::Gonthier { restitution, .. } => {
            u[0] = 1;
            f[5] = gonthier_damping(restitution) / restitution;
        }
        NormalLaw::GonthierTable { .. } => unreachable!("handled by law_row_with_table"),
        NormalLaw::LankaraniNikravesh { restitution, .. } => {
            u[0] = 3;
            f[6] = 0.75 * (1.0 - restitution * restitution);
        }
        NormalLaw::Linear {
            stiffness_n_m,
            restitution,
            clip_attractive,
        } => {
            u[0] = 4;
            f[7] = stiffness_n_m;
            let l = restitution.ln();
            f[8] = 2.0 * l.abs() / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt();
            u[2] = clip_attractive as u32;
        }
        NormalLaw::HertzMindlin {
            clip_attractive, ..
        } => {
            u[0] = 5;
            u[2] = clip_attractive as u32;
        }
    }
    match model.friction {
        FrictionLaw::Frictionless => u[1] = 0,
        FrictionLaw::RegularizedSliding {
            friction_coefficient,
            regularization_s_m,
        } => {
            u[1] = 1;
            f[10] = friction_coefficient;
            f[11] = regularization_s_m;
        }
        FrictionLaw::CoulombSpring {
            friction_coefficient,
            stiffness_ratio,
            damping_ratio,
        } => {
            u[1] = 2;
            f[10] = friction_coefficient;
            let nu = el.poisson_mean;
            f[12] = stiffness_ratio.unwrap_or((1.0 - nu) / (1.0 - 0.5 * nu));
            f[13] = damping_ratio;
        }
        FrictionLaw::Mindlin {
            friction_coefficient,
        } => {
            u[1] = 3;
            f[10] = friction_coefficient;
        }
    }
    Ok((f, u))
}

/// Kernel description of one wall: kind, three rows of geometry, two-sided flag.
fn wall_rows(g: &Geometry) -> Result<(u32, [[f64; 4]; 3], u32), GpuFeature> {
    let v = |a: &Vec3, w: f64| [a.x, a.y, a.z, w];
    Ok(match g {
        Geometry::Plane(p) => (
            0,
            [v(&p.point_m, 0.0), v(&p.normal, 0.0), [0.0; 4]],
            p.two_sided as u32,
        ),
        Geometry::BoxInside(b) => (
            1,
            [v(&b.center_m, 0.0), v(&b.half_extents_m, 0.0), [0.0; 4]],
            0,
        ),
        Geometry::CylinderInside(c) => (
            2,
            [
                v(&c.base_center_m, 0.0),
                v(&c.axis, 0.0),
                [c.radius_m, c.length_m, 0.0, 0.0],
            ],
            0,
        ),
        Geometry::CylinderOutside(_) => return Err(GpuFeature::CylinderOutside),
        Geometry::Mesh(_) => return Err(GpuFeature::MeshWall),
    })
}

/// Whether the GPU kernels can run `world` (integrator, walls, body motions, contact laws,
/// external forces); the error says what they lack, naming the wall, body or materials. Cheap:
/// call it before preparing a bed for the GPU.
pub fn check_world(world: &World) -> Result<(), GpuUnsupported> {
    if !matches!(world.integrator, Integrator::VelocityVerlet) {
        return Err(GpuUnsupported::Integrator);
    }
    if world
        .particles
        .external_force
        .iter()
        .any(|f| *f != Vec3::zeros())
    {
        return Err(GpuUnsupported::ExternalForces);
    }
    for b in &world.bodies {
        if matches!(b.motion, Motion::Driven) {
            return Err(GpuUnsupported::DrivenBody {
                body: b.name.clone(),
            });
        }
        for wall in &b.walls {
            wall_rows(&wall.geometry).map_err(|feature| GpuUnsupported::Wall {
                feature,
                wall: wall.name.clone(),
                body: b.name.clone(),
            })?;
        }
    }
    let n = world.interactions.num_materials();
    let mut tables = Vec::new();
    for a in 0..n {
        for b in 0..n {
            let (model, el) = world.interactions.get(a as u16, b as u16);
            law_row_with_table(model, el, &mut tables).map_err(|feature| {
                GpuUnsupported::ContactLaw {
                    feature,
                    material_a: world.materials[a].name.clone(),
                    material_b: world.materials[b].name.clone(),
                }
            })?;
        }
    }
    Ok(())
}

fn v4(a: &Vec3, w: f64) -> [f64; 4] {
    [a.x, a.y, a.z, w]
}

impl GpuBatch {
    /// Takes over the state of `worlds` (each built, initialised with velocity Verlet and with
    /// no half kick pending): particles, forces, contact histories, bodies, clock and ledger.
    /// The worlds must share materials, contact laws and time step; each keeps its own
    /// particles, walls, motions and gravity. Memory is estimated and checked against the
    /// device's limits before anything is allocated.
    pub fn new(gpu: &GpuDevice, worlds: &[&World]) -> Result<Self, GpuError> {
        let w0 = worlds.first().ok_or_else(|| GpuError::Mismatch {
            world: 0,
            what: "the batch has no world".into(),
        })?;
        let n_mat = w0.interactions.num_materials();
        // Check everything before allocating.
        let mut skin: f64 = 0.0;
        let (mut rmin, mut rmax) = (f64::INFINITY, 0.0f64);
        for (k, w) in worlds.iter().enumerate() {
            let unsupported = |what: String| GpuError::Unsupported { world: k, what };
            check_world(w).map_err(|e| unsupported(e.to_string()))?;
            if w.step_pending() {
                return Err(unsupported(
                    "a world with a half kick pending (call complete_step)".into(),
                ));
            }
            if w.skin_m() <= 0.0 {
                return Err(unsupported(
                    "an uninitialised world (call initialize)".into(),
                ));
            }
            if !(w.dt_s > 0.0 && w.dt_s.is_finite()) {
                return Err(unsupported(format!("time step {} s", w.dt_s)));
            }
            if w.materials != w0.materials || w.interactions.models() != w0.interactions.models() {
                return Err(GpuError::Mismatch {
                    world: k,
                    what: "materials or contact laws".into(),
                });
            }
            skin = skin.max(w.skin_m());
            rmin = rmin.min(w.particles.min_radius());
            rmax = rmax.max(w.particles.max_radius());
        }
        let mut law_f = Vec::with_capacity(n_mat * n_mat * LAW_F);
        let mut law_u = Vec::with_capacity(n_mat * n_mat);
        // The tables after the law rows: the dense d̄(ε)/ε of D Eq. 2.79 at ε = k/4096 (the CPU
        // engine's), then the restitution tables of `gonthier-table` laws.
        let mut tables: Vec<f64> = (1..=4096)
            .map(|k| {
                let e = k as f64 / 4096.0;
                gonthier_damping(e) / e
            })
            .collect();
        for a in 0..n_mat {
            for b in 0..n_mat {
                let (model, el) = w0.interactions.get(a as u16, b as u16);
                let (f, u) = law_row_with_table(model, el, &mut tables).map_err(|feature| {
                    GpuError::Unsupported {
                        world: 0,
                        what: GpuUnsupported::ContactLaw {
                            feature,
                            material_a: w0.materials[a].name.clone(),
                            material_b: w0.materials[b].name.clone(),
                        }
                        .to_string(),
                    }
                })?;
                law_f.extend_from_slice(&f);
                law_u.push(u);
            }
        }
        let n: usize = worlds.iter().map(|w| w.particles.len()).sum();
        if n == 0 {
            return Err(GpuError::Mismatch {
                world: 0,
                what: "no particles".into(),
            });
        }
        // Capacities from the size distribution.
        let q = rmax / rmin;
        let max_c = ((12.0 * (0.5 * (1.0 + q)).powi(2)).ceil() as u32 + 2).min(32);
        let max_nb =
            ((18.0 * ((2.0 * rmax + skin) / (2.0 * rmin)).powi(3)).ceil() as u32).clamp(16, 512);
        let max_wc = 4u32;
        // Neighbour grids, one per world.
        let mut world_f: Vec<[f64; 4]> = Vec::new();
        let mut world_u: Vec<[u32; 4]> = Vec::new();
        let mut wall_f: Vec<[f64; 4]> = Vec::new();
        let mut wall_u: Vec<[u32; 4]> = Vec::new();
        let mut n_cells: u64 = 0;
        let mut max_cell = 0.0f64;
        let mut metas = Vec::new();
        let mut first = 0usize;
        let mut body_offset = 0usize;
        let mut wall_index: Vec<Vec<Vec<u32>>> = Vec::new();
        for w in worlds {
            let p = &w.particles;
            let mut lo = Vec3::repeat(f64::INFINITY);
            let mut hi = Vec3::repeat(f64::NEG_INFINITY);
            for x in &p.position {
                lo = lo.inf(x);
                hi = hi.sup(x);
            }
            for b in &w.bodies {
                for wall in &b.walls {
                    if let Some((a, c)) = wall.geometry.bounding_box() {
                        lo = lo.inf(&(a + b.reference.position_m));
                        hi = hi.sup(&(c + b.reference.position_m));
                    }
                }
            }
            let mut cell = 2.0 * p.max_radius() + skin;
            lo -= Vec3::repeat(cell);
            hi += Vec3::repeat(cell);
            let budget = 4.0 * p.len() as f64 + 64.0;
            let count = |c: f64| ((hi - lo) / c).map(|e| e.ceil().max(1.0));
            let cells = count(cell);
            let total = cells.x * cells.y * cells.z;
            if total > budget {
                cell *= (total / budget).cbrt() * 1.0001;
            }
            let d = count(cell);
            max_cell = max_cell.max(cell);
            world_f.push(v4(&lo, cell));
            world_f.push(v4(&w.gravity_m_s2, 0.0));
            world_u.push([d.x as u32, d.y as u32, d.z as u32, n_cells as u32]);
            n_cells += (d.x * d.y * d.z) as u64;
            let wall_start = wall_u.len() as u32;
            let mut idx = Vec::new();
            for (bi, b) in w.bodies.iter().enumerate() {
                let mut per = Vec::new();
                for wall in &b.walls {
                    let (kind, rows, two) = wall_rows(&wall.geometry).expect("checked above");
                    per.push(wall_u.len() as u32);
                    wall_f.extend_from_slice(&rows);
                    wall_u.push([kind, (body_offset + bi) as u32, wall.material as u32, two]);
                }
                idx.push(per);
            }
            wall_index.push(idx);
            world_u.push([wall_start, wall_u.len() as u32 - wall_start, 0, 0]);
            metas.push(WorldMeta {
                first,
                n: p.len(),
                bodies: w.bodies.clone(),
                body_offset,
                time_s: w.time_s,
                dt_s: w.dt_s,
                target: Target::Steps(0),
                sampling: None,
                sample_times: Vec::new(),
                steps: 0,
                ledger0: w.ledger,
                stepped: false,
                gravity: w.gravity_m_s2,
            });
            first += p.len();
            body_offset += w.bodies.len();
        }
        if n_cells > u32::MAX as u64 / 2 {
            return Err(GpuError::TooLarge {
                what: "neighbour cells".into(),
                needed_bytes: n_cells,
                limit_bytes: u32::MAX as u64 / 2,
            });
        }
        let n_bodies = body_offset.max(1);
        let cell_cap = ((max_cell / (2.0 * rmin) + 1.0).powi(3).ceil() as u32).clamp(4, 1024);
        // Memory, before allocating.
        let nu = n as u64;
        let sizes: Vec<(&str, u64)> = vec![
            ("particle state", 5 * nu * 32 + nu * 16 + nu * 32),
            ("neighbour cells", n_cells * 4 * (1 + cell_cap as u64)),
            ("neighbour lists", nu * 4 * (1 + max_nb as u64)),
            (
                "contacts",
                2 * nu * 4 * (1 + max_c as u64) + 2 * 3 * nu * max_c as u64 * 32,
            ),
            (
                "wall contacts",
                2 * nu * 4 * (1 + max_wc as u64) + 2 * 4 * nu * max_wc as u64 * 32,
            ),
            ("ledger and loads", nu * 192),
            ("body table", (CHUNK_STEPS * n_bodies * 64) as u64),
        ];
        let largest = [
            nu * 32,
            n_cells * 4 * cell_cap as u64,
            nu * 4 * max_nb as u64,
            nu * max_c as u64 * 32,
            nu * max_wc as u64 * 128,
            nu * 192,
        ]
        .into_iter()
        .max()
        .unwrap_or(0);
        let total: u64 = sizes.iter().map(|(_, s)| s).sum();
        let memory = MemoryEstimate {
            total_bytes: total,
            largest_buffer_bytes: largest,
            bytes_per_particle: total as f64 / n as f64,
            contacts_per_particle: max_c,
            neighbors_per_particle: max_nb,
        };
        let limits = gpu.limits();
        let binding_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if largest > binding_limit {
            return Err(GpuError::TooLarge {
                what: "one buffer".into(),
                needed_bytes: largest,
                limit_bytes: binding_limit,
            });
        }
        let wg = n
            .div_ceil(WG as usize)
            .max(n_cells as usize / WG as usize + 1);
        if wg > limits.max_compute_workgroups_per_dimension as usize {
            return Err(GpuError::TooLarge {
                what: "workgroups of one dispatch (particles or cells / 256)".into(),
                needed_bytes: wg as u64,
                limit_bytes: limits.max_compute_workgroups_per_dimension as u64,
            });
        }

        // Host copies of the initial state.
        let mut pos = vec![[0.0f64; 4]; n];
        let mut vel = vec![[0.0f64; 4]; n];
        let mut omg = vec![[0.0f64; 4]; n];
        let mut frc = vec![[0.0f64; 4]; n];
        let mut trq = vec![[0.0f64; 4]; n];
        let mut pinfo = vec![[0u32; 4]; n];
        let mc = max_c as usize;
        let mut c_ids = vec![0u32; n * (mc + 1)];
        let mut c_s = [
            vec![[0.0f64; 4]; n * mc],
            vec![[0.0f64; 4]; n * mc],
            vec![[0.0f64; 4]; n * mc],
        ];
        let mw = max_wc as usize;
        let mut w_keys = vec![0u32; n * (mw + 1)];
        let mut w_st = vec![[0.0f64; 4]; 4 * n * mw];
        // ledger rows; row 2 = the wall load of the last evaluation (the DFT's first sample)
        let mut ledger0 = vec![[0.0f64; 4]; 6 * n];
        for (k, (w, meta)) in worlds.iter().zip(&metas).enumerate() {
            let p = &w.particles;
            for i in 0..p.len() {
                let g = meta.first + i;
                pos[g] = v4(&p.position[i], p.radius[i]);
                vel[g] = v4(&p.velocity[i], p.mass[i]);
                omg[g] = v4(&p.angular_velocity[i], p.inv_inertia[i]);
                frc[g] = v4(&p.force[i], 0.0);
                trq[g] = v4(&p.torque[i], 0.0);
                pinfo[g] = [p.material[i] as u32, k as u32, 0, 0];
            }
            let capacity = |particle: usize, what, capacity| GpuError::Capacity {
                world: k,
                particle,
                time_s: w.time_s,
                what,
                capacity,
            };
            for c in w.particle_contacts() {
                if !c.state.active {
                    continue;
                }
                let s = &c.state;
                let h = &s.history;
                for (a, b, sign) in [(c.i, c.j, 1.0), (c.j, c.i, -1.0)] {
                    let g = meta.first + a as usize;
                    let m = c_ids[g * (mc + 1)] as usize;
                    if m >= mc {
                        return Err(capacity(a as usize, "particle contacts", max_c));
                    }
                    c_ids[g * (mc + 1) + 1 + m] = meta.first as u32 + b;
                    c_s[0][g * mc + m] = v4(&(h.spring_m * sign), h.impact_velocity_m_s);
                    c_s[1][g * mc + m] = v4(&(s.normal_force_prev * sign), s.normal_energy_prev);
                    c_s[2][g * mc + m] =
                        v4(&(s.tangential_force_prev * sign), s.tangential_energy_prev);
                    c_ids[g * (mc + 1)] += 1;
                }
            }
            for (i, slots) in w.wall_contacts().iter().enumerate() {
                let g = meta.first + i;
                for s in slots.iter().filter(|s| s.state.active) {
                    let m = w_keys[g * (mw + 1)] as usize;
                    if m >= mw {
                        return Err(capacity(i, "wall contacts", max_wc));
                    }
                    let wall = wall_index[k][s.body as usize][s.wall as usize];
                    w_keys[g * (mw + 1) + 1 + m] = wall * 8 + s.feature;
                    let st = &s.state;
                    let r = 4 * (g * mw + m);
                    w_st[r] = v4(&st.history.spring_m, st.history.impact_velocity_m_s);
                    w_st[r + 1] = v4(&st.normal_force_prev, st.normal_energy_prev);
                    w_st[r + 2] = v4(&st.tangential_force_prev, st.tangential_energy_prev);
                    w_st[r + 3] = v4(&s.normal, 0.0);
                    w_keys[g * (mw + 1)] += 1;
                    let l = &mut ledger0[6 * g + 2];
                    for (a, f) in l.iter_mut().zip(s.force.iter()) {
                        *a += f;
                    }
                }
            }
        }
        // The f64 and u32 tables (see dem.wgsl).
        let off_wall_f = world_f.len();
        let off_law_f = off_wall_f + wall_f.len();
        let off_tables = off_law_f + law_f.len() / 4;
        for (row, u) in law_f.chunks_mut(LAW_F).zip(&law_u) {
            if u[0] == 2 {
                row[14] += 4.0 * off_tables as f64;
            }
        }
        tables.resize(tables.len().div_ceil(4) * 4, 0.0);
        let off_body = off_tables + tables.len() / 4;
        let mut tab_f = world_f;
        tab_f.extend_from_slice(&wall_f);
        tab_f.extend(law_f.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
        tab_f.extend(tables.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
        let off_wstep = off_body + 2 * CHUNK_STEPS * n_bodies;
        tab_f.resize(off_wstep + 2 * CHUNK_STEPS * worlds.len(), [0.0; 4]);
        let off_world_u = n;
        let off_wall_u = off_world_u + world_u.len();
        let off_law_u = off_wall_u + wall_u.len();
        let mut tab_u = pinfo;
        tab_u.extend_from_slice(&world_u);
        tab_u.extend_from_slice(&wall_u);
        tab_u.extend_from_slice(&law_u);
        let params = Params {
            n: n as u32,
            n_mat: n_mat as u32,
            max_nb,
            max_c,
            max_wc,
            n_cells: n_cells as u32,
            cell_cap,
            n_bodies: n_bodies as u32,
            off_wall_f: off_wall_f as u32,
            off_law_f: off_law_f as u32,
            off_body: off_body as u32,
            off_world_u: off_world_u as u32,
            off_wall_u: off_wall_u as u32,
            off_law_u: off_law_u as u32,
            n_worlds: worlds.len() as u32,
            off_wstep: off_wstep as u32,
            skin,
            pad: 0.0,
        };

        let device = gpu.device.clone();
        let queue = gpu.queue.clone();
        let storage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let init = |label: &str, bytes: &[u8]| {
            let mut v = bytes.to_vec();
            if v.len() < 32 {
                v.resize(32, 0);
            }
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &v,
                usage: storage,
            })
        };
        let zeroed = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(32),
                usage: storage,
                mapped_at_creation: false,
            })
        };
        let b = bytemuck::cast_slice::<[f64; 4], u8>;
        let p_buf = init("params", bytemuck::bytes_of(&params));
        let pos_buf = init("pos", b(&pos));
        let vel_buf = init("vel", b(&vel));
        let omg_buf = init("omg", b(&omg));
        let frc_buf = init("frc", b(&frc));
        let trq_buf = init("trq", b(&trq));
        let tab_f_buf = init("tab_f", b(&tab_f));
        let tab_u_buf = init("tab_u", bytemuck::cast_slice(&tab_u));
        let cell_count = zeroed("cell_count", n_cells * 4);
        let cell_items = zeroed("cell_items", n_cells * 4 * cell_cap as u64);
        let nb = zeroed("nb", nu * 4 * (1 + max_nb as u64));
        let c_a = [
            init("c_ids_a", bytemuck::cast_slice(&c_ids)),
            init("c_s0_a", b(&c_s[0])),
            init("c_s1_a", b(&c_s[1])),
            init("c_s2_a", b(&c_s[2])),
        ];
        let c_b = [
            zeroed("c_ids_b", nu * 4 * (1 + max_c as u64)),
            zeroed("c_s0_b", nu * 32 * max_c as u64),
            zeroed("c_s1_b", nu * 32 * max_c as u64),
            zeroed("c_s2_b", nu * 32 * max_c as u64),
        ];
        let w_a = [
            init("w_keys_a", bytemuck::cast_slice(&w_keys)),
            init("w_st_a", b(&w_st)),
        ];
        let w_b = [
            zeroed("w_keys_b", nu * 4 * (1 + max_wc as u64)),
            zeroed("w_st_b", nu * 128 * max_wc as u64),
        ];
        let ledger = init("ledger", b(&ledger0));
        // ctrl: displacement bits, step, builds, flags, first failing particle, force rebuild
        let ctrl = init(
            "ctrl",
            bytemuck::cast_slice(&[0u32, 0, 0, 0, u32::MAX, 1, 0, 0]),
        );
        let args = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("args"),
            size: 32,
            usage: storage | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let ref_pos = init("ref_pos", b(&pos));

        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pdamp-gpu"),
            entries: &(0..BINDINGS)
                .map(|k| wgpu::BindGroupLayoutEntry {
                    binding: k,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                })
                .collect::<Vec<_>>(),
        });
        let group = |inp: (&[wgpu::Buffer; 4], &[wgpu::Buffer; 2]),
                     out: (&[wgpu::Buffer; 4], &[wgpu::Buffer; 2])| {
            let mut list: Vec<&wgpu::Buffer> = vec![
                &p_buf,
                &pos_buf,
                &vel_buf,
                &omg_buf,
                &frc_buf,
                &trq_buf,
                &tab_f_buf,
                &tab_u_buf,
                &cell_count,
                &cell_items,
                &nb,
            ];
            list.extend(inp.0.iter());
            list.extend(out.0.iter());
            list.extend(inp.1.iter());
            list.extend(out.1.iter());
            list.extend([&ledger, &ctrl, &ref_pos]);
            debug_assert_eq!(list.len(), BINDINGS as usize);
            let entries: Vec<_> = list
                .iter()
                .enumerate()
                .map(|(k, b)| wgpu::BindGroupEntry {
                    binding: k as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pdamp-gpu"),
                layout: &layout,
                entries: &entries,
            })
        };
        let groups = [
            group((&c_a, &w_a), (&c_b, &w_b)),
            group((&c_b, &w_b), (&c_a, &w_a)),
        ];
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("dem.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("dem.wgsl").into()),
        });
        let args_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pdamp-gpu args"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let args_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pdamp-gpu args"),
            layout: &args_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: args.as_entire_binding(),
            }],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pdamp-gpu"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        let pl_decide = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pdamp-gpu decide"),
            bind_group_layouts: &[Some(&layout), Some(&args_layout)],
            ..Default::default()
        });
        let pipe = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(if entry == "decide" { &pl_decide } else { &pl }),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let pipes = Pipes {
            drift: pipe("drift"),
            decide: pipe("decide"),
            clear: pipe("clear_cells"),
            bin: pipe("bin"),
            sort: pipe("sort_cells"),
            neighbors: pipe("neighbors"),
            forces: pipe("forces"),
            kick: pipe("kick"),
        };
        Ok(Self {
            device,
            queue,
            pipes,
            groups,
            args_group,
            pos: pos_buf,
            vel: vel_buf,
            omg: omg_buf,
            frc: frc_buf,
            trq: trq_buf,
            ledger,
            ctrl,
            args,
            tab_f: tab_f_buf,
            off_body: off_body as u64,
            off_wstep: off_wstep as u64,
            worlds: metas,
            n,
            n_bodies,
            parity: 0,
            memory,
            caps: (max_c, max_nb, max_wc, cell_cap),
            failed: None,
            builds: 0,
        })
    }

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
