//! `pdamp bench`: the shaken-box benchmark on the CPU engine or the GPU backend.

use crate::dem_commands::Device;
#[cfg(feature = "gpu")]
use crate::gpu;
use anyhow::{Result, bail};
use clap::Args;
use std::path::PathBuf;

// The arguments of `pdamp bench` (the command's help is the variant's doc in `Command`).
#[derive(Args)]
pub(crate) struct BenchArgs {
    /// Number of particles.
    #[arg(long, default_value_t = 8000)]
    particles: usize,
    /// Timed steps.
    #[arg(long, default_value_t = 2000)]
    steps: u64,
    /// Reuse the settled bed stored in this file (settle and store it if missing).
    #[arg(long)]
    settled: Option<PathBuf>,
    /// Also write a LIGGGHTS case of the same run into this folder (bench/peers).
    #[arg(long)]
    export_liggghts: Option<PathBuf>,
    /// Print the energy balance of the timed steps too (peer comparison).
    #[arg(long)]
    peer: bool,
    /// Where the steps run: `cpu` (the reference engine) or `gpu` (the wgpu/Vulkan
    /// backend; lavapipe counts as a GPU driver).
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    device: Device,
    /// GPU: independent shaken boxes advanced together (the points of a field).
    #[arg(long, default_value_t = 1)]
    batch: usize,
    /// GPU: steps of settling with the boxes at rest before the timed steps (not timed).
    #[arg(long, default_value_t = 10_000)]
    settle_steps: u64,
}

/// Runs `pdamp bench`: prints particle-timesteps per second (or the peer comparison's energy
/// balance) as JSON.
pub(crate) fn run(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        particles,
        steps,
        settled,
        export_liggghts,
        peer,
        device,
        batch,
        settle_steps,
    } = args;
    if device == Device::Gpu {
        #[cfg(feature = "gpu")]
        {
            if peer || settled.is_some() || export_liggghts.is_some() || batch == 0 {
                bail!(
                    "--device gpu takes --particles, --steps, --batch (≥ 1) and --settle-steps only"
                );
            }
            let r = gpu::bench(particles, steps, batch, settle_steps)?;
            println!("{}", serde_json::to_string_pretty(&r)?);
            return Ok(());
        }
        #[cfg(not(feature = "gpu"))]
        {
            let _ = (batch, settle_steps);
            bail!("this pdamp was built without the `gpu` feature");
        }
    }
    if batch != 1 {
        bail!("--batch needs --device gpu");
    }
    bench_limits(particles, steps)?;
    if !peer && settled.is_none() && export_liggghts.is_none() {
        let r = pdamp_scenario::bench::shaken_box_bench(particles, steps)
            .map_err(anyhow::Error::msg)?;
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "particles": r.particles,
                "steps": r.steps,
                "threads": rayon::current_num_threads(),
                "wall_time_s": r.wall_time_s,
                "particle_steps_per_s": r.particle_steps_per_s,
                "neighbor_builds": r.neighbor_builds,
                "contacts_pp": r.contacts_pp,
                "settling_wall_time_s": r.settling_wall_time_s,
            }))?
        );
        return Ok(());
    }
    let mut world = pdamp_scenario::bench::settled_shaken_box(particles, settled.as_deref())
        .map_err(anyhow::Error::msg)?;
    if let Some(dir) = &export_liggghts {
        pdamp_scenario::bench::write_liggghts_case(&world, steps, dir)
            .map_err(anyhow::Error::msg)?;
    }
    let r = pdamp_scenario::bench::run_peer(&mut world, steps);
    println!("{}", serde_json::to_string_pretty(&r)?);
    Ok(())
}

/// `pdamp bench`: the shaken box's size and length within the machine (see
/// [`pdamp_scenario::estimate`]).
fn bench_limits(particles: usize, steps: u64) -> Result<()> {
    if particles == 0 || steps == 0 {
        bail!("--particles and --steps must be >= 1");
    }
    let mut sc = pdamp_scenario::examples::shaken_box(particles.min(1000), 0.0);
    if let Some(g) = sc.particles.first_mut() {
        g.count = Some(particles);
    }
    sc.simulation.duration_s = steps as f64 * sc.simulation.time_step_s;
    sc.output.vtk_interval_s = 0.0;
    sc.output.energy_interval_s = sc.simulation.duration_s.max(1e-12);
    pdamp_scenario::estimate::Estimate::of(&sc, 1, rayon::current_num_threads())
        .check()
        .map_err(|e| anyhow::anyhow!("--particles/--steps: {e}"))
}
