//! The shaken-box throughput benchmark behind `pdamp bench`.

use crate::examples::shaken_box;
use crate::run::settle;
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
}

/// Builds the shaken box with `n` particles, settles it for 20 ms (not timed), then times
/// `steps` steps of shaking.
pub fn shaken_box_bench(n: usize, steps: u64) -> Result<BenchResult, String> {
    let sc = shaken_box(n, 1.0);
    let mut world = sc.build_world(Path::new("."))?;
    settle(&mut world, 0.02, 0.0, |_| {});
    world.initialize();
    let builds0 = world.counters.neighbor_builds;
    let start = std::time::Instant::now();
    for _ in 0..steps {
        world.step();
    }
    let wall = start.elapsed().as_secs_f64();
    Ok(BenchResult {
        particles: n,
        steps,
        wall_time_s: wall,
        particle_steps_per_s: (n as f64) * (steps as f64) / wall.max(1e-12),
        neighbor_builds: world.counters.neighbor_builds - builds0,
        contacts_pp: world.num_pp_contacts(),
    })
}
