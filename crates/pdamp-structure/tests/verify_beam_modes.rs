//! Must-show 1: beam eigenfrequencies against the Euler–Bernoulli closed forms
//! $\omega_n = (\beta_n L)^2\sqrt{EI/(\rho A L^4)}$ (cantilever βL = 1.875104, 4.694091,
//! 7.854757, 10.995541; free–free βL = 4.730041, 7.853205, 10.995608, 14.137165), and a hex8
//! cantilever converging towards them.

use pdamp_structure::fe::{BeamSection, Dof, FeModel, SolidMaterial};
use pdamp_structure::modal::lowest_modes;
use std::f64::consts::TAU;

const CANTILEVER: [f64; 4] = [1.875104069, 4.694091133, 7.854757438, 10.99554073];
const FREE_FREE: [f64; 4] = [4.730040745, 7.853204624, 10.99560784, 14.13716549];

fn closed_form(beta_l: f64, e: f64, i: f64, rho: f64, a: f64, l: f64) -> f64 {
    beta_l * beta_l * (e * i / (rho * a * l.powi(4))).sqrt() / TAU
}

/// Planar bending in x–y (uz, θx, θy fixed everywhere) of a steel bar 20 mm × 10 mm, 1 m.
fn planar_beam(elements: usize, timoshenko: bool) -> (FeModel, BeamSection) {
    let s = BeamSection::rectangle(0.02, 0.01, 210e9, 0.3, 7850.0, timoshenko);
    let mut m = FeModel::straight_beam([0.0; 3], [1.0, 0.0, 0.0], elements, s, [0.0, 1.0, 0.0]);
    m.fix_all_nodes(&[Dof::Uz, Dof::Rx, Dof::Ry]);
    (m, s)
}

fn frequencies(m: &FeModel, n: usize, min_hz: f64) -> Vec<f64> {
    let a = m.assemble().unwrap();
    let b = lowest_modes(&a.stiffness, &a.mass, n, min_hz).unwrap();
    b.omega_rad_s.iter().map(|w| w / TAU).collect()
}

#[test]
fn cantilever_and_free_free_beams_match_euler_bernoulli_within_half_percent() {
    for timoshenko in [false, true] {
        let (mut m, s) = planar_beam(40, timoshenko);
        m.fix(0, &Dof::ALL);
        let f = frequencies(&m, 4, 0.0);
        for (k, bl) in CANTILEVER.iter().enumerate() {
            let exact = closed_form(
                *bl,
                s.youngs_modulus_pa,
                s.iz_m4,
                s.density_kg_m3,
                s.area_m2,
                1.0,
            );
            let err = (f[k] - exact).abs() / exact;
            println!(
                "cantilever timoshenko={timoshenko} mode {}: {:.4} Hz vs {:.4} Hz, {:.4} %",
                k + 1,
                f[k],
                exact,
                100.0 * err
            );
            assert!(err < 0.005, "mode {}: {} vs {}", k + 1, f[k], exact);
        }
        let (m, s) = planar_beam(40, timoshenko);
        // rigid-body modes (ux, uy, θz) are dropped by the 1 Hz threshold
        let f = frequencies(&m, 4, 1.0);
        for (k, bl) in FREE_FREE.iter().enumerate() {
            let exact = closed_form(
                *bl,
                s.youngs_modulus_pa,
                s.iz_m4,
                s.density_kg_m3,
                s.area_m2,
                1.0,
            );
            let err = (f[k] - exact).abs() / exact;
            println!(
                "free-free timoshenko={timoshenko} mode {}: {:.4} Hz vs {:.4} Hz, {:.4} %",
                k + 1,
                f[k],
                exact,
                100.0 * err
            );
            assert!(err < 0.005, "mode {}: {} vs {}", k + 1, f[k], exact);
        }
    }
}

/// The full 3D free–free beam has six rigid-body modes at 0 Hz.
#[test]
fn free_free_3d_beam_has_six_rigid_body_modes() {
    let s = BeamSection::rectangle(0.02, 0.01, 210e9, 0.3, 7850.0, true);
    let m = FeModel::straight_beam([0.0; 3], [1.0, 0.0, 0.0], 20, s, [0.0, 1.0, 0.0]);
    let f = frequencies(&m, 8, 0.0);
    let exact = closed_form(
        FREE_FREE[0],
        s.youngs_modulus_pa,
        s.iz_m4,
        s.density_kg_m3,
        s.area_m2,
        1.0,
    );
    assert!(f[..6].iter().all(|x| *x < 1e-3 * exact), "{f:?}");
    assert!(f[6] > 0.99 * exact, "{f:?}");
}

/// hex8 cantilever (1 m × 50 mm × 50 mm, ν = 0) with incompatible modes converges towards the
/// first two bending frequencies as the mesh is refined along the length; the plain
/// (fully integrated) hex8 locks and stays much stiffer on the same mesh.
#[test]
fn hex8_cantilever_converges_towards_beam_theory() {
    let (l, h) = (1.0, 0.05);
    let mat = SolidMaterial {
        youngs_modulus_pa: 210e9,
        poisson_ratio: 0.0,
        density_kg_m3: 7850.0,
    };
    let i = h * h * h * h / 12.0;
    let exact: Vec<f64> = CANTILEVER[..2]
        .iter()
        .map(|bl| closed_form(*bl, 210e9, i, 7850.0, h * h, l))
        .collect();
    let run = |nx: usize, inc: bool| {
        let mut m = FeModel::default();
        m.add_solid_block([0.0; 3], [l, h, h], [nx, 2, 2], mat, inc);
        for n in 0..m.nodes.len() {
            if m.nodes[n][0] == 0.0 {
                m.fix(n, &Dof::TRANSLATIONS);
            }
        }
        let f = frequencies(&m, 4, 0.0);
        // square section: bending modes come in pairs (y, z)
        [f[0], f[2]]
    };
    // The solid includes shear deformation, so it converges to a limit slightly below the
    // Euler–Bernoulli value (Timoshenko-like); convergence is checked by shrinking changes
    // between successive meshes.
    let mut prev = [f64::INFINITY; 2];
    let mut prev_change = [f64::INFINITY; 2]; // first mesh: no previous change
    for nx in [5, 10, 20] {
        let f = run(nx, true);
        let err: Vec<f64> = f.iter().zip(&exact).map(|(a, b)| (a - b) / b).collect();
        println!("hex8 incompatible nx={nx}: f = {f:?}, exact = {exact:?}, rel. error = {err:?}");
        for k in 0..2 {
            let change = (f[k] - prev[k]).abs();
            assert!(
                prev_change[k].is_infinite() || change < 0.5 * prev_change[k],
                "no convergence at nx={nx}"
            );
            prev_change[k] = change;
        }
        prev = f;
    }
    for k in 0..2 {
        let err = (prev[k] - exact[k]).abs() / exact[k];
        assert!(err < 0.01, "mode {k}: {err}");
    }
    let plain = run(20, false);
    let err_plain = (plain[0] - exact[0]) / exact[0];
    println!(
        "hex8 plain nx=20: f1 = {} (error {:.2} %)",
        plain[0],
        100.0 * err_plain
    );
    assert!(
        err_plain > 0.05,
        "plain hex8 should lock in bending: {err_plain}"
    );
}
