//! The DEM–FEM paper (P, Praegla et al. 2024): its closed forms and stated particle counts.
//! The coupled-run results (Table 1, the packing-density study) are the powder rows of
//! docs/powder.md until they are registered as `Full` rows.

use crate::{Category, Target, closed_form, exact, rel, stated, worded};
use pdamp_powder::cantilever::CantileverScenario;
use pdamp_powder::psd::LogNormal;
use pdamp_structure::formulas::{
    bending_work, bending_work_discrete, shear_work, shear_work_discrete,
};

const CH: &str = "P — DEM–FEM powder damper";

/// The paper's cantilever example as shipped.
const PAPER_EXAMPLE: &str = include_str!("../../../examples/powder_cantilever_paper.toml");

/// A powder-category closed form.
fn powder(t: Target) -> Target {
    Target {
        category: Category::Powder,
        ..t
    }
}

/// Particles that fill the paper's 18 × 18 × 110 mm³ cavity at packing density `phi` with
/// the Table A.2 distribution of median `d50_m`.
fn particles(d50_m: f64, phi: f64) -> f64 {
    phi * 0.018 * 0.018 * 0.110 / LogNormal::paper(d50_m).mean_volume_m3()
}

/// The P targets.
pub fn targets() -> Vec<Target> {
    vec![
        powder(closed_form(
            "paper.eq20.shear_work_r_independent",
            CH,
            "discrete/continuum shear friction work at R = 0.5 mm, l = 110 mm (eq. 18–20: \
             independent of R for many particles)",
            worded(1.0, "independent of R", "1", "P eq. 20, L280–300"),
            rel(0.02),
            |_| {
                let (l, mu, f, phi) = (0.11, 0.4, 10.0, 1e-3);
                exact(
                    shear_work_discrete(l, 5e-4, mu, f, phi) / shear_work(l, mu, f, phi),
                    "shear_work_discrete(0.11, 5e-4, …)/shear_work(0.11, …)",
                )
            },
        )),
        powder(closed_form(
            "paper.eq26.bending_work_r_independent",
            CH,
            "discrete/continuum bending friction work at R = 0.5 mm, 18 × 110 mm (eq. 21–26: \
             independent of R for many particles)",
            worded(1.0, "independent of R", "1", "P eq. 26, L300–331"),
            rel(0.05),
            |_| {
                let (l, b, mu, f, phi) = (0.11, 0.018, 0.4, 10.0, 1e-3);
                exact(
                    bending_work_discrete(l, b, 5e-4, mu, f, phi) / bending_work(l, b, mu, f, phi),
                    "bending_work_discrete(0.11, 0.018, 5e-4, …)/bending_work(0.11, 0.018, …)",
                )
            },
        )),
        powder(closed_form(
            "paper.tabA2.d90",
            CH,
            "D90 of the Table A.2 log-normal distribution (D50 = 0.0265646 mm, σ = 0.2707)",
            stated(0.0375828e-3, "m", "P Table A.2, L372–395"),
            rel(1e-4),
            |_| {
                let p = LogNormal::paper(0.0265646e-3);
                exact(
                    p.d50_m * (1.281_551_6 * p.sigma).exp(),
                    "LogNormal::paper(0.0265646e-3): D50·exp(z₀.₉·σ)",
                )
            },
        )),
        powder(closed_form(
            "paper.sec2_4.particles_1mm",
            CH,
            "particles of D50 = 1 mm that fill the cavity (the shipped paper example, Φ = 58 %)",
            worded(32_000.0, "roughly 32 000", "1", "P L194"),
            rel(0.10),
            |_| {
                let sc = CantileverScenario::from_toml(PAPER_EXAMPLE)
                    .map_err(crate::ComputeError::new)?;
                exact(
                    sc.estimate().particles,
                    "CantileverScenario(examples/powder_cantilever_paper.toml).estimate().particles",
                )
            },
        )),
        powder(closed_form(
            "paper.sec3_2.particles_0p5mm",
            CH,
            "particles of D50 = 0.5 mm at Φ = 58 % (the paper: Φ = 56–62 %)",
            worded(250_000.0, "~ 250 000", "1", "P L228"),
            rel(0.15),
            |_| {
                exact(
                    particles(5e-4, 0.58),
                    "Φ·V_cavity/mean_volume(LogNormal::paper(0.5 mm))",
                )
            },
        )),
        powder(closed_form(
            "paper.sec3_2.particles_0p25mm",
            CH,
            "particles of D50 = 0.25 mm at Φ = 58 % (the paper: Φ = 56–62 %)",
            worded(2.0e6, "~ 2.0 million", "1", "P L228"),
            rel(0.15),
            |_| {
                exact(
                    particles(2.5e-4, 0.58),
                    "Φ·V_cavity/mean_volume(LogNormal::paper(0.25 mm))",
                )
            },
        )),
    ]
}
