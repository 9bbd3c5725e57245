//! Tests of the single-bin DFT and the one-sided spectrum.

mod common;

use std::f64::consts::TAU;

use common::rel_err_c;
use pdamp_signal::harmonic::{CycleRule, harmonic_amplitude_with_rule, whole_cycle_window};
use pdamp_signal::{Complex64, SignalError, harmonic_amplitude, spectrum};

/// Samples of `g(t)` at `t0 + k·dt`.
fn sample(n: usize, t0_s: f64, dt_s: f64, g: impl Fn(f64) -> f64) -> Vec<f64> {
    (0..n).map(|k| g(t0_s + k as f64 * dt_s)).collect()
}

fn assert_close(got: Complex64, want: Complex64, tol: f64, what: &str) {
    let err = (got - want).norm();
    eprintln!("{what}: |err| = {err:.3e}");
    assert!(
        err <= tol,
        "{what}: got {got}, want {want}, |err| = {err:e}"
    );
}

#[test]
fn pure_cosine_amplitude_and_phase_exact() {
    let (f, dt, t0) = (5.0, 1e-3, 0.123);
    for &(a, phi) in &[(2.5, 0.7), (1.0, -2.9), (0.01, 3.0)] {
        let x = sample(1000, t0, dt, |t| a * (TAU * f * t + phi).cos());
        let h = harmonic_amplitude(&x, t0, dt, f).unwrap();
        assert_close(
            h.amplitude,
            Complex64::from_polar(a, phi),
            1e-12 * a.max(1.0),
            "cosine",
        );
        assert!((h.magnitude() - a).abs() < 1e-12);
        assert!((h.phase_rad() - phi).abs() < 1e-11);
        assert_eq!(
            (h.window.n_cycles, h.window.n_samples, h.window.first_sample),
            (5, 1000, 0)
        );
    }
}

#[test]
fn pure_sine_is_minus_i_times_amplitude() {
    let (f, dt, t0) = (2.0, 1e-3, 0.0);
    let x = sample(2000, t0, dt, |t| 3.0 * (TAU * f * t).sin());
    let h = harmonic_amplitude(&x, t0, dt, f).unwrap();
    assert_close(h.amplitude, Complex64::new(0.0, -3.0), 1e-12, "sine");
    // Container velocity of [D Eq. 3.9]: V cos(Ωt) → V* = V (real).
    let v = sample(2000, t0, dt, |t| 0.4 * (TAU * f * t).cos());
    let hv = harmonic_amplitude(&v, t0, dt, f).unwrap();
    assert_close(hv.amplitude, Complex64::new(0.4, 0.0), 1e-12, "velocity");
}

#[test]
fn other_harmonics_do_not_leak_over_whole_cycles() {
    let (f, dt, t0) = (4.0, 1.0 / 1000.0, -0.37);
    let comps = [(1, 1.3, 0.2), (2, 0.4, -1.5), (3, 0.7, -1.0), (7, 0.1, 2.0)];
    let x = sample(3000, t0, dt, |t| {
        comps
            .iter()
            .map(|&(m, a, p)| a * (TAU * m as f64 * f * t + p).cos())
            .sum()
    });
    for &(m, a, p) in &comps {
        let h = harmonic_amplitude(&x, t0, dt, m as f64 * f).unwrap();
        assert_close(h.amplitude, Complex64::from_polar(a, p), 1e-12, "harmonic");
    }
    // A frequency that is not present (5th harmonic) gives zero.
    let h5 = harmonic_amplitude(&x, t0, dt, 5.0 * f).unwrap();
    assert_close(
        h5.amplitude,
        Complex64::new(0.0, 0.0),
        1e-12,
        "absent harmonic",
    );
}

#[test]
fn dc_offset_is_rejected() {
    let (f, dt, t0) = (10.0, 1e-3, 0.05);
    let base = sample(500, t0, dt, |t| 0.8 * (TAU * f * t - 0.3).cos());
    let shifted: Vec<f64> = base.iter().map(|x| x + 123.0).collect();
    let a = harmonic_amplitude(&base, t0, dt, f).unwrap().amplitude;
    let b = harmonic_amplitude(&shifted, t0, dt, f).unwrap().amplitude;
    assert_close(b, Complex64::from_polar(0.8, -0.3), 1e-12, "with DC");
    assert_close(a, b, 1e-12, "DC vs no DC");
    let dc_only = vec![7.0; 500];
    let z = harmonic_amplitude(&dc_only, t0, dt, f).unwrap().amplitude;
    assert_close(z, Complex64::new(0.0, 0.0), 1e-12, "pure DC");
}

#[test]
fn trimming_keeps_last_whole_cycles() {
    // 200 samples per cycle, 1234 samples → last 6 cycles (1200 samples).
    let w = whole_cycle_window(1234, 1e-3, 5.0, CycleRule::Exact).unwrap();
    assert_eq!((w.n_cycles, w.n_samples, w.first_sample), (6, 1200, 34));
    // 333.33 samples per cycle: 4 cycles = 1333.3 samples is no integer, 3 cycles = 1000.
    let w = whole_cycle_window(1500, 1e-3, 3.0, CycleRule::Exact).unwrap();
    assert_eq!((w.n_cycles, w.n_samples, w.first_sample), (3, 1000, 500));
    // The trimmed result is still exact, including a transient in the dropped part.
    let (f, dt, t0) = (3.0, 1e-3, 0.2);
    let x = sample(1500, t0, dt, |t| {
        let transient = if t < t0 + 0.5 {
            5.0 * (-(t - t0) * 3.0).exp()
        } else {
            0.0
        };
        transient + 1.7 * (TAU * f * t + 1.1).cos() + 0.3 * (TAU * 2.0 * f * t).cos()
    });
    let h = harmonic_amplitude(&x, t0, dt, f).unwrap();
    assert_close(
        h.amplitude,
        Complex64::from_polar(1.7, 1.1),
        1e-12,
        "trimmed",
    );
}

#[test]
fn nearest_rule_for_incommensurate_sampling() {
    // 1/(f·dt) = 104.72… samples per cycle: no exact window of ≤ 3 cycles.
    let f = 1.0 / (1e-3 * 100.0 * std::f64::consts::PI / 3.0);
    let x = sample(350, 0.0, 1e-3, |t| (TAU * f * t).cos());
    assert!(matches!(
        harmonic_amplitude(&x, 0.0, 1e-3, f),
        Err(SignalError::NoWholeCycleWindow { .. })
    ));
    // With many cycles the nearest rule has an O(1/N) error.
    let n = 100_000;
    let x = sample(n, 0.0, 1e-3, |t| 2.0 * (TAU * f * t + 0.5).cos() + 1.0);
    let h = harmonic_amplitude_with_rule(&x, 0.0, 1e-3, f, CycleRule::Nearest).unwrap();
    let err = rel_err_c(h.amplitude, Complex64::from_polar(2.0, 0.5));
    eprintln!(
        "nearest rule, N = {}: rel err = {err:.3e}",
        h.window.n_samples
    );
    assert!(err < 10.0 / h.window.n_samples as f64);
}

#[test]
fn invalid_inputs_are_errors() {
    let x = vec![0.0; 100];
    assert!(matches!(
        harmonic_amplitude(&x, 0.0, 1e-3, 5.0),
        Err(SignalError::LessThanOneCycle { .. })
    ));
    let mut y = vec![0.0; 1000];
    y[17] = f64::NAN;
    assert_eq!(
        harmonic_amplitude(&y, 0.0, 1e-3, 5.0),
        Err(SignalError::NonFinite {
            name: "samples",
            index: 17
        })
    );
    let z = vec![0.0; 1000];
    assert!(harmonic_amplitude(&z, 0.0, 1e-3, 500.0).is_err(), "Nyquist");
    assert!(harmonic_amplitude(&z, 0.0, 0.0, 5.0).is_err(), "dt = 0");
    assert!(harmonic_amplitude(&z, 0.0, 1e-3, -5.0).is_err(), "f < 0");
    assert!(
        harmonic_amplitude(&z, f64::INFINITY, 1e-3, 5.0).is_err(),
        "t0 = inf"
    );
    assert!(spectrum(&[1.0], 0.0, 1e-3).is_err());
}

#[test]
fn spectrum_matches_convention_and_single_bin() {
    // N = 1000, dt = 1 ms → bins every 1 Hz.
    let (dt, t0) = (1e-3, 0.0371);
    let x = sample(1000, t0, dt, |t| {
        0.25 + 1.5 * (TAU * 12.0 * t + 0.4).cos() + 0.2 * (TAU * 37.0 * t - 2.0).cos()
    });
    let s = spectrum(&x, t0, dt).unwrap();
    assert_eq!(s.frequencies_hz.len(), 501);
    assert!((s.frequency_resolution_hz - 1.0).abs() < 1e-12);
    assert_close(
        s.amplitudes[0],
        Complex64::new(0.25, 0.0),
        1e-12,
        "DC bin = mean",
    );
    assert_eq!(s.nearest_bin(12.2), Some(12));
    assert_eq!(s.nearest_bin(600.0), None);
    assert_close(
        s.amplitude_at(12.0).unwrap(),
        Complex64::from_polar(1.5, 0.4),
        1e-12,
        "12 Hz bin",
    );
    assert_close(
        s.amplitude_at(37.0).unwrap(),
        Complex64::from_polar(0.2, -2.0),
        1e-12,
        "37 Hz bin",
    );
    let mags = s.magnitudes();
    let others = mags
        .iter()
        .enumerate()
        .filter(|&(j, _)| ![0, 12, 37].contains(&j))
        .map(|(_, m)| *m)
        .fold(0.0, f64::max);
    assert!(others < 1e-12, "leakage {others:e}");
    for f in [12.0, 37.0] {
        let h = harmonic_amplitude(&x, t0, dt, f).unwrap().amplitude;
        assert_close(
            s.amplitude_at(f).unwrap(),
            h,
            1e-12,
            "spectrum vs single bin",
        );
    }
    // Odd length works too (no Nyquist bin).
    let s = spectrum(&x[..999], t0, dt).unwrap();
    assert_eq!(s.amplitudes.len(), 500);
}
