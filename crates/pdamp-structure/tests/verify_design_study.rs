//! Design studies against the dissertation's optima (brute force with the analytical formulas,
//! approach 3):
//!
//! - D Sect. 5.2.1 (`examples/study_ch5_layers.toml`): three layers of at most 48 spheres in
//!   steps of four, stroke at 4 s. D's optimum (36, 36, 40), 463 g. The optimum is flat: the
//!   best design must have D's total mass within 5 % and D's design must be within 15 % of the
//!   best stroke and among the ten best of 455.
//! - D Sect. 7.2.3 (`examples/study_ch7_vertical.toml`): one vertical bed in steps of 16, stroke
//!   at 0.8 s. D's optimum 64 particles is not reproduced (96); the test asserts D's undamped
//!   51 mm and the measured cause, a flat valley from 64 to 128 spheres.

use std::path::Path;

fn run(example: &str) -> serde_json::Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let out = std::env::temp_dir().join(format!("pdamp_study_{example}_{}", std::process::id()));
    let s = pdamp_structure::study::run_layer_study_file(&root.join(example), &out).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    s
}

#[test]
fn ch5_layer_optimum_matches_dissertation() {
    let s = run("study_ch5_layers.toml");
    let best = &s["best"];
    let best_stroke = best["stroke_m"].as_f64().unwrap();
    let best_mass = best["bed_mass_kg"].as_f64().unwrap();
    let top: Vec<&serde_json::Value> = s["top_10"].as_array().unwrap().iter().collect();
    let d = top
        .iter()
        .position(|v| v["particles"] == serde_json::json!([36, 36, 40]));
    println!(
        "best {:?}: {:.4} kg, stroke {:.2} mm; D's (36, 36, 40) rank {:?}",
        best["particles"],
        best_mass,
        best_stroke * 1e3,
        d.map(|i| i + 1)
    );
    assert_eq!(s["designs"].as_u64(), Some(455));
    assert!((best_mass / 0.463 - 1.0).abs() < 0.05, "{best_mass}");
    let i = d.expect("D's design among the ten best");
    let ds = top[i]["stroke_m"].as_f64().unwrap();
    println!(
        "D's design stroke at 4 s {:.2} mm (D measured 3 mm)",
        ds * 1e3
    );
    assert!(ds <= 1.15 * best_stroke);
}

/// D Sect. 7.2.3 is not reproduced (optimum 96, D 64; `pdamp validate` row
/// ch7.sec7_2_3.optimum_particles). What is asserted is D's undamped stroke and the measured
/// cause: the objective is flat — every filling from 64 to 128 spheres reaches the solid-like
/// floor g (M + m̄)/K ≈ 9–11 mm by 0.8 s and their strokes lie within 20 % of each other — so the
/// brute-force optimum is decided inside that valley. The best stroke is within 30 % of the
/// measured 10 mm (D L3042, 64 particles).
#[test]
fn ch7_vertical_study_reaches_the_floor_from_64_particles() {
    let s = run("study_ch7_vertical.toml");
    let top: Vec<&serde_json::Value> = s["top_10"].as_array().unwrap().iter().collect();
    let stroke = |n: u64| {
        top.iter()
            .find(|v| v["particles"] == serde_json::json!([n]))
            .and_then(|v| v["stroke_m"].as_f64())
            .unwrap_or_else(|| panic!("{n} particles among the ten best"))
    };
    let valley: Vec<f64> = (4..=8).map(|k| stroke(16 * k)).collect();
    let best = s["best"]["stroke_m"].as_f64().unwrap();
    let empty = s["no_particles"]["stroke_m"].as_f64().unwrap();
    println!(
        "best {:?} {:.1} mm; 64..128: {:?} mm; 32: {:.1} mm; empty {:.1} mm",
        s["best"]["particles"],
        best * 1e3,
        valley
            .iter()
            .map(|x| (x * 1e4).round() / 10.0)
            .collect::<Vec<_>>(),
        stroke(32) * 1e3,
        empty * 1e3
    );
    assert!((empty - 0.051).abs() < 0.002, "undamped {empty} (D 51 mm)");
    let hi = valley.iter().cloned().fold(0.0, f64::max);
    assert!(
        hi <= 1.2 * best,
        "64–128 spheres not within 20 % of the best: {valley:?}"
    );
    assert!(
        (best / 0.010 - 1.0).abs() < 0.3,
        "best stroke {best} (D ≈ 10 mm)"
    );
    // 32 spheres decay slower than 64 (D: 19 against 10 mm)
    assert!(stroke(32) > 1.5 * stroke(64));
}
