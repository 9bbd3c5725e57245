//! The shaken-box throughput benchmark behind `pdamp bench`.

use crate::examples::shaken_box;
use crate::run::settle;
use pdamp_dem::{World, WorldState};
use std::path::Path;

/// Result of a benchmark run.
#[derive(Debug, Clone, Copy)]
pub struct BenchResult {
    /// Number of particles.
    pub particles: usize,
    /// Timed steps.
    pub steps: u64,
    /// Wall-clock time of the timed steps, s.
    pub wall_time_s: f64,
    /// Particle time steps per second.
    pub particle_steps_per_s: f64,
    /// Neighbour-list builds during the timed steps.
    pub neighbor_builds: u64,
    /// Particle–particle contacts at the end.
    pub contacts_pp: usize,
    /// Wall-clock time of the settling before the timed steps (not timed), s.
    pub settling_wall_time_s: f64,
}

/// Why the benchmark cannot run or write its peer case.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The shaken box's world cannot be built.
    #[error(transparent)]
    Input(#[from] crate::InputError),
    /// The settled bed cannot be stored.
    #[error(transparent)]
    Checkpoint(#[from] pdamp_io::checkpoint::CheckpointError),
    /// The stored settled bed does not fit the box.
    #[error(transparent)]
    State(#[from] pdamp_dem::state::StateError),
    /// The `--settled` path holds a file that is not a settled bed of the bench.
    #[error(
        "--settled {}: the file exists and is not a settled bed of `pdamp bench`; it is left as \
         it is: choose another path",
        .0.display()
    )]
    NotSettledBed(std::path::PathBuf),
    /// A file of the LIGGGHTS case cannot be written.
    #[error("{}: {cause}", dir.display())]
    Write {
        /// The case directory.
        dir: std::path::PathBuf,
        /// Cause.
        cause: std::io::Error,
    },
}

/// Builds the shaken box with `n` particles, settles it for 20 ms (not timed), then times
/// `steps` steps of shaking.
pub fn shaken_box_bench(n: usize, steps: u64) -> Result<BenchResult, BenchError> {
    let sc = shaken_box(n, 1.0);
    let mut world = sc.build_world(Path::new("."))?;
    let settling = std::time::Instant::now();
    settle(&mut world, 0.02, 0.0, |_| {});
    world.initialize();
    let settling_wall_time_s = settling.elapsed().as_secs_f64();
    let builds0 = world.counters.neighbor_builds;
    let start = std::time::Instant::now();
    // Nothing reads the particles between steps: the second half kick of every step is done
    // with the next step's drift (the same arithmetic, one pass over the particles less).
    for _ in 0..steps {
        world.step_deferred();
    }
    world.complete_step();
    let wall = start.elapsed().as_secs_f64();
    Ok(BenchResult {
        particles: n,
        steps,
        wall_time_s: wall,
        particle_steps_per_s: (n as f64) * (steps as f64) / wall.max(1e-12),
        neighbor_builds: world.counters.neighbor_builds - builds0,
        contacts_pp: world.num_pp_contacts(),
        settling_wall_time_s,
    })
}

/// Settling time of the shaken box before timed runs, s (box at rest, not timed).
pub const SETTLE_S: f64 = 0.02;

/// The shaken box with `n` particles, settled for [`SETTLE_S`] with the box at rest and the clock
/// restarted at 0. With `cache`, a settled bed stored there (for the same `n`) is reused, and a
/// new one is stored there, so that repeated benchmarks start from one bed.
pub fn settled_shaken_box(n: usize, cache: Option<&Path>) -> Result<World, BenchError> {
    let sc = shaken_box(n, 1.0);
    let mut world = sc.build_world(Path::new("."))?;
    let kind = format!("bench-settled-{n}-layers");
    let digest = pdamp_io::checkpoint::digest(format!("{sc:?}").as_bytes());
    // The settled bed is a cache: one written for another scenario or by another version of
    // the bench (e.g. another particle numbering) is settled again and overwritten.
    // A file that is not a settled bed of the bench is the user's: never overwritten.
    if let Some(path) = cache
        && let Ok(bytes) = std::fs::read(path)
    {
        let head = &bytes[..bytes.len().min(256)];
        let ours =
            head.starts_with(b"PDAMPCK\0") && head.windows(14).any(|w| w == b"bench-settled-");
        if !ours {
            return Err(BenchError::NotSettledBed(path.to_path_buf()));
        }
    }
    let cached =
        match cache.map(|path| pdamp_io::checkpoint::load::<WorldState>(path, &kind, &digest)) {
            Some(Ok(state)) => state,
            Some(Err(e)) => {
                eprintln!(
                    "settled bed {}: {e}; settling again",
                    cache.unwrap().display()
                );
                None
            }
            None => None,
        };
    if let Some(state) = cached {
        world.restore_state(state)?;
        world.restart_clock();
        return Ok(world);
    }
    settle(&mut world, SETTLE_S, 0.0, |_| {});
    world.initialize();
    if let Some(path) = cache {
        let header = pdamp_io::checkpoint::CheckpointHeader::new(&kind, &digest);
        pdamp_io::checkpoint::save(path, &header, &world.save_state())?;
    }
    Ok(world)
}

/// Timing and energy balance of a shaken-box run, for the comparison with LIGGGHTS.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct PeerRun {
    /// Number of particles.
    pub particles: usize,
    /// Timed steps.
    pub steps: u64,
    /// Worker threads.
    pub threads: usize,
    /// Wall-clock time of the timed steps, s.
    pub wall_time_s: f64,
    /// Particle time steps per second.
    pub particle_steps_per_s: f64,
    /// Simulated time, s.
    pub duration_s: f64,
    /// Work done by the moving box on the bed, J.
    pub wall_work_j: f64,
    /// Change of kinetic energy (translation + rotation), J.
    pub delta_kinetic_j: f64,
    /// Change of potential energy, J.
    pub delta_potential_j: f64,
    /// Change of elastic contact energy, J.
    pub delta_elastic_j: f64,
    /// Dissipated energy from the ledger (contact laws), J.
    pub dissipated_ledger_j: f64,
    /// Dissipated energy from the balance W − ΔE_kin − ΔE_pot (elastic energy left out, as
    /// LIGGGHTS does not report it), J.
    pub dissipated_balance_j: f64,
    /// `dissipated_balance_j / duration_s`, W.
    pub dissipated_power_w: f64,
    /// Pairs in the neighbour list at the end.
    pub neighbor_pairs: usize,
    /// Touching particle–particle contacts at the end.
    pub contacts_pp: usize,
    /// Touching particle–wall contacts at the end.
    pub contacts_pw: usize,
    /// Neighbour-list builds during the timed steps.
    pub neighbor_builds: u64,
    /// Where the time went.
    pub phases: pdamp_dem::world::PhaseTimes,
}

/// Runs `steps` steps of the (settled) shaken box and measures time and energy balance.
pub fn run_peer(world: &mut World, steps: u64) -> PeerRun {
    let (k0, p0, e0) = (
        world.ledger.kinetic_j,
        world.ledger.potential_j,
        world.ledger.elastic_j,
    );
    let (w0, d0) = (world.ledger.wall_work_j, world.ledger.dissipated_j());
    let t0 = world.time_s;
    let builds0 = world.counters.neighbor_builds;
    world.profile = Some(Default::default());
    let start = std::time::Instant::now();
    // Nothing reads the particles between steps: the second half kick of every step is done
    // with the next step's drift (the same arithmetic, one pass over the particles less).
    for _ in 0..steps {
        world.step_deferred();
    }
    world.complete_step();
    let wall = start.elapsed().as_secs_f64();
    let l = &world.ledger;
    let duration = world.time_s - t0;
    let wall_work = l.wall_work_j - w0;
    let balance = wall_work - (l.kinetic_j - k0) - (l.potential_j - p0);
    let n = world.particles.len();
    PeerRun {
        particles: n,
        steps,
        threads: rayon::current_num_threads(),
        wall_time_s: wall,
        particle_steps_per_s: n as f64 * steps as f64 / wall.max(1e-12),
        duration_s: duration,
        wall_work_j: wall_work,
        delta_kinetic_j: l.kinetic_j - k0,
        delta_potential_j: l.potential_j - p0,
        delta_elastic_j: l.elastic_j - e0,
        dissipated_ledger_j: l.dissipated_j() - d0,
        dissipated_balance_j: balance,
        dissipated_power_w: balance / duration.max(1e-300),
        neighbor_pairs: world.num_neighbor_pairs(),
        contacts_pp: world.num_pp_contacts(),
        contacts_pw: world.num_pw_contacts(),
        neighbor_builds: world.counters.neighbor_builds - builds0,
        phases: world.profile.take().unwrap_or_default(),
    }
}

/// The LIGGGHTS input script of the peer benchmark (`bench/peers/in.shaken_box`).
pub const LIGGGHTS_INPUT: &str = include_str!("../../../bench/peers/in.shaken_box");

/// Writes a LIGGGHTS case of the shaken box in the state of `world` into `dir`:
/// `particles.data` (positions, velocities, spins), `box.stl` (the box as 12 triangles) and
/// `in.shaken_box` (the script with `steps` and the domain bounds), plus `case.json`
/// (amplitude, frequency, time step) for the driver that evaluates the run.
pub fn write_liggghts_case(world: &World, steps: u64, dir: &Path) -> Result<(), BenchError> {
    use std::fmt::Write;
    let err = |e: std::io::Error| BenchError::Write {
        dir: dir.to_path_buf(),
        cause: e,
    };
    std::fs::create_dir_all(dir).map_err(err)?;
    let n = world.particles.len();
    let side = crate::examples::shaken_box_side_m(n);
    let (hx, h) = (0.5 * side, 0.040);
    let amp = 0.002;
    // The box moves by ±2 mm along x; keep a margin of 3 mm around it.
    let (xlo, xhi) = (-hx - amp - 0.003, hx + amp + 0.003);
    let (ylo, yhi) = (-hx - 0.003, hx + 0.003);
    let (zlo, zhi) = (-0.003, h + 0.003);
    let p = &world.particles;
    let mut data = String::new();
    let _ = writeln!(
        data,
        "pdamp shaken box, settled bed\n\n{n} atoms\n1 atom types\n"
    );
    let _ = writeln!(
        data,
        "{xlo:.9e} {xhi:.9e} xlo xhi\n{ylo:.9e} {yhi:.9e} ylo yhi\n{zlo:.9e} {zhi:.9e} zlo zhi\n"
    );
    let _ = writeln!(data, "Atoms\n");
    for i in 0..n {
        let x = p.position[i];
        let rho = p.mass[i] / (4.0 / 3.0 * std::f64::consts::PI * p.radius[i].powi(3));
        let _ = writeln!(
            data,
            "{} 1 {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
            i + 1,
            2.0 * p.radius[i],
            rho,
            x.x,
            x.y,
            x.z
        );
    }
    let _ = writeln!(data, "\nVelocities\n");
    for i in 0..n {
        let (v, w) = (p.velocity[i], p.angular_velocity[i]);
        let _ = writeln!(
            data,
            "{} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
            i + 1,
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    std::fs::write(dir.join("particles.data"), data).map_err(err)?;

    // Closed box [−hx, hx]² × [0, h] as 12 triangles.
    let c = |i: usize| {
        [
            if i & 1 == 0 { -hx } else { hx },
            if i & 2 == 0 { -hx } else { hx },
            if i & 4 == 0 { 0.0 } else { h },
        ]
    };
    let faces: [[usize; 4]; 6] = [
        [0, 1, 3, 2], // bottom
        [4, 6, 7, 5], // top
        [0, 4, 5, 1], // y = −hx
        [2, 3, 7, 6], // y = +hx
        [0, 2, 6, 4], // x = −hx
        [1, 5, 7, 3], // x = +hx
    ];
    let mut stl = String::from("solid box\n");
    for f in faces {
        for tri in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            let v = tri.map(c);
            let a = [v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]];
            let b = [v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]];
            let nrm = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let l = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
            let _ = writeln!(
                stl,
                "  facet normal {:e} {:e} {:e}\n    outer loop",
                nrm[0] / l,
                nrm[1] / l,
                nrm[2] / l
            );
            for q in v {
                let _ = writeln!(
                    stl,
                    "      vertex {:.12e} {:.12e} {:.12e}",
                    q[0], q[1], q[2]
                );
            }
            let _ = writeln!(stl, "    endloop\n  endfacet");
        }
    }
    stl.push_str("endsolid box\n");
    std::fs::write(dir.join("box.stl"), stl).map_err(err)?;

    let script = format!("variable steps equal {steps}\n\n{}", LIGGGHTS_INPUT);
    std::fs::write(dir.join("in.shaken_box"), script).map_err(err)?;
    let case = serde_json::json!({
        "particles": n,
        "steps": steps,
        "time_step_s": world.dt_s,
        "amplitude_m": amp,
        "frequency_hz": 20.0,
        "gravity_m_s2": 9.81,
        "box_side_m": side,
        "box_height_m": h,
    });
    std::fs::write(
        dir.join("case.json"),
        serde_json::to_string_pretty(&case).unwrap(),
    )
    .map_err(err)?;
    Ok(())
}
