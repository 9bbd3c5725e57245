//! Times the parts of a structure step of the paper's beam (no powder): internal forces,
//! double- and single-precision solves, mass products, and whole generalized-α steps under the
//! paper load. Run from the repository root:
//! `cargo run --release -p pdamp-powder --example structure_profile`
//! (`GA_STEPS` = steps timed, default 200; `GA_TOL` = Newton tolerance, default 1e-10).
use pdamp_powder::cantilever::{CantileverScenario, build_structure};
use pdamp_powder::fe::gen_alpha::{Dynamics, GenAlpha};
use std::time::Instant;

fn main() {
    let text = std::fs::read_to_string("examples/powder_cantilever_paper.toml")
        .expect("run from the repository root (examples/powder_cantilever_paper.toml)");
    let sc = CantileverScenario::from_toml(&text).unwrap();
    let t0 = Instant::now();
    let (mut s, _tip) = build_structure(&sc.beam, &sc.load, sc.run.gravity_m_s2);
    println!(
        "build {:.3} s, dofs {}",
        t0.elapsed().as_secs_f64(),
        s.free_dofs.len()
    );
    let n = s.n_dof();
    let t0 = Instant::now();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.8),
        sc.run.time_step_s,
        vec![0.0; n],
        vec![0.0; n],
        Default::default(),
    )
    .unwrap();
    println!(
        "dynamics new (2 factorizations) {:.3} s",
        t0.elapsed().as_secs_f64()
    );
    let mut out = vec![0.0; n];
    let t0 = Instant::now();
    for _ in 0..20 {
        s.internal_force(&dy.d, &mut out);
    }
    println!(
        "internal force {:.3} ms",
        t0.elapsed().as_secs_f64() / 20.0 * 1e3
    );
    {
        use pdamp_fem::Cholesky;
        let t0 = Instant::now();
        let c = Cholesky::new(&s.k0).unwrap();
        println!(
            "factor k0 {:.3} s, nnz(L) {}",
            t0.elapsed().as_secs_f64(),
            c.nnz()
        );
        let mut b = vec![1.0; s.free_dofs.len()];
        let t0 = Instant::now();
        for _ in 0..20 {
            c.solve_in_place(&mut b);
        }
        println!("solve {:.3} ms", t0.elapsed().as_secs_f64() / 20.0 * 1e3);
        let mut c = pdamp_fem::SingleCholesky::new(&s.k0).unwrap();
        let t0 = Instant::now();
        for _ in 0..20 {
            c.solve_in_place(&mut b);
        }
        println!(
            "single solve {:.3} ms",
            t0.elapsed().as_secs_f64() / 20.0 * 1e3
        );
        let x = vec![1.0; s.free_dofs.len()];
        let mut y = vec![0.0; s.free_dofs.len()];
        let t0 = Instant::now();
        for _ in 0..50 {
            s.mass.mul(&x, &mut y);
        }
        println!("mass.mul {:.3} ms", t0.elapsed().as_secs_f64() / 50.0 * 1e3);
        let t0 = Instant::now();
        for _ in 0..50 {
            s.mass_mul(&x, &mut y);
        }
        println!("mass_mul {:.3} ms", t0.elapsed().as_secs_f64() / 50.0 * 1e3);
    }
    if let Ok(t) = std::env::var("GA_TOL") {
        dy.newton.tolerance = t.parse().unwrap();
    }
    let t0 = Instant::now();
    let mut its = 0;
    let steps: usize = std::env::var("GA_STEPS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(200);
    let mut block = 0;
    for k in 0..steps {
        let it = dy.step(&mut s).unwrap();
        its += it;
        block += it;
        if (k + 1) % 500 == 0 {
            println!(
                "t = {:.2} ms: {:.2} iterations per step over the last 500",
                dy.t * 1e3,
                block as f64 / 500.0
            );
            block = 0;
        }
    }
    println!(
        "step {:.3} ms, mean iterations {:.2}",
        t0.elapsed().as_secs_f64() / steps as f64 * 1e3,
        its as f64 / steps as f64
    );
}
