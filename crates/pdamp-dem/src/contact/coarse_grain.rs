//! Coarse-graining of a contact model: particles `f` times larger than the real ones (P Sect. 2.4
//! after Bierwisch et al. 2009; Sect. 3.6 for adhesion), so that a bed of N/f³ particles stands for
//! one of N.
//!
//! For the linear spring–dashpot [P Eq. (2)–(4)] the stiffness scales with the size,
//! $k' = f\,k$: with masses $m' = f^3 m$ the contact time grows as $t' = f\,t$ (the time scale of a
//! particle crossing its own size under the same accelerations), the damping follows from
//! eq. (4) with the scaled masses ($d' = f^2 d$) and the restitution is unchanged. Hertz-type laws
//! need no change: their stiffness already grows with the particles' radius. The DMT surface
//! energy follows the paper's rule $\gamma' = f^2\gamma$ (P Sect. 3.6). Friction and rolling
//! coefficients are dimensionless and stay.

use super::{ContactModel, NormalLaw};

impl ContactModel {
    /// The model for particles `f` times the size of the real ones (see the module docs).
    /// `f` must be positive and finite.
    pub fn coarse_grained(&self, f: f64) -> Result<ContactModel, crate::ParameterError> {
        if !(f.is_finite() && f > 0.0) {
            return Err(crate::ParameterError::out_of_range(
                "coarse-graining factor",
                "be positive and finite",
                f,
            ));
        }
        let mut m = self.clone();
        if let NormalLaw::Linear { stiffness_n_m, .. } = &mut m.normal {
            *stiffness_n_m *= f;
        }
        if let Some(a) = m.adhesion.as_mut() {
            a.surface_energy_j_m2 *= f * f;
        }
        Ok(m)
    }
}
