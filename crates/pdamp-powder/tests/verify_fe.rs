//! Must-show 1 of issue 5: the structural solver alone.
//!
//! - The hex8/SVK element: tangent = derivative of the internal force (finite differences),
//!   rigid-body invariance of SVK (no force under a finite rotation).
//! - First bending frequency of an empty square tube against Timoshenko beam theory (2 %), and
//!   of the paper's hollow beam (cavity with solid ends) against a piecewise Timoshenko beam and
//!   under mesh refinement (2 %).
//! - Generalized-α with ρ∞ = 1 conserves the energy of a free oscillation (≤ 1e-6 relative per
//!   period); with ρ∞ = 0.8 the first mode keeps its energy while unresolved modes decay with
//!   spectral radius 0.8 per step.

use pdamp_powder::cantilever::{BeamSpec, LoadSpec, build_structure};
use pdamp_powder::fe::beam_theory::{self, Segment};
use pdamp_powder::fe::modes::lowest_modes;
use pdamp_powder::fe::svk::{self, element_force, element_tangent};
use pdamp_powder::fe::{
    Aabb, BoxMeshDivisions, Dynamics, GenAlpha, HexMesh, MassKind, Rayleigh, Structure, SvkMaterial,
};

const MAT: SvkMaterial = SvkMaterial::STEEL_316L;

fn tube(length: f64, h_core: f64, h_len: f64) -> Structure {
    let mesh = HexMesh::box_with_cavity(
        [0.02, 0.02, length],
        Some(Aabb {
            min: [0.001, 0.001, 0.0],
            max: [0.019, 0.019, length],
        }),
        BoxMeshDivisions {
            wall_element_m: 0.001,
            core_element_m: h_core,
            length_element_m: h_len,
        },
    );
    let clamped = mesh.nodes_on_plane(2, 0.0, 1e-12);
    Structure::new(mesh, MAT, &clamped, MassKind::Consistent, [0.0; 3])
}

#[test]
fn tangent_is_the_derivative_of_the_internal_force() {
    let mesh = HexMesh::box_with_cavity(
        [1e-3, 2e-3, 1.5e-3],
        None,
        BoxMeshDivisions {
            wall_element_m: 1.0,
            core_element_m: 1.0,
            length_element_m: 1.0,
        },
    );
    let g = &svk::precompute(&mesh)[0];
    let (lam, mu) = MAT.lame();
    let mut u = [[0.0; 3]; 8];
    for (a, ua) in u.iter_mut().enumerate() {
        for (i, x) in ua.iter_mut().enumerate() {
            *x = 1e-4 * (((a * 3 + i) * 37 % 11) as f64 - 5.0) * 1e-1;
        }
    }
    let k = element_tangent(g, &u, lam, mu);
    let h = 1e-9;
    let mut max_err = 0.0f64;
    let kmax = k.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for c in 0..24 {
        let mut up = u;
        let mut um = u;
        up[c / 3][c % 3] += h;
        um[c / 3][c % 3] -= h;
        let (fp, _) = element_force(g, &up, lam, mu);
        let (fm, _) = element_force(g, &um, lam, mu);
        for r in 0..24 {
            max_err = max_err.max(((fp[r] - fm[r]) / (2.0 * h) - k[r * 24 + c]).abs());
        }
    }
    assert!(
        max_err < 1e-6 * kmax,
        "tangent error {max_err:e} (scale {kmax:e})"
    );
    // rigid rotation by 30° about z: SVK gives zero force (objectivity)
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let el = mesh.elements[0];
    let mut ur = [[0.0; 3]; 8];
    for a in 0..8 {
        let x = mesh.nodes[el[a]];
        ur[a] = [c * x[0] - s * x[1] - x[0], s * x[0] + c * x[1] - x[1], 0.0];
    }
    let (f, w) = element_force(g, &ur, lam, mu);
    assert!(f.iter().all(|x| x.abs() < 1e-12 * kmax * 1e-3), "{f:?}");
    assert!(w.abs() < 1e-12);
}

#[test]
fn tube_first_bending_frequency_matches_timoshenko_within_2_percent() {
    let length = 0.2;
    let s = tube(length, 0.003, 0.0025);
    let (f, _) = lowest_modes(&s, 2).unwrap();
    let seg = Segment {
        length_m: length,
        outer_m: 0.02,
        inner_m: 0.018,
    };
    let f_timo = beam_theory::timoshenko_f1(
        &[seg],
        MAT.youngs_modulus_pa,
        MAT.poisson_ratio,
        MAT.density_kg_m3,
        400,
        &[],
    );
    let f_eb = beam_theory::euler_bernoulli_f1(&seg, MAT.youngs_modulus_pa, MAT.density_kg_m3);
    eprintln!(
        "tube L = 0.2 m: hex8 f1 = {:.2} Hz, f2 = {:.2} Hz; Timoshenko {f_timo:.2} Hz; Euler–Bernoulli {f_eb:.2} Hz; dofs {}",
        f[0],
        f[1],
        s.n_dof()
    );
    // square section: the two bending modes coincide
    assert!((f[1] / f[0] - 1.0).abs() < 1e-6);
    assert!(
        (f[0] / f_timo - 1.0).abs() < 0.02,
        "hex8 {} vs Timoshenko {f_timo}",
        f[0]
    );
}

fn paper_beam(h_wall: f64, h_core: f64, h_len: f64) -> BeamSpec {
    BeamSpec {
        length_m: 0.132,
        width_m: 0.02,
        wall_thickness_m: 0.001,
        cavity_length_m: 0.11,
        cavity_offset_m: 0.002,
        material: MAT,
        wall_element_m: h_wall,
        core_element_m: h_core,
        length_element_m: h_len,
        mass: MassKind::Consistent,
        rho_inf: 0.8,
        rayleigh: Rayleigh::default(),
        kinematics: Default::default(),
    }
}

#[test]
fn paper_beam_frequency_beam_theory_and_mesh_convergence() {
    let coarse =
        pdamp_powder::cantilever::empty_beam_modes(&paper_beam(0.001, 0.006, 0.004), 1).unwrap()[0];
    let medium =
        pdamp_powder::cantilever::empty_beam_modes(&paper_beam(0.001, 0.003, 0.002), 1).unwrap()[0];
    let segs = [
        Segment {
            length_m: 0.002,
            outer_m: 0.02,
            inner_m: 0.0,
        },
        Segment {
            length_m: 0.11,
            outer_m: 0.02,
            inner_m: 0.018,
        },
        Segment {
            length_m: 0.02,
            outer_m: 0.02,
            inner_m: 0.0,
        },
    ];
    let f_timo = beam_theory::timoshenko_f1(
        &segs,
        MAT.youngs_modulus_pa,
        MAT.poisson_ratio,
        MAT.density_kg_m3,
        660,
        &[],
    );
    eprintln!(
        "paper beam empty: coarse {coarse:.2} Hz, medium {medium:.2} Hz, Timoshenko (piecewise) {f_timo:.2} Hz"
    );
    assert!(
        (coarse / medium - 1.0).abs() < 0.02,
        "mesh change {coarse} → {medium}"
    );
    assert!(
        (medium / f_timo - 1.0).abs() < 0.02,
        "hex8 {medium} vs Timoshenko {f_timo}"
    );
}

fn energy(dy: &Dynamics, s: &Structure) -> f64 {
    dy.kinetic_energy(s) + dy.strain_energy
}

#[test]
fn gen_alpha_rho1_conserves_energy_of_free_oscillation() {
    let mut s = tube(0.1, 0.006, 0.005);
    let (f, shapes) = lowest_modes(&s, 1).unwrap();
    let period = 1.0 / f[0];
    let dt = period / 40.0;
    // first mode, tip amplitude 0.1 mm (small strains, nonlinear SVK forces)
    let tip = s.mesh.nearest_node([0.01, 0.0, 0.1]);
    let scale = 1e-4
        / shapes[0][3 * tip..3 * tip + 3]
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
    // start from the undeformed state with the modal velocity (a0 = 0, no rough initial forces)
    let v0: Vec<f64> = shapes[0]
        .iter()
        .map(|x| x * scale * 2.0 * std::f64::consts::PI * f[0])
        .collect();
    let n = s.n_dof();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(1.0),
        dt,
        vec![0.0; n],
        v0,
        Rayleigh::default(),
    )
    .unwrap();
    dy.newton.tolerance = 1e-13;
    let e0 = energy(&dy, &s);
    let periods = 5;
    let mut worst = 0.0f64;
    for _ in 0..periods * 40 {
        dy.step(&mut s).unwrap();
        worst = worst.max((energy(&dy, &s) - e0).abs() / e0);
    }
    let drift_per_period = (energy(&dy, &s) - e0).abs() / e0 / periods as f64;
    eprintln!(
        "ρ∞ = 1: max |ΔE|/E0 over {periods} periods = {worst:e}, drift per period = {drift_per_period:e}"
    );
    assert!(drift_per_period < 1e-6 && worst < 1e-6 * periods as f64);
}

#[test]
fn gen_alpha_rho08_damps_unresolved_modes_and_keeps_the_first() {
    // (a) first mode resolved with 40 steps per period loses little energy per period
    let mut s = tube(0.1, 0.006, 0.005);
    let (f, shapes) = lowest_modes(&s, 1).unwrap();
    let dt = 1.0 / f[0] / 40.0;
    let n = s.n_dof();
    let v0: Vec<f64> = shapes[0]
        .iter()
        .map(|x| x * 1e-6 * 2.0 * std::f64::consts::PI * f[0])
        .collect();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.8),
        dt,
        vec![0.0; n],
        v0,
        Rayleigh::default(),
    )
    .unwrap();
    let e0 = energy(&dy, &s);
    for _ in 0..40 {
        dy.step(&mut s).unwrap();
    }
    let loss = 1.0 - energy(&dy, &s) / e0;
    // generalized-α with ρ∞ = 0.8 at Ω = ωΔt = 2π/40: ξ̄ ≈ O(Ω³) → energy loss ≈ 4πξ̄ ~ 1e-3
    eprintln!("ρ∞ = 0.8: first-mode energy loss per period at 40 steps/period = {loss:e}");
    assert!(loss > 0.0 && loss < 5e-3, "{loss}");
    // (b) a random initial velocity with Δt = 1000 × the period of mode 1: everything is
    // unresolved; the energy decays by ρ∞² per step asymptotically
    let dt = 1000.0 / f[0];
    let v0: Vec<f64> = (0..n)
        .map(|i| ((i * 7919 % 101) as f64 - 50.0) * 2e-8)
        .collect();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.8),
        dt,
        vec![0.0; n],
        v0,
        Rayleigh::default(),
    )
    .unwrap();
    dy.newton.tolerance = 1e-12;
    let mut e = Vec::new();
    for _ in 0..200 {
        dy.step(&mut s).unwrap();
        e.push(energy(&dy, &s));
    }
    let rate = (e[199] / e[99]).powf(1.0 / 200.0); // per-step amplitude factor
    eprintln!("ρ∞ = 0.8, Δt ≫ T: amplitude factor per step = {rate:.4} (ρ∞ = 0.8)");
    assert!((rate - 0.8).abs() < 0.03, "{rate}");
    // and ρ∞ = 1 keeps it (no algorithmic damping)
    let v0: Vec<f64> = (0..n)
        .map(|i| ((i * 7919 % 101) as f64 - 50.0) * 2e-8)
        .collect();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(1.0),
        dt,
        vec![0.0; n],
        v0,
        Rayleigh::default(),
    )
    .unwrap();
    dy.newton.tolerance = 1e-12;
    let e0 = energy(&dy, &s);
    for _ in 0..50 {
        dy.step(&mut s).unwrap();
    }
    assert!((energy(&dy, &s) / e0 - 1.0).abs() < 1e-6);
}

#[test]
fn static_tip_deflection_under_the_paper_load() {
    // 0.1 N/mm² on the x = 0 face, quasi-static (slow ramp, strongly damped) → ≈ 0.1 mm (paper Sect. 2.4)
    let beam = paper_beam(0.001, 0.006, 0.004);
    let (mut s, tip) = build_structure(
        &beam,
        &LoadSpec {
            pressure_pa: 1e5,
            rise_s: 1e-9,
            hold_s: f64::INFINITY,
        },
        [0.0; 3],
    );
    let n = s.n_dof();
    let mut dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.0),
        1.0,
        vec![0.0; n],
        vec![0.0; n],
        Rayleigh::default(),
    )
    .unwrap();
    for _ in 0..3 {
        dy.step(&mut s).unwrap();
    }
    let x = dy.d[3 * tip];
    // Closed form: Timoshenko cantilever under the line load q = p·b over its whole length,
    // piecewise in z (solid 2 mm, tube 110 mm with 1 mm walls, solid 20 mm), by the unit-load
    // method: bending Σ q[(L−a)⁴ − (L−b)⁴]/(8EI), shear Σ q[(L−a)² − (L−b)²]/(2κGA), κ = 5/6
    // for the solid square and the web share 2th/A for the thin-walled tube (shear is ≈ 7 %
    // of the total; κ between 0.44 and 0.53 moves the total by < 1 %).
    let (e, nu) = (MAT.youngs_modulus_pa, MAT.poisson_ratio);
    let g = e / (2.0 * (1.0 + nu));
    let (b, t, l): (f64, f64, f64) = (0.02, 0.001, 0.132);
    let q = 1e5 * b;
    let solid = (b.powi(4) / 12.0, b * b, 5.0 / 6.0);
    let inner = b - 2.0 * t;
    let tube_area = b * b - inner * inner;
    let tube = (
        (b.powi(4) - inner.powi(4)) / 12.0,
        tube_area,
        2.0 * t * b / tube_area,
    );
    let closed: f64 = [(0.0, 0.002, solid), (0.002, 0.112, tube), (0.112, l, solid)]
        .iter()
        .map(|&(za, zb, (i, a, k)): &(f64, f64, (f64, f64, f64))| {
            q * ((l - za).powi(4) - (l - zb).powi(4)) / (8.0 * e * i)
                + q * ((l - za).powi(2) - (l - zb).powi(2)) / (2.0 * k * g * a)
        })
        .sum();
    eprintln!(
        "static tip deflection under q = 0.1 N/mm²: {:.4} mm (Timoshenko closed form {:.4} mm; paper ≈ 0.1 mm)",
        x * 1e3,
        closed * 1e3
    );
    // (the same integrals summed numerically, independently of this code: 0.0969 mm)
    assert!(
        (closed - 0.0969e-3).abs() < 0.0002e-3,
        "closed form {closed}"
    );
    assert!(
        (x / closed - 1.0).abs() < 0.03,
        "FE {x} vs closed form {closed}"
    );
}

#[test]
fn single_precision_modified_newton_converges_to_the_double_precision_full_newton_answer() {
    // The paper load on a coarse paper beam with a fast ramp, 40 steps: modified Newton with
    // the single-precision factor of the reference tangent against full Newton with a
    // double-precision factor of the current tangent in every iteration. Both stop at a
    // relative residual of 1e-12, so the displacements agree to ≈ 1e-11 of their size (the
    // single-precision factor only changes the path, not the answer; a factor that solved the
    // wrong system, or a residual in single precision, would show here as 1e-7 or worse).
    let beam = paper_beam(0.001, 0.006, 0.004);
    let load = LoadSpec {
        pressure_pa: 1e5,
        rise_s: 2e-4,
        hold_s: f64::INFINITY,
    };
    let run = |full: bool| {
        let (mut s, _) = build_structure(&beam, &load, [0.0, 0.0, -9.81]);
        let n = s.n_dof();
        let mut dy = Dynamics::new(
            &mut s,
            GenAlpha::from_rho_inf(0.8),
            5e-6,
            vec![0.0; n],
            vec![0.0; n],
            Rayleigh::default(),
        )
        .unwrap();
        dy.newton.tolerance = 1e-12;
        dy.newton.full_newton = full;
        let mut iterations = 0;
        for _ in 0..40 {
            iterations += dy.step(&mut s).unwrap();
        }
        (dy.d, iterations)
    };
    let (modified, it_modified) = run(false);
    let (full, it_full) = run(true);
    let size = full.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = modified
        .iter()
        .zip(&full)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!(
        "modified Newton (single-precision factor) vs full Newton: max |Δd| = {:.2e} of max |d| = {size:.3e} m; iterations {it_modified} vs {it_full}",
        diff / size
    );
    assert!(size > 1e-6, "the load must deform the beam: {size}");
    assert!(diff < 1e-9 * size, "{diff} of {size}");
    // four digits per iteration (the tangent changes little at strains of 1e-5)
    assert!(it_modified <= 4 * 40, "{it_modified} iterations");
}

#[test]
fn double_precision_factor_is_part_of_the_checkpoint() {
    // A run whose tangent factor went to double precision (automatically when the single-
    // precision factor stops converging, or asked for) must resume with it: the two factors
    // take different Newton paths, whose converged states differ in the last bits.
    let mut s = tube(0.05, 0.006, 0.005);
    let n = s.n_dof();
    let tip = s.mesh.nearest_node([0.01, 0.0, 0.05]);
    let new = |s: &mut Structure| {
        Dynamics::new(
            s,
            GenAlpha::from_rho_inf(0.8),
            2e-6,
            vec![0.0; n],
            vec![0.0; n],
            Rayleigh::default(),
        )
        .unwrap()
    };
    let mut load = vec![0.0; n];
    load[3 * tip] = 10.0;
    let step = |dy: &mut Dynamics, s: &mut Structure| {
        dy.solve(s, Some(&load), true).unwrap();
        dy.commit();
    };
    let mut single = new(&mut s);
    let mut double = new(&mut s);
    double.use_double_factor().unwrap();
    for _ in 0..10 {
        step(&mut single, &mut s);
        step(&mut double, &mut s);
    }
    assert!(!single.save_state().double_factor);
    let saved = double.save_state();
    assert!(saved.double_factor);
    let mut resumed = new(&mut s);
    resumed.restore_state(saved).unwrap();
    let mut from_single = new(&mut s);
    from_single.restore_state(single.save_state()).unwrap();
    let mut differs = false;
    for _ in 0..10 {
        step(&mut double, &mut s);
        step(&mut resumed, &mut s);
        step(&mut single, &mut s);
        step(&mut from_single, &mut s);
        let same = |a: &Dynamics, b: &Dynamics| {
            a.d.iter()
                .zip(&b.d)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        };
        assert!(same(&double, &resumed) && same(&single, &from_single));
        differs |= !same(&single, &double);
    }
    assert!(double.d[3 * tip] > 0.0);
    assert!(
        differs,
        "the two factors must take different paths (else this test cannot fail)"
    );
}

#[test]
fn gmsh_and_abaqus_import_give_the_same_hex() {
    let msh = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n$EndNodes\n$Elements\n1\n1 5 2 0 1 1 2 3 4 5 6 7 8\n$EndElements\n";
    let inp = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n";
    let a = pdamp_powder::fe::read_gmsh(msh, 1e-3).unwrap();
    let b = pdamp_powder::fe::read_abaqus_inp(inp, 1e-3).unwrap();
    assert_eq!(a.elements, b.elements);
    assert_eq!(a.nodes, b.nodes);
    assert!((a.volume() - 1e-9).abs() < 1e-22);
    assert_eq!(a.boundary_faces().len(), 6);
}

#[test]
fn linear_kinematics_is_the_first_order_term_of_the_finite_model() {
    // A bending-like displacement field d on the coarse paper beam (tip 0.1 mm, the paper's
    // amplitude). Small deformation: f_int = K₀ d exactly (the same sparse product) and the
    // strain energy ½ dᵀK₀d. Finite deformation: f_int(d) − K₀ d is the second-order term, so it
    // grows 4 × when d doubles (±2 %), and it is small against the nodal forces K₀d.
    let beam = paper_beam(0.001, 0.006, 0.004);
    let load = LoadSpec {
        pressure_pa: 1e5,
        rise_s: 5e-3,
        hold_s: 1e-3,
    };
    let (mut s, _) = build_structure(&beam, &load, [0.0; 3]);
    let n = s.n_dof();
    let (nodes, free) = (s.mesh.nodes.clone(), s.free.clone());
    let field = |scale: f64| -> Vec<f64> {
        let mut d = vec![0.0; n];
        for (a, x) in nodes.iter().enumerate() {
            let z = x[2] / 0.132;
            // cantilever-like bending along x with a little shear along y
            d[3 * a] = scale * 1e-4 * z * z * (3.0 - z) / 2.0;
            d[3 * a + 1] = scale * 1e-6 * z;
            d[3 * a + 2] = -scale * 1e-4 * (x[0] - 0.01) * 3.0 * z * (2.0 - z) / 2.0 / 0.132;
        }
        for (g, x) in d.iter_mut().enumerate() {
            if free[g] == usize::MAX {
                *x = 0.0;
            }
        }
        d
    };
    let k0_times = |s: &Structure, d: &[f64]| -> (Vec<f64>, f64) {
        let df: Vec<f64> = s.free_dofs.iter().map(|&g| d[g]).collect();
        let mut kd = vec![0.0; df.len()];
        s.k0.mul(&df, &mut kd);
        let e = 0.5 * df.iter().zip(&kd).map(|(a, b)| a * b).sum::<f64>();
        (kd, e)
    };
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let d1 = field(1.0);
    let (kd, e_lin) = k0_times(&s, &d1);
    let mut f = vec![0.0; n];
    s.set_kinematics(pdamp_powder::fe::Kinematics::Linear);
    let e = s.internal_force(&d1, &mut f);
    for (k, &g) in s.free_dofs.iter().enumerate() {
        assert_eq!(f[g].to_bits(), kd[k].to_bits(), "free dof {k}");
    }
    assert!((e - e_lin).abs() <= 1e-14 * e_lin, "{e} vs {e_lin}");
    assert_eq!(s.tangent(&d1).values, s.k0.values);
    s.set_kinematics(pdamp_powder::fe::Kinematics::Finite);
    let second_order = |s: &mut Structure, d: &[f64]| -> f64 {
        let (kd, _) = k0_times(s, d);
        let mut f = vec![0.0; n];
        s.internal_force(d, &mut f);
        let diff: Vec<f64> = s
            .free_dofs
            .iter()
            .enumerate()
            .map(|(k, &g)| f[g] - kd[k])
            .collect();
        max_abs(&diff)
    };
    let r1 = second_order(&mut s, &d1);
    let r2 = second_order(&mut s, &field(2.0));
    eprintln!(
        "finite − linear internal force: {r1:.3e} N at a 0.1 mm tip, {r2:.3e} N at 0.2 mm \
         (ratio {:.4}); max |K₀d| = {:.3e} N",
        r2 / r1,
        max_abs(&kd)
    );
    assert!((r2 / r1 - 4.0).abs() < 0.08, "ratio {}", r2 / r1);
    // a few per cent of the nodal forces of this (non-equilibrium) field at 0.1 mm: 1.4 %
    assert!(r1 < 3e-2 * max_abs(&kd), "{r1} vs {}", max_abs(&kd));
}
