//! A bed prepared by one process and saved (`pdamp_scenario::prepare::save_prepared`) continues in
//! another bit for bit: the tasks of a sweep on other nodes start from the same state as a
//! local field run that prepared the bed itself (issue 27).

use pdamp_design::report::{BedSource, field_damper, prepared_bed_path};
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn without_time(mut r: pdamp_design::PointResult) -> pdamp_design::PointResult {
    r.wall_time_s = 0.0;
    r
}

#[test]
fn a_saved_prepared_bed_continues_bit_for_bit() {
    let base = examples();
    let sc = pdamp_scenario::schema::Scenario::load(&base.join("damper_cylinder_small.toml"))
        .expect("scenario");
    let dir = std::env::temp_dir().join(format!("pdamp_prepared_bed_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // Packing 1 (another seed than the scenario's): prepared here, saved, then read back as a
    // task on another node would.
    let fresh = field_damper(&sc, &base, 1, BedSource::Prepare, |_| {}).expect("prepare");
    let saved = field_damper(&sc, &base, 1, BedSource::Saved(&dir), |_| {}).expect("save");
    assert!(prepared_bed_path(&dir, 1).is_file());
    let loaded = field_damper(&sc, &base, 1, BedSource::Saved(&dir), |_| {}).expect("load");
    assert_eq!(
        loaded.settled.particles.position,
        fresh.settled.particles.position
    );
    assert_eq!(loaded.settling_time_s, fresh.settling_time_s);
    assert_eq!(loaded.fill_statistics, fresh.fill_statistics);
    // One short point on each: every number equal (timing aside).
    let (f, x) = (
        160.0,
        20.0 * 9.81 / (2.0 * std::f64::consts::PI * 160.0_f64).powi(2),
    );
    let a = without_time(fresh.run_point(f, x, &mut ()).expect("fresh point"));
    let b = without_time(saved.run_point(f, x, &mut ()).expect("saved point"));
    let c = without_time(loaded.run_point(f, x, &mut ()).expect("loaded point"));
    assert!(a.effective_loss_factor.is_finite() && a.effective_loss_factor > 0.0);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    assert_eq!(format!("{a:?}"), format!("{c:?}"));

    // The saved bed belongs to its scenario: another seed's packing, a changed material or a
    // damaged file is refused with the reason, never silently used.
    let other = pdamp_scenario::prepare::scenario_for_packing(&sc, 2);
    let Err(e) = pdamp_scenario::prepare::load_prepared(&prepared_bed_path(&dir, 1), &other, &base)
    else {
        panic!("another packing's scenario must be refused");
    };
    let e = e.to_string();
    assert!(e.contains("different scenario"), "{e}");
    let path = prepared_bed_path(&dir, 1);
    let mut bytes = std::fs::read(&path).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&path, &bytes).unwrap();
    let Err(e) = field_damper(&sc, &base, 1, BedSource::Saved(&dir), |_| {}) else {
        panic!("a damaged bed must be refused");
    };
    let e = e.to_string();
    assert!(
        e.contains("damaged") && e.contains("packing_001.pdprep"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
