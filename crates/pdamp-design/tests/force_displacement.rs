//! The force–displacement record of a damper point (`force_displacement.csv`, the `force_time`
//! and `hysteresis` plots of `pdamp run DAMPER.toml`) against the complex power method.
//!
//! The summary's `dissipated_energy_per_cycle_j` is Ẽ_diss of the complex power method
//! [D Eq. 3.12–3.13] (`PointResult::evaluate` takes it from `complex_power`, not from the
//! ledger): Ẽ_diss = (T/2) Re(F̂ V̂*), with F the driving force m_con ẍ − f_p and V the
//! container velocity, both as single-bin DFTs over the evaluated cycles. Since ẋ is a pure
//! sinusoid, (T/2) Re(F̂ V̂*) is the mean of ∮F dx per cycle, and the inertial part ∮m_con ẍ dx
//! vanishes over whole cycles, so Ẽ_diss is the mean loop area ∮(−f_p) dx of the bed force
//! over the container displacement [D Sect. 3.2.2]: the work of the container on the bed.
//! From the decimated CSV rows (200 per cycle, the instantaneous force of the sampled steps)
//! the loop area matches it up to the sampling of a force made of contact pulses.

use pdamp_design::motion::FORCE_DISPLACEMENT_COLUMNS;
use pdamp_design::report::run_damper_scenario;
use pdamp_scenario::schema::{DamperSpec, MotionOutputSpec};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-fd-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The shaken box (100 spheres of 1 mm, restitution 0.6, friction 0.3) as a damper point:
/// 20 Hz, X = 2 mm (Γ = 3.2), 6 cycles of which 2 are transient; m_con = 0.2 kg.
fn scenario() -> pdamp_scenario::schema::Scenario {
    let mut sc = pdamp_scenario::examples::shaken_box(100, 0.0);
    sc.damper = Some(DamperSpec {
        container_body: "box".into(),
        container_mass_kg: 0.2,
        direction: [1.0, 0.0, 0.0],
        frequency_hz: Some(20.0),
        amplitude_m: Some(2e-3),
        acceleration_m_s2: None,
        intensity: None,
        cycles: 6,
        transient_cycles: 2,
        convergence: None,
        motion_output: MotionOutputSpec {
            phases_per_cycle: 2,
            field_cells: 12,
            trajectory_particles: vec![0, 50],
            vtk_frames_per_cycle: 0,
        },
        packings: 1,
    });
    sc
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The record: every row is the container's exact harmonic motion at its time and the
/// driving force m_con ẍ − f_p; each cycle has 200 rows plus its closing one. The mean loop
/// area ∮(−f_p) dx per evaluated cycle from the CSV rows equals `dissipated_energy_per_cycle_j`
/// (complex power, see the file header) within 2 % (measured −0.96 %: the bed's impacts are
/// phase-locked, so sampling 200 instants per cycle misses the same parts of the contact
/// pulses every cycle) and the ledger's wall work per cycle within 2 %; the increase of
/// `work_on_bed_j` (integrated over every step) over the evaluated cycles equals it within
/// 1e-6. The plots exist with their axis titles.
#[test]
fn loop_area_equals_complex_power_dissipation() {
    let dir = scratch("point");
    let sc = scenario();
    let s = run_damper_scenario(&sc, Path::new("."), &dir, |_, _| {}).expect("damper point");
    let (f, x_amp, m_con) = (20.0, 2e-3, 0.2);
    let w = 2.0 * std::f64::consts::PI * f;

    let (header, rows) = read_csv(&dir.join("force_displacement.csv"));
    assert_eq!(header, FORCE_DISPLACEMENT_COLUMNS.to_vec());
    assert_eq!(
        header,
        [
            "time_s",
            "cycle",
            "displacement_m",
            "velocity_m_s",
            "bed_force_n",
            "driving_force_n",
            "work_on_bed_j"
        ]
    );
    for r in &rows {
        let (t, x, v, fp, fd) = (r[0], r[2], r[3], r[4], r[5]);
        assert!(
            (x - x_amp * (w * t).sin()).abs() < 1e-9 * x_amp,
            "x at t = {t}"
        );
        assert!(
            (v - x_amp * w * (w * t).cos()).abs() < 1e-9 * x_amp * w,
            "v at t = {t}"
        );
        assert!((fd - (-m_con * w * w * x - fp)).abs() < 1e-9 * (m_con * w * w * x_amp));
    }
    assert!(rows.windows(2).all(|p| p[1][0] >= p[0][0]), "time ordered");
    for c in 1..6 {
        let n = rows.iter().filter(|r| r[1] == c as f64).count();
        assert_eq!(n, 201, "rows of cycle {c}");
    }

    // Mean loop area over the evaluated cycles, each cycle's rows on their own.
    let evaluated = 2..6;
    let mut areas = Vec::new();
    for c in evaluated.clone() {
        let cyc: Vec<&Vec<f64>> = rows.iter().filter(|r| r[1] == c as f64).collect();
        assert!(
            (cyc[0][0] * f - c as f64).abs() < 1e-9,
            "cycle {c} starts at its boundary"
        );
        assert!((cyc[200][0] * f - (c + 1) as f64).abs() < 1e-9);
        areas.push(
            cyc.windows(2)
                .map(|p| -0.5 * (p[0][4] + p[1][4]) * (p[1][2] - p[0][2]))
                .sum::<f64>(),
        );
    }
    let mean = areas.iter().sum::<f64>() / areas.len() as f64;
    // The same through all evaluated rows in order (the repeated boundary rows add nothing).
    let all: Vec<&Vec<f64>> = rows.iter().filter(|r| r[1] >= 2.0).collect();
    let sequential = all
        .windows(2)
        .map(|p| -0.5 * (p[0][4] + p[1][4]) * (p[1][2] - p[0][2]))
        .sum::<f64>()
        / 4.0;
    let e = s.dissipated_energy_per_cycle_j;
    let rel = mean / e - 1.0;
    // The work on the bed, integrated over every step: exactly the complex power's Ẽ_diss.
    let w_start = rows.iter().find(|r| r[1] == 2.0).unwrap()[6];
    let w_end = rows.last().unwrap()[6];
    let rel_work = (w_end - w_start) / 4.0 / e - 1.0;
    let rel_wall = mean / s.point.ledger_wall_work_per_cycle_j - 1.0;
    eprintln!(
        "loop area per cycle {mean:.6e} J (cycles {areas:?}), Ẽ_diss complex power {e:.6e} J, \
         rel. diff {rel:+.3e}; ledger wall work {:.6e} J/cycle ({rel_wall:+.3e}), dissipated \
         {:.6e} J/cycle; work on the bed from work_on_bed_j {:.6e} J/cycle ({rel_work:+.3e}); \
         η̄ = {:.4}",
        s.point.ledger_wall_work_per_cycle_j,
        s.point.ledger_dissipated_per_cycle_j,
        (w_end - w_start) / 4.0,
        s.effective_loss_factor
    );
    assert!(e > 0.0 && s.effective_loss_factor > 0.02);
    assert!((sequential / mean - 1.0).abs() < 1e-12);
    assert!(rel.abs() < 0.02, "loop area vs Ẽ_diss: {rel}");
    assert!(rel_work.abs() < 1e-6, "work_on_bed_j vs Ẽ_diss: {rel_work}");
    assert!(rel_wall.abs() < 0.02, "loop area vs wall work: {rel_wall}");

    let svg = |name: &str| {
        assert!(dir.join(format!("{name}.png")).is_file(), "{name}.png");
        std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap()
    };
    let ft = svg("force_time");
    for label in [
        "time t (s)",
        "bed force on the container f_p (N)",
        "container displacement x (mm)",
        "transient cycles (not evaluated)",
    ] {
        assert!(ft.contains(label), "force_time lacks {label:?}");
    }
    let hy = svg("hysteresis");
    for label in [
        "container displacement x (mm)",
        "bed force on the container f_p (N)",
        "∮(−f_p)dx",
        "transient cycles 0–1",
        "cycle 5",
    ] {
        assert!(hy.contains(label), "hysteresis lacks {label:?}");
    }
    let vf = svg("velocity_field_phase0");
    assert!(vf.contains("mean velocity v/V = "), "reference arrow");
    assert!(svg("trajectories").contains("container"));
    // PDAMP_PLOT_KEEP keeps the outputs to look at.
    if std::env::var_os("PDAMP_PLOT_KEEP").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
}
