//! `pdamp bench --device gpu`: the shaken-box benchmark on the GPU backend (large bed, or a
//! batch of independent worlds as in an effective field).

use anyhow::{Result, anyhow};
use pdamp_dem::{Motion, World};
use pdamp_gpu::{GpuBatch, GpuDevice};
use std::path::Path;
use std::time::Instant;

/// Builds `batch` shaken boxes of `n` spheres (the `pdamp bench` scenario; world k shaken at
/// 20 Hz × (1 + k / batch), as the points of a field differ), settles them on the device for
/// `settle_steps` steps with the boxes at rest (not timed), then times `steps` steps.
pub fn bench(n: usize, steps: u64, batch: usize, settle_steps: u64) -> Result<serde_json::Value> {
    let t_setup = Instant::now();
    let gpu = GpuDevice::open()?;
    let sc = pdamp_scenario::examples::shaken_box(n, 1.0);
    let mut worlds: Vec<World> = Vec::with_capacity(batch);
    let mut motions = Vec::with_capacity(batch);
    for k in 0..batch {
        let mut s = sc.clone();
        if let pdamp_scenario::schema::MotionSpec::Harmonic(h) = &mut s.bodies[0].motion {
            h.frequency_hz *= 1.0 + k as f64 / batch as f64;
        }
        let mut w = s.build_world(Path::new(".")).map_err(|e| anyhow!(e))?;
        motions.push(w.bodies[0].motion.clone());
        w.bodies[0].motion = Motion::Fixed;
        w.initialize();
        worlds.push(w);
    }
    let refs: Vec<&World> = worlds.iter().collect();
    let mut b = GpuBatch::new(&gpu, &refs)?;
    drop(refs);
    let total: usize = worlds.iter().map(|w| w.particles.len()).sum();
    let setup_s = t_setup.elapsed().as_secs_f64();
    let t_settle = Instant::now();
    b.step(settle_steps)?;
    let settle_s = t_settle.elapsed().as_secs_f64();
    for (k, m) in motions.into_iter().enumerate() {
        b.set_motion(k, 0, m)?;
        b.restart_clock(k);
    }
    let before: Vec<_> = (0..batch.min(4))
        .map(|k| b.snapshot(k))
        .collect::<Result<_, _>>()?;
    let builds0 = b.neighbor_builds();
    let t = Instant::now();
    b.step(steps)?;
    let wall = t.elapsed().as_secs_f64();
    // Energy balance of the timed steps (first worlds).
    let mut closure: f64 = 0.0;
    for (k, s0) in before.iter().enumerate() {
        let s1 = b.snapshot(k)?;
        let (l0, l1) = (&s0.ledger, &s1.ledger);
        let work = l1.wall_work_j - l0.wall_work_j;
        let (dk, dp) = (l1.kinetic_j - l0.kinetic_j, l1.potential_j - l0.potential_j);
        let dd = l1.dissipated_j() - l0.dissipated_j();
        let change = dk + dp + (l1.elastic_j - l0.elastic_j) + dd;
        let turnover = work
            .abs()
            .max(dk.abs())
            .max(dp.abs())
            .max(dd.abs())
            .max(1e-300);
        closure = closure.max((work - change).abs() / turnover);
    }
    // Digest of world 0's final positions and velocities (bits): equal digests of two runs
    // show the run-to-run determinism on this device.
    let s0 = b.snapshot(0)?;
    let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
    for v in s0.position.iter().chain(&s0.velocity) {
        for c in v.iter() {
            digest = (digest ^ c.to_bits()).wrapping_mul(0x0100_0000_01b3);
        }
    }
    let mem = b.memory();
    Ok(serde_json::json!({
        "device": gpu.name(),
        "particles": total,
        "particles_per_world": n,
        "worlds": batch,
        "steps": steps,
        "wall_time_s": wall,
        "particle_steps_per_s": total as f64 * steps as f64 / wall.max(1e-12),
        "neighbor_builds": b.neighbor_builds() - builds0,
        "settle_steps": settle_steps,
        "settle_wall_time_s": settle_s,
        "setup_wall_time_s": setup_s,
        "device_memory_bytes": mem.total_bytes,
        "device_memory_gb_per_million_particles": mem.bytes_per_particle * 1e6 / 1e9,
        "contacts_per_particle_capacity": mem.contacts_per_particle,
        "energy_closure_relative": closure,
        "state_digest": format!("{digest:016x}"),
        "energy_closure_note": "closure = |W_wall − ΔE_kin − ΔE_pot − ΔE_el − D| / turnover over the timed steps of the first (up to 4) worlds",
    }))
}
