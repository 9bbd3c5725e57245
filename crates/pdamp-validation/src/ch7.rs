//! D Ch. 7, vertical dampers: the vertical collect-and-collide model (D Eq. 7.1–7.19) and the
//! structure of Sect. 7.2.

use crate::{Target, abs, closed_form, exact, rel, stated, worded};
use pdamp_structure::formulas::{VerticalDamper, clearance_m};
use pdamp_structure::modal::ModalStructure;
use std::f64::consts::{PI, TAU};

const CH: &str = "D Ch. 7 — vertical dampers";
const VERTICAL32: &str = "couple_ch7_free_vertical32.toml";

/// The 32-sphere vertical bed of Sect. 7.2 (h = 100 mm).
const BED: VerticalDamper = VerticalDamper {
    bed_mass_kg: 0.131,
    clearance_m: 0.1,
};

/// The Ch. 7 targets.
pub fn targets() -> Vec<Target> {
    let mut t = model_and_structure();
    t.extend(free_decay_32());
    t.extend(layer_study());
    t.extend(model_points());
    t
}

/// One point of the notes' own evaluation of the vertical model (h = 0.1 m).
macro_rules! vertical_eta_row {
    ($id:literal, $f:literal, $x:literal, $eta:literal, $mode:literal) => {
        closed_form(
            $id,
            CH,
            concat!(
                "η̄ of the vertical model, h = 0.1 m, f = ",
                stringify!($f),
                " Hz, X = ",
                stringify!($x),
                " m (",
                $mode,
                ")"
            ),
            stated(
                $eta,
                "1",
                "notes N69 L321–333 (the notes' own evaluation of D Eq. 7.1–7.18, not D numbers)",
            ),
            abs(0.01),
            |_| {
                exact(
                    BED.state($x, TAU * $f).effective_loss_factor,
                    concat!(
                        "VerticalDamper { h 0.1 }.state(",
                        stringify!($x),
                        ", 2π·",
                        stringify!($f),
                        ")"
                    ),
                )
            },
        )
    };
}

/// m̄/m_bed of Eq. 7.19 at a point of the vertical model in the named mode.
macro_rules! vertical_mbar_row {
    ($id:literal, $f:literal, $x:literal, $mbar:literal, $mode:literal) => {
        closed_form(
            $id,
            CH,
            concat!(
                "m̄/m_bed of Eq. 7.19, ",
                $mode,
                " (the model at f = ",
                stringify!($f),
                " Hz, X = ",
                stringify!($x),
                " m)"
            ),
            stated($mbar, "1", "D Eq. 7.19, L2980"),
            abs(1e-9),
            |_| {
                exact(
                    BED.state($x, TAU * $f).effective_mass_ratio,
                    concat!(
                        "VerticalDamper { h 0.1 }.state(",
                        stringify!($x),
                        ", 2π·",
                        stringify!($f),
                        ").effective_mass_ratio"
                    ),
                )
            },
        )
    };
}

/// The zero-gravity optimum, the 64-sphere bed's mass, Eq. 7.19 in the three other modes and
/// the notes' evaluation of the model.
fn model_points() -> Vec<Target> {
    vec![
        closed_form(
            "ch7.eq7_16.xopt",
            CH,
            "zero-gravity optimal stroke X_opt = h/π of the 32-sphere bed (h = 0.1 m)",
            stated(0.032, "m", "D Eq. 7.16, L2929; 32 mm at L2970"),
            abs(5e-4),
            |_| {
                exact(
                    clearance_m(0.12, 32.0, 192.0) / PI,
                    "clearance_m(0.12, 32, 192)/π",
                )
            },
        ),
        closed_form(
            "ch7.masses.m_64",
            CH,
            "bed mass of 64 steel spheres r = 5 mm",
            stated(0.265, "kg", "D L3033"),
            rel(0.02),
            |_| {
                exact(
                    64.0 * pdamp_impact::hertz::sphere_mass(0.005, 7900.0),
                    "64·sphere_mass(0.005, 7900)",
                )
            },
        ),
        vertical_mbar_row!(
            "ch7.eq7_19.mbar_single",
            4.0,
            0.040,
            0.65,
            "harmonic single collect-and-collide"
        ),
        vertical_mbar_row!(
            "ch7.eq7_19.mbar_subharmonic",
            8.0,
            0.020,
            0.2,
            "subharmonic single collect-and-collide"
        ),
        vertical_mbar_row!("ch7.eq7_19.mbar_scattered", 10.0, 0.026, 0.1, "scattered"),
        vertical_eta_row!(
            "ch7.model.eta_20hz_32mm",
            20.0,
            0.032,
            1.271,
            "double, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_15hz_32mm",
            15.0,
            0.032,
            1.266,
            "double, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_10hz_32mm",
            10.0,
            0.032,
            1.234,
            "double, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_5hz_40mm",
            5.0,
            0.040,
            1.036,
            "double, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_4hz_40mm",
            4.0,
            0.040,
            0.719,
            "single, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_2hz_100mm",
            2.0,
            0.100,
            0.328,
            "single, harmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_8hz_20mm",
            8.0,
            0.020,
            0.186,
            "single, subharmonic"
        ),
        vertical_eta_row!(
            "ch7.model.eta_10hz_200mm",
            10.0,
            0.200,
            0.27,
            "double, harmonic"
        ),
    ]
}

/// The vertical model's limits and the structure of Sect. 7.2.
fn model_and_structure() -> Vec<Target> {
    let mut known = closed_form(
        "ch7.sec7_2_1.f0_stated_mass",
        CH,
        "eigenfrequency of the Ch. 7 beam from D's stated M = 1.139 kg, K = 1848 N/m",
        stated(5.56, "Hz", "D L3001"),
        abs(0.01),
        |_| {
            let s = ModalStructure::single_mode(1.139, 1848.0, 0.55);
            exact(
                s.modes[0].frequency_hz,
                "ModalStructure::single_mode(1.139, 1848, 0.55)",
            )
        },
    );
    known.known_cause = Some(
        "D's stated M and K are inconsistent with its 5.56 Hz: √(K/M)/2π = 6.41 Hz; M = 1.514 kg \
         reproduces 5.56 Hz and is what examples/structure_ch7_beam.toml uses",
    );
    vec![
        closed_form(
            "ch7.eq7_4.h_32",
            CH,
            "clearance of 32 of 192 spheres",
            stated(0.100, "m", "D Eq. 7.4, L3008"),
            abs(1e-9),
            |_| exact(clearance_m(0.12, 32.0, 192.0), "clearance_m(0.12, 32, 192)"),
        ),
        closed_form(
            "ch7.eq7_4.h_64",
            CH,
            "clearance of 64 of 192 spheres",
            stated(0.080, "m", "D L3038"),
            abs(1e-9),
            |_| exact(clearance_m(0.12, 64.0, 192.0), "clearance_m(0.12, 64, 192)"),
        ),
        closed_form(
            "ch7.masses.m_32",
            CH,
            "bed mass of 32 steel spheres r = 5 mm",
            stated(0.131, "kg", "D L3008"),
            rel(0.02),
            |_| {
                exact(
                    32.0 * pdamp_impact::hertz::sphere_mass(0.005, 7900.0),
                    "32·sphere_mass(0.005, 7900)",
                )
            },
        ),
        closed_form(
            "ch7.eq7_18.eta_max",
            CH,
            "maximal vertical loss factor for A ≫ g at X = h/π",
            worded(1.27, "4/π ≈ 1.27", "1", "D Eq. 7.16–7.18, L2939"),
            abs(0.01),
            |_| {
                let s = BED.state(0.1 / PI, TAU * 200.0);
                exact(
                    s.effective_loss_factor,
                    "VerticalDamper{0.131 kg, h 0.1}.state(h/π, 2π·200)",
                )
            },
        ),
        closed_form(
            "ch7.eq7_5.eta_solid",
            CH,
            "solid-like loss factor (A < g)",
            stated(0.001, "1", "D Eq. 7.5, L2875–2879"),
            abs(1e-12),
            |_| {
                let s = BED.state(0.005, TAU * 5.0);
                exact(s.effective_loss_factor, "VerticalDamper.state(0.005, 2π·5)")
            },
        ),
        closed_form(
            "ch7.eq7_19.mbar_solid",
            CH,
            "effective mass ratio of a solid-like bed",
            stated(0.75, "1", "D Eq. 7.19, L2980"),
            abs(1e-12),
            |_| {
                let s = BED.state(0.005, TAU * 5.0);
                exact(s.effective_mass_ratio, "VerticalDamper.state(0.005, 2π·5)")
            },
        ),
        known,
        closed_form(
            "ch7.sec7_2_2.zeta_undamped",
            CH,
            "structural damping ratio of the Ch. 7 beam (D = 0.55 kg/s, M 1.514 kg)",
            worded(0.005, "≈ 0.005", "1", "D L3012"),
            abs(0.0005),
            |_| {
                let s = ModalStructure::single_mode(1.514, 1848.0, 0.55);
                exact(
                    s.modes[0].damping_ratio,
                    "ModalStructure::single_mode(1.514, 1848, 0.55)",
                )
            },
        ),
    ]
}

/// The measured free decay of Fig. 7.6 (32 spheres, vertical formulas, approach 3).
fn free_decay_32() -> Vec<Target> {
    vec![
        crate::quick_run(
            "ch7.fig7_6.zeta_first_cycle",
            CH,
            "32 spheres from X_0 = 58 mm, vertical formulas: ζ of the first cycle between negative peaks (D: ≈ 0.035 at 53 mm, measured)",
            worded(0.035, "≈ 0.035", "1", "D L3010, Fig. 7.6"),
            rel(0.3),
            None,
            |c| {
                let d = crate::decay::free_decay(c, VERTICAL32)?;
                Ok(crate::Measured::exact(
                    crate::decay::first_damping(&d)?,
                    "pdamp couple examples/couple_ch7_free_vertical32.toml: cycle 1",
                ))
            },
        ),
        crate::quick_run(
            "ch7.fig7_6.zeta_rises",
            CH,
            "32 spheres: ζ rises from the first cycle to X = 41 mm, negative peaks (D: 0.035 → 0.05, ratio 1.43)",
            worded(1.43, "rises (ratio > 1)", "1", "D L3010, Fig. 7.6"),
            crate::Tolerance::Range {
                lo: 1.0,
                hi: f64::INFINITY,
            },
            None,
            |c| {
                let d = crate::decay::free_decay(c, VERTICAL32)?;
                let r = crate::decay::damping_at_amplitude(&d, 0.041)?
                    / crate::decay::first_damping(&d)?;
                Ok(crate::Measured::exact(
                    r,
                    "couple_ch7_free_vertical32: ζ(41 mm)/ζ(cycle 1)",
                ))
            },
        ),
        crate::quick_run(
            "ch7.fig7_6.zeta_41mm",
            CH,
            "32 spheres: ζ rising to 0.05 at X = 41 mm (experiment)",
            stated(0.05, "1", "D L3010, Fig. 7.6"),
            rel(0.3),
            None,
            |c| {
                let d = crate::decay::free_decay(c, VERTICAL32)?;
                Ok(crate::Measured::exact(
                    crate::decay::damping_at_amplitude(&d, 0.041)?,
                    "couple_ch7_free_vertical32: ζ at 41 mm",
                ))
            },
        ),
        crate::quick_run(
            "ch7.fig7_6.solid_like_time",
            CH,
            "32 spheres: time from which the particles hardly damp (their share of ζ, ζ − ζ_structure, below the structure's own 0.0052)",
            stated(1.66, "s", "D L3012, Fig. 7.6"),
            abs(0.2),
            None,
            |c| {
                let d = crate::decay::free_decay(c, VERTICAL32)?;
                let z_s = ModalStructure::single_mode(1.514, 1848.0, 0.55).modes[0].damping_ratio;
                Ok(crate::Measured::exact(
                    crate::decay::time_damping_falls_below(&d, 2.0 * z_s)?,
                    "couple_ch7_free_vertical32: first time ζ per cycle < 2·0.0052",
                ))
            },
        ),
        closed_form(
            "ch7.sec7_2_2.x_min",
            CH,
            "smallest amplitude X_min = g/ω_bed² (32 spheres as static mass)",
            stated(0.0088, "m", "D L3012"),
            abs(2e-4),
            |_| {
                let g = pdamp_dem::math::STANDARD_GRAVITY_M_S2;
                exact(
                    g * (1.514 + 0.131) / 1848.0,
                    "g (M + m_bed)/K, M 1.514 kg, K 1848 N/m",
                )
            },
        ),
        closed_form(
            "ch7.sec7_2_2.undamped_2s",
            CH,
            "amplitude of the structure without particles after 2 s from X_0 = 58 mm",
            worded(0.040, "about 40 mm", "m", "D L3012"),
            abs(1e-3),
            |_| {
                let m = ModalStructure::single_mode(1.514, 1848.0, 0.55).modes[0];
                let w = TAU * m.frequency_hz;
                exact(
                    0.058 * (-m.damping_ratio * w * 2.0).exp(),
                    "0.058·exp(−ζ ω_0 · 2 s), single_mode(1.514, 1848, 0.55)",
                )
            },
        ),
    ]
}

/// The brute-force study of D Sect. 7.2.3 (`examples/study_ch7_vertical.toml`: particles in
/// steps of 16, stroke at t = 0.8 s; D quotes 0.75 s), run by `pdamp structure optimize-layers`.
fn study(ctx: &crate::Context) -> Result<serde_json::Value, crate::ComputeError> {
    let out = ctx.work_dir.join("study_ch7_vertical");
    let _ = std::fs::remove_dir_all(&out);
    pdamp_structure::study::run_layer_study_file(&ctx.example("study_ch7_vertical.toml"), &out)
        .map_err(crate::ComputeError::new)
}

/// The stroke (m) of the design with `particles` in the study's ten best (`0`: no damper).
fn stroke_of(s: &serde_json::Value, particles: u64) -> Result<f64, crate::ComputeError> {
    let entry = if particles == 0 {
        Some(&s["no_particles"])
    } else {
        s["top_10"].as_array().and_then(|top| {
            top.iter()
                .find(|v| v["particles"] == serde_json::json!([particles]))
        })
    };
    entry.and_then(|v| v["stroke_m"].as_f64()).ok_or_else(|| {
        crate::ComputeError::new(format!("{particles} particles not among the ten best"))
    })
}

const STUDY: &str = "pdamp structure optimize-layers examples/study_ch7_vertical.toml";

/// Why the vertical brute force does not give D's 64 (measured, 2026-12-07).
const FLAT_VALLEY: &str = "the objective is flat: 64, 80, 96, 112 and 128 spheres give 13.8, 12.4, \
    11.8, 12.0 and 12.3 mm at 0.8 s (all within 17 %), every one close to the solid-like floor \
    g(M + m̄)/K ≈ 9–11 mm; the optimum moves inside that valley with the evaluation time (0.75 s: \
    112) and the structure data (D's printed M = 1.139 kg: 112; M 1.139 kg with K = 1390 N/m, \
    which give D's 5.56 Hz: 128), so D's 64 is one point of a valley the model does not resolve";

/// Why the model's strokes lie above the measured ones (measured, 2026-12-07).
const SLOW_SINGLE: &str = "after the switch from double to single collect-and-collide (X just \
    below X_opt = 32 mm) the vertical formulas give η̄ = 0.38–0.58 (at 5.4 Hz the bed lands \
    after the container has turned down, Ωt_imp > 2π, Eq. 7.6–7.9 as printed) and ζ per cycle \
    0.020–0.027, where the experiment's 34 → 19 mm in two cycles needs ζ ≈ 0.046; the double \
    collect-and-collide cycles before match (ζ 0.043 and 0.049 against 0.035 and 0.05)";

/// D Sect. 7.2.3 and Fig. 7.7: the optimum particle number and the strokes after 0.75 s.
fn layer_study() -> Vec<Target> {
    vec![
        crate::quick_run(
            "ch7.sec7_2_3.optimum_particles",
            CH,
            "brute-force optimum particle number (steps of 16, smallest stroke)",
            stated(64.0, "1", "D L3038"),
            abs(0.5),
            Some(FLAT_VALLEY),
            |c| {
                let s = study(c)?;
                let n = s["best"]["particles"][0]
                    .as_f64()
                    .ok_or_else(|| crate::ComputeError::new("no best design"))?;
                Ok(crate::Measured::exact(n, STUDY))
            },
        ),
        crate::quick_run(
            "ch7.fig7_7.stroke_undamped",
            CH,
            "stroke without particles after 0.75 s (pdamp: 0.8 s)",
            stated(0.051, "m", "D L3042"),
            abs(2e-3),
            None,
            |c| Ok(crate::Measured::exact(stroke_of(&study(c)?, 0)?, STUDY)),
        ),
        crate::quick_run(
            "ch7.fig7_7.stroke_64",
            CH,
            "stroke with 64 particles after 0.75 s (measured; pdamp: 0.8 s)",
            worded(0.010, "≈ 10 mm", "m", "D L3042"),
            rel(0.3),
            Some(SLOW_SINGLE),
            |c| Ok(crate::Measured::exact(stroke_of(&study(c)?, 64)?, STUDY)),
        ),
        crate::quick_run(
            "ch7.fig7_7.stroke_32",
            CH,
            "stroke with 32 particles after 0.75 s (measured; pdamp: 0.8 s)",
            stated(0.019, "m", "D L3042"),
            rel(0.3),
            Some(SLOW_SINGLE),
            |c| Ok(crate::Measured::exact(stroke_of(&study(c)?, 32)?, STUDY)),
        ),
    ]
}
