//! Powder ensembles (issue 24, item 5): `run_ensemble` and `run_study_packings` prepare every
//! packing with its own seed, report the mean and the 95 % confidence interval over the
//! packings, are deterministic, and reuse finished packings.

use pdamp_design::ensemble::EnsembleStat;
use pdamp_powder::cantilever::{CantileverScenario, RunOptions};
use pdamp_powder::study::{self, StudyParameter};
use std::path::PathBuf;

fn tiny() -> CantileverScenario {
    CantileverScenario::from_toml(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/tiny_cantilever.toml"
        ))
        .unwrap(),
    )
    .unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-powder-ens-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn ensemble_of_three_packings() {
    let out = tmp("run");
    let e = study::run_ensemble(
        &tiny(),
        3,
        &out,
        RunOptions::new(0.0, false),
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(e.packings, 3);
    assert_eq!(e.seeds, vec![1, 1_000_004, 2_000_007]);
    for k in 0..3 {
        assert!(out.join(format!("packing_{k:03}/summary.json")).exists());
        assert_eq!(e.members[k].packing, k);
    }
    // Independent beds: the settled densities differ from packing to packing.
    let settled: Vec<f64> = e
        .members
        .iter()
        .map(|r| r.prep.as_ref().unwrap().settled_packing_density)
        .collect();
    assert!(
        settled[0] != settled[1] && settled[1] != settled[2],
        "{settled:?}"
    );
    // The statistics are those of the members (Student's t, K − 1 = 2: t = 4.303).
    assert_eq!(e.settled_packing_density, EnsembleStat::of(&settled));
    let s = e.settled_packing_density;
    assert!((s.ci95_half_width - 4.302_652_7 * s.std / 3f64.sqrt()).abs() < 1e-12);
    let zeta: Vec<f64> = e
        .members
        .iter()
        .map(|r| r.damping.zeta_1.unwrap_or(f64::NAN))
        .collect();
    let z = EnsembleStat::of(&zeta);
    assert_eq!(e.zeta_1.count, z.count);
    assert!(e.zeta_1.mean == z.mean || (e.zeta_1.mean.is_nan() && z.mean.is_nan()));
    // Files: one table line per packing, the ensemble as JSON.
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert!(table.starts_with("packing,zeta_1,"), "{table}");
    assert_eq!(table.lines().count(), 4);
    assert!(out.join("ensemble.json").exists());
    // Packing 0 is the scenario's own run: the same as a single run of it.
    let single = tmp("single");
    let r = pdamp_powder::cantilever::run_in_dir(
        &tiny(),
        &single,
        RunOptions::new(0.0, false),
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(r.prep.as_ref().unwrap().settled_packing_density, settled[0]);
    // Run again: the finished packings are reused, with the same result.
    let again = study::run_ensemble(
        &tiny(),
        3,
        &out,
        RunOptions::new(0.0, false),
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(
        serde_json::to_string(&again.settled_packing_density).unwrap(),
        serde_json::to_string(&e.settled_packing_density).unwrap()
    );
    // Too few packings and an empty beam are refused.
    assert!(
        study::run_ensemble(
            &tiny(),
            1,
            &tmp("one"),
            RunOptions::new(0.0, false),
            &mut |_, _| {}
        )
        .unwrap_err()
        .to_string()
        .contains("at least 2")
    );
    let mut empty = tiny();
    empty.powder = None;
    assert!(
        study::run_ensemble(
            &empty,
            2,
            &tmp("empty"),
            RunOptions::new(0.0, false),
            &mut |_, _| {}
        )
        .unwrap_err()
        .to_string()
        .contains("[powder] section")
    );
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&single);
}

#[test]
fn study_with_packings_writes_the_ensemble_per_value() {
    let out = tmp("study");
    let rows = study::run_study_packings(
        &tiny(),
        StudyParameter::Friction,
        &[0.2, 0.4],
        2,
        &out,
        RunOptions::new(0.0, false),
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(rows.len(), 4);
    assert!(out.join("friction_0.2/packing_001/summary.json").exists());
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert!(table.starts_with("friction,packing,zeta_1,"), "{table}");
    let ens = std::fs::read_to_string(out.join("ensemble.csv")).unwrap();
    let lines: Vec<&str> = ens.lines().collect();
    assert!(
        lines[0].starts_with("friction,packings,zeta_1_mean,"),
        "{ens}"
    );
    assert_eq!(lines.len(), 3);
    assert!(lines[1].starts_with("0.2,2,"), "{ens}");
    let _ = std::fs::remove_dir_all(&out);
}
