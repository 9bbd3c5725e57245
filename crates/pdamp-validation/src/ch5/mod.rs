//! D Ch. 5, low-excitation horizontal dampers (rolling collect-and-collide), the beam and the
//! Flexor: the closed forms of D Sect. 5.1.2 and the design formulas of Sect. 5.2.

use crate::{
    ComputeError, Context, Measured, Target, abs, closed_form, exact, quick_run, rel, stated,
    worded,
};
use pdamp_structure::design::{
    bed_mass_for_damping, damping_ratio_single_mode, layer_clearances_m, optimal_base_amplitude_m,
    optimal_bed_mass_kg, optimal_forced_damping_ratio, optimal_resonance_amplitude_m,
};
use pdamp_structure::formulas::{
    RollingDamper, clearance_m, rolling_loss_factor, rolling_optimal_stroke_m,
};
use pdamp_structure::modal::ModalStructure;

mod statements;

const CH: &str = "D Ch. 5 — rolling dampers, beam and Flexor";

/// η̄ of a rolling bed of clearance `h` at amplitude `x` (D Eq. 5.3/5.8/5.10).
fn rolling_eta(h: f64, x: f64) -> f64 {
    RollingDamper {
        bed_mass_kg: 0.147,
        clearance_m: h,
        smoothing_log_width: None,
    }
    .loss_factor_and_mass_ratio(x)
    .0
}

/// First eigenfrequency (Hz) and damping ratio of the single-mode structure (M, K, D).
fn single_mode(m: f64, k: f64, d: f64) -> (f64, f64) {
    let s = ModalStructure::single_mode(m, k, d);
    (s.modes[0].frequency_hz, s.modes[0].damping_ratio)
}

/// Bed mass of `n` steel spheres of radius 5 mm (ρ 7900 kg/m³, the examples' steel).
fn bed_mass(n: f64) -> f64 {
    n * pdamp_impact::hertz::sphere_mass(0.005, 7900.0)
}

/// Why the Flexor decay from D Eq. 5.19's start misses the measured 5 s amplitude (measured,
/// 2026-12-07).
const FLEXOR_START: &str = "the 5 s amplitude is decided by the start: the same damper from the \
    unscaled 78 mm is at 11.9 mm after 5 s (row ch5.fig5_19.flexor_amplitude_5s_from_78mm), and \
    pdamp's brute force over the five layers finds D's 24/28-sphere layers only from 78 mm (best \
    [20, 20, 20, 24, 24]; from 104 mm [8, 12, 12, 12, 16], D's design rank 1059 of 3003): D's \
    optimisation and formula curve appear to start from 78 mm; the experiment's undamped 1.09 Hz \
    (model 0.99 Hz) takes the 78 mm decay to 8.7 mm";

/// The Ch. 5 targets.
pub fn targets() -> Vec<Target> {
    let mut t = Vec::new();
    t.extend(clearances());
    t.extend(loss_factors());
    t.extend(guideline());
    t.extend(design_formulas());
    t.extend(structures());
    t.extend(bed_masses());
    t.extend(table_5_2());
    t.extend(free_decays());
    t.extend(flexor_decays());
    t.extend(statements::rolling_table_and_tilt());
    t.extend(statements::forced_and_free_statements());
    t.extend(statements::layer_optimum());
    t
}

/// Clearances and optimal strokes (D Eq. 5.1, 5.13).
fn clearances() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.eq5_1.h_rol_36",
            CH,
            "clearance h_rol of 36 spheres in the 120 mm box (n_max 48)",
            stated(0.030, "m", "D Eq. 5.1, L2016"),
            abs(1e-9),
            |_| exact(clearance_m(0.12, 36.0, 48.0), "clearance_m(0.12, 36, 48)"),
        ),
        closed_form(
            "ch5.eq5_1.h_rol_44",
            CH,
            "clearance h_rol of 44 spheres in the 120 mm box",
            stated(0.010, "m", "D Eq. 5.1, L2016"),
            abs(1e-9),
            |_| exact(clearance_m(0.12, 44.0, 48.0), "clearance_m(0.12, 44, 48)"),
        ),
        closed_form(
            "ch5.eq5_1.h_rol_144_r2p5",
            CH,
            "clearance of 144 spheres of r = 2.5 mm (n_max 192)",
            stated(0.030, "m", "D L2202"),
            abs(1e-9),
            |_| {
                exact(
                    clearance_m(0.12, 144.0, 192.0),
                    "clearance_m(0.12, 144, 192)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_1.h_rol_176_r2p5",
            CH,
            "clearance of 176 spheres of r = 2.5 mm",
            stated(0.010, "m", "D L2202"),
            abs(1e-9),
            |_| {
                exact(
                    clearance_m(0.12, 176.0, 192.0),
                    "clearance_m(0.12, 176, 192)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_1.h_rol_cyl30",
            CH,
            "cylinder L = 2R = 78 mm: 30 spheres give the 36-sphere clearance",
            stated(0.030, "m", "D L2247"),
            abs(1e-3),
            |_| exact(clearance_m(0.078, 30.0, 48.0), "clearance_m(0.078, 30, 48)"),
        ),
        closed_form(
            "ch5.eq5_1.h_rol_cyl42",
            CH,
            "cylinder: 42 spheres give the 44-sphere clearance",
            stated(0.010, "m", "D L2247"),
            abs(1e-3),
            |_| exact(clearance_m(0.078, 42.0, 48.0), "clearance_m(0.078, 42, 48)"),
        ),
        closed_form(
            "ch5.eq5_13.xopt_ratio",
            CH,
            "optimal rolling stroke X_opt/h_rol",
            worded(0.4, "≈ 0.4", "1", "D Eq. 5.13, L2155"),
            abs(0.01),
            |_| exact(rolling_optimal_stroke_m(1.0), "rolling_optimal_stroke_m(1)"),
        ),
        closed_form(
            "ch5.eq5_13.xopt_36",
            CH,
            "optimal stroke of 36 spheres (h 30 mm; observed)",
            stated(0.012, "m", "D L2034, L2311"),
            abs(0.5e-3),
            |_| {
                exact(
                    rolling_optimal_stroke_m(0.03),
                    "rolling_optimal_stroke_m(0.03)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_13.xopt_44",
            CH,
            "optimal stroke of 44 spheres (h 10 mm; observed)",
            stated(0.004, "m", "D L2034"),
            abs(0.5e-3),
            |_| {
                exact(
                    rolling_optimal_stroke_m(0.01),
                    "rolling_optimal_stroke_m(0.01)",
                )
            },
        ),
    ]
}

/// Rolling loss factors (D Eq. 5.10, 5.12, 5.16).
fn loss_factors() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.eq5_12.eta_rol_max",
            CH,
            "maximal rolling loss factor 20/(7π)",
            worded(0.91, "≈ 0.91", "1", "D Eq. 5.12, L2149"),
            abs(0.005),
            |_| {
                exact(
                    rolling_loss_factor(std::f64::consts::PI),
                    "rolling_loss_factor(π)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_10.eta_x40",
            CH,
            "scattered rolling η̄ at X = 40 mm, h = 30 mm",
            worded(0.46, "≈ 0.46", "1", "D L2498"),
            abs(0.005),
            |_| {
                exact(
                    rolling_eta(0.03, 0.04),
                    "RollingDamper{h: 0.03}.loss_factor_and_mass_ratio(0.04)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_16.eta0_2",
            CH,
            "guideline η̄_0 at X_0 = 2 X_opt",
            stated(0.69, "1", "D L2357"),
            abs(0.005),
            |_| {
                exact(
                    rolling_eta(1.0, 2.0 * rolling_optimal_stroke_m(1.0)),
                    "RollingDamper{h: 1} at 2 X_opt",
                )
            },
        ),
        closed_form(
            "ch5.eq5_16.eta0_4",
            CH,
            "guideline η̄_0 at X_0 = 4 X_opt",
            stated(0.38, "1", "D L2357"),
            abs(0.005),
            |_| {
                exact(
                    rolling_eta(1.0, 4.0 * rolling_optimal_stroke_m(1.0)),
                    "RollingDamper{h: 1} at 4 X_opt",
                )
            },
        ),
        closed_form(
            "ch5.eq5_16.eta0_6",
            CH,
            "guideline η̄_0 at X_0 = 6 X_opt",
            stated(0.25, "1", "D L2357"),
            abs(0.005),
            |_| {
                exact(
                    rolling_eta(1.0, 6.0 * rolling_optimal_stroke_m(1.0)),
                    "RollingDamper{h: 1} at 6 X_opt",
                )
            },
        ),
    ]
}

/// The three-layer guideline (D Eq. 5.17, 5.18).
fn guideline() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.eq5_17.h_layer1",
            CH,
            "guideline layer clearance 1 for X_0 = 63 mm",
            worded(0.080, "≈ 80 mm", "m", "D Eq. 5.17, L2355, L2365"),
            abs(2e-3),
            |_| exact(layer_clearances_m(0.063)[0], "layer_clearances_m(0.063)[0]"),
        ),
        closed_form(
            "ch5.eq5_17.h_layer2",
            CH,
            "guideline layer clearance 2",
            worded(0.040, "≈ 40 mm", "m", "D Eq. 5.17, L2365"),
            abs(2e-3),
            |_| exact(layer_clearances_m(0.063)[1], "layer_clearances_m(0.063)[1]"),
        ),
        closed_form(
            "ch5.eq5_17.h_layer3",
            CH,
            "guideline layer clearance 3",
            worded(0.025, "≈ 25 mm", "m", "D Eq. 5.17, L2365"),
            abs(2e-3),
            |_| exact(layer_clearances_m(0.063)[2], "layer_clearances_m(0.063)[2]"),
        ),
        closed_form(
            "ch5.eq5_18.xopt_layer1",
            CH,
            "optimal stroke of guideline layer 1",
            stated(0.032, "m", "D Eq. 5.18, L2361–2365"),
            abs(1e-3),
            |_| {
                let h = layer_clearances_m(0.063)[0];
                exact(
                    rolling_optimal_stroke_m(h),
                    "rolling_optimal_stroke_m(layer_clearances_m(0.063)[0])",
                )
            },
        ),
        closed_form(
            "ch5.eq5_18.xopt_layer2",
            CH,
            "optimal stroke of guideline layer 2",
            stated(0.016, "m", "D Eq. 5.18"),
            abs(1e-3),
            |_| {
                let h = layer_clearances_m(0.063)[1];
                exact(
                    rolling_optimal_stroke_m(h),
                    "rolling_optimal_stroke_m(layer_clearances_m(0.063)[1])",
                )
            },
        ),
        closed_form(
            "ch5.eq5_18.xopt_layer3",
            CH,
            "optimal stroke of guideline layer 3",
            stated(0.010, "m", "D Eq. 5.18"),
            abs(1e-3),
            |_| {
                let h = layer_clearances_m(0.063)[2];
                exact(
                    rolling_optimal_stroke_m(h),
                    "rolling_optimal_stroke_m(layer_clearances_m(0.063)[2])",
                )
            },
        ),
    ]
}

/// Design formulas of free and forced vibration (D Eq. 3.52, 5.15, 5.20–5.23).
fn design_formulas() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.eq5_15.bed_zeta046",
            CH,
            "bed mass for ζ_d = 0.046 on M = 1.058 kg at η̄ = 0.5 (D: 196 g)",
            stated(0.196, "kg", "D Eq. 5.15, L2365"),
            rel(0.01),
            |_| {
                exact(
                    bed_mass_for_damping(1.058, 0.046, 0.5),
                    "bed_mass_for_damping(1.058, 0.046, 0.5)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_15.bed_zeta025_2kg",
            CH,
            "bed mass for ζ_d = 0.025 on M = 2.0 kg (D: the same 196 g)",
            stated(0.196, "kg", "D L2373"),
            rel(0.025),
            |_| {
                exact(
                    bed_mass_for_damping(2.0, 0.025, 0.5),
                    "bed_mass_for_damping(2.0, 0.025, 0.5)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_15.bed_beam_efficient",
            CH,
            "bed mass for ζ = 0.11 on the beam (D: 463 g)",
            stated(0.463, "kg", "D L2408"),
            rel(0.02),
            |_| {
                exact(
                    bed_mass_for_damping(1.058, 0.11, 0.5),
                    "bed_mass_for_damping(1.058, 0.11, 0.5)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_15.bed_flexor_efficient",
            CH,
            "bed mass for ζ = 0.08 on the Flexor (D: 563 g)",
            stated(0.563, "kg", "D L2441"),
            rel(0.05),
            |_| {
                exact(
                    bed_mass_for_damping(1.69, 0.08, 0.5),
                    "bed_mass_for_damping(1.69, 0.08, 0.5)",
                )
            },
        ),
        closed_form(
            "ch5.eq3_52.zeta_091",
            CH,
            "free-vibration damping ratio at η̄ = 0.91 (149 g, M 1.058 kg)",
            stated(0.056, "1", "D Eq. 3.52, L2336"),
            abs(0.0006),
            |_| {
                exact(
                    damping_ratio_single_mode(1.058, 0.149, 0.91),
                    "damping_ratio_single_mode(1.058, 0.149, 0.91)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_20.zeta_opt",
            CH,
            "optimal forced damping ratio (147 g)",
            stated(0.055, "1", "D Eq. 5.20, L2508"),
            abs(0.0006),
            |_| {
                exact(
                    optimal_forced_damping_ratio(1.058, 0.147, 0.147),
                    "optimal_forced_damping_ratio(1.058, 0.147, 0.147)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_23.u_opt",
            CH,
            "base amplitude U_opt driving 36 spheres to X_opt = 12 mm",
            stated(1.34e-3, "m", "D Eq. 5.23, L2522"),
            abs(0.02e-3),
            |_| {
                exact(
                    optimal_base_amplitude_m(1.058, 0.147, 0.012),
                    "optimal_base_amplitude_m(1.058, 0.147, 0.012)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_21.x_resonance",
            CH,
            "resonance amplitude driven by U = 1.34 mm (K 143 N/m)",
            stated(0.012, "m", "D Eq. 5.21, L2510–2514"),
            rel(0.01),
            |_| {
                let x = optimal_resonance_amplitude_m(1.34e-3 * 143.0, 1.058, 143.0, 0.147);
                exact(
                    x,
                    "optimal_resonance_amplitude_m(1.34e-3·143, 1.058, 143, 0.147)",
                )
            },
        ),
        closed_form(
            "ch5.eq5_22.bed_for_x12",
            CH,
            "bed mass for X_max = 12 mm at U = 1.34 mm",
            stated(0.147, "kg", "D Eq. 5.22, L2514"),
            rel(0.01),
            |_| {
                let m = optimal_bed_mass_kg(1.34e-3 * 143.0, 1.058, 143.0, 0.012)
                    .ok_or_else(|| ComputeError::new("no bed reaches 12 mm"))?;
                exact(m, "optimal_bed_mass_kg(1.34e-3·143, 1.058, 143, 0.012)")
            },
        ),
        closed_form(
            "ch5.eq5_22.h_over_xmax",
            CH,
            "h_rol = 2.5 X_max",
            stated(2.5, "1", "D L2514–2516"),
            abs(0.05),
            |_| {
                exact(
                    1.0 / rolling_optimal_stroke_m(1.0),
                    "1/rolling_optimal_stroke_m(1)",
                )
            },
        ),
    ]
}

/// The beam and the Flexor (D Sect. 5.2, Eq. 3.37, 5.19).
fn structures() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.sec5_2.f1_beam",
            CH,
            "first eigenfrequency of the beam (M 1.058 kg, K 143 N/m)",
            stated(1.85, "Hz", "D L2309"),
            abs(0.005),
            |_| {
                exact(
                    single_mode(1.058, 143.0, 0.032).0,
                    "ModalStructure::single_mode(1.058, 143, 0.032)",
                )
            },
        ),
        closed_form(
            "ch5.sec5_2.zeta_beam",
            CH,
            "structural damping ratio of the beam (D = 0.032 kg/s)",
            stated(0.0013, "1", "D L2478"),
            abs(0.00005),
            |_| {
                exact(
                    single_mode(1.058, 143.0, 0.032).1,
                    "ModalStructure::single_mode(1.058, 143, 0.032)",
                )
            },
        ),
        closed_form(
            "ch5.sec5_2.f_2kg",
            CH,
            "eigenfrequency with M = 2.0 kg",
            stated(1.35, "Hz", "D L2373"),
            abs(0.005),
            |_| {
                exact(
                    single_mode(2.0, 143.0, 0.0).0,
                    "ModalStructure::single_mode(2.0, 143, 0)",
                )
            },
        ),
        closed_form(
            "ch5.sec5_2.f_flexor",
            CH,
            "first eigenfrequency of the Flexor (M 1.69 kg, K 65 N/m)",
            stated(0.99, "Hz", "D L2434"),
            abs(0.005),
            |_| {
                exact(
                    single_mode(1.69, 65.0, 0.32).0,
                    "ModalStructure::single_mode(1.69, 65, 0.32)",
                )
            },
        ),
        closed_form(
            "ch5.eq3_37.f_with_bed",
            CH,
            "beam eigenfrequency with 147 g attached as effective mass",
            stated(1.73, "Hz", "D Eq. 3.37, L2478"),
            abs(0.005),
            |_| {
                let s = ModalStructure::single_mode(1.058, 143.0, 0.032);
                let w = pdamp_structure::free::effective_omega(
                    &s,
                    0,
                    &[(vec![1.058f64.powf(-0.5)], 0.147)],
                );
                exact(
                    w / std::f64::consts::TAU,
                    "effective_omega(single_mode(1.058, 143), 0, [(φ, 0.147)])/2π",
                )
            },
        ),
        closed_form(
            "ch5.eq5_19.x0_flexor",
            CH,
            "Flexor start amplitude 78 mm scaled by the bed mass (Eq. 5.19)",
            stated(0.104, "m", "D Eq. 5.19, L2423, L2436"),
            abs(0.5e-3),
            |_| {
                let s = pdamp_structure::free::bed_mass_scale(1.69f64.powf(-0.5), 0.563);
                exact(0.078 * s, "0.078·bed_mass_scale(1/√1.69, 0.563)")
            },
        ),
    ]
}

/// Bed masses of the designs (D App. B.9).
fn bed_masses() -> Vec<Target> {
    vec![
        closed_form(
            "ch5.b9.mass_36",
            CH,
            "bed mass of 36 steel spheres r = 5 mm",
            stated(0.149, "kg", "D L2311"),
            rel(0.02),
            |_| exact(bed_mass(36.0), "36·sphere_mass(0.005, 7900)"),
        ),
        closed_form(
            "ch5.b9.mass_48",
            CH,
            "bed mass of 48 spheres",
            stated(0.196, "kg", "D L2365"),
            rel(0.02),
            |_| exact(bed_mass(48.0), "48·sphere_mass(0.005, 7900)"),
        ),
        closed_form(
            "ch5.b9.mass_112",
            CH,
            "bed mass of 112 spheres (the (36, 36, 40) optimum)",
            stated(0.463, "kg", "D L2379"),
            rel(0.02),
            |_| exact(bed_mass(112.0), "112·sphere_mass(0.005, 7900)"),
        ),
        closed_form(
            "ch5.b9.mass_136",
            CH,
            "bed mass of 136 spheres (the Flexor design)",
            stated(0.563, "kg", "D L2436"),
            rel(0.02),
            |_| exact(bed_mass(136.0), "136·sphere_mass(0.005, 7900)"),
        ),
    ]
}

/// ζ of the steady-state FRF (D Eq. 3.47) of a coupling file of the examples, run by
/// `pdamp couple` into the work folder.
fn couple_damping_ratio(ctx: &Context, file: &str) -> Result<Measured, ComputeError> {
    let (v, _) = crate::decay::run_couple_example(ctx, file)?;
    let z = v["damping_ratio_eq_3_47"]
        .as_f64()
        .ok_or_else(|| ComputeError::new("no damping_ratio_eq_3_47 in the summary"))?;
    Ok(Measured::exact(z, format!("pdamp couple examples/{file}")))
}

const TAB52: &str = "D Tab. 5.2, L2482–2489 (simulation column)";

/// D Tab. 5.2: forced vibration of the beam with 36 spheres, approach 3 (formulas).
fn table_5_2() -> Vec<Target> {
    vec![
        quick_run(
            "ch5.tab5_2.zeta_u0p5",
            CH,
            "steady-state ζ (Eq. 3.47) at U = 0.5 mm, rolling formulas",
            stated(0.025, "1", TAB52),
            abs(0.003),
            None,
            |c| couple_damping_ratio(c, "couple_ch5_forced_u0p5mm.toml"),
        ),
        quick_run(
            "ch5.tab5_2.zeta_u2",
            CH,
            "steady-state ζ at U = 2 mm, rolling formulas",
            stated(0.029, "1", TAB52),
            abs(0.003),
            Some(
                "D's own formulas (Eq. 5.10, 5.14, 3.44) give the scattered-rolling resonance at \
                 X ≈ 21 mm and ζ ≈ 0.047 at U = 2 mm; D's 0.029 with X ≈ 40 mm does not follow \
                 from its stated model (notes N45 L416); docs/structure.md finds D's numbers at \
                 U ≈ 2.35 mm",
            ),
            |c| couple_damping_ratio(c, "couple_ch5_forced_u2mm.toml"),
        ),
        quick_run(
            "ch5.fig5_25.zeta_u_opt",
            CH,
            "steady-state ζ at U_opt = 1.34 mm, rolling formulas with the jump at X_opt smoothed",
            stated(0.048, "1", "D L2522, Fig. 5.25 (simulation)"),
            rel(0.15),
            None,
            |c| couple_damping_ratio(c, "couple_ch5_forced_uopt.toml"),
        ),
    ]
}

const GUIDELINE: &str = "couple_ch5_free_guideline.toml";
const OPTIMUM: &str = "couple_ch5_free_optimum.toml";

/// The measured free decays of D Sect. 5.2.1 (Fig. 5.15–5.17: the three-layer guideline and
/// the brute-force optimum (36, 36, 40) on the beam, approach 3). D's numbers are measurements:
/// ±30 % where D gives no tighter statement.
fn free_decays() -> Vec<Target> {
    use crate::decay::{
        amplitude_at, amplitude_of_max_damping, first_damping, free_decay, max_damping,
        mean_damping_in,
    };
    vec![
        quick_run(
            "ch5.fig5_13.zeta_max",
            CH,
            "36 spheres from X_0 = 63 mm, rolling formulas: largest ζ per cycle (Eq. 3.52 ideal)",
            stated(0.056, "1", "D L2311–2336, Fig. 5.13"),
            rel(0.1),
            None,
            |c| {
                let d = free_decay(c, "couple_ch5_free_formulas.toml")?;
                Ok(Measured::exact(
                    max_damping(&d),
                    "pdamp couple examples/couple_ch5_free_formulas.toml: largest ζ",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_13.amplitude_of_zeta_max",
            CH,
            "36 spheres: amplitude of the largest ζ (experiment 13 mm)",
            stated(0.013, "m", "D L2311–2336, Fig. 5.13"),
            abs(2e-3),
            None,
            |c| {
                let d = free_decay(c, "couple_ch5_free_formulas.toml")?;
                Ok(Measured::exact(
                    amplitude_of_max_damping(&d)?,
                    "couple_ch5_free_formulas: amplitude of the cycle with the largest ζ",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_15.zeta_first_cycle",
            CH,
            "guideline (3 × 16 spheres): ζ of the first cycle (measured)",
            stated(0.035, "1", "D Fig. 5.15, L2367"),
            rel(0.3),
            None,
            |c| {
                let d = free_decay(c, GUIDELINE)?;
                Ok(Measured::exact(
                    first_damping(&d)?,
                    "pdamp couple examples/couple_ch5_free_guideline.toml: damping.csv, cycle 1",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_15.zeta_plateau",
            CH,
            "guideline: ζ plateau between 12 and 40 mm",
            worded(0.046, "≈ 0.046", "1", "D Fig. 5.15, L2367"),
            rel(0.15),
            None,
            |c| {
                let d = free_decay(c, GUIDELINE)?;
                Ok(Measured::exact(
                    mean_damping_in(&d, 0.012..0.040)?,
                    "couple_ch5_free_guideline: mean ζ of the cycles at 12–40 mm",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_15.amplitude_4s",
            CH,
            "guideline: amplitude after 4 s (measured)",
            stated(0.010, "m", "D L2395"),
            rel(0.15),
            None,
            |c| {
                let d = free_decay(c, GUIDELINE)?;
                Ok(Measured::exact(
                    amplitude_at(&d, 4.0)?,
                    "couple_ch5_free_guideline: amplitude at 4 s",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_17.zeta_first_cycle",
            CH,
            "optimum (36, 36, 40): ζ of the first cycle (measured)",
            stated(0.05, "1", "D L2395"),
            rel(0.2),
            None,
            |c| {
                let d = free_decay(c, OPTIMUM)?;
                Ok(Measured::exact(
                    first_damping(&d)?,
                    "pdamp couple examples/couple_ch5_free_optimum.toml: cycle 1",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_17.zeta_max",
            CH,
            "optimum: largest ζ (measured)",
            stated(0.11, "1", "D L2395"),
            rel(0.2),
            None,
            |c| {
                let d = free_decay(c, OPTIMUM)?;
                Ok(Measured::exact(
                    max_damping(&d),
                    "couple_ch5_free_optimum: largest ζ per cycle",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_17.amplitude_4s",
            CH,
            "optimum: amplitude after 4 s (measured)",
            stated(0.003, "m", "D L2395"),
            rel(0.3),
            Some(
                "D's 3 mm is a measurement; D's own formula model, run by the extraction notes, \
                 gives 3.9 mm (N45 L373): the formulas, not pdamp, lie above the experiment",
            ),
            |c| {
                let d = free_decay(c, OPTIMUM)?;
                Ok(Measured::exact(
                    amplitude_at(&d, 4.0)?,
                    "couple_ch5_free_optimum: amplitude at 4 s",
                ))
            },
        ),
    ]
}

/// The Flexor decay of D Sect. 5.2.1 (Fig. 5.20) with the optimised layers, from the start of
/// D Eq. 5.19 and from the unscaled 78 mm.
fn flexor_decays() -> Vec<Target> {
    use crate::decay::{amplitude_at, free_decay};
    vec![
        quick_run(
            "ch5.fig5_19.flexor_amplitude_5s",
            CH,
            "Flexor with (24, 28, 28, 28, 28): amplitude after 5 s (measured below 11 mm)",
            worded(0.011, "< 11 mm", "m", "D L2441, Fig. 5.19"),
            crate::Tolerance::Range {
                lo: 0.0,
                hi: 0.011 * 1.3,
            },
            Some(FLEXOR_START),
            |c| {
                let d = free_decay(c, "couple_ch5_flexor_formulas.toml")?;
                Ok(Measured::exact(
                    amplitude_at(&d, 5.0)?,
                    "pdamp couple examples/couple_ch5_flexor_formulas.toml: amplitude at 5 s",
                ))
            },
        ),
        quick_run(
            "ch5.fig5_19.flexor_amplitude_5s_from_78mm",
            CH,
            "Flexor with (24, 28, 28, 28, 28) from the unscaled X_0 = 78 mm: amplitude after 5 s (measured below 11 mm)",
            worded(0.011, "< 11 mm", "m", "D L2441, Fig. 5.19"),
            crate::Tolerance::Range {
                lo: 0.0,
                hi: 0.011 * 1.3,
            },
            None,
            |c| {
                let d = free_decay(c, "couple_ch5_flexor_formulas_x78.toml")?;
                Ok(Measured::exact(
                    amplitude_at(&d, 5.0)?,
                    "pdamp couple examples/couple_ch5_flexor_formulas_x78.toml: amplitude at 5 s",
                ))
            },
        ),
    ]
}
