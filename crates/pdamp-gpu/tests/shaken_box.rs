//! The 1 000-sphere shaken box on the GPU kernels against the CPU engine.

mod common;
use common::*;
use pdamp_gpu::GpuBatch;

/// Same start state (settled bed with its contact histories), 1 000 steps of shaking: the GPU
/// trajectory stays within 1e-9 m of the CPU engine's (only the summation order of the forces
/// differs), and both ledgers agree and close.
#[test]
fn shaken_box_trajectory_matches_cpu() {
    let Some(gpu) = device() else { return };
    let mut w = shaken_box(1000, 40_000, 7);
    let mut batch = GpuBatch::new(&gpu, &[&w]).expect("batch");
    let contacts = w.num_pp_contacts();
    assert!(contacts > 500, "a settled bed has contacts: {contacts}");
    let mut worst: f64 = 0.0;
    for _ in 0..10 {
        for _ in 0..100 {
            w.step();
        }
        batch.step(100).expect("gpu steps");
        let s = batch.snapshot(0).expect("snapshot");
        assert_eq!(s.time_s, w.time_s);
        worst = worst.max(max_position_difference(&w, &s));
    }
    let s = batch.snapshot(0).unwrap();
    eprintln!(
        "largest position difference over 1 000 steps: {worst:.3e} m; neighbour builds {}",
        batch.neighbor_builds()
    );
    assert!(
        worst <= 1e-9,
        "GPU trajectory left the CPU one by {worst:e} m"
    );
    let (a, b) = (&w.ledger, &s.ledger);
    eprintln!("CPU ledger {a:?}\nGPU ledger {b:?}");
    let rel = |x: f64, y: f64| (x - y).abs() / x.abs().max(y.abs()).max(1e-300);
    assert!(rel(a.wall_work_j, b.wall_work_j) < 1e-6);
    assert!(rel(a.dissipated_j(), b.dissipated_j()) < 1e-6);
    assert!(rel(a.kinetic_j, b.kinetic_j) < 1e-6);
    assert!(rel(a.elastic_j, b.elastic_j) < 1e-5);
    let closure = b.closure_error_j().abs() / b.turnover_j();
    assert!(closure < 1e-3, "GPU ledger closure {closure:e}");
    assert!(rel(w.bodies[0].contact_force_n.x, s.body_force_n.x) < 1e-6);
}
