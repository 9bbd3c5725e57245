//! Wall time of the sparse modal reduction (`pdamp_structure::sparse::lowest_modes_sparse`) on
//! clamped hex8 bars and a free–free plate-like block of growing size, with the first and last
//! frequency: `cargo run --release -p pdamp-structure --example sparse_modes_bench`.
//! The same source ran against the previous solver (skyline LDLᵀ + subspace iteration, commit
//! 5a65de8) for the comparison in docs/structure.md.

use pdamp_structure::fe::{Dof, FeModel, SolidMaterial};
use pdamp_structure::sparse;
use std::time::Instant;

fn block(size: [f64; 3], cells: [usize; 3], clamp: bool) -> FeModel {
    let mat = SolidMaterial {
        youngs_modulus_pa: 70e9,
        poisson_ratio: 0.3,
        density_kg_m3: 2700.0,
    };
    let mut m = FeModel::default();
    m.add_solid_block([0.0; 3], size, cells, mat, true);
    if clamp {
        for n in 0..m.nodes.len() {
            if m.nodes[n][0] == 0.0 {
                m.fix(n, &Dof::TRANSLATIONS);
            }
        }
    }
    m
}

fn main() {
    let cases = [
        (
            "clamped bar 0.6 m",
            [0.6, 0.05, 0.03],
            [48, 4, 3],
            true,
            10,
            0.0,
        ),
        (
            "clamped bar 0.6 m",
            [0.6, 0.05, 0.03],
            [96, 8, 5],
            true,
            10,
            0.0,
        ),
        (
            "clamped bar 0.6 m",
            [0.6, 0.05, 0.03],
            [160, 12, 8],
            true,
            20,
            0.0,
        ),
        (
            "free-free plate",
            [0.4, 0.3, 0.01],
            [40, 30, 2],
            false,
            20,
            1.0,
        ),
    ];
    for (name, size, cells, clamp, n_modes, f_min) in cases {
        let a = block(size, cells, clamp).assemble_sparse().unwrap();
        let t0 = Instant::now();
        let b = sparse::lowest_modes_sparse(&a.stiffness, &a.mass, n_modes, f_min).unwrap();
        let t = t0.elapsed().as_secs_f64();
        let f = |i: usize| b.omega_rad_s[i] / std::f64::consts::TAU;
        println!(
            "{name} {cells:?}: {} dof, {n_modes} modes: {t:.3} s, f1 = {:.6} Hz, f{n_modes} = {:.6} Hz",
            a.dofs.len(),
            f(0),
            f(n_modes - 1)
        );
    }
}
