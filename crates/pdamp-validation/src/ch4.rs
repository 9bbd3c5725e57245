//! D Ch. 4, single impacts (level I): the closed forms of the impact models. The FE impact
//! rows (contact times, restitution curves, energy splits) are simulations and follow as
//! `Full` rows.

use crate::{ComputeError, Target, closed_form, exact, rel, stated, worded};
use pdamp_impact::hertz::HertzPair;
use pdamp_impact::{FeOptions, ImpactResult, Material, MaterialModel, MeshDensity, Partner};
use std::sync::OnceLock;

const CH: &str = "D Ch. 4 — single impacts";

/// The Hertz pair of a 30 mm S235 sphere and `partner` (D Sect. 4.2.1).
fn hertz_30mm(partner: &Partner) -> HertzPair {
    pdamp_impact::study::hertz_pair(&Material::s235(), partner, 0.015)
}

/// The Perzyna overstress factor β = 1 + (ε̇/ζ)^λ of `m` at the plastic strain rate `rate`
/// (D Eq. 4.2), with ζ and λ of pdamp's built-in material.
fn perzyna_beta(m: &Material, rate_1_s: f64) -> Result<f64, ComputeError> {
    match &m.model {
        MaterialModel::ViscoplasticJ2 {
            perzyna_zeta_1_s: Some(z),
            perzyna_lambda,
            ..
        } => Ok(1.0 + (rate_1_s / z).powf(*perzyna_lambda)),
        _ => Err(ComputeError::new(format!(
            "{} has no Perzyna rate dependence",
            m.name
        ))),
    }
}

/// One coarse-mesh FE impact of a 30 mm S235 sphere at 1 m/s on a wall of `wall` (D Sect.
/// 4.2.2), computed once per process and shared by the rows that read it.
fn fe_impact_1m_s(
    wall: fn() -> Material,
    cache: &'static OnceLock<ImpactResult>,
) -> &'static ImpactResult {
    cache.get_or_init(|| {
        pdamp_impact::simulate_impact(
            &Material::s235(),
            &Partner::Wall(wall()),
            0.015,
            1.0,
            &FeOptions::with_density(MeshDensity::Coarse),
        )
    })
}

static FE_STEEL: OnceLock<ImpactResult> = OnceLock::new();
static FE_AL: OnceLock<ImpactResult> = OnceLock::new();

fn fe_steel() -> &'static ImpactResult {
    fe_impact_1m_s(Material::s235, &FE_STEEL)
}

fn fe_al() -> &'static ImpactResult {
    fe_impact_1m_s(Material::al6060, &FE_AL)
}

/// The share of the plastic dissipation that happens in the wall.
fn wall_share(r: &ImpactResult) -> f64 {
    let e = &r.energy;
    e.plastic_wall_j / (e.plastic_wall_j + e.plastic_sphere_j)
}

/// A row read from the coarse FE impact at 1 m/s (`Quick`: the two impacts take ≈ 10 s on 2
/// cores together).
macro_rules! fe_row {
    ($id:literal, $what:literal, $reference:expr, $tol:expr, $impact:ident, $value:expr, $how:literal) => {
        Target {
            category: crate::Category::Impact,
            ..closed_form($id, CH, $what, $reference, $tol, |_| {
                let r = $impact();
                if !r.completed {
                    return Err(ComputeError::new("the impact did not separate in time"));
                }
                #[allow(clippy::redundant_closure_call)]
                exact(($value)(r), $how)
            })
        }
    };
}

/// The FE impacts of D Sect. 4.2.2 at 1 m/s (30 mm steel sphere, coarse mesh).
fn fe_impacts() -> Vec<Target> {
    vec![
        fe_row!(
            "ch4.fe.te_steel_steel",
            "FE contact time, 30 mm steel sphere on a steel wall at 1 m/s (coarse mesh)",
            stated(101e-6, "s", "D L1859"),
            rel(0.03),
            fe_steel,
            |r: &ImpactResult| r.contact_time_s,
            "simulate_impact(s235, Wall(s235), 0.015, 1 m/s, coarse).contact_time_s"
        ),
        fe_row!(
            "ch4.fe.te_steel_al",
            "FE contact time, 30 mm steel sphere on an Al 6060 wall at 1 m/s (coarse mesh)",
            stated(133e-6, "s", "D L1859"),
            rel(0.03),
            fe_al,
            |r: &ImpactResult| r.contact_time_s,
            "simulate_impact(s235, Wall(al6060), 0.015, 1 m/s, coarse).contact_time_s"
        ),
        fe_row!(
            "ch4.fig4_22.fmax_steel",
            "peak contact force, steel sphere on steel at 1 m/s (measured; FE coarse mesh)",
            stated(3027.0, "N", "D L1936 (experiment)"),
            rel(0.15),
            fe_steel,
            |r: &ImpactResult| r.max_force_n,
            "simulate_impact(s235, Wall(s235), 0.015, 1 m/s, coarse).max_force_n"
        ),
        fe_row!(
            "ch4.fig4_22.fmax_al",
            "peak contact force, steel sphere on Al 6060 at 1 m/s (measured; FE coarse mesh)",
            stated(2180.0, "N", "D L1936 (experiment)"),
            rel(0.15),
            fe_al,
            |r: &ImpactResult| r.max_force_n,
            "simulate_impact(s235, Wall(al6060), 0.015, 1 m/s, coarse).max_force_n"
        ),
        fe_row!(
            "ch4.fig4_9.split_steel",
            "share of the plastic dissipation in the wall, steel on steel (D: about equal)",
            worded(0.5, "≈ equal in sphere and wall", "1", "D L1820, Fig. 4.9"),
            crate::abs(0.1),
            fe_steel,
            wall_share,
            "plastic_wall_j/(plastic_wall_j + plastic_sphere_j), steel on steel, coarse"
        ),
        fe_row!(
            "ch4.fig4_15.split_al",
            "share of the plastic dissipation in the wall, steel on Al 6060 (D: ≈ 90 %)",
            worded(0.9, "approximately 90 %", "1", "D L1861, Fig. 4.15"),
            crate::abs(0.07),
            fe_al,
            wall_share,
            "plastic_wall_j/(plastic_wall_j + plastic_sphere_j), steel on Al 6060, coarse"
        ),
    ]
}

/// The Ch. 4 targets.
pub fn targets() -> Vec<Target> {
    let mut t = closed_forms();
    t.extend(hertz_partners());
    t.extend(fe_impacts());
    t
}

/// The closed forms of the impact models.
fn closed_forms() -> Vec<Target> {
    vec![
        closed_form(
            "ch4.eq4_2.beta_s235",
            CH,
            "Perzyna overstress factor β of S235 at ε̇_pl = 1000 1/s",
            worded(3.0, "about three", "1", "D Eq. 4.2, Tab. 4.1, L1684"),
            crate::Tolerance::Range { lo: 2.5, hi: 3.5 },
            |_| {
                let b = perzyna_beta(&Material::s235(), 1000.0)?;
                exact(b, "1 + (1000/ζ)^λ of Material::s235()")
            },
        ),
        closed_form(
            "ch4.eq4_2.beta_al6060",
            CH,
            "Perzyna β of Al 6060 at 1000 1/s (\"minor\" rate effect)",
            worded(1.18, "minor (< 1.3)", "1", "D L1670, L1684"),
            crate::Tolerance::Range { lo: 1.0, hi: 1.3 },
            |_| {
                let b = perzyna_beta(&Material::al6060(), 1000.0)?;
                exact(b, "1 + (1000/ζ)^λ of Material::al6060()")
            },
        ),
        closed_form(
            "ch4.eq4_7.g_inf_saa",
            CH,
            "long-term shear modulus G∞ = E/(2(1+ν)) of SAA 9579 (E 54.97 MPa, ν 0.4477)",
            stated(18.985e6, "Pa", "D Eq. 4.7, Tab. 4.2, L1709–1743"),
            rel(1e-4),
            |_| {
                exact(
                    Material::saa9579().shear_modulus(),
                    "Material::saa9579().shear_modulus()",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.te_steel_steel",
            CH,
            "Hertz contact time, 30 mm steel sphere on a steel wall at 1 m/s",
            worded(100e-6, "≈ 100 µs", "s", "D Eq. 4.8, L1777, L1859"),
            rel(0.05),
            |_| {
                let p = hertz_30mm(&Partner::Wall(Material::s235()));
                exact(
                    p.contact_time(1.0),
                    "hertz_pair(s235, Wall(s235), 0.015).contact_time(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_7.g0_saa",
            CH,
            "instantaneous shear modulus G₀ = G∞/(1 − Σg_i) of SAA 9579 (Prony series of Tab. 4.2)",
            stated(
                8.58e9,
                "Pa",
                "notes N45 L48–50, derived from D Eq. 4.7 and Tab. 4.2, L1709–1743",
            ),
            rel(2e-3),
            |_| {
                exact(
                    Material::saa9579().instantaneous_shear_modulus(),
                    "Material::saa9579().instantaneous_shear_modulus()",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.fmax_steel_steel",
            CH,
            "Hertz peak force, 30 mm steel sphere on a steel wall at 1 m/s",
            stated(
                3909.0,
                "N",
                "notes N45 L103–107, derived from D Eq. 4.8, L1777",
            ),
            rel(0.01),
            |_| {
                exact(
                    hertz_30mm(&Partner::Wall(Material::s235())).max_force(1.0),
                    "hertz_pair(s235, Wall(s235), 0.015).max_force(1.0)",
                )
            },
        ),
    ]
}

/// The Hertz contact of the 30 mm steel sphere with the other partners of D Sect. 4.2 (the
/// notes' evaluation of D Eq. 4.8).
fn hertz_partners() -> Vec<Target> {
    vec![
        closed_form(
            "ch4.eq4_8.te_steel_al",
            CH,
            "Hertz contact time, 30 mm steel sphere on an Al 6060 wall at 1 m/s",
            stated(
                137.1e-6,
                "s",
                "notes N45 L107, derived from D Eq. 4.8, L1777",
            ),
            rel(0.01),
            |_| {
                exact(
                    hertz_30mm(&Partner::Wall(Material::al6060())).contact_time(1.0),
                    "hertz_pair(s235, Wall(al6060), 0.015).contact_time(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.fmax_steel_al",
            CH,
            "Hertz peak force, 30 mm steel sphere on an Al 6060 wall at 1 m/s",
            stated(2960.0, "N", "notes N45 L107, derived from D Eq. 4.8, L1777"),
            rel(0.01),
            |_| {
                exact(
                    hertz_30mm(&Partner::Wall(Material::al6060())).max_force(1.0),
                    "hertz_pair(s235, Wall(al6060), 0.015).max_force(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.te_sphere_sphere",
            CH,
            "Hertz contact time, two 30 mm steel spheres at 1 m/s",
            stated(
                90.4e-6,
                "s",
                "notes N45 L107, derived from D Eq. 4.8, L1777",
            ),
            rel(0.01),
            |_| {
                exact(
                    hertz_30mm(&Partner::Sphere).contact_time(1.0),
                    "hertz_pair(s235, Sphere, 0.015).contact_time(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.te_steel_saa",
            CH,
            "Hertz contact time (long-term modulus), 30 mm steel sphere on SAA 9579 at 1 m/s",
            worded(
                2.0e-3,
                "≈ 2.0 ms",
                "s",
                "notes N45 L107, derived from D Eq. 4.8, L1777",
            ),
            rel(0.03),
            |_| {
                exact(
                    hertz_30mm(&Partner::Wall(Material::saa9579())).contact_time(1.0),
                    "hertz_pair(s235, Wall(saa9579), 0.015).contact_time(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.fmax_steel_saa",
            CH,
            "Hertz peak force (long-term modulus), 30 mm steel sphere on SAA 9579 at 1 m/s",
            stated(201.0, "N", "notes N45 L107, derived from D Eq. 4.8, L1777"),
            rel(0.01),
            |_| {
                exact(
                    hertz_30mm(&Partner::Wall(Material::saa9579())).max_force(1.0),
                    "hertz_pair(s235, Wall(saa9579), 0.015).max_force(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.te_steel_pvc",
            CH,
            "Hertz contact time, 30 mm steel sphere on PVC (E 3 GPa, ν 0.38) at 1 m/s",
            worded(
                0.42e-3,
                "≈ 0.42 ms",
                "s",
                "notes N45 L107, derived from D Eq. 4.8, L1777",
            ),
            rel(0.03),
            |_| {
                let pvc = Material::elastic("pvc", 3e9, 0.38, 1400.0);
                exact(
                    hertz_30mm(&Partner::Wall(pvc)).contact_time(1.0),
                    "hertz_pair(s235, Wall(elastic pvc 3 GPa, 0.38), 0.015).contact_time(1.0)",
                )
            },
        ),
        closed_form(
            "ch4.eq4_8.fmax_steel_pvc",
            CH,
            "Hertz peak force, 30 mm steel sphere on PVC (E 3 GPa, ν 0.38) at 1 m/s",
            stated(964.0, "N", "notes N45 L107, derived from D Eq. 4.8, L1777"),
            rel(0.01),
            |_| {
                let pvc = Material::elastic("pvc", 3e9, 0.38, 1400.0);
                exact(
                    hertz_30mm(&Partner::Wall(pvc)).max_force(1.0),
                    "hertz_pair(s235, Wall(elastic pvc 3 GPa, 0.38), 0.015).max_force(1.0)",
                )
            },
        ),
    ]
}
