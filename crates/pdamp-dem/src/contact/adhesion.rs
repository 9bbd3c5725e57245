//! DMT van der Waals adhesion [P Eq. (6), (7)].

use super::{DmtAdhesion, PairProps};

impl DmtAdhesion {
    /// Pull-off force $F_{S0} = 4\pi\gamma\bar R$ [P Eq. (6)], N.
    #[inline]
    pub fn pull_off_force_n(&self, p: &PairProps) -> f64 {
        4.0 * std::f64::consts::PI * self.surface_energy_j_m2 * p.r_eff_m
    }

    /// Gap $g_0 = \sqrt{A\bar R/(6F_{S0})}$ at which the force reaches $F_{S0}$ [P Eq. (7)], m.
    #[inline]
    pub fn saturation_gap_m(&self, p: &PairProps) -> f64 {
        (self.hamaker_constant_j * p.r_eff_m / (6.0 * self.pull_off_force_n(p))).sqrt()
    }

    /// Cut-off gap $g^* = g_0/\sqrt{c_{FS0}}$ [P Eq. (7)], m (0 when γ = 0).
    #[inline]
    pub fn cutoff_gap_m(&self, p: &PairProps) -> f64 {
        if self.pull_off_force_n(p) > 0.0 {
            self.saturation_gap_m(p) / self.cutoff_ratio.sqrt()
        } else {
            0.0
        }
    }

    /// Attractive force magnitude (N, ≥ 0) and potential (J, ≤ 0) at overlap `overlap_m`
    /// (gap $g = -\delta$). The potential is 0 for $g \ge g^*$ and
    /// $U = \frac{A\bar R}{6}\left(\frac1{g^*}-\frac1g\right)$ for $g_0 < g < g^*$,
    /// continued linearly with slope $F_{S0}$ for $g \le g_0$, so that $dU/d\delta = -F$: the work
    /// done by the adhesion force equals −ΔU (the force jumps from $c F_{S0}$ to 0 at $g^*$, the
    /// potential is continuous).
    #[inline]
    pub(crate) fn force_and_potential(&self, p: &PairProps, overlap_m: f64) -> (f64, f64) {
        let fs0 = self.pull_off_force_n(p);
        if fs0.is_nan() || fs0 <= 0.0 {
            return (0.0, 0.0);
        }
        let ar6 = self.hamaker_constant_j * p.r_eff_m / 6.0;
        let g0 = (ar6 / fs0).sqrt();
        let g_star = g0 / self.cutoff_ratio.sqrt();
        let g = -overlap_m;
        if g >= g_star {
            (0.0, 0.0)
        } else if g > g0 {
            (ar6 / (g * g), ar6 * (1.0 / g_star - 1.0 / g))
        } else {
            (fs0, ar6 * (1.0 / g_star - 1.0 / g0) - fs0 * (g0 - g))
        }
    }
}
