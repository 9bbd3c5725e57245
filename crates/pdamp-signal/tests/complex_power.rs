//! Known-answer tests of the complex power method [D Eqs. 3.12–3.17].

mod common;

use std::f64::consts::{PI, TAU};

use common::rel_err;
use pdamp_signal::{
    Complex64, ComplexPowerResult, SignalError, complex_power, complex_power_from_time_series,
};

const F_HZ: f64 = 4.0;
const DT_S: f64 = 1.0 / 2000.0;
const N: usize = 2000; // 4 whole cycles
const X_M: f64 = 0.01;
const M_BED_KG: f64 = 0.8;
const M_CON_KG: f64 = 0.5;

/// Container kinematics of [D Eqs. 3.8–3.10], with an optional phase, and a
/// driving force `F(x, v, a, t)`; returns (force, velocity) samples.
fn shake(phase_rad: f64, force: impl Fn(f64, f64, f64, f64) -> f64) -> (Vec<f64>, Vec<f64>) {
    let w = TAU * F_HZ;
    let mut f = Vec::with_capacity(N);
    let mut v = Vec::with_capacity(N);
    for k in 0..N {
        let t = k as f64 * DT_S;
        let x = X_M * (w * t + phase_rad).sin();
        let vel = X_M * w * (w * t + phase_rad).cos();
        let a = -X_M * w * w * (w * t + phase_rad).sin();
        f.push(force(x, vel, a, t));
        v.push(vel);
    }
    (f, v)
}

/// Time-domain work done by the drive per cycle, `∮ F v dt` (rectangle rule
/// over whole cycles, exact for trigonometric polynomials).
fn work_per_cycle_j(f: &[f64], v: &[f64]) -> f64 {
    let n_cycles = (N as f64 * DT_S * F_HZ).round();
    f.iter().zip(v).map(|(f, v)| f * v).sum::<f64>() * DT_S / n_cycles
}

fn check(got: f64, want: f64, tol: f64, what: &str) {
    let err = (got - want).abs();
    eprintln!("{what}: got {got:.15e}, want {want:.15e}, |err| = {err:.2e}");
    assert!(err <= tol, "{what}: got {got}, want {want}, err {err:e}");
}

#[test]
fn rigid_mass_gives_no_dissipation_and_full_mass() {
    // Container plus a rigidly attached bed: F = (m_con + m_bed)·a exactly.
    let m = M_CON_KG + M_BED_KG;
    for phase in [0.0, 0.9] {
        let (f, v) = shake(phase, |_, _, a, _| m * a);
        let r =
            complex_power_from_time_series(&f, &v, 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG).unwrap();
        let w = TAU * F_HZ;
        check(
            r.dissipated_energy_per_cycle_j,
            0.0,
            1e-14,
            "rigid: E_cycle",
        );
        check(r.effective_loss_factor, 0.0, 1e-12, "rigid: eta_eff");
        check(r.loss_factor, 0.0, 1e-12, "rigid: eta");
        // Im P* = ½ m Ω |V|² (reactive, positive for a mass).
        check(
            r.complex_power_im_w,
            0.5 * m * w * (X_M * w).powi(2),
            1e-12,
            "rigid: Im P",
        );
        check(r.effective_moving_mass_re_kg, m, 1e-12, "rigid: Re M*");
        check(r.effective_moving_mass_im_kg, 0.0, 1e-12, "rigid: Im M*");
        check(
            r.effective_particle_mass_kg,
            M_BED_KG,
            1e-12,
            "rigid: m_bed_eff",
        );
        check(r.effective_mass_ratio, 1.0, 1e-12, "rigid: ratio");
    }
}

#[test]
fn viscous_damper_matches_analytic_energy() {
    // Massless viscous damper: F = c·v. With V = XΩ:
    //   Ẽ = π c Ω X², E_diss = ½ c Ω X², η̄ = c/(m_bed Ω), η = +∞,
    //   M* = −i c/Ω, m̄_bed = |M*| = c/Ω (m_con = 0).
    let c = 3.7;
    let w = TAU * F_HZ;
    let (f, v) = shake(0.3, |_, vel, _, _| c * vel);
    let r = complex_power_from_time_series(&f, &v, 0.0, DT_S, F_HZ, M_BED_KG, 0.0).unwrap();
    let e_cycle = PI * c * w * X_M * X_M;
    check(
        rel_err(r.dissipated_energy_per_cycle_j, e_cycle),
        0.0,
        1e-12,
        "viscous: E_cycle rel",
    );
    check(
        rel_err(r.dissipated_energy_per_radian_j, e_cycle / TAU),
        0.0,
        1e-12,
        "viscous: E_rad rel",
    );
    check(
        rel_err(r.effective_loss_factor, c / (M_BED_KG * w)),
        0.0,
        1e-12,
        "viscous: eta_eff rel",
    );
    // Equivalent form used in Ch. 5: Ẽ = π m_bed V² η̄.
    check(
        rel_err(
            r.dissipated_energy_per_cycle_j,
            PI * M_BED_KG * (X_M * w).powi(2) * r.effective_loss_factor,
        ),
        0.0,
        1e-12,
        "viscous: E = pi m V^2 eta_eff",
    );
    assert!(
        r.loss_factor.abs() > 1e10,
        "η = Re/Im with Im P* ≈ 0: {}",
        r.loss_factor
    );
    check(r.effective_moving_mass_re_kg, 0.0, 1e-12, "viscous: Re M*");
    check(
        r.effective_moving_mass_im_kg,
        -c / w,
        1e-12,
        "viscous: Im M*",
    );
    check(
        r.effective_particle_mass_kg,
        c / w,
        1e-12,
        "viscous: m_bed_eff",
    );
    // Energy flowing into the damper is positive and equals the time-domain work.
    assert!(r.dissipated_energy_per_cycle_j > 0.0);
    check(
        rel_err(r.dissipated_energy_per_cycle_j, work_per_cycle_j(&f, &v)),
        0.0,
        1e-12,
        "viscous: E vs time-domain work",
    );
}

#[test]
fn viscous_damper_in_container_has_finite_loss_factor() {
    // F = m_con a + c v: η = c/(m_con Ω), M* = m_con − i c/Ω, m̄_bed = c/Ω.
    let c = 2.0;
    let w = TAU * F_HZ;
    let (f, v) = shake(0.0, |_, vel, a, _| M_CON_KG * a + c * vel);
    let r = complex_power_from_time_series(&f, &v, 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG).unwrap();
    check(
        rel_err(r.loss_factor, c / (M_CON_KG * w)),
        0.0,
        1e-12,
        "damper+container: eta rel",
    );
    check(
        rel_err(r.effective_particle_mass_kg, c / w),
        0.0,
        1e-12,
        "damper+container: m_bed_eff rel",
    );
    check(
        rel_err(r.effective_mass_ratio, c / w / M_BED_KG),
        0.0,
        1e-12,
        "damper+container: ratio rel",
    );
}

#[test]
fn mass_spring_damper_combination() {
    // F = m a + c v + k x  ⇒  F* = (c + i(mΩ − k/Ω)) V*,
    //   P* = ½ (c + i(mΩ − k/Ω)) |V*|², η = cΩ/(mΩ² − k),
    //   M* = (m − k/Ω²) − i c/Ω.
    let (m, c, k) = (1.1, 4.0, 250.0);
    let w = TAU * F_HZ;
    let (f, v) = shake(-1.2, |x, vel, a, _| m * a + c * vel + k * x);
    let r = complex_power_from_time_series(&f, &v, 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG).unwrap();
    let v2 = (X_M * w).powi(2);
    check(
        rel_err(r.complex_power_re_w, 0.5 * c * v2),
        0.0,
        1e-12,
        "msd: Re P rel",
    );
    check(
        rel_err(r.complex_power_im_w, 0.5 * (m * w - k / w) * v2),
        0.0,
        1e-12,
        "msd: Im P rel",
    );
    check(
        rel_err(r.loss_factor, c * w / (m * w * w - k)),
        0.0,
        1e-12,
        "msd: eta rel",
    );
    check(
        rel_err(r.effective_moving_mass_re_kg, m - k / (w * w)),
        0.0,
        1e-12,
        "msd: Re M* rel",
    );
    check(
        rel_err(r.effective_moving_mass_im_kg, -c / w),
        0.0,
        1e-12,
        "msd: Im M* rel",
    );
    let m_eff = Complex64::new(m - k / (w * w) - M_CON_KG, -c / w).norm();
    check(
        rel_err(r.effective_particle_mass_kg, m_eff),
        0.0,
        1e-12,
        "msd: m_bed_eff rel",
    );
    check(
        rel_err(r.dissipated_energy_per_cycle_j, work_per_cycle_j(&f, &v)),
        0.0,
        1e-12,
        "msd: E vs time-domain work",
    );
}

#[test]
fn higher_force_harmonics_do_not_change_the_result() {
    // Impact-like higher harmonics in the force (as for particle beds) carry
    // no mean power with a harmonic velocity and do not leak.
    let c = 3.0;
    let w = TAU * F_HZ;
    let (f0, v) = shake(0.0, |_, vel, a, _| M_CON_KG * a + c * vel);
    let (f1, _) = shake(0.0, |_, vel, a, t| {
        M_CON_KG * a + c * vel + 0.8 * (2.0 * w * t).cos() + 0.5 * (3.0 * w * t + 1.0).sin() + 0.2
    });
    let r0 = complex_power_from_time_series(&f0, &v, 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG).unwrap();
    let r1 = complex_power_from_time_series(&f1, &v, 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG).unwrap();
    check(
        rel_err(
            r1.dissipated_energy_per_cycle_j,
            r0.dissipated_energy_per_cycle_j,
        ),
        0.0,
        1e-12,
        "harmonics: E rel",
    );
    check(
        rel_err(r1.effective_particle_mass_kg, r0.effective_particle_mass_kg),
        0.0,
        1e-12,
        "harmonics: m_bed_eff rel",
    );
    check(
        rel_err(r1.dissipated_energy_per_cycle_j, work_per_cycle_j(&f1, &v)),
        0.0,
        1e-12,
        "harmonics: E vs time-domain work",
    );
}

#[test]
fn sign_convention_energy_into_damper_is_positive() {
    let w = TAU * F_HZ;
    let v = Complex64::from_polar(X_M * w, 0.4);
    // Force leading the velocity component-wise in phase with it: dissipative.
    let r = complex_power(Complex64::new(2.0, 0.0) * v, v, F_HZ, M_BED_KG, 0.0).unwrap();
    assert!(r.complex_power_re_w > 0.0 && r.dissipated_energy_per_cycle_j > 0.0);
    // An active element (F = −c v) feeds energy into the system: negative.
    let r = complex_power(Complex64::new(-2.0, 0.0) * v, v, F_HZ, M_BED_KG, 0.0).unwrap();
    assert!(r.dissipated_energy_per_cycle_j < 0.0 && r.effective_loss_factor < 0.0);
    // A mass (F = iΩ m V) stores energy: Im P* > 0; a spring: Im P* < 0.
    let r = complex_power(Complex64::new(0.0, w) * v, v, F_HZ, M_BED_KG, 0.0).unwrap();
    assert!(r.complex_power_im_w > 0.0);
    let r = complex_power(Complex64::new(0.0, -100.0 / w) * v, v, F_HZ, M_BED_KG, 0.0).unwrap();
    assert!(r.complex_power_im_w < 0.0);
    // Accessors round-trip.
    assert_eq!(r.velocity_amplitude_m_per_s(), v);
    assert_eq!(r.complex_power_w(), 0.5 * r.force_amplitude_n() * v.conj());
    assert!(
        rel_err_abs(
            r.effective_moving_mass_kg(),
            Complex64::new(-100.0 / (w * w), 0.0)
        ) < 1e-12
    );
}

fn rel_err_abs(a: Complex64, b: Complex64) -> f64 {
    (a - b).norm() / b.norm()
}

#[test]
fn invalid_inputs_are_errors() {
    let one = Complex64::new(1.0, 0.0);
    let zero = Complex64::new(0.0, 0.0);
    assert!(matches!(
        complex_power(one, zero, F_HZ, M_BED_KG, M_CON_KG),
        Err(SignalError::Degenerate { .. })
    ));
    assert!(complex_power(one, one, F_HZ, 0.0, M_CON_KG).is_err());
    assert!(complex_power(one, one, F_HZ, M_BED_KG, -1.0).is_err());
    assert!(complex_power(one, one, 0.0, M_BED_KG, M_CON_KG).is_err());
    assert!(complex_power(Complex64::new(f64::NAN, 0.0), one, F_HZ, M_BED_KG, M_CON_KG).is_err());
    assert!(matches!(
        complex_power_from_time_series(&[0.0; 10], &[0.0; 11], 0.0, DT_S, F_HZ, M_BED_KG, M_CON_KG),
        Err(SignalError::LengthMismatch { .. })
    ));
}

#[test]
fn result_is_serializable() {
    fn assert_serialize<T: serde::Serialize>() {}
    assert_serialize::<ComplexPowerResult>();
}
