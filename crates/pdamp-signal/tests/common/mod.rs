//! Shared helpers for the integration tests: deterministic pseudo-random
//! numbers and a 1-DOF oscillator integrator.

#![allow(dead_code)]

use num_complex::Complex64;

/// SplitMix64 pseudo-random generator (deterministic, seedable).
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// Next raw 64-bit value.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal via Box–Muller.
    pub fn gaussian(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Linear 1-DOF oscillator `m ẍ + c ẋ + k x = F`.
#[derive(Clone, Copy)]
pub struct Sdof {
    pub m_kg: f64,
    pub c_n_s_per_m: f64,
    pub k_n_per_m: f64,
}

impl Sdof {
    /// Oscillator with natural frequency `f_n` and damping ratio `ζ`.
    pub fn from_modal(m_kg: f64, natural_frequency_hz: f64, damping_ratio: f64) -> Self {
        let omega = std::f64::consts::TAU * natural_frequency_hz;
        Self {
            m_kg,
            c_n_s_per_m: 2.0 * damping_ratio * m_kg * omega,
            k_n_per_m: m_kg * omega * omega,
        }
    }

    /// Receptance `H(ω) = 1/(k − mω² + icω)` in m/N.
    pub fn receptance_m_per_n(&self, frequency_hz: f64) -> Complex64 {
        let w = std::f64::consts::TAU * frequency_hz;
        1.0 / Complex64::new(self.k_n_per_m - self.m_kg * w * w, self.c_n_s_per_m * w)
    }

    /// Displacement response (from rest) to the sampled force `force_n`,
    /// interpolated linearly between samples, integrated by classical RK4
    /// with step `dt_s` (the force at the half step is the mean of the two
    /// neighbouring samples).
    pub fn simulate_rk4(&self, force_n: &[f64], dt_s: f64) -> Vec<f64> {
        let (m, c, k) = (self.m_kg, self.c_n_s_per_m, self.k_n_per_m);
        let acc = |x: f64, v: f64, f: f64| (f - c * v - k * x) / m;
        let mut out = Vec::with_capacity(force_n.len());
        let (mut x, mut v) = (0.0, 0.0);
        out.push(x);
        for w in force_n.windows(2) {
            let (f0, f1) = (w[0], w[1]);
            let fh = 0.5 * (f0 + f1);
            let h = dt_s;
            let (k1x, k1v) = (v, acc(x, v, f0));
            let (k2x, k2v) = (
                v + 0.5 * h * k1v,
                acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v, fh),
            );
            let (k3x, k3v) = (
                v + 0.5 * h * k2v,
                acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v, fh),
            );
            let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v, f1));
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            out.push(x);
        }
        out
    }
}

/// Relative error `|a − b|/|b|`.
pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Relative complex error `|a − b|/|b|`.
pub fn rel_err_c(a: Complex64, b: Complex64) -> f64 {
    (a - b).norm() / b.norm()
}
