//! Lowest eigenpairs of $\mathbf K_0\boldsymbol\phi = \omega^2\mathbf M\boldsymbol\phi$ of the
//! structure (free dofs), by `pdamp-fem`'s sparse eigensolver (faer sparse Cholesky of the
//! shifted pencil, faer Krylov–Schur, Rayleigh–Ritz refinement; [`crate::eigen`]).

use super::structure::Structure;
use crate::EigenError;

/// Eigenfrequencies \[Hz\] (ascending) and mass-normalised mode shapes (all dofs, zero on the
/// constrained ones) of the `count` lowest modes.
///
/// # Errors
/// The eigensolver's: a structure that is not constrained (singular K₀ is allowed only
/// through the shift; a dof without mass is not), or no convergence.
pub fn lowest_modes(s: &Structure, count: usize) -> Result<(Vec<f64>, Vec<Vec<f64>>), EigenError> {
    let modes = crate::lowest_modes(&s.k0, &s.mass, count, 0.0)?;
    let f = modes
        .omega_rad_s
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    let shapes = (0..modes.omega_rad_s.len())
        .map(|j| {
            let mut full = vec![0.0; s.n_dof()];
            for (k, &g) in s.free_dofs.iter().enumerate() {
                full[g] = modes.shapes[(k, j)];
            }
            full
        })
        .collect();
    Ok((f, shapes))
}
