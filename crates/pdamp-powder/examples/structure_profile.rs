//! Times the parts of a structure step of the paper's beam (no powder): internal forces,
//! double- and single-precision solves, mass products, and whole generalized-α steps under the
//! paper load. Run from the repository root:
//! `cargo run --release -p pdamp-powder --example structure_profile`
//! (`GA_STEPS` = steps timed, default 200; `GA_TOL` = Newton tolerance, default 1e-10;
//! `GA_DOUBLE=1`: the double-precision factor from the start; `GA_LINEAR=1`: small-deformation
//! kinematics; `GA_CHECK=1`: after the steps, how far the internal force is from K₀d).
use pdamp_powder::cantilever::{CantileverScenario, build_structure};
use pdamp_powder::fe::gen_alpha::{Dynamics, GenAlpha};
use std::time::Instant;

fn main() {
    let text = std::fs::read_to_string("examples/powder_cantilever_paper.toml")
        .expect("run from the repository root (examples/powder_cantilever_paper.toml)");
    let sc = CantileverScenario::from_toml(&text).unwrap();
    let t0 = Instant::now();
    let mut beam = sc.beam;
    if std::env::var("GA_LINEAR").is_ok() {
        beam.kinematics = pdamp_powder::fe::Kinematics::Linear;
    }
    let (mut s, _tip) = build_structure(&beam, &sc.load, sc.run.gravity_m_s2);
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
    if std::env::var("GA_DOUBLE").is_ok() {
        dy.use_double_factor().unwrap();
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
    if std::env::var("GA_CHECK").is_ok() {
        // consistency of the reference tangent with the internal force at the current state
        let nf = s.free_dofs.len();
        let dfree: Vec<f64> = s.free_dofs.iter().map(|&g| dy.d[g]).collect();
        let mut kd = vec![0.0; nf];
        s.k0.mul(&dfree, &mut kd);
        let mut fint = vec![0.0; n];
        s.internal_force(&dy.d, &mut fint);
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (k, &g) in s.free_dofs.iter().enumerate() {
            num = num.max((fint[g] - kd[k]).abs());
            den = den.max(kd[k].abs());
        }
        println!("max |fint(d) - K0 d| / max |K0 d| = {:.3e}", num / den);
        let dmax = dy.d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let nodes = &s.mesh.nodes;
        let (mut worst, mut wk) = (0.0f64, 0);
        for (k, &g) in s.free_dofs.iter().enumerate() {
            if (fint[g] - kd[k]).abs() > worst {
                worst = (fint[g] - kd[k]).abs();
                wk = k;
            }
        }
        let g = s.free_dofs[wk];
        println!(
            "max |d| = {dmax:.3e} m; worst dof {g} (node at {:?}): fint {:.4e} K0d {:.4e}",
            nodes[g / 3],
            fint[g],
            kd[wk]
        );
        // the same for a tiny displacement (linear regime)
        let eps = 1e-9;
        let dt: Vec<f64> = dy.d.iter().map(|x| x * eps).collect();
        let dfree: Vec<f64> = s.free_dofs.iter().map(|&g| dt[g]).collect();
        s.k0.mul(&dfree, &mut kd);
        s.internal_force(&dt, &mut fint);
        let (mut num, mut den, mut at) = (0.0f64, 0.0f64, 0);
        for (k, &g) in s.free_dofs.iter().enumerate() {
            if (fint[g] - kd[k]).abs() > num {
                at = k;
            }
            num = num.max((fint[g] - kd[k]).abs());
            den = den.max(kd[k].abs());
        }
        println!(
            "tiny: max |fint - K0 d| / max |K0 d| = {:.3e} (at free dof {at}: fint {:.3e}, K0d {:.3e}; free_dofs[{at}] = {})",
            num / den,
            fint[s.free_dofs[at]],
            kd[at],
            s.free_dofs[at]
        );
    }
    println!(
        "step {:.3} ms, mean iterations {:.2}",
        t0.elapsed().as_secs_f64() / steps as f64 * 1e3,
        its as f64 / steps as f64
    );
    // the final state, to compare Newton tolerances (GA_TOL)
    let (dmax, dsum) =
        dy.d.iter()
            .fold((0.0f64, 0.0f64), |(m, s), x| (m.max(x.abs()), s + x));
    println!("final max |d| = {dmax:.12e} m, sum d = {dsum:.12e} m");
}
