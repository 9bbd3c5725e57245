//! Head-on impacts through the full DEM pipeline (neighbour list, walls, integrator) compared
//! with Hertz impact theory: contact time [D Eq. 4.8] and maximum overlap [D Eq. 2.80] for
//! elastic contact, and restitution of the dissipative laws.

use pdamp_dem::Material;
use pdamp_dem::contact::NormalLaw;
use pdamp_dem::impact::{ImpactSetup, Partner, head_on_impact, hertz_equivalent_linear_stiffness};

const VELOCITIES: [f64; 4] = [0.01, 0.1, 1.0, 5.0];
const RADII: [f64; 3] = [0.5e-3, 5e-3, 15e-3];

fn steel() -> Material {
    Material::new("steel", 7850.0, 210e9, 0.3)
}

fn setup(partner: Partner, r: f64, v: f64, normal: NormalLaw) -> ImpactSetup {
    ImpactSetup {
        partner,
        radius_m: r,
        material: steel(),
        normal,
        velocity_m_s: v,
        steps_per_contact: 1000.0,
    }
}

/// Elastic contact of every Hertz-type law: contact time and max overlap within 2 % of theory.
#[test]
fn elastic_contact_time_and_overlap_match_hertz() {
    let laws = [
        NormalLaw::Hertz,
        NormalLaw::Gonthier {
            restitution: 1.0,
            min_impact_velocity_m_s: 1e-3,
        },
        NormalLaw::HertzMindlin {
            restitution: 1.0,
            clip_attractive: false,
        },
    ];
    let mut worst: f64 = 0.0;
    for law in &laws {
        for partner in [Partner::Wall, Partner::Sphere] {
            for &r in &RADII {
                for &v in &VELOCITIES {
                    let res = head_on_impact(&setup(partner, r, v, law.clone()));
                    let et = (res.contact_time_s / res.hertz_contact_time_s - 1.0).abs();
                    let ed = (res.max_overlap_m / res.hertz_max_overlap_m - 1.0).abs();
                    let ef = (res.max_force_n / res.hertz_max_force_n - 1.0).abs();
                    worst = worst.max(et).max(ed);
                    assert!(
                        et < 0.02,
                        "{law:?} {partner:?} r={r} v={v}: contact time {:.4e} vs Hertz {:.4e}",
                        res.contact_time_s,
                        res.hertz_contact_time_s
                    );
                    assert!(
                        ed < 0.02,
                        "{law:?} {partner:?} r={r} v={v}: overlap {:.4e} vs Hertz {:.4e}",
                        res.max_overlap_m,
                        res.hertz_max_overlap_m
                    );
                    assert!(
                        ef < 0.02,
                        "{law:?} {partner:?} r={r} v={v}: force {:.4e} vs Hertz {:.4e}",
                        res.max_force_n,
                        res.hertz_max_force_n
                    );
                    assert!(
                        (res.restitution - 1.0).abs() < 0.01,
                        "{law:?}: elastic restitution {}",
                        res.restitution
                    );
                }
            }
        }
    }
    eprintln!("largest relative deviation from Hertz theory: {worst:.2e}");
}

/// The published check: a 30 mm steel sphere hitting a steel wall at 1 m/s.
#[test]
fn steel_sphere_30mm_at_1m_s() {
    let res = head_on_impact(&setup(Partner::Wall, 15e-3, 1.0, NormalLaw::Hertz));
    // Hertz theory for E = 210 GPa, ν = 0.3, ρ = 7850 kg/m³: t ≈ 103.8 µs, F_max ≈ 3.9 kN.
    assert!(
        (res.hertz_contact_time_s - 103.8e-6).abs() < 0.5e-6,
        "{}",
        res.hertz_contact_time_s
    );
    assert!((res.contact_time_s / res.hertz_contact_time_s - 1.0).abs() < 0.01);
    assert!((res.max_force_n / res.hertz_max_force_n - 1.0).abs() < 0.01);
}

/// Gonthier and the linear spring–dashpot reproduce the requested restitution within 2 %.
#[test]
fn restitution_gonthier_and_linear() {
    for eps in [0.2, 0.5, 0.8, 0.95] {
        for partner in [Partner::Wall, Partner::Sphere] {
            for &v in &VELOCITIES {
                for &r in &[0.5e-3, 15e-3] {
                    let g = head_on_impact(&setup(
                        partner,
                        r,
                        v,
                        NormalLaw::Gonthier {
                            restitution: eps,
                            min_impact_velocity_m_s: 1e-3,
                        },
                    ));
                    assert!(
                        (g.restitution / eps - 1.0).abs() < 0.02,
                        "Gonthier eps={eps} {partner:?} v={v} r={r}: got {}",
                        g.restitution
                    );
                    let k = hertz_equivalent_linear_stiffness(partner, r, &steel(), v);
                    let l = head_on_impact(&setup(
                        partner,
                        r,
                        v,
                        NormalLaw::Linear {
                            stiffness_n_m: k,
                            restitution: eps,
                            clip_attractive: false,
                        },
                    ));
                    assert!(
                        (l.restitution / eps - 1.0).abs() < 0.02,
                        "linear eps={eps} {partner:?} v={v} r={r}: got {}",
                        l.restitution
                    );
                }
            }
        }
    }
}

/// Hertz–Mindlin (LIGGGHTS damping) gives the requested restitution when not clipped.
#[test]
fn restitution_hertz_mindlin() {
    for eps in [0.3, 0.6, 0.9] {
        for &v in &[0.1, 1.0] {
            let res = head_on_impact(&setup(
                Partner::Sphere,
                1e-3,
                v,
                NormalLaw::HertzMindlin {
                    restitution: eps,
                    clip_attractive: false,
                },
            ));
            assert!(
                (res.restitution / eps - 1.0).abs() < 0.02,
                "eps={eps} v={v}: {}",
                res.restitution
            );
        }
    }
}

/// Velocity-dependent restitution [D Tab. 8.1, Chap. 4]: Gonthier's law with ε(δ̇₀) from a table
/// reproduces the interpolated ε of every impact velocity within 1 %, sphere–wall and
/// sphere–sphere.
#[test]
fn restitution_table_follows_impact_velocity() {
    let law = NormalLaw::GonthierTable {
        impact_velocities_m_s: vec![0.01, 0.1, 0.5, 2.0],
        restitutions: vec![0.95, 0.85, 0.65, 0.55],
        min_impact_velocity_m_s: 1e-3,
    };
    let mut worst: f64 = 0.0;
    for partner in [Partner::Wall, Partner::Sphere] {
        for v in [0.005, 0.01, 0.03, 0.1, 0.3, 1.0, 2.0, 5.0] {
            let expect = law.restitution_at(v);
            let res = head_on_impact(&setup(partner, 5e-3, v, law.clone()));
            let err = (res.restitution / expect - 1.0).abs();
            worst = worst.max(err);
            assert!(
                err < 0.01,
                "{partner:?} v = {v}: restitution {} vs table {expect}",
                res.restitution
            );
        }
    }
    eprintln!("ε(v) table: largest relative restitution error {worst:.2e}");
}

/// Stability cap of Gonthier's dashpot: an enduring contact that formed at rest (δ̇₀ at its
/// floor) and is then compressed fast has its damping coefficient limited to M̄/Δt, so the
/// dissipative force is at most M̄·δ̇/Δt; without Δt (impact integrators) the law is unchanged.
#[test]
fn gonthier_damping_capped_for_enduring_contacts() {
    use pdamp_dem::Vec3;
    use pdamp_dem::contact::{
        ContactHistory, ContactKinematics, ContactModel, FrictionLaw, PairProps,
    };
    let model = ContactModel {
        normal: NormalLaw::Gonthier {
            restitution: 0.6,
            min_impact_velocity_m_s: 1e-3,
        },
        friction: FrictionLaw::Frictionless,
        rolling: None,
        adhesion: None,
    };
    let p = PairProps {
        e_eff_pa: 1e11,
        g_eff_pa: 4e10,
        poisson_mean: 0.3,
        r_eff_m: 1e-3,
        m_eff_kg: 3e-5,
    };
    let kin = |dt: f64| ContactKinematics {
        overlap_m: 1e-6,
        overlap_rate_m_s: 1.0,
        normal: Vec3::z(),
        tangential_velocity_m_s: Vec3::zeros(),
        relative_angular_velocity_rad_s: Vec3::zeros(),
        dt_s: dt,
    };
    let mut h = ContactHistory {
        impact_velocity_m_s: 1e-3,
        ..Default::default()
    };
    let dt = 1e-6;
    let capped = model.evaluate(&p, &kin(dt), &mut h);
    assert!((capped.normal_dissipative_n - p.m_eff_kg / dt * 1.0).abs() < 1e-9);
    let uncapped = model.evaluate(&p, &kin(0.0), &mut h);
    assert!(uncapped.normal_dissipative_n > 10.0 * capped.normal_dissipative_n);
}
