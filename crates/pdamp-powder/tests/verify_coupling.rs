//! Must-show 2 of issue 5: the Dirichlet–Neumann coupling (paper Sect. 2.3).
//!
//! - A particle bouncing on (and then resting on) a stiff deformable plate has the contact force
//!   history of the same particle on a rigid plane (1 % of the peak force), and rests with
//!   F = m g.
//! - Interface equilibrium: the nodal interface forces of eq. 15 balance the particle wall
//!   forces (Σ N_j = 1) to round-off.
//! - Energy balance of the coupled system (elastic contact, ρ∞ = 1): stored energy of particle
//!   and plate + dissipation − load work stays constant within 1e-3 of the initial energy.

use pdamp_dem::walls::{Geometry, Plane};
use pdamp_dem::{BodyState, Motion, RigidBody, Vec3};
use pdamp_powder::bed::{PowderBed, WALL_MATERIAL};
use pdamp_powder::couple::{Coupled, CouplingSettings, Interface};
use pdamp_powder::fe::{
    BoxMeshDivisions, Dynamics, GenAlpha, HexMesh, MassKind, Rayleigh, Structure, SvkMaterial,
};
use pdamp_powder::law::PowderLaw;

const R: f64 = 1e-3;
const TOP: f64 = 2e-3;

fn plate(e_pa: f64) -> (Structure, Interface) {
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
        youngs_modulus_pa: e_pa,
        ..SvkMaterial::STEEL_316L
    };
    (
        Structure::new(mesh, mat, &clamped, MassKind::Consistent, [0.0; 3]),
        Interface::new(faces),
    )
}

fn particle(law: PowderLaw, height: f64, vz: f64, dt: f64) -> PowderBed {
    // slightly off the plate centre so that the contact is inside a face
    let mut p = PowderBed::at_rest(
        law,
        &[[0.0093, 0.0107, TOP + R + height]],
        &[R],
        8000.0,
        [0.0, 0.0, -9.81],
        dt,
    );
    p.world.particles.velocity[0] = Vec3::new(0.0, 0.0, vz);
    p
}

fn coupled(e_pa: f64, law: PowderLaw, rho_inf: f64, dt: f64) -> Coupled {
    coupled_with(e_pa, particle(law, 1e-5, -0.2, dt), rho_inf, dt)
}

fn coupled_with(e_pa: f64, p: PowderBed, rho_inf: f64, dt: f64) -> Coupled {
    let settings = CouplingSettings {
        tolerance: 1e-6,
        ..Default::default()
    };
    coupled_with_settings(e_pa, p, rho_inf, dt, settings)
}

fn coupled_with_settings(
    e_pa: f64,
    p: PowderBed,
    rho_inf: f64,
    dt: f64,
    settings: CouplingSettings,
) -> Coupled {
    let (mut s, iface) = plate(e_pa);
    let n = s.n_dof();
    let dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(rho_inf),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        Rayleigh::default(),
    )
    .unwrap();
    Coupled::new(s, dy, p, iface, settings).unwrap()
}

#[test]
fn bouncing_and_resting_particle_matches_rigid_plate() {
    let law = PowderLaw::PAPER;
    let dt = 1e-6;
    let steps = 2_000; // the first impact (contact time ≈ 0.24 ms) and the start of the rebound
    // rigid plane
    let mut p = particle(law, 1e-5, -0.2, dt).world;
    p.add_body(
        RigidBody::new("plane", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "top",
            Geometry::Plane(Plane::new(Vec3::new(0.0, 0.0, TOP), Vec3::z(), false)),
            WALL_MATERIAL,
        ),
    );
    let mut f_rigid = Vec::with_capacity(steps);
    for _ in 0..steps {
        p.step();
        f_rigid.push(-p.body_load(0).0.z);
    }
    // deformable plate, 1000 × steel stiffness
    let mut c = coupled(175e12, law, 0.8, dt);
    let mut f_def = Vec::with_capacity(steps);
    let mut worst_eq = 0.0f64;
    for _ in 0..steps {
        c.step().unwrap();
        f_def.push(c.wall_force(0)[2]);
        let (fp, fs) = c.interface_force_sums();
        for k in 0..3 {
            worst_eq = worst_eq.max((fp[k] + fs[k]).abs());
        }
    }
    let peak = f_rigid.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = f_rigid
        .iter()
        .zip(&f_def)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "peak contact force {peak:.4e} N, max |F_deformable − F_rigid| = {diff:.3e} N ({:.3e} of peak); interface equilibrium |Σ f_particle + Σ f_nodes| ≤ {worst_eq:.1e} N; mean coupling iterations {:.2}",
        diff / peak,
        c.total_iterations as f64 / c.steps as f64
    );
    assert!(f_def.iter().any(|&f| f > 0.5 * peak), "impact must happen");
    assert!(diff < 0.01 * peak);
    assert!(worst_eq < 1e-12 * peak);
}

#[test]
fn resting_particle_carries_its_weight() {
    // start near the static overlap m g / k_N, damped by e = 0.4: after ~20 contact periods F = m g
    let law = PowderLaw::PAPER;
    let dt = 2e-6;
    let mg = 8000.0 * 4.0 / 3.0 * std::f64::consts::PI * R.powi(3) * 9.81;
    let mut c = coupled_with(
        175e9,
        particle(law, -0.9 * mg / law.normal_stiffness_n_m, 0.0, dt),
        0.8,
        dt,
    );
    for _ in 0..2500 {
        c.step().unwrap();
    }
    let f = c.wall_force(0)[2];
    let (_, fs) = c.interface_force_sums();
    eprintln!(
        "resting: wall force {f:.6e} N, m g = {mg:.6e} N, force on the plate {:.6e} N",
        fs[2]
    );
    assert!((f / mg - 1.0).abs() < 1e-3);
    assert!((fs[2] / mg + 1.0).abs() < 1e-3);
}

/// The paper's law made elastic and frictionless (nothing dissipated in the contacts).
fn elastic_frictionless() -> PowderLaw {
    PowderLaw {
        restitution: 1.0,
        friction: 0.0,
        ..PowderLaw::PAPER
    }
}

#[test]
fn coupled_energy_balance_closes() {
    // elastic, frictionless particle on a soft plate (E = 1 GPa): the plate takes up energy
    let law = elastic_frictionless();
    let dt = 5e-7;
    let mut c = coupled(1e9, law, 1.0, dt);
    let e0 = c.energy();
    let scale = e0.particle_kinetic_j + e0.structure_kinetic_j;
    let mut worst = 0.0f64;
    let mut max_plate = 0.0f64;
    for _ in 0..4_000 {
        c.step().unwrap();
        let e = c.energy();
        worst = worst.max((e.balance_j - e0.balance_j).abs() / scale);
        max_plate = max_plate.max(e.structure_kinetic_j + e.structure_strain_j);
    }
    eprintln!(
        "energy closure {worst:.2e} of the initial kinetic energy; peak plate energy {:.2e} of it; mean iterations {:.2}",
        max_plate / scale,
        c.total_iterations as f64 / c.steps as f64
    );
    assert!(max_plate > 1e-6 * scale, "the plate must take part");
    assert!(worst < 1e-3);
}

/// `run.coupling.structure_tolerance` reaches the structure's Newton loop, and a looser one
/// (1e-7 instead of 1e-10) saves iterations without changing the coupled result: the elastic
/// particle on the soft plate of `coupled_energy_balance_closes`.
#[test]
fn looser_structure_tolerance_keeps_the_coupled_result() {
    let law = elastic_frictionless();
    let dt = 5e-7;
    let run = |structure_tolerance: f64| {
        let settings = CouplingSettings {
            tolerance: 1e-6,
            structure_tolerance: Some(structure_tolerance),
            ..Default::default()
        };
        let mut c = coupled_with_settings(1e9, particle(law, 1e-5, -0.2, dt), 1.0, dt, settings);
        assert_eq!(c.dynamics.newton.tolerance, structure_tolerance);
        let e0 = c.energy();
        let scale = e0.particle_kinetic_j + e0.structure_kinetic_j;
        let (mut worst, mut newton) = (0.0f64, 0usize);
        for _ in 0..4_000 {
            c.step().unwrap();
            newton += c.dynamics.last_iterations;
            worst = worst.max((c.energy().balance_j - e0.balance_j).abs() / scale);
        }
        (
            c.world.particles.position[0],
            c.dynamics.d.clone(),
            worst,
            newton,
        )
    };
    let (x0, d0, w0, n0) = run(1e-10);
    let (x1, d1, w1, n1) = run(1e-7);
    let dmax = d0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let ddiff = d0
        .iter()
        .zip(&d1)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!(
        "structure tolerance 1e-10 / 1e-7: Newton iterations of the last solve per step {n0} / \
         {n1}; particle position differs by {:.2e} m; plate displacement by {:.2e} of its \
         largest; energy closure {w0:.2e} / {w1:.2e}",
        (x0 - x1).norm(),
        ddiff / dmax
    );
    // the same trajectory to far below the coupling tolerance, the ledger still closed
    assert!(
        (x0 - x1).norm() < 1e-6 * R,
        "particle moved by {:e} m",
        (x0 - x1).norm()
    );
    assert!(
        ddiff < 1e-5 * dmax,
        "plate displacement differs by {:e} of its largest",
        ddiff / dmax
    );
    assert!(w1 < 1e-3, "energy closure {w1:e}");
    assert!(n1 <= n0, "a looser tolerance must not take more iterations");
}
