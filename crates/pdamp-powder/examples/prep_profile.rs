//! Times the paper's powder preparation every 10 ms of simulated time (wall time, neighbour
//! builds, kinetic energy), from the repository root:
//! `cargo run --release -p pdamp-powder --example prep_profile [FILE]`
//! (FILE default examples/powder_cantilever_paper.toml; `FIXED=1`: the fixed skin instead of
//! the adaptive one; `SKIN=f`: a fixed skin of f × the smallest radius; `TMAX=t`: stop at the
//! simulated time t in s).
use pdamp_powder::cantilever::CantileverScenario;
use pdamp_powder::prep::Preparation;
use std::ops::ControlFlow;
use std::time::Instant;

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("examples/powder_cantilever_paper.toml".into());
    let sc = CantileverScenario::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap();
    let p = sc.powder.as_ref().unwrap();
    let mut pr = Preparation::new(
        sc.beam.cavity(),
        &p.psd(),
        p.scaled_law(),
        p.density_kg_m3,
        sc.run.time_step_s,
        &p.scaled_prep(),
    );
    if std::env::var("FIXED").is_ok() {
        pr.world_mut().set_adaptive_skin(None);
    }
    if let Ok(f) = std::env::var("SKIN") {
        let rmin = pr.world().particles.min_radius();
        pr.world_mut().set_skin(f.parse::<f64>().unwrap() * rmin);
    }
    let t0 = Instant::now();
    let mut last = String::new();
    let mut t_last = 0.0;
    let mut b_last = 0;
    let mut s_last = 0.0;
    let t_max: f64 = std::env::var("TMAX").map_or(f64::INFINITY, |v| v.parse().unwrap());
    let _ = pr
        .run(
            &mut |stage, _| {
                if stage != last {
                    println!("-> {stage}");
                    last = stage.to_string();
                }
            },
            &mut |pr| {
                let t = pr.time_s();
                if (t - s_last) > 0.01 {
                    let b = pr.world().counters.neighbor_builds;
                    let w = t0.elapsed().as_secs_f64();
                    println!(
                        "t {:.3} s wall {:.1} s (+{:.1}) builds +{} ke {:.3e} plate {:.4} N",
                        t,
                        w,
                        w - t_last,
                        b - b_last,
                        pr.world().ledger.kinetic_j,
                        pr.world().body_load(1).0.z
                    );
                    t_last = w;
                    b_last = b;
                    s_last = t;
                }
                if t > t_max {
                    println!(
                        "stopped at {t:.4} s, wall {:.1} s, builds {}",
                        t0.elapsed().as_secs_f64(),
                        pr.world().counters.neighbor_builds
                    );
                    std::process::exit(0);
                }
                ControlFlow::Continue(())
            },
        )
        .unwrap();
    let (_bed, rep) = pr.finish();
    println!("{rep:?}\ntotal {:.1} s", t0.elapsed().as_secs_f64());
}
