//! Efficiency and design formulas of the structural level: ζ(η̄) [D Eq. 3.51, 3.52], the free
//! vibration guideline [D Eq. 5.15, 5.17] and the forced-vibration optimum [D Eq. 5.20–5.23].

use std::f64::consts::PI;

/// Damping ratio of mode k reached with effective loss factor η̄ [D Eq. 3.51] (structural
/// damping neglected): $\zeta_k = \phi^2 m_{bed}\bar\eta / (2(1 + \phi^2\bar m_{bed}))$, with
/// `shape_value` = $\phi^{(k)}_{pd}$ (mass-normalised, 1/√kg).
pub fn damping_ratio_modal(
    shape_value: f64,
    bed_mass_kg: f64,
    effective_mass_kg: f64,
    effective_loss_factor: f64,
) -> f64 {
    let p2 = shape_value * shape_value;
    p2 * bed_mass_kg * effective_loss_factor / (2.0 * (1.0 + p2 * effective_mass_kg))
}

/// Eq. 3.52 for a single-mode structure of modal mass M at the damper:
/// $\zeta_1 = \tfrac12\bar\eta\, m_{bed}/(M + m_{bed})$.
pub fn damping_ratio_single_mode(
    modal_mass_kg: f64,
    bed_mass_kg: f64,
    effective_loss_factor: f64,
) -> f64 {
    0.5 * effective_loss_factor * bed_mass_kg / (modal_mass_kg + bed_mass_kg)
}

/// Bed mass for a desired damping ratio [D Eq. 5.15]: $m_{bed} \approx 2M\zeta_d/\bar\eta$
/// (= 4Mζ_d for the design value η̄ = 0.5).
pub fn bed_mass_for_damping(
    modal_mass_kg: f64,
    damping_ratio: f64,
    effective_loss_factor: f64,
) -> f64 {
    2.0 * modal_mass_kg * damping_ratio / effective_loss_factor
}

/// Layer clearances of the three-layer free-vibration guideline [D Eq. 5.17]:
/// $h_{rol} = \{5/4, 5/8, 5/12\}X_0$.
pub fn layer_clearances_m(initial_amplitude_m: f64) -> [f64; 3] {
    [1.25, 0.625, 5.0 / 12.0].map(|c| c * initial_amplitude_m)
}

/// Optimal forced damping ratio of a rolling damper operated at $X^{opt}_{rol}$ [D Eq. 5.20]:
/// $\zeta_{opt} = 10 m_{bed}/(7\pi(M + \bar m_{bed}))$.
pub fn optimal_forced_damping_ratio(
    modal_mass_kg: f64,
    bed_mass_kg: f64,
    effective_mass_kg: f64,
) -> f64 {
    10.0 * bed_mass_kg / (7.0 * PI * (modal_mass_kg + effective_mass_kg))
}

/// Resonance amplitude at the optimum [D Eq. 5.21]: $X = 7\pi R'(M+m_{bed})/(20 m_{bed}K)$.
pub fn optimal_resonance_amplitude_m(
    force_n: f64,
    modal_mass_kg: f64,
    stiffness_n_m: f64,
    bed_mass_kg: f64,
) -> f64 {
    7.0 * PI * force_n * (modal_mass_kg + bed_mass_kg) / (20.0 * bed_mass_kg * stiffness_n_m)
}

/// Bed mass for a desired resonance amplitude [D Eq. 5.22]:
/// $m^{opt}_{bed} = 7\pi R'M/(20KX_{max} - 7\pi R')$; `None` if $20KX_{max} \le 7\pi R'$.
pub fn optimal_bed_mass_kg(
    force_n: f64,
    modal_mass_kg: f64,
    stiffness_n_m: f64,
    max_amplitude_m: f64,
) -> Option<f64> {
    let den = 20.0 * stiffness_n_m * max_amplitude_m - 7.0 * PI * force_n;
    (den > 0.0).then(|| 7.0 * PI * force_n * modal_mass_kg / den)
}

/// Base amplitude that drives the damper to its optimal stroke [D Eq. 5.23]:
/// $U_{opt} = 20 m_{bed}X^{opt}_{rol}/(7\pi(M + m_{bed}))$.
pub fn optimal_base_amplitude_m(
    modal_mass_kg: f64,
    bed_mass_kg: f64,
    optimal_stroke_m: f64,
) -> f64 {
    20.0 * bed_mass_kg * optimal_stroke_m / (7.0 * PI * (modal_mass_kg + bed_mass_kg))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D Sect. 5.2: ζ(η̄ = 0.91) = 0.056 (M = 1.058 kg, 149 g); ζ_opt = 0.055 and
    /// U_opt = 1.34 mm (147 g, X_opt = 12 mm); D Sect. 6.2: ζ_d = 0.044 from 196 g on 1.108 kg.
    #[test]
    fn dissertation_design_numbers() {
        let z = damping_ratio_single_mode(1.058, 0.149, 0.91);
        assert!((z - 0.056).abs() < 0.0006, "{z}");
        let z = optimal_forced_damping_ratio(1.058, 0.147, 0.147);
        assert!((z - 0.055).abs() < 0.0006, "{z}");
        let u = optimal_base_amplitude_m(1.058, 0.147, 0.012);
        assert!((u - 1.34e-3).abs() < 0.01e-3, "{u}");
        let zd = 0.196 / (4.0 * 1.108);
        assert!((bed_mass_for_damping(1.108, zd, 0.5) - 0.196).abs() < 1e-12);
        // Eq. 3.51 with φ² = 1/M equals Eq. 3.52 when m̄ = m_bed.
        let a = damping_ratio_modal(1.0 / 1.058f64.sqrt(), 0.149, 0.149, 0.91);
        assert!((a - damping_ratio_single_mode(1.058, 0.149, 0.91)).abs() < 1e-15);
        // Eq. 5.21 and 5.22 are inverse to each other.
        let x = optimal_resonance_amplitude_m(0.3, 1.058, 143.0, 0.147);
        let m = optimal_bed_mass_kg(0.3, 1.058, 143.0, x).unwrap();
        assert!((m - 0.147).abs() < 1e-12);
    }
}
