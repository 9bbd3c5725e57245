//! Sparse eigen solver (faer Krylov–Schur on the shift-inverted pencil with a Rayleigh–Ritz
//! refinement, `pdamp_fem::eigen` through `pdamp_structure::sparse`)
//! against the dense solver on hex8 models: eigenfrequencies to 1e-7 relative (the dense
//! solver's own residual is ~1e-8 on these stiff models; the sparse residual must not be larger)
//! and mode shapes to 1e-6 (|φ_sparseᵀ M φ_dense| = 1), for a clamped hex8 cantilever and a free–free hex8 bar
//! (six rigid-body modes dropped by `min_frequency_hz`).

use pdamp_structure::fe::{Dof, FeModel, SolidMaterial};
use pdamp_structure::modal;
use pdamp_structure::sparse::{self, from_dense, mul_columns};
use std::time::Instant;

fn bar(cells: [usize; 3], clamp: bool) -> FeModel {
    let mat = SolidMaterial {
        youngs_modulus_pa: 70e9,
        poisson_ratio: 0.3,
        density_kg_m3: 2700.0,
    };
    let mut m = FeModel::default();
    // rectangular section (no degenerate bending pairs)
    m.add_solid_block([0.0; 3], [0.6, 0.05, 0.03], cells, mat, true);
    if clamp {
        for n in 0..m.nodes.len() {
            if m.nodes[n][0] == 0.0 {
                m.fix(n, &Dof::TRANSLATIONS);
            }
        }
    }
    m
}

fn compare(model: &FeModel, n_modes: usize, min_frequency_hz: f64) {
    let t0 = Instant::now();
    let dense_a = model.assemble().unwrap();
    let dense =
        modal::lowest_modes(&dense_a.stiffness, &dense_a.mass, n_modes, min_frequency_hz).unwrap();
    let t_dense = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let a = model.assemble_sparse().unwrap();
    let sp = sparse::lowest_modes_sparse(&a.stiffness, &a.mass, n_modes, min_frequency_hz).unwrap();
    let t_sparse = t0.elapsed().as_secs_f64();
    assert_eq!(a.dofs, dense_a.dofs);
    let m = from_dense(&dense_a.mass);
    println!(
        "{} dof: dense {t_dense:.2} s, sparse {t_sparse:.2} s",
        a.dofs.len()
    );
    for i in 0..n_modes {
        let (fs, fd) = (
            sp.omega_rad_s[i] / std::f64::consts::TAU,
            dense.omega_rad_s[i] / std::f64::consts::TAU,
        );
        let mphi = mul_columns(&m, &dense.shapes.columns(i, 1).into_owned());
        let c = (sp.shapes.column(i).transpose() * mphi)[(0, 0)];
        let kk = from_dense(&dense_a.stiffness);
        let res = |phi: nalgebra::DMatrix<f64>, w: f64| {
            let kp = mul_columns(&kk, &phi);
            let mp = mul_columns(&m, &phi);
            (&kp - &mp * (w * w)).norm() / kp.norm()
        };
        let (rd, rs) = (
            res(
                dense.shapes.columns(i, 1).into_owned(),
                dense.omega_rad_s[i],
            ),
            res(sp.shapes.columns(i, 1).into_owned(), sp.omega_rad_s[i]),
        );
        println!(
            "mode {}: dense {fd:.7} Hz, sparse {fs:.7} Hz ({:+.1e}), |φsᵀMφd| = {:.9}, \
             residual ‖Kφ − ω²Mφ‖/‖Kφ‖ dense {rd:.1e}, sparse {rs:.1e}",
            i + 1,
            fs / fd - 1.0,
            c.abs()
        );
        // the dense solver's residual is ~1e-8 here (L⁻¹KL⁻ᵀ of a stiff hex8 model): the sparse
        // pairs must be at least as accurate and agree to 1e-7
        assert!(rs <= rd.max(1e-8), "mode {}", i + 1);
        assert!((fs / fd - 1.0).abs() < 1e-7, "mode {}", i + 1);
        assert!((c.abs() - 1.0).abs() < 1e-6, "mode {}", i + 1);
    }
}

#[test]
fn sparse_matches_dense_on_hex8_cantilever() {
    compare(&bar([24, 3, 2], true), 6, 1e-3);
}

#[test]
fn sparse_matches_dense_on_free_free_hex8_bar_without_rigid_modes() {
    let m = bar([16, 2, 2], false);
    compare(&m, 4, 1.0);
}

/// `solver = "auto"` picks the sparse solver above 1500 dof: a 3D steel cantilever
/// (1 m × 20 × 10 mm, 400 Euler–Bernoulli elements, 2400 dof) through the scenario layer gives
/// the first four bending modes in the weak direction (βL = 1.8751, 4.6941, 7.8548, 10.9955)
/// within 0.01 %.
#[test]
fn auto_solver_uses_sparse_for_a_large_beam_model() {
    let text = r#"
[structure]
n_modes = 8
min_frequency_hz = 0.0

[structure.beam]
length_m = 1.0
elements = 400
youngs_modulus_pa = 210e9
poisson_ratio = 0.3
density_kg_m3 = 7850.0
width_m = 0.02
height_m = 0.01
timoshenko = false
planar = false
supports = [{ position_m = 0.0, kind = "clamped" }]

[[structure.points]]
name = "tip"
position_m = 1.0
"#;
    let file: pdamp_structure::scenario::StructureFile = toml::from_str(text).unwrap();
    let t0 = Instant::now();
    let built = file.structure.build(std::path::Path::new(".")).unwrap();
    println!(
        "{:?} dof, solver {:?}, {:.2} s",
        built.dof_count,
        built.solver,
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(built.dof_count, Some(2400));
    assert_eq!(built.solver, Some("sparse"));
    // bending about the weak axis (h = 10 mm): EI with I = w h³/12
    let (e, rho, w, h, l): (f64, f64, f64, f64, f64) = (210e9, 7850.0, 0.02, 0.01, 1.0);
    let i_weak = w * h * h * h / 12.0;
    let c = (e * i_weak / (rho * w * h)).sqrt() / (std::f64::consts::TAU * l * l);
    let f_exact: Vec<f64> = [1.875_104_07, 4.694_091_13, 7.854_757_44, 10.995_540_73]
        .iter()
        .map(|b| b * b * c)
        .collect();
    // the weak-axis modes among the computed ones (strong-axis, torsion and axial interleave)
    for fe in &f_exact {
        let best = built
            .modal
            .modes
            .iter()
            .map(|m| m.frequency_hz)
            .min_by(|a, b| (a - fe).abs().total_cmp(&(b - fe).abs()))
            .unwrap();
        println!("closed form {fe:.4} Hz, sparse {best:.4} Hz");
        assert!((best / fe - 1.0).abs() < 1e-4, "{best} vs {fe}");
    }
}
