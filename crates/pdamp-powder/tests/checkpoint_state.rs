//! Checkpoint states of the DEM–FEM model (docs/reliability.md): a preparation and a coupled
//! particle–plate run saved to a checkpoint file at many points, read back and continued end
//! bit for bit as the uninterrupted ones. The end-to-end test (`pdamp powder run` killed and
//! resumed) is `crates/pdamp-cli/tests/kill_resume.rs`.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use pdamp_dem::Vec3;
use pdamp_io::checkpoint::{self as ck, CheckpointHeader};
use pdamp_powder::bed::PowderBed;
use pdamp_powder::couple::{Coupled, CoupledState, CouplingSettings, Interface};
use pdamp_powder::fe::{
    Aabb, BoxMeshDivisions, Dynamics, GenAlpha, HexMesh, MassKind, Rayleigh, Structure, SvkMaterial,
};
use pdamp_powder::law::PowderLaw;
use pdamp_powder::prep::{self, PrepSettings, Preparation};
use pdamp_powder::psd::LogNormal;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-powder-ck-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes `value` through the checkpoint writer and reads it back.
fn round_trip<T: serde::Serialize + for<'de> serde::Deserialize<'de>>(dir: &Path, value: &T) -> T {
    let p = dir.join("state.bin");
    ck::save(&p, &CheckpointHeader::new("test", "digest"), value).unwrap();
    ck::load(&p, "test", "digest").unwrap().unwrap()
}

/// The bytes of a checkpoint file holding `value` (equal bytes = equal state, bit for bit).
fn bytes<T: serde::Serialize>(dir: &Path, name: &str, value: &T) -> Vec<u8> {
    let p = dir.join(name);
    ck::save(&p, &CheckpointHeader::new("test", "digest"), value).unwrap();
    std::fs::read(p).unwrap()
}

#[test]
fn preparation_continued_from_checkpoints_is_bit_identical() {
    let dir = scratch("prep");
    // ≈ 60 coarse particles (D50 = 2 mm) in a 6 × 6 × 12 mm cavity: settling, relaxation,
    // compression and holding in ≈ 3 000 steps
    let cavity = Aabb {
        min: [0.0; 3],
        max: [0.006, 0.006, 0.012],
    };
    let psd = LogNormal::paper(2e-3);
    let law = PowderLaw::PAPER.coarse_grained(2.0);
    let dt = 5e-6;
    // with the preparation's own friction and adhesion: a restored preparation must rebuild
    // its world with them (and hand the bed over with the law)
    let s = PrepSettings {
        packing_density: 0.5,
        max_settling_time_s: 0.01,
        relax_time_s: 5e-4,
        friction: Some(0.8),
        surface_energy_j_m2: Some(1.0),
        ..PrepSettings::default()
    };
    let (p_ref, mut rep_ref) =
        prep::prepare(cavity, &psd, law, 8000.0, dt, &s, &mut |_, _| {}).unwrap();
    assert!(rep_ref.compressed, "the test must cover the compression");
    let mut pr = Preparation::new(cavity, &psd, law, 8000.0, dt, &s);
    let (mut calls, mut stops) = (0u64, 0);
    loop {
        let flow = pr
            .run(&mut |_, _| {}, &mut |_| {
                calls += 1;
                if calls.is_multiple_of(311) {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .unwrap();
        if flow.is_continue() {
            break;
        }
        stops += 1;
        pr = round_trip(&dir, &pr.snapshot());
        pr.check_consistency().unwrap();
    }
    let (p, mut rep) = pr.finish();
    eprintln!(
        "{} particles, {} steps, continued {stops} times from a checkpoint",
        p.len(),
        rep.steps
    );
    assert!(stops > 20, "{stops}");
    (rep.wall_time_s, rep_ref.wall_time_s) = (0.0, 0.0);
    assert_eq!(rep, rep_ref);
    assert!(
        bytes(&dir, "a.bin", &p.world.save_state())
            == bytes(&dir, "b.bin", &p_ref.world.save_state())
    );
    let _ = std::fs::remove_dir_all(&dir);
}

const R: f64 = 1e-3;
const TOP: f64 = 2e-3;

/// A 20 × 20 × 2 mm plate clamped at its edges (E = 1 GPa, so that it takes part) with four
/// touching particles sliding and rolling on it.
fn system() -> Coupled {
    let mesh = HexMesh::box_with_cavity(
        [0.02, 0.02, TOP],
        None,
        BoxMeshDivisions {
            wall_element_m: 1e-3,
            core_element_m: 2e-3,
            length_element_m: 1e-3,
        },
    );
    let tol = 1e-12;
    let mut clamped = Vec::new();
    for (axis, v) in [(0, 0.0), (0, 0.02), (1, 0.0), (1, 0.02)] {
        clamped.extend(mesh.nodes_on_plane(axis, v, tol));
    }
    clamped.sort_unstable();
    clamped.dedup();
    let faces = HexMesh::faces_on_plane(&mesh.boundary_faces(), &mesh.nodes, 2, TOP, tol);
    let mat = SvkMaterial {
        youngs_modulus_pa: 1e9,
        ..SvkMaterial::STEEL_316L
    };
    let mut s = Structure::new(mesh, mat, &clamped, MassKind::Consistent, [0.0; 3]);
    let dt = 1e-6;
    let n = s.n_dof();
    let dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.8),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        Rayleigh::default(),
    )
    .unwrap();
    let z = TOP + R - 2e-6;
    let pos = vec![
        [0.00701, 0.0093, z],
        [0.00900, 0.0093, z],
        [0.01099, 0.0093, z],
        [0.00900, 0.01119, z + 1e-5],
    ];
    let mut p = PowderBed::at_rest(
        PowderLaw::PAPER,
        &pos,
        &[R, R, R, 0.9 * R],
        8000.0,
        [0.0, 0.0, -9.81],
        dt,
    );
    let v = &mut p.world.particles.velocity;
    v[0] = Vec3::new(0.05, 0.0, -0.02);
    v[1] = Vec3::new(-0.03, 0.01, 0.0);
    v[2] = Vec3::new(0.0, -0.04, -0.05);
    v[3] = Vec3::new(0.02, 0.02, -0.1);
    p.world.particles.angular_velocity[1] = Vec3::new(0.0, 30.0, 0.0);
    Coupled::new(
        s,
        dy,
        p,
        Interface::new(faces),
        CouplingSettings {
            tolerance: 1e-6,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn coupled_run_continued_from_checkpoints_is_bit_identical() {
    let dir = scratch("coupled");
    let steps = 600;
    let mut a = system();
    let mut pp = 0;
    for _ in 0..steps {
        a.step().unwrap();
        pp = pp.max(a.world.num_pp_contacts());
    }
    let l = a.world.ledger;
    let (pp_j, pw_j) = (
        l.dissipated_normal_pp_j + l.dissipated_tangential_pp_j,
        l.dissipated_normal_pw_j + l.dissipated_tangential_pw_j,
    );
    eprintln!(
        "touching pairs ≤ {pp}, dissipated pp {pp_j:.2e} J, pw {pw_j:.2e} J, iterations {}",
        a.total_iterations
    );
    assert!(
        pp > 0 && pp_j > 0.0 && pw_j > 0.0,
        "contacts between the particles and with the plate"
    );
    let mut b = system();
    for k in 0..steps {
        if k % 150 == 75 {
            let st: CoupledState = round_trip(&dir, &b.save_state());
            let fresh = system();
            b = Coupled::from_state(
                fresh.structure,
                fresh.dynamics,
                fresh.interface,
                fresh.settings,
                st,
            )
            .unwrap();
        }
        b.step().unwrap();
    }
    assert_eq!(a.energy(), b.energy());
    assert!(
        bytes(&dir, "a.bin", &a.save_state()) == bytes(&dir, "b.bin", &b.save_state()),
        "same state bit for bit"
    );
    // a state of another system is refused, not a panic
    let mut other = b.save_state();
    other.law.friction = -1.0;
    let fresh = system();
    let e = Coupled::from_state(
        fresh.structure,
        fresh.dynamics,
        fresh.interface,
        fresh.settings,
        other,
    )
    .err()
    .expect("refused");
    assert!(
        e.to_string().contains("coupling state: law.friction"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
