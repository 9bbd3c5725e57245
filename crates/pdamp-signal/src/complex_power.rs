//! Complex power method for the effective fields of a particle damper
//! [D Sect. 3.2.2, Eqs. 3.12–3.17].
//!
//! Inputs are the complex amplitudes, at the driving frequency, of the force
//! driving the container `F*` and of the container velocity `V*`, both in the
//! convention `x(t) = Re(X̂ e^{iΩt})` of [`crate::harmonic`]. The force is the
//! force exerted *on* the container by the drive, in the direction of the
//! velocity, so power flowing from the drive into the damper is positive:
//! `Re(P*)` equals the cycle-averaged `F(t)·v(t)`.

use std::f64::consts::{PI, TAU};

use num_complex::Complex64;
use serde::Serialize;

use crate::error::{Result, SignalError, check_finite_scalar, check_positive, check_same_len};
use crate::harmonic::harmonic_amplitude;

/// Effective fields of a particle damper at one driving frequency.
///
/// Complex quantities are stored as real and imaginary parts (`*_re_*`,
/// `*_im_*`) in the convention `x(t) = Re(X̂ e^{iΩt})`; phases refer to
/// `t = 0`. Accessors return them as [`Complex64`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ComplexPowerResult {
    /// Driving frequency `f = Ω/(2π)`.
    pub frequency_hz: f64,
    /// Real part of the force amplitude `F*`.
    pub force_amplitude_re_n: f64,
    /// Imaginary part of the force amplitude `F*`.
    pub force_amplitude_im_n: f64,
    /// Real part of the container velocity amplitude `V*`.
    pub velocity_amplitude_re_m_per_s: f64,
    /// Imaginary part of the container velocity amplitude `V*`.
    pub velocity_amplitude_im_m_per_s: f64,
    /// `Re P*`, the mean power flowing into the damper [D Eq. 3.12].
    pub complex_power_re_w: f64,
    /// `Im P*`, the reactive power amplitude [D Eq. 3.12].
    pub complex_power_im_w: f64,
    /// Dissipated energy per cycle `Ẽ_diss = (2π/Ω) Re P*` [D Eq. 3.13].
    pub dissipated_energy_per_cycle_j: f64,
    /// Dissipated energy per radian `E_diss = Ẽ_diss/(2π) = Re P*/Ω` [D Eq. 3.13].
    pub dissipated_energy_per_radian_j: f64,
    /// Classical loss factor `η = Re P*/Im P*` [D Eq. 3.14]; `±∞` (or NaN) when `Im P* = 0`.
    pub loss_factor: f64,
    /// Effective loss factor `η̄ = E_diss/(½ m_bed |V*|²)` [D Eq. 3.15]; not bounded by 1.
    pub effective_loss_factor: f64,
    /// Real part of the effective moving mass `M* = F*/(iΩV*)` [D Eq. 3.16].
    pub effective_moving_mass_re_kg: f64,
    /// Imaginary part of the effective moving mass `M*` [D Eq. 3.16].
    pub effective_moving_mass_im_kg: f64,
    /// Effective particle mass `m̄_bed = |M* − m_con|` [D Eq. 3.17].
    pub effective_particle_mass_kg: f64,
    /// Effective particle mass ratio `m̄_bed/m_bed` [D Sect. 3.2.2].
    pub effective_mass_ratio: f64,
    /// Total particle (bed) mass used for the normalisation.
    pub m_bed_kg: f64,
    /// Container mass subtracted in [D Eq. 3.17].
    pub m_container_kg: f64,
}

impl ComplexPowerResult {
    /// Force amplitude `F*`.
    pub fn force_amplitude_n(&self) -> Complex64 {
        Complex64::new(self.force_amplitude_re_n, self.force_amplitude_im_n)
    }

    /// Velocity amplitude `V*`.
    pub fn velocity_amplitude_m_per_s(&self) -> Complex64 {
        Complex64::new(
            self.velocity_amplitude_re_m_per_s,
            self.velocity_amplitude_im_m_per_s,
        )
    }

    /// Complex power `P*`.
    pub fn complex_power_w(&self) -> Complex64 {
        Complex64::new(self.complex_power_re_w, self.complex_power_im_w)
    }

    /// Effective moving mass `M*`.
    pub fn effective_moving_mass_kg(&self) -> Complex64 {
        Complex64::new(
            self.effective_moving_mass_re_kg,
            self.effective_moving_mass_im_kg,
        )
    }
}

/// Evaluates the complex power method [D Eqs. 3.12–3.17] from the complex
/// amplitudes of the driving force `force_amplitude_n` (`F*`) and the
/// container velocity `velocity_amplitude_m_per_s` (`V*`) at the driving
/// frequency `frequency_hz`.
///
/// `m_bed_kg` is the total particle mass (must be > 0) and `m_container_kg`
/// the container mass (≥ 0; use 0 if the measured force excludes the
/// container inertia). Errors on non-finite input or `V* = 0`.
pub fn complex_power(
    force_amplitude_n: Complex64,
    velocity_amplitude_m_per_s: Complex64,
    frequency_hz: f64,
    m_bed_kg: f64,
    m_container_kg: f64,
) -> Result<ComplexPowerResult> {
    check_positive("frequency_hz", frequency_hz)?;
    check_positive("m_bed_kg", m_bed_kg)?;
    check_finite_scalar("m_container_kg", m_container_kg)?;
    if m_container_kg < 0.0 {
        return Err(SignalError::InvalidArgument {
            name: "m_container_kg",
            value: m_container_kg,
            reason: "must be >= 0",
        });
    }
    for (name, z) in [
        ("force_amplitude_n", force_amplitude_n),
        ("velocity_amplitude_m_per_s", velocity_amplitude_m_per_s),
    ] {
        if !z.is_finite() {
            return Err(SignalError::InvalidArgument {
                name,
                value: if z.re.is_finite() { z.im } else { z.re },
                reason: "must be finite",
            });
        }
    }
    let v_sq = velocity_amplitude_m_per_s.norm_sqr();
    if v_sq == 0.0 {
        return Err(SignalError::Degenerate {
            reason: "velocity amplitude V* is zero",
        });
    }
    let omega = TAU * frequency_hz;
    // [D Eq. 3.12]
    let p = 0.5 * force_amplitude_n * velocity_amplitude_m_per_s.conj();
    // [D Eq. 3.13]
    let e_cycle = TAU / omega * p.re;
    let e_rad = e_cycle / (2.0 * PI);
    // [D Eq. 3.14]
    let eta = p.re / p.im;
    // [D Eq. 3.15]
    let eta_eff = e_rad / (0.5 * m_bed_kg * v_sq);
    // [D Eq. 3.16]
    let m_mov = force_amplitude_n / (Complex64::new(0.0, omega) * velocity_amplitude_m_per_s);
    // [D Eq. 3.17]
    let m_bed_eff = (m_mov - m_container_kg).norm();
    Ok(ComplexPowerResult {
        frequency_hz,
        force_amplitude_re_n: force_amplitude_n.re,
        force_amplitude_im_n: force_amplitude_n.im,
        velocity_amplitude_re_m_per_s: velocity_amplitude_m_per_s.re,
        velocity_amplitude_im_m_per_s: velocity_amplitude_m_per_s.im,
        complex_power_re_w: p.re,
        complex_power_im_w: p.im,
        dissipated_energy_per_cycle_j: e_cycle,
        dissipated_energy_per_radian_j: e_rad,
        loss_factor: eta,
        effective_loss_factor: eta_eff,
        effective_moving_mass_re_kg: m_mov.re,
        effective_moving_mass_im_kg: m_mov.im,
        effective_particle_mass_kg: m_bed_eff,
        effective_mass_ratio: m_bed_eff / m_bed_kg,
        m_bed_kg,
        m_container_kg,
    })
}

/// Complex power method from time series: the amplitudes `F*` and `V*` at
/// `frequency_hz` are taken with [`harmonic_amplitude`] (largest exact
/// whole-cycle window at the end of the record; both signals share
/// `t0_s`/`dt_s` and so the window), then [`complex_power`] is evaluated.
///
/// `force_n` and `velocity_m_per_s` must have equal length. To discard
/// start-up cycles (e.g. the first two cycles in [D Sect. 5.1.1]), pass
/// the sub-slices and the matching `t0_s`. For an arbitrary `dt_s` that
/// admits no exact window, call
/// [`crate::harmonic::harmonic_amplitude_with_rule`] with
/// [`crate::harmonic::CycleRule::Nearest`] and then [`complex_power`].
pub fn complex_power_from_time_series(
    force_n: &[f64],
    velocity_m_per_s: &[f64],
    t0_s: f64,
    dt_s: f64,
    frequency_hz: f64,
    m_bed_kg: f64,
    m_container_kg: f64,
) -> Result<ComplexPowerResult> {
    check_same_len(
        "force_n",
        force_n.len(),
        "velocity_m_per_s",
        velocity_m_per_s.len(),
    )?;
    let f = harmonic_amplitude(force_n, t0_s, dt_s, frequency_hz)?;
    let v = harmonic_amplitude(velocity_m_per_s, t0_s, dt_s, frequency_hz)?;
    complex_power(
        f.amplitude,
        v.amplitude,
        frequency_hz,
        m_bed_kg,
        m_container_kg,
    )
}
