//! The shipped examples through the library entry points of `pdamp structure modes` and
//! `pdamp couple`: output files and columns, and two results against the dissertation.

use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-structure-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `structure_cantilever_small.toml`: modes.csv with the closed-form first frequency
/// (βL = 1.875104, f1 = 8.3552 Hz; 20 Euler–Bernoulli elements).
#[test]
fn modes_of_the_small_cantilever() {
    let out = out_dir("modes");
    pdamp_structure::report::run_modes(&examples().join("structure_cantilever_small.toml"), &out)
        .unwrap();
    let (h, rows) = pdamp_io::csv::read_csv_f64(out.join("modes.csv")).unwrap();
    assert_eq!(&h[..3], ["mode", "frequency_hz", "damping_ratio"]);
    assert_eq!(rows.len(), 4);
    assert!(
        (rows[0][1] - 8.3552).abs() / 8.3552 < 1e-3,
        "{}",
        rows[0][1]
    );
    std::fs::remove_dir_all(&out).ok();
}

/// `couple_ch6_free_layers.toml`: the layered design of D Sect. 6.2 reaches the design damping
/// ratio ζ_d = m_bed/(4M) = 0.044 (Eq. 5.15) over the amplitude range of the layers
/// (mean of the cycles with 10–45 mm within ±15 %), and all outputs are written.
#[test]
fn layered_design_reaches_the_design_damping_ratio() {
    let out = out_dir("ch6");
    let s = pdamp_structure::report::run_couple_default(
        &examples().join("couple_ch6_free_layers.toml"),
        &out,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(s["analysis"], "free");
    for f in [
        "decay.csv",
        "damping.csv",
        "updates.csv",
        "summary.json",
        "decay.png",
        "decay.svg",
        "damping.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let (h, rows) = pdamp_io::csv::read_csv_f64(out.join("damping.csv")).unwrap();
    assert_eq!(
        &h[..3],
        ["mean_amplitude_m", "damping_ratio", "frequency_hz"]
    );
    let z: Vec<f64> = rows
        .iter()
        .filter(|r| (0.010..0.045).contains(&r[0]))
        .map(|r| r[1])
        .collect();
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    println!(
        "ch6 layered damper: mean ζ over 10–45 mm = {mean:.4} ({} cycles), design 0.044",
        z.len()
    );
    assert!(z.len() >= 4 && (mean - 0.044).abs() / 0.044 < 0.15);
    let (h, _) = pdamp_io::csv::read_csv_f64(out.join("decay.csv")).unwrap();
    assert_eq!(&h[..2], ["time_s", "displacement_m"]);
    std::fs::remove_dir_all(&out).ok();
}

/// `couple_ch5_forced_u0p5mm.toml`: frf.csv columns and D Tab. 5.2 (simulation ζ = 0.025).
#[test]
fn table_5_2_example_through_the_cli_entry_point() {
    let out = out_dir("ch5u05");
    let s = pdamp_structure::report::run_couple_default(
        &examples().join("couple_ch5_forced_u0p5mm.toml"),
        &out,
        &mut |_| {},
    )
    .unwrap();
    let z = s["damping_ratio_eq_3_47"].as_f64().unwrap();
    assert!((z - 0.025).abs() < 0.003, "{z}");
    let (h, rows) = pdamp_io::csv::read_csv_f64(out.join("frf.csv")).unwrap();
    assert_eq!(&h[..3], ["frequency_hz", "magnitude_m_per_n", "phase_rad"]);
    assert_eq!(rows.len(), 1000);
    assert!(out.join("frf.png").exists() && out.join("frf.svg").exists());
    std::fs::remove_dir_all(&out).ok();
}

/// `couple_ch8_fields_segments.toml` shortened to 60 s: the segmented sweep (frequency-domain
/// approach) writes frf.csv and frf_segments.csv, and `modal_parameters` finds all four modes of
/// the Tab. 8.6 beam within 3 % of the bare frequencies (the damper lowers them slightly).
#[test]
fn segmented_sweep_example_finds_all_modes() {
    let out = out_dir("segments");
    let text = std::fs::read_to_string(examples().join("couple_ch8_fields_segments.toml"))
        .unwrap()
        .replace("duration_s = 300.0", "duration_s = 60.0")
        .replace(
            "structure_file = \"structure_ch8_beam2.toml\"",
            &format!(
                "structure_file = {:?}",
                examples().join("structure_ch8_beam2.toml")
            ),
        )
        .replace(
            "path = \"../docs/figures/baseline_coarse/fields.csv\"",
            &format!(
                "path = {:?}",
                examples().join("../docs/figures/baseline_coarse/fields.csv")
            ),
        );
    let scn = out.join("segments.toml");
    std::fs::write(&scn, text).unwrap();
    let s = pdamp_structure::report::run_couple_default(&scn, &out, &mut |_| {}).unwrap();
    assert_eq!(s["segments"], 8);
    assert!(out.join("frf_segments.csv").exists());
    let (h, rows) = pdamp_io::csv::read_csv_f64(out.join("frf.csv")).unwrap();
    assert_eq!(h, ["frequency_hz", "magnitude_m_per_n", "phase_rad"]);
    assert!(rows.windows(2).all(|w| w[1][0] >= w[0][0]));
    let modes = s["modal_parameters"]["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4);
    for m in modes {
        let (f, f0) = (
            m["frequency_hz"].as_f64().unwrap(),
            m["structural_frequency_hz"].as_f64().unwrap(),
        );
        println!("{f0:.1} Hz → {f:.2} Hz, ζ = {}", m["damping_ratio"]);
        assert!((f / f0 - 1.0).abs() < 0.03, "{f} vs {f0}");
        assert!(m["damping_ratio"].as_f64().unwrap() > 0.0);
    }
    std::fs::remove_dir_all(&out).ok();
}
