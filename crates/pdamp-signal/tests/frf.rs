//! FRF tests against the receptance of a 1-DOF oscillator,
//! `H(ω) = 1/(k − mω² + icω)`.

mod common;

use std::f64::consts::TAU;

use common::{Sdof, SplitMix64, rel_err, rel_err_c};
use pdamp_signal::frf::{
    h1_estimate, half_power_damping, resonance_peak, stepped_sine_frf, stepped_sine_point,
};
use pdamp_signal::{Complex64, SignalError, harmonic_amplitude};

const F_N_HZ: f64 = 10.0;

#[test]
fn stepped_sine_from_steady_state_time_series_is_exact() {
    let sys = Sdof::from_modal(2.0, F_N_HZ, 0.02);
    let dt = 1e-3;
    let freqs: Vec<f64> = [2.0, 5.0, 8.0, 9.5, 10.0, 10.5, 12.5, 20.0, 40.0].to_vec();
    let mut f_amps = Vec::new();
    let mut x_amps = Vec::new();
    let mut max_err: f64 = 0.0;
    for (i, &f) in freqs.iter().enumerate() {
        let f_hat = Complex64::from_polar(5.0 + i as f64, 0.3 * i as f64);
        let x_hat = sys.receptance_m_per_n(f) * f_hat;
        let t0 = 0.25;
        let n = 2000; // 2 s: whole cycles for all frequencies above
        let force: Vec<f64> = (0..n)
            .map(|k| (f_hat * Complex64::from_polar(1.0, TAU * f * (t0 + k as f64 * dt))).re)
            .collect();
        let resp: Vec<f64> = (0..n)
            .map(|k| (x_hat * Complex64::from_polar(1.0, TAU * f * (t0 + k as f64 * dt))).re)
            .collect();
        let h = stepped_sine_point(&force, &resp, t0, dt, f).unwrap();
        max_err = max_err.max(rel_err_c(h, sys.receptance_m_per_n(f)));
        f_amps.push(harmonic_amplitude(&force, t0, dt, f).unwrap().amplitude);
        x_amps.push(harmonic_amplitude(&resp, t0, dt, f).unwrap().amplitude);
    }
    let frf = stepped_sine_frf(&freqs, &f_amps, &x_amps).unwrap();
    for (f, h) in frf.frequencies_hz.iter().zip(&frf.h_per_n) {
        max_err = max_err.max(rel_err_c(*h, sys.receptance_m_per_n(*f)));
    }
    eprintln!("stepped sine: max rel err {max_err:.2e}");
    assert!(max_err < 1e-12);
    // Phase convention: −90° at resonance (displacement lags force).
    let h_res = frf.h_per_n[4];
    assert!((h_res.arg() + std::f64::consts::FRAC_PI_2).abs() < 1e-9);
}

#[test]
fn h1_from_random_excitation_matches_receptance() {
    let zeta = 0.02;
    let sys = Sdof::from_modal(1.0, F_N_HZ, zeta);
    let fs = 1000.0;
    let dt = 1.0 / fs;
    let seg = 65_536; // Δf = 0.015 Hz, half-power bandwidth 0.4 Hz
    let n_seg = 32;
    let skip = 5_000; // start-up transient (4 s ≫ 1/(ζω) = 0.8 s)
    let n = skip + seg / 2 * (n_seg + 1);
    let mut rng = SplitMix64(42);
    let force: Vec<f64> = (0..n).map(|_| 10.0 * rng.gaussian()).collect();
    let x = sys.simulate_rk4(&force, dt);
    let est = h1_estimate(&force[skip..], &x[skip..], dt, seg).unwrap();
    assert_eq!(est.n_segments, n_seg);
    let mut max_err: f64 = 0.0;
    let mut min_coh: f64 = 1.0;
    for (j, &f) in est.frf.frequencies_hz.iter().enumerate() {
        if (f - F_N_HZ).abs() <= 5.0 * zeta * F_N_HZ {
            max_err = max_err.max(rel_err_c(est.frf.h_per_n[j], sys.receptance_m_per_n(f)));
            min_coh = min_coh.min(est.coherence[j]);
        }
    }
    let mut max_err_wide: f64 = 0.0;
    for (j, &f) in est.frf.frequencies_hz.iter().enumerate() {
        if (2.0..=50.0).contains(&f) {
            max_err_wide =
                max_err_wide.max(rel_err_c(est.frf.h_per_n[j], sys.receptance_m_per_n(f)));
        }
    }
    let hp = half_power_damping(
        &est.frf.frequencies_hz,
        &est.frf.magnitudes(),
        Some((5.0, 20.0)),
    )
    .unwrap();
    let e_zeta = rel_err(hp.damping_ratio, zeta);
    let e_fr = rel_err(hp.resonance_frequency_hz, F_N_HZ);
    eprintln!(
        "H1: max rel err {max_err:.2e} within ±5ζ f_n, {max_err_wide:.2e} on 2–50 Hz, \
         min coherence {min_coh:.4}; half-power on H1: ζ err {e_zeta:.2e}, f_r err {e_fr:.2e}"
    );
    assert!(max_err < 0.03, "H1 error near resonance {max_err}");
    assert!(max_err_wide < 0.03, "H1 error 2–50 Hz {max_err_wide}");
    assert!(min_coh > 0.95);
    assert!(e_zeta < 0.02);
}

/// Receptance magnitudes of `sys` on a uniform grid over `f_n·[0.5, 1.5]`.
fn receptance_grid(sys: &Sdof, df_hz: f64) -> (Vec<f64>, Vec<f64>) {
    let n = (F_N_HZ / df_hz).round() as usize;
    let freqs: Vec<f64> = (0..=n).map(|j| 0.5 * F_N_HZ + j as f64 * df_hz).collect();
    let mags = freqs
        .iter()
        .map(|&f| sys.receptance_m_per_n(f).norm())
        .collect();
    (freqs, mags)
}

#[test]
fn half_power_damping_on_analytic_receptance() {
    for zeta in [0.01, 0.02, 0.03, 0.05] {
        let sys = Sdof::from_modal(1.5, F_N_HZ, zeta);
        // 40 grid points per half-power bandwidth 2ζ f_n.
        let (freqs, mags) = receptance_grid(&sys, 2.0 * zeta * F_N_HZ / 40.0);
        let hp = half_power_damping(&freqs, &mags, None).unwrap();
        let e = rel_err(hp.damping_ratio, zeta);
        let f_peak = F_N_HZ * (1.0 - 2.0 * zeta * zeta).sqrt();
        let e_f = rel_err(hp.resonance_frequency_hz, f_peak);
        eprintln!(
            "half power ζ = {zeta}: ζ err {e:.2e}, f_r err {e_f:.2e} (vs peak f_n√(1−2ζ²)), f1 = {:.5}, f2 = {:.5}",
            hp.lower_frequency_hz, hp.upper_frequency_hz
        );
        assert!(e < 0.02, "ζ = {zeta}: relative error {e}");
        assert!(e_f < zeta / 20.0);
        assert!(hp.lower_frequency_hz < hp.resonance_frequency_hz);
        assert!(hp.upper_frequency_hz > hp.resonance_frequency_hz);
    }
}

#[test]
fn peak_picking_and_band_selection() {
    // Two well-separated modes; the band picks the second.
    let a = Sdof::from_modal(1.0, 10.0, 0.02);
    let b = Sdof::from_modal(0.5, 30.0, 0.01);
    let freqs: Vec<f64> = (0..4000).map(|j| 1.0 + j as f64 * 0.01).collect();
    let mags: Vec<f64> = freqs
        .iter()
        .map(|&f| (a.receptance_m_per_n(f) + b.receptance_m_per_n(f)).norm())
        .collect();
    let p1 = resonance_peak(&freqs, &mags, None).unwrap();
    assert!((p1.frequency_hz - 10.0).abs() < 0.02);
    let p2 = resonance_peak(&freqs, &mags, Some((20.0, 40.0))).unwrap();
    assert!((p2.frequency_hz - 30.0).abs() < 0.02);
    let hp2 = half_power_damping(&freqs, &mags, Some((20.0, 40.0))).unwrap();
    eprintln!("second mode half-power ζ = {:.5} (0.01)", hp2.damping_ratio);
    assert!(rel_err(hp2.damping_ratio, 0.01) < 0.05);
}

#[test]
fn invalid_inputs_are_errors() {
    let sys = Sdof::from_modal(1.0, F_N_HZ, 0.05);
    let (freqs, mags) = receptance_grid(&sys, 0.01);
    // A band that cuts off the lower −3 dB point.
    let lo = freqs.iter().position(|&f| f >= 9.9).unwrap();
    assert!(matches!(
        half_power_damping(&freqs[lo..], &mags[lo..], None),
        Err(SignalError::HalfPowerCrossingNotFound { side: "lower", .. })
    ));
    assert!(resonance_peak(&freqs, &mags, Some((100.0, 200.0))).is_err());
    assert!(resonance_peak(&[1.0, 1.0, 2.0], &[1.0, 2.0, 1.0], None).is_err());
    assert!(resonance_peak(&[1.0, 2.0], &[1.0, 2.0, 1.0], None).is_err());
    let one = Complex64::new(1.0, 0.0);
    let zero = Complex64::new(0.0, 0.0);
    assert!(matches!(
        stepped_sine_frf(&[1.0], &[zero], &[one]),
        Err(SignalError::Degenerate { .. })
    ));
    assert!(stepped_sine_frf(&[1.0, 2.0], &[one], &[one]).is_err());
    assert!(h1_estimate(&[0.0; 100], &[0.0; 100], 1e-3, 128).is_err());
    assert!(h1_estimate(&[0.0; 100], &[0.0; 99], 1e-3, 32).is_err());
}
