//! The parameters of the cohesive powder contact law of paper Sect. 2.1, used for
//! particle–particle and particle–wall contacts (walls enter with $r_{eff} = r_i$,
//! $m_{eff} = m_i$); pdamp-dem evaluates it ([`crate::bed::contact_model`]):
//!
//! - normal spring–dashpot, eq. 2–4: $\mathbf f_{CN} = \min(0, k_Ng_N + d_N\dot g_N)\,\mathbf n$ for
//!   $g_N \le 0$, $d_N = 2|\ln e|\sqrt{k_Nm_{eff}/(\ln^2e+\pi^2)}$;
//! - Coulomb tangential spring–dashpot, eq. 5, with $k_T = \frac{1-\nu}{1-\nu/2}k_N$, $d_T = d_N$,
//!   $\|\mathbf f_{CT}\| \le \mu\|\mathbf f_{CN}\|$, stick/slip by return mapping;
//! - DMT adhesion, eq. 6–7: pull-off force $F_{S0} = 4\pi\gamma r_{eff}$ (attractive) for
//!   $g_N \le g_0$, $A r_{eff}/(6g_N^2)$ for $g_0 < g_N < g^*$, zero beyond
//!   $g^* = g_0/\sqrt{c_{FS0}}$, $g_0 = \sqrt{A r_{eff}/(6F_{S0})}$.
//!
//! Sign convention: $\mathbf n$ points from particle i to its partner, $g_N$ is the gap
//! (negative = overlap), forces are those acting on particle i.

use crate::error::ParameterError;

/// Constant parameters of the powder contact law.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PowderLaw {
    /// Normal penalty stiffness $k_N$ [N/m] (paper Table A.2: 5642 N/m for D50 = 1 mm).
    pub normal_stiffness_n_m: f64,
    /// Coefficient of restitution $e$ (Table A.2: 0.4).
    pub restitution: f64,
    /// Coefficient of friction $\mu$ (Table A.2: 0.4).
    pub friction: f64,
    /// Poisson's ratio $\nu$ for $k_T$ (Table A.2: 0.27).
    pub poisson_ratio: f64,
    /// Surface energy $\gamma$ [J/m²] (0 = no adhesion; Sect. 3.6: 0.085 J/m² scaled).
    pub surface_energy_j_m2: f64,
    /// Hamaker constant $A$ \[J\] (Table A.2: 40e-20 J).
    pub hamaker_j: f64,
    /// Relative adhesion cut-off $c_{FS0}$ (Table A.2: 0.01).
    pub adhesion_cutoff: f64,
}

impl PowderLaw {
    /// Paper Table A.2 (D50 = 1 mm, no adhesion as in Sect. 3.1–3.5).
    pub const PAPER: PowderLaw = PowderLaw {
        normal_stiffness_n_m: 5642.0,
        restitution: 0.4,
        friction: 0.4,
        poisson_ratio: 0.27,
        surface_energy_j_m2: 0.0,
        hamaker_j: 40e-20,
        adhesion_cutoff: 0.01,
    };

    /// Coarse-graining by the size factor `f = r'/r` (Sect. 2.4, Bierwisch et al. 2009), the
    /// parameters of pdamp-dem's transform `ContactModel::coarse_grained` (tested equal):
    /// $k' = f k$; damping follows from eq. 4 with the scaled masses, which gives $d' = f^2 d$;
    /// the surface energy scales with $f$ … here the paper's rule $\gamma' = f^2\gamma$ (Sect. 3.6).
    pub fn coarse_grained(&self, f: f64) -> Self {
        Self {
            normal_stiffness_n_m: self.normal_stiffness_n_m * f,
            surface_energy_j_m2: self.surface_energy_j_m2 * f * f,
            ..*self
        }
    }

    /// $k_T/k_N = (1-\nu)/(1-\nu/2)$.
    pub fn tangential_ratio(&self) -> f64 {
        (1.0 - self.poisson_ratio) / (1.0 - 0.5 * self.poisson_ratio)
    }

    /// $2|\ln e|/\sqrt{\ln^2e+\pi^2}$, so that $d_N = c\sqrt{k_N m_{eff}}$.
    pub fn damping_factor(&self) -> f64 {
        if self.restitution >= 1.0 {
            return 0.0;
        }
        let l = self.restitution.max(1e-12).ln();
        2.0 * l.abs() / (l * l + std::f64::consts::PI.powi(2)).sqrt()
    }

    /// Largest gap at which adhesion acts for the effective radius \[m\] (0 without adhesion).
    pub fn adhesion_range(&self, r_eff: f64) -> f64 {
        if self.surface_energy_j_m2 <= 0.0 {
            return 0.0;
        }
        let fs0 = 4.0 * std::f64::consts::PI * self.surface_energy_j_m2 * r_eff;
        (self.hamaker_j * r_eff / (6.0 * fs0)).sqrt() / self.adhesion_cutoff.sqrt()
    }

    /// Checks that every value is finite and in its physical range; the error names the key
    /// (with `prefix`), the value and the range.
    pub fn validate(&self, prefix: &str) -> Result<(), ParameterError> {
        let chk = |ok: bool, key: &str, v: f64, what: &str| {
            if ok {
                Ok(())
            } else {
                Err(ParameterError::out_of_range(
                    format!("{prefix}{key}"),
                    v,
                    what,
                ))
            }
        };
        let k = self.normal_stiffness_n_m;
        chk(
            k > 0.0 && k <= 1e12,
            "normal_stiffness_n_m",
            k,
            "must be a finite stiffness in (0, 1e12] N/m (Table A.2: 5642)",
        )?;
        chk(
            self.restitution > 0.0 && self.restitution <= 1.0,
            "restitution",
            self.restitution,
            "must be in (0, 1]",
        )?;
        chk(
            self.friction >= 0.0 && self.friction <= 10.0,
            "friction",
            self.friction,
            "must be in [0, 10]",
        )?;
        chk(
            self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5,
            "poisson_ratio",
            self.poisson_ratio,
            "must be in (-1, 0.5)",
        )?;
        chk(
            self.surface_energy_j_m2 >= 0.0 && self.surface_energy_j_m2 <= 100.0,
            "surface_energy_j_m2",
            self.surface_energy_j_m2,
            "must be in [0, 100] J/m² (Sect. 3.6: 0.085)",
        )?;
        chk(
            self.hamaker_j > 0.0 && self.hamaker_j <= 1e-15,
            "hamaker_j",
            self.hamaker_j,
            "must be in (0, 1e-15] J (Table A.2: 4e-19)",
        )?;
        chk(
            self.adhesion_cutoff > 0.0 && self.adhesion_cutoff < 1.0,
            "adhesion_cutoff",
            self.adhesion_cutoff,
            "must be in (0, 1)",
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restitution_damping_factor_matches_eq4() {
        // e = 0.4: 2|ln 0.4|/sqrt(ln² 0.4 + π²) = 0.5600…
        let l: f64 = 0.4f64.ln();
        let c = 2.0 * l.abs() / (l * l + std::f64::consts::PI.powi(2)).sqrt();
        assert!((PowderLaw::PAPER.damping_factor() - c).abs() < 1e-15);
        assert!((c - 0.5600).abs() < 1e-4, "{c}");
        assert!((PowderLaw::PAPER.tangential_ratio() - 0.73 / 0.865).abs() < 1e-12);
        assert_eq!(
            PowderLaw {
                restitution: 1.0,
                ..PowderLaw::PAPER
            }
            .damping_factor(),
            0.0
        );
    }

    #[test]
    fn coarse_graining_scales_stiffness_and_surface_energy() {
        let law = PowderLaw {
            surface_energy_j_m2: 0.085,
            ..PowderLaw::PAPER
        };
        let cg = law.coarse_grained(2.0);
        assert_eq!(cg.normal_stiffness_n_m, 2.0 * 5642.0);
        assert!((cg.surface_energy_j_m2 - 4.0 * 0.085).abs() < 1e-15);
        assert_eq!(cg.friction, law.friction);
    }
}
