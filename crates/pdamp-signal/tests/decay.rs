//! Free-decay tests against the exact response of a linear oscillator.

mod common;

use std::f64::consts::TAU;

use common::{SplitMix64, rel_err};
use pdamp_signal::SignalError;
use pdamp_signal::decay::{
    PeakOptions, amplitude_dependent_damping, damping_ratio_from_log_decrement, find_peaks,
    fit_exponential_decay, log_decrement, log_decrement_from_damping_ratio,
};

const F_N_HZ: f64 = 10.0;

/// Exact free response `X e^{−ζωt} cos(ω_d t)` sampled with
/// `samples_per_period` samples per undamped period over `n_periods`.
fn free_decay(zeta: f64, samples_per_period: f64, n_periods: usize) -> (Vec<f64>, f64) {
    let w = TAU * F_N_HZ;
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let dt = 1.0 / (F_N_HZ * samples_per_period);
    let n = (samples_per_period * n_periods as f64) as usize;
    let x = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            2.0 * (-zeta * w * t).exp() * (wd * t).cos()
        })
        .collect();
    (x, dt)
}

#[test]
fn parabolic_interpolation_is_exact_for_a_parabola() {
    let dt = 0.01;
    let (tp, h) = (0.5137, 3.25);
    let x: Vec<f64> = (0..101)
        .map(|k| h - 40.0 * (k as f64 * dt - tp).powi(2))
        .collect();
    let peaks = find_peaks(&x, 0.0, dt, &PeakOptions::default()).unwrap();
    assert_eq!(peaks.len(), 1);
    assert_eq!(peaks[0].index, 51);
    assert!((peaks[0].time_s - tp).abs() < 1e-12, "{}", peaks[0].time_s);
    assert!((peaks[0].value - h).abs() < 1e-12, "{}", peaks[0].value);
}

#[test]
fn linear_oscillator_damping_and_frequency_recovered() {
    let fd = |z: f64| F_N_HZ * (1.0 - z * z).sqrt();
    for &(zeta, n_periods, spp) in &[
        (0.001, 100, 123.4567),
        (0.01, 60, 123.4567),
        (0.05, 20, 123.4567),
        (0.2, 8, 123.4567),
        (0.001, 100, 20.3),
        (0.01, 60, 20.3),
        (0.05, 20, 20.3),
        (0.2, 8, 20.3),
    ] {
        let (x, dt) = free_decay(zeta, spp, n_periods);
        let peaks = find_peaks(&x, 0.0, dt, &PeakOptions::default()).unwrap();
        assert_eq!(peaks.len(), n_periods - 1, "ζ = {zeta}");

        let ld = log_decrement(&peaks).unwrap();
        let e_ld = rel_err(ld.damping_ratio, zeta);
        let e_ld_fn = rel_err(ld.undamped_frequency_hz, F_N_HZ);
        let e_ld_fd = rel_err(ld.damped_frequency_hz, fd(zeta));
        assert!(rel_err(ld.log_decrement, log_decrement_from_damping_ratio(zeta)) < 1e-3);

        let fit = fit_exponential_decay(&peaks).unwrap();
        let e_fit = rel_err(fit.damping_ratio, zeta);
        let e_fit_fn = rel_err(fit.undamped_frequency_hz, F_N_HZ);
        assert!(rel_err(fit.decay_rate_1_per_s, zeta * TAU * F_N_HZ) < 1e-3);
        assert!(fit.r_squared > 0.999_999);

        let pairs = amplitude_dependent_damping(&peaks, 1).unwrap();
        let e_pair = pairs
            .iter()
            .map(|p| rel_err(p.damping_ratio, zeta))
            .fold(0.0, f64::max);
        eprintln!(
            "ζ = {zeta}, {spp} samples/period: log-dec ζ err {e_ld:.2e}, f_n err {e_ld_fn:.2e}, f_d err {e_ld_fd:.2e}; \
             fit ζ err {e_fit:.2e}, f_n err {e_fit_fn:.2e}; per-pair ζ max err {e_pair:.2e}"
        );
        for e in [e_ld, e_ld_fn, e_ld_fd, e_fit, e_fit_fn] {
            assert!(e < 1e-3, "ζ = {zeta}: relative error {e:e}");
        }
        // Per pair the decrement of a single period is tiny for small ζ, so
        // the per-pair relative error grows as the sampling gets coarse.
        let tol_pair = if spp > 100.0 { 1e-4 } else { 5e-2 };
        assert!(e_pair < tol_pair, "ζ = {zeta}: per-pair error {e_pair:e}");
    }
}

#[test]
fn noisy_decay_is_robust() {
    let zeta = 0.02;
    let (mut x, dt) = free_decay(zeta, 100.0, 30);
    let mut rng = SplitMix64(0x5EED);
    let noise = 0.01; // ±1 % of the initial amplitude 2.0 (uniform)
    for v in &mut x {
        *v += noise * 2.0 * (2.0 * rng.uniform() - 1.0);
    }
    // Without a separation, noise creates spurious maxima.
    let raw = find_peaks(&x, 0.0, dt, &PeakOptions::default()).unwrap();
    let opts = PeakOptions {
        min_separation_s: 0.7 / F_N_HZ,
        min_value: 10.0 * noise * 2.0,
        fit_half_width_samples: 10,
    };
    let peaks = find_peaks(&x, 0.0, dt, &opts).unwrap();
    assert!(raw.len() > peaks.len());
    // One peak per period above the threshold, evenly spaced.
    for w in peaks.windows(2) {
        assert!(rel_err(w[1].time_s - w[0].time_s, 1.0 / F_N_HZ) < 0.05);
    }
    let fit = fit_exponential_decay(&peaks).unwrap();
    let ld = log_decrement(&peaks).unwrap();
    let e_fit = rel_err(fit.damping_ratio, zeta);
    let e_ld = rel_err(ld.damping_ratio, zeta);
    let e_f = rel_err(fit.undamped_frequency_hz, F_N_HZ);
    eprintln!(
        "noisy (±1 %): {} raw maxima, {} peaks; fit ζ err {e_fit:.2e}, log-dec ζ err {e_ld:.2e}, f_n err {e_f:.2e}",
        raw.len(),
        peaks.len()
    );
    assert!(e_fit < 0.03, "fit ζ error {e_fit}");
    assert!(e_ld < 0.05, "log-dec ζ error {e_ld}");
    assert!(e_f < 2e-3, "frequency error {e_f}");
}

#[test]
fn amplitude_dependence_of_dry_friction_decay() {
    // Coulomb friction: every half cycle the amplitude drops by 2a, a = F_c/k;
    // the exact piecewise solution is built half cycle by half cycle.
    let (a, x0): (f64, f64) = (0.01, 1.0);
    let w = TAU * F_N_HZ;
    let dt = 1.0 / (F_N_HZ * 401.3);
    let half = 0.5 / F_N_HZ;
    let mut x = Vec::new();
    let mut amp = x0; // signed extreme at the start of the half cycle
    let mut t_start = 0.0;
    let mut k = 0usize;
    while amp.abs() > 3.0 * a {
        let s = amp.signum();
        while (k as f64) * dt < t_start + half {
            let tau = k as f64 * dt - t_start;
            x.push((amp - s * a) * (w * tau).cos() + s * a);
            k += 1;
        }
        t_start += half;
        amp = -amp + 2.0 * a * s;
    }
    let peaks = find_peaks(&x, 0.0, dt, &PeakOptions::default()).unwrap();
    let pairs = amplitude_dependent_damping(&peaks, 1).unwrap();
    assert!(pairs.len() >= 15);
    let mut max_err: f64 = 0.0;
    let mut max_err_f: f64 = 0.0;
    for p in &pairs {
        // Successive positive maxima differ by 4a: x_{i+1} = x_i − 4a.
        let upper = p.amplitude; // geometric mean of x_i and x_i − 4a
        let xi = 2.0 * a + (upper * upper + 4.0 * a * a).sqrt();
        let want = damping_ratio_from_log_decrement((xi / (xi - 4.0 * a)).ln());
        max_err = max_err.max(rel_err(p.damping_ratio, want));
        max_err_f = max_err_f.max(rel_err(p.damped_frequency_hz, F_N_HZ));
    }
    // The peaks sit on a jump of the curvature (the friction force reverses
    // there), so the parabolic refinement is not exact here.
    eprintln!(
        "dry friction: {} pairs, max rel err of ζ(A) {max_err:.2e}, of f {max_err_f:.2e}",
        pairs.len()
    );
    assert!(max_err < 1e-3);
    assert!(max_err_f < 1e-3);
    // ζ grows as the amplitude decays.
    assert!(
        pairs
            .windows(2)
            .all(|w| w[1].damping_ratio > w[0].damping_ratio)
    );
    // A longer span averages: still monotone and between the extremes.
    let pairs3 = amplitude_dependent_damping(&peaks, 3).unwrap();
    assert_eq!(pairs3.len(), pairs.len() - 2);
}

#[test]
fn invalid_inputs_are_errors() {
    let (x, dt) = free_decay(0.01, 50.0, 3);
    let peaks = find_peaks(&x, 0.0, dt, &PeakOptions::default()).unwrap();
    assert!(matches!(
        log_decrement(&peaks[..1]),
        Err(SignalError::TooFew { .. })
    ));
    assert!(matches!(
        fit_exponential_decay(&peaks[..2]),
        Err(SignalError::TooFew { .. })
    ));
    assert!(amplitude_dependent_damping(&peaks, 0).is_err());
    let mut bad = peaks.clone();
    bad[1].value = -1.0;
    assert!(log_decrement(&bad).is_err());
    assert!(find_peaks(&[0.0, f64::NAN, 0.0], 0.0, dt, &PeakOptions::default()).is_err());
    let opts = PeakOptions {
        min_separation_s: -1.0,
        ..PeakOptions::default()
    };
    assert!(find_peaks(&x, 0.0, dt, &opts).is_err());
    let opts = PeakOptions {
        fit_half_width_samples: 0,
        ..PeakOptions::default()
    };
    assert!(find_peaks(&x, 0.0, dt, &opts).is_err());
}
