//! Paper Sect. 4 bending friction model as an approach-3 damper on the powder cantilever
//! (`examples/couple_powder_cantilever_friction.toml`): a friction damper with Ẽ = 4W(κX) = cX
//! makes a Coulomb decay — the free-vibration amplitude drops by the same
//! ΔX = Ẽ/(K X) = c/K every cycle (K = ω²/φ_tip² the modal stiffness at the tip), i.e. the
//! equivalent dry-friction force F_eq = c/4 gives ΔX = 4F_eq/K. Checked to 1 % per cycle.

use pdamp_structure::formulas::bending_work;
use pdamp_structure::scenario::CoupleScenario;
use std::path::Path;

#[test]
fn powder_cavity_bending_friction_gives_a_coulomb_decay() {
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let path = ex.join("couple_powder_cantilever_friction.toml");
    let out = std::env::temp_dir().join(format!("pdamp_powder_friction_{}", std::process::id()));
    let s = pdamp_structure::report::run_couple_default(&path, &out, &mut |_| {}).unwrap();
    let (_, spec) = CoupleScenario::load(&path).unwrap();
    let m = spec.build(&ex).unwrap().modal;
    let phi = |p: &str| m.point(p).unwrap()[0];
    let kappa = 0.5 * (phi("cavity_end_rz") - phi("cavity_start_rz")) / phi("tip");
    let k_tip = (m.modes[0].omega_rad_s() / phi("tip")).powi(2);
    // c = Ẽ/X = 4 W(κX)/X (tan φ ≈ φ at φ ~ 1e-4 rad)
    let x = 1e-4;
    let c = 4.0 * bending_work(0.110, 0.018, 0.4, 56.5, kappa * x) / x;
    let dx_expected = c / k_tip;
    let text = std::fs::read_to_string(out.join("damping.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() >= 10);
    for w in rows.windows(2) {
        let dx = w[0][0] - w[1][0];
        assert!(
            (dx / dx_expected - 1.0).abs() < 0.01,
            "{dx} vs {dx_expected}"
        );
    }
    println!(
        "κ = {kappa:.3} rad/m, K_tip = {k_tip:.4e} N/m, ΔX per cycle {:.4e} m (expected {dx_expected:.4e}); ζ first/last cycle {} / {}",
        rows[0][0] - rows[1][0],
        s["first_cycle"]["damping_ratio"],
        s["last_cycle"]["damping_ratio"]
    );
    std::fs::remove_dir_all(&out).ok();
}
