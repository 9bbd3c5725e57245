//! Must-show 2: a single-degree-of-freedom oscillator with a known viscous damper
//! (f = 10 Hz, ζ = 0.02). The log-decrement tool [D Eq. 3.40, 3.41] and the FRF tools (sweep FRF
//! [D Eq. 3.42] + half-power bandwidth, and a rational fraction polynomial fit) return ζ within
//! 1 %; Eq. 3.47 from the resonance peak of a slow linear sweep returns it within 2 %.

use pdamp_structure::forced::{self, Sweep, SweepLaw, SweepSpec};
use pdamp_structure::free::{self, FreeVibrationSpec, UpdateRule};
use pdamp_structure::modal::ModalStructure;
use std::f64::consts::TAU;

const F0: f64 = 10.0;
const ZETA: f64 = 0.02;
const MASS: f64 = 2.0;

fn sdof() -> ModalStructure {
    let k = MASS * (TAU * F0).powi(2);
    let d = 2.0 * ZETA * (k * MASS).sqrt();
    ModalStructure::single_mode(MASS, k, d)
}

#[test]
fn log_decrement_returns_set_damping_ratio() {
    let s = sdof();
    let spec = FreeVibrationSpec {
        duration_s: 3.0,
        time_step_s: 1.0 / (F0 * 400.0),
        mode: 0,
        initial_point: "damper".into(),
        initial_displacement_m: 0.01,
        initial_velocity_m_s: 0.0,
        output_point: "output".into(),
        update: UpdateRule::Never,
        sample_every: 1,
        scale_initial_by_bed_mass: false,
    };
    let h = free::run_free_vibration(&s, &[], &spec).unwrap();
    let peaks = free::decay_peaks(&h, 0.5 / F0).unwrap();
    let cyc = free::damping_per_cycle(&peaks);
    assert!(cyc.len() >= 25, "{}", cyc.len());
    let worst = cyc
        .iter()
        .map(|c| (c.damping_ratio - ZETA).abs() / ZETA)
        .fold(0.0, f64::max);
    let fd = F0 * (1.0 - ZETA * ZETA).sqrt();
    println!(
        "log decrement: {} cycles, worst relative error {:.3e}, f = {:.4} Hz (f_d = {fd:.4})",
        cyc.len(),
        worst,
        cyc[0].frequency_hz
    );
    assert!(worst < 0.01);
    assert!((cyc[0].frequency_hz - fd).abs() / fd < 1e-3);
}

#[test]
fn sweep_frf_half_power_rfp_and_eq_3_47() {
    let s = sdof();
    // 0.01 Hz/s through the resonance (half-power bandwidth 2ζf = 0.4 Hz)
    let sweep = Sweep {
        start_hz: 8.5,
        end_hz: 11.5,
        duration_s: 300.0,
        law: SweepLaw::Linear,
    };
    let spec = SweepSpec {
        sweep,
        force_amplitude_n: 1.0,
        excitation_point: "excitation".into(),
        output_point: "output".into(),
        time_step_s: 1.0 / (F0 * 100.0),
        sample_every: 1,
    };
    let h = forced::run_sweep(&s, &[], &spec).unwrap();
    let frf = forced::sweep_frf(&h, &sweep, 4);
    let f: Vec<f64> = frf.iter().map(|p| p.frequency_hz).collect();
    let mag: Vec<f64> = frf.iter().map(|p| p.h_m_per_n.norm()).collect();
    let hp = pdamp_signal::frf::half_power_damping(&f, &mag, None).unwrap();
    let e_hp = (hp.damping_ratio - ZETA) / ZETA;
    // exact receptance peak 1/(2ζk√(1−ζ²))
    let k = MASS * (TAU * F0).powi(2);
    let peak_exact = 1.0 / (2.0 * ZETA * k * (1.0 - ZETA * ZETA).sqrt());
    println!(
        "sweep FRF: {} points, peak |H| = {:.5e} (exact {:.5e}), half-power ζ = {:.5} ({:+.3} %)",
        frf.len(),
        hp.peak_magnitude,
        peak_exact,
        hp.damping_ratio,
        100.0 * e_hp
    );
    assert!(e_hp.abs() < 0.01);
    let band: Vec<_> = frf
        .iter()
        .copied()
        .filter(|p| p.h_m_per_n.norm() > 0.5 * hp.peak_magnitude)
        .collect();
    let fit = forced::rfp_single_mode(&band).unwrap();
    let e_rfp = (fit.damping_ratio - ZETA) / ZETA;
    println!(
        "RFP: f = {:.5} Hz, ζ = {:.5} ({:+.3} %)",
        fit.frequency_hz,
        fit.damping_ratio,
        100.0 * e_rfp
    );
    assert!(e_rfp.abs() < 0.01);
    assert!((fit.frequency_hz - F0).abs() / F0 < 1e-3);
    let phi = s.point("damper").unwrap()[0];
    let pk = forced::peak_damping(&h, &sweep, 1.0, phi, phi, TAU * F0, Some(1.0)).unwrap();
    let e_pk = (pk.damping_ratio - ZETA) / ZETA;
    println!(
        "Eq. 3.47 at 0.01 Hz/s (= {:.2e} ω per s): ζ = {:.5} ({:+.3} %), f_R = {:.4} Hz",
        0.01 / F0,
        pk.damping_ratio,
        100.0 * e_pk,
        pk.resonance_frequency_hz
    );
    assert!(e_pk.abs() < 0.02);
}
