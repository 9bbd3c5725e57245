//! Setting up a batch ([`GpuBatch::new`]): the checks, the contact-law and wall tables, the
//! neighbour grids, the memory estimate, the host copies of the state, the device buffers,
//! bind groups and pipelines.

use crate::{GpuDevice, GpuError, GpuUnsupported};
use pdamp_dem::contact::hertz::gonthier_damping;
use pdamp_dem::{Vec3, World};
use wgpu::util::DeviceExt;

use super::laws::{check_world, law_row_with_table, wall_rows};
use super::{
    BINDINGS, CHUNK_STEPS, GpuBatch, LAW_F, MemoryEstimate, Params, Pipes, Target, WG, WorldMeta,
    v4,
};

/// Sizes of the kernels' fixed-capacity tables.
#[derive(Debug, Clone, Copy)]
struct Capacities {
    /// Particle–particle contacts per particle.
    max_c: u32,
    /// Neighbour-list entries per particle.
    max_nb: u32,
    /// Wall contacts per particle.
    max_wc: u32,
    /// Particles per neighbour cell.
    cell_cap: u32,
}

/// The contact-law rows (`LAW_F` numbers and four kinds per material pair) and the tables
/// after them.
struct LawTables {
    law_f: Vec<f64>,
    law_u: Vec<[u32; 4]>,
    tables: Vec<f64>,
}

/// Rows of the f64 and u32 tables per world (grid origin, cell size, gravity; grid
/// dimensions, first cell, walls) and per wall.
struct GridTables {
    world_f: Vec<[f64; 4]>,
    world_u: Vec<[u32; 4]>,
    wall_f: Vec<[f64; 4]>,
    wall_u: Vec<[u32; 4]>,
}

/// The neighbour grids and walls of all worlds and where each world's particles and bodies
/// lie in the batch.
struct WorldGrids {
    tables: GridTables,
    n_cells: u64,
    max_cell: f64,
    metas: Vec<WorldMeta>,
    body_offset: usize,
    /// Kernel wall index of wall `[world][body][wall]`.
    wall_index: Vec<Vec<Vec<u32>>>,
}

/// Host copies of the initial state of all particles, contacts and the ledger.
struct HostState {
    pos: Vec<[f64; 4]>,
    vel: Vec<[f64; 4]>,
    omg: Vec<[f64; 4]>,
    frc: Vec<[f64; 4]>,
    trq: Vec<[f64; 4]>,
    pinfo: Vec<[u32; 4]>,
    c_ids: Vec<u32>,
    c_s: [Vec<[f64; 4]>; 3],
    w_keys: Vec<u32>,
    w_st: Vec<[f64; 4]>,
    ledger0: Vec<[f64; 4]>,
}

/// The f64 and u32 tables (see dem.wgsl) and the offsets of their parts.
struct PackedTables {
    tab_f: Vec<[f64; 4]>,
    tab_u: Vec<[u32; 4]>,
    off_wall_f: usize,
    off_law_f: usize,
    off_body: usize,
    off_world_u: usize,
    off_wall_u: usize,
    off_law_u: usize,
    off_wstep: usize,
}

/// The device buffers of a batch (contacts and wall contacts double-buffered: `_a`, `_b`).
struct Buffers {
    params: wgpu::Buffer,
    pos: wgpu::Buffer,
    vel: wgpu::Buffer,
    omg: wgpu::Buffer,
    frc: wgpu::Buffer,
    trq: wgpu::Buffer,
    tab_f: wgpu::Buffer,
    tab_u: wgpu::Buffer,
    cell_count: wgpu::Buffer,
    cell_items: wgpu::Buffer,
    nb: wgpu::Buffer,
    c_a: [wgpu::Buffer; 4],
    c_b: [wgpu::Buffer; 4],
    w_a: [wgpu::Buffer; 2],
    w_b: [wgpu::Buffer; 2],
    ledger: wgpu::Buffer,
    ctrl: wgpu::Buffer,
    args: wgpu::Buffer,
    ref_pos: wgpu::Buffer,
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
        let (skin, rmin, rmax) = check_worlds(worlds, w0)?;
        let laws = law_tables(w0, n_mat)?;
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
        let grids = neighbour_grids(worlds, skin)?;
        let n_bodies = grids.body_offset.max(1);
        let cell_cap = ((grids.max_cell / (2.0 * rmin) + 1.0).powi(3).ceil() as u32).clamp(4, 1024);
        let caps = Capacities {
            max_c,
            max_nb,
            max_wc,
            cell_cap,
        };
        let memory = estimate_memory(gpu, n, grids.n_cells, n_bodies, caps)?;
        let WorldGrids {
            tables: grid_tables,
            n_cells,
            metas,
            wall_index,
            ..
        } = grids;
        let mut host = HostState::gather(worlds, &metas, &wall_index, n, caps)?;
        let pinfo = std::mem::take(&mut host.pinfo);
        let packed = pack_tables(grid_tables, laws, pinfo, n, n_bodies, worlds.len());
        let params = Params {
            n: n as u32,
            n_mat: n_mat as u32,
            max_nb,
            max_c,
            max_wc,
            n_cells: n_cells as u32,
            cell_cap,
            n_bodies: n_bodies as u32,
            off_wall_f: packed.off_wall_f as u32,
            off_law_f: packed.off_law_f as u32,
            off_body: packed.off_body as u32,
            off_world_u: packed.off_world_u as u32,
            off_wall_u: packed.off_wall_u as u32,
            off_law_u: packed.off_law_u as u32,
            n_worlds: worlds.len() as u32,
            off_wstep: packed.off_wstep as u32,
            skin,
            pad: 0.0,
        };

        let device = gpu.device.clone();
        let queue = gpu.queue.clone();
        let buf = create_buffers(&device, &params, &host, &packed, n_cells, caps);
        let (layout, groups) = bind_groups(&device, &buf);
        let (pipes, args_group) = pipelines(&device, &layout, &buf.args);
        Ok(Self {
            device,
            queue,
            pipes,
            groups,
            args_group,
            pos: buf.pos,
            vel: buf.vel,
            omg: buf.omg,
            frc: buf.frc,
            trq: buf.trq,
            ledger: buf.ledger,
            ctrl: buf.ctrl,
            args: buf.args,
            tab_f: buf.tab_f,
            off_body: packed.off_body as u64,
            off_wstep: packed.off_wstep as u64,
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
}

/// Checks that every world can run on the kernels (initialised, no half kick pending, a
/// finite time step, the materials and contact laws of the first world `w0`); returns the
/// largest skin and the smallest and largest particle radius of the batch.
fn check_worlds(worlds: &[&World], w0: &World) -> Result<(f64, f64, f64), GpuError> {
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
    Ok((skin, rmin, rmax))
}

/// The contact-law rows of all material pairs of `w0` and the tables after them.
fn law_tables(w0: &World, n_mat: usize) -> Result<LawTables, GpuError> {
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
    Ok(LawTables {
        law_f,
        law_u,
        tables,
    })
}

/// Neighbour grids, one per world (the box of its particles and walls, widened by a cell;
/// cells enlarged to stay within a budget of cells per particle), the kernel rows of its
/// walls and its place in the batch.
fn neighbour_grids(worlds: &[&World], skin: f64) -> Result<WorldGrids, GpuError> {
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
    Ok(WorldGrids {
        tables: GridTables {
            world_f,
            world_u,
            wall_f,
            wall_u,
        },
        n_cells,
        max_cell,
        metas,
        body_offset,
        wall_index,
    })
}

/// Device memory of the batch, before allocating, checked against the device's largest
/// buffer and its workgroups per dispatch.
fn estimate_memory(
    gpu: &GpuDevice,
    n: usize,
    n_cells: u64,
    n_bodies: usize,
    caps: Capacities,
) -> Result<MemoryEstimate, GpuError> {
    let Capacities {
        max_c,
        max_nb,
        max_wc,
        cell_cap,
    } = caps;
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
    Ok(memory)
}

impl HostState {
    /// Host copies of the initial state: particles, the active particle and wall contacts
    /// with their histories (both partners of a pair, the second with negated vectors) and
    /// the wall load of the last evaluation; fails when a particle has more contacts than
    /// the capacities allow.
    fn gather(
        worlds: &[&World],
        metas: &[WorldMeta],
        wall_index: &[Vec<Vec<u32>>],
        n: usize,
        caps: Capacities,
    ) -> Result<Self, GpuError> {
        let (max_c, max_wc) = (caps.max_c, caps.max_wc);
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
        for (k, (w, meta)) in worlds.iter().zip(metas).enumerate() {
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
        Ok(Self {
            pos,
            vel,
            omg,
            frc,
            trq,
            pinfo,
            c_ids,
            c_s,
            w_keys,
            w_st,
            ledger0,
        })
    }
}

/// Lays out the f64 table (world rows, wall rows, law rows, the law tables, then the body
/// and per-world step rows) and the u32 table (particle info, world, wall and law rows);
/// the tables of `gonthier-table` laws get their absolute place.
fn pack_tables(
    grid: GridTables,
    laws: LawTables,
    pinfo: Vec<[u32; 4]>,
    n: usize,
    n_bodies: usize,
    n_worlds: usize,
) -> PackedTables {
    let GridTables {
        world_f,
        world_u,
        wall_f,
        wall_u,
    } = grid;
    let LawTables {
        mut law_f,
        law_u,
        mut tables,
    } = laws;
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
    tab_f.resize(off_wstep + 2 * CHUNK_STEPS * n_worlds, [0.0; 4]);
    let off_world_u = n;
    let off_wall_u = off_world_u + world_u.len();
    let off_law_u = off_wall_u + wall_u.len();
    let mut tab_u = pinfo;
    tab_u.extend_from_slice(&world_u);
    tab_u.extend_from_slice(&wall_u);
    tab_u.extend_from_slice(&law_u);
    PackedTables {
        tab_f,
        tab_u,
        off_wall_f,
        off_law_f,
        off_body,
        off_world_u,
        off_wall_u,
        off_law_u,
        off_wstep,
    }
}

/// Allocates the device buffers, initialised from the host copies (buffers the kernels fill
/// themselves are zeroed; every buffer has at least 32 bytes).
fn create_buffers(
    device: &wgpu::Device,
    params: &Params,
    host: &HostState,
    packed: &PackedTables,
    n_cells: u64,
    caps: Capacities,
) -> Buffers {
    let Capacities {
        max_c,
        max_nb,
        max_wc,
        cell_cap,
    } = caps;
    let nu = host.pos.len() as u64;
    let storage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
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
    let params = init("params", bytemuck::bytes_of(params));
    let pos = init("pos", b(&host.pos));
    let vel = init("vel", b(&host.vel));
    let omg = init("omg", b(&host.omg));
    let frc = init("frc", b(&host.frc));
    let trq = init("trq", b(&host.trq));
    let tab_f = init("tab_f", b(&packed.tab_f));
    let tab_u = init("tab_u", bytemuck::cast_slice(&packed.tab_u));
    let cell_count = zeroed("cell_count", n_cells * 4);
    let cell_items = zeroed("cell_items", n_cells * 4 * cell_cap as u64);
    let nb = zeroed("nb", nu * 4 * (1 + max_nb as u64));
    let c_a = [
        init("c_ids_a", bytemuck::cast_slice(&host.c_ids)),
        init("c_s0_a", b(&host.c_s[0])),
        init("c_s1_a", b(&host.c_s[1])),
        init("c_s2_a", b(&host.c_s[2])),
    ];
    let c_b = [
        zeroed("c_ids_b", nu * 4 * (1 + max_c as u64)),
        zeroed("c_s0_b", nu * 32 * max_c as u64),
        zeroed("c_s1_b", nu * 32 * max_c as u64),
        zeroed("c_s2_b", nu * 32 * max_c as u64),
    ];
    let w_a = [
        init("w_keys_a", bytemuck::cast_slice(&host.w_keys)),
        init("w_st_a", b(&host.w_st)),
    ];
    let w_b = [
        zeroed("w_keys_b", nu * 4 * (1 + max_wc as u64)),
        zeroed("w_st_b", nu * 128 * max_wc as u64),
    ];
    let ledger = init("ledger", b(&host.ledger0));
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
    let ref_pos = init("ref_pos", b(&host.pos));
    Buffers {
        params,
        pos,
        vel,
        omg,
        frc,
        trq,
        tab_f,
        tab_u,
        cell_count,
        cell_items,
        nb,
        c_a,
        c_b,
        w_a,
        w_b,
        ledger,
        ctrl,
        args,
        ref_pos,
    }
}

/// The storage bind-group layout of the kernels (`BINDINGS` read-write buffers) and its two
/// bind groups, one per parity of the double-buffered contacts (read `_a` write `_b`, and the
/// reverse).
fn bind_groups(
    device: &wgpu::Device,
    buf: &Buffers,
) -> (wgpu::BindGroupLayout, [wgpu::BindGroup; 2]) {
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
            &buf.params,
            &buf.pos,
            &buf.vel,
            &buf.omg,
            &buf.frc,
            &buf.trq,
            &buf.tab_f,
            &buf.tab_u,
            &buf.cell_count,
            &buf.cell_items,
            &buf.nb,
        ];
        list.extend(inp.0.iter());
        list.extend(out.0.iter());
        list.extend(inp.1.iter());
        list.extend(out.1.iter());
        list.extend([&buf.ledger, &buf.ctrl, &buf.ref_pos]);
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
        group((&buf.c_a, &buf.w_a), (&buf.c_b, &buf.w_b)),
        group((&buf.c_b, &buf.w_b), (&buf.c_a, &buf.w_a)),
    ];
    (layout, groups)
}

/// The compute pipelines of dem.wgsl (`decide` also binds the indirect-dispatch arguments
/// `args`) and the bind group of `args`.
fn pipelines(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    args: &wgpu::Buffer,
) -> (Pipes, wgpu::BindGroup) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("dem.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("../dem.wgsl").into()),
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
        bind_group_layouts: &[Some(layout)],
        ..Default::default()
    });
    let pl_decide = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("pdamp-gpu decide"),
        bind_group_layouts: &[Some(layout), Some(&args_layout)],
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
    (pipes, args_group)
}
