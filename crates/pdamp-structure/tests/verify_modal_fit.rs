//! Modal parameter extraction (issue 4, forced vibration): a known 2-dof spring–mass chain with
//! modal damping ζ = (0.02, 0.01) is swept slowly in the time domain (logarithmic sweep, Newmark),
//! its FRF is demodulated from the sweep [D Eq. 3.42] and the global rational fraction
//! polynomial fit and the half-power bandwidth must return both eigenfrequencies and damping
//! ratios within 1 % (the modal constants φ_out φ_ex within 2 %).

use nalgebra::DMatrix;
use pdamp_structure::forced::{self, Sweep, SweepLaw, SweepSpec};
use pdamp_structure::modal::{self, ModalPoint, ModalStructure, Mode};
use pdamp_structure::modal_fit;
use std::f64::consts::TAU;

#[test]
fn two_dof_sweep_rfp_and_half_power_within_one_percent() {
    // ground –k1– m1 –k2– m2
    let (m1, m2, k1, k2) = (1.0, 0.5, 6000.0, 4000.0);
    let k = DMatrix::from_row_slice(2, 2, &[k1 + k2, -k2, -k2, k2]);
    let m = DMatrix::from_row_slice(2, 2, &[m1, 0.0, 0.0, m2]);
    let basis = modal::lowest_modes(&k, &m, 2, 0.0).unwrap();
    let zetas = [0.02, 0.01];
    let s = ModalStructure {
        modes: basis
            .omega_rad_s
            .iter()
            .zip(zetas)
            .map(|(w, z)| Mode {
                frequency_hz: w / TAU,
                damping_ratio: z,
            })
            .collect(),
        points: (0..2)
            .map(|i| ModalPoint {
                name: format!("p{}", i + 1),
                shape: basis.shapes.row(i).iter().copied().collect(),
            })
            .collect(),
    };
    let f_exact: Vec<f64> = s.modes.iter().map(|m| m.frequency_hz).collect();
    println!("exact: f = {f_exact:?} Hz, ζ = {zetas:?}");
    // ≈ 0.6e-3 f per second at every frequency (D: 15–600 Hz in 300 s is 0.012 f/s)
    let sweep = Sweep {
        start_hz: 0.6 * f_exact[0],
        end_hz: 1.4 * f_exact[1],
        duration_s: 3000.0,
        law: SweepLaw::Logarithmic,
    };
    let spec = SweepSpec {
        sweep,
        force_amplitude_n: 1.0,
        excitation_point: "p1".into(),
        output_point: "p2".into(),
        time_step_s: 1.0 / (sweep.end_hz * 40.0),
        sample_every: 1,
    };
    let h = forced::run_sweep(&s, &[], &spec).unwrap();
    let frf = forced::sweep_frf(&h, &sweep, 8);
    let f: Vec<f64> = frf.iter().map(|p| p.frequency_hz).collect();
    let hc: Vec<_> = frf.iter().map(|p| p.h_m_per_n).collect();
    let fit = modal_fit::rfp_fit(&f, &hc, 2).unwrap();
    println!(
        "RFP ({} points, rel. error {:.2e}): {:?}",
        f.len(),
        fit.relative_error,
        fit.modes
    );
    assert_eq!(fit.modes.len(), 2);
    for k in 0..2 {
        let e_f = fit.modes[k].frequency_hz / f_exact[k] - 1.0;
        let e_z = fit.modes[k].damping_ratio / zetas[k] - 1.0;
        let a_exact = s.point("p1").unwrap()[k] * s.point("p2").unwrap()[k];
        let e_a = fit.modes[k].modal_constant_re / a_exact - 1.0;
        println!(
            "mode {}: RFP f error {:+.4} %, ζ error {:+.3} %, modal constant error {:+.3} %",
            k + 1,
            100.0 * e_f,
            100.0 * e_z,
            100.0 * e_a
        );
        assert!(e_f.abs() < 0.01 && e_z.abs() < 0.01, "mode {}", k + 1);
        assert!(e_a.abs() < 0.02, "mode {}", k + 1);
    }
    let mag: Vec<f64> = hc.iter().map(|c| c.norm()).collect();
    let hp = modal_fit::half_power_per_mode(&f, &mag, &f_exact);
    for k in 0..2 {
        let r = hp[k].expect("half-power crossing");
        let e_z = r.damping_ratio / zetas[k] - 1.0;
        println!(
            "mode {}: half-power ζ = {:.5} ({:+.3} %), f_r = {:.4} Hz",
            k + 1,
            r.damping_ratio,
            100.0 * e_z,
            r.resonance_frequency_hz
        );
        assert!(e_z.abs() < 0.01, "mode {}", k + 1);
    }
}

/// Frequency-domain approach of D Sect. 3.3.2: the same 2-dof sweep split into 5 overlapping
/// segments (each from rest, start-up transients cut off), FRFs combined by peak hold; the kept
/// ranges cover the band without gaps and the RFP fit of the combined FRF returns f and ζ of
/// both modes within 1 %.
#[test]
fn segmented_sweep_with_peak_hold_within_one_percent() {
    let (m1, m2, k1, k2) = (1.0, 0.5, 6000.0, 4000.0);
    let k = DMatrix::from_row_slice(2, 2, &[k1 + k2, -k2, -k2, k2]);
    let m = DMatrix::from_row_slice(2, 2, &[m1, 0.0, 0.0, m2]);
    let basis = modal::lowest_modes(&k, &m, 2, 0.0).unwrap();
    let zetas = [0.02, 0.01];
    let s = ModalStructure {
        modes: basis
            .omega_rad_s
            .iter()
            .zip(zetas)
            .map(|(w, z)| Mode {
                frequency_hz: w / TAU,
                damping_ratio: z,
            })
            .collect(),
        points: (0..2)
            .map(|i| ModalPoint {
                name: format!("p{}", i + 1),
                shape: basis.shapes.row(i).iter().copied().collect(),
            })
            .collect(),
    };
    let f_exact: Vec<f64> = s.modes.iter().map(|m| m.frequency_hz).collect();
    let sweep = Sweep {
        start_hz: 0.6 * f_exact[0],
        end_hz: 1.4 * f_exact[1],
        duration_s: 3000.0,
        law: SweepLaw::Logarithmic,
    };
    let plan = forced::segment_sweep(&sweep, 5, 0.3);
    for w in plan.windows(2) {
        assert!(w[1].keep_from_hz < w[0].keep_to_hz, "gap between segments");
    }
    assert!((plan[0].keep_from_hz - sweep.start_hz).abs() < 1e-9);
    assert!((plan[4].keep_to_hz - sweep.end_hz).abs() < 1e-9);
    let mut frfs = Vec::new();
    for sg in &plan {
        let spec = SweepSpec {
            sweep: sg.sweep,
            force_amplitude_n: 1.0,
            excitation_point: "p1".into(),
            output_point: "p2".into(),
            time_step_s: 1.0 / (sweep.end_hz * 40.0),
            sample_every: 1,
        };
        let h = forced::run_sweep(&s, &[], &spec).unwrap();
        frfs.push(
            forced::sweep_frf(&h, &sg.sweep, 8)
                .into_iter()
                .filter(|p| p.frequency_hz >= sg.keep_from_hz && p.frequency_hz <= sg.keep_to_hz)
                .collect::<Vec<_>>(),
        );
    }
    let frf = forced::peak_hold(&frfs);
    let f: Vec<f64> = frf.iter().map(|p| p.frequency_hz).collect();
    let hc: Vec<_> = frf.iter().map(|p| p.h_m_per_n).collect();
    let fit = modal_fit::rfp_fit(&f, &hc, 2).unwrap();
    println!(
        "segments {:?}, {} peak-held points, RFP {:?}",
        plan.iter()
            .map(|p| (p.sweep.start_hz, p.sweep.end_hz))
            .collect::<Vec<_>>(),
        f.len(),
        fit.modes
    );
    assert_eq!(fit.modes.len(), 2);
    for kk in 0..2 {
        assert!((fit.modes[kk].frequency_hz / f_exact[kk] - 1.0).abs() < 0.01);
        assert!((fit.modes[kk].damping_ratio / zetas[kk] - 1.0).abs() < 0.01);
    }
}
