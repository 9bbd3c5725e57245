//! Errors of the packing generators.

use super::Lattice;
use crate::ParameterError;

// ------------------------------------------------------------------------------------------------

/// Errors of the packing generators ([`grid_packing`](super::grid_packing),
/// [`tight_packing`](super::tight_packing), [`random_insertion`](super::random_insertion),
/// [`lattice_sites`](super::lattice_sites)).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PackingError {
    /// A region, radius, spacing, gap or layering parameter out of range.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The lattice would need more candidate sites than 5e7.
    #[error(
        "lattice packing would need about {sites:.3e} candidate sites (spacing {spacing_m} m too small for the region)"
    )]
    TooManySites {
        /// Estimated number of candidate sites.
        sites: f64,
        /// Lattice spacing in m.
        spacing_m: f64,
    },
    /// The region holds fewer lattice sites than particles.
    #[error(
        "region holds only {fitted} of {requested} particles on a {lattice:?} lattice with spacing {spacing_m:.6e} m (2 r_max + gap)"
    )]
    RegionTooSmall {
        /// Sites that fit.
        fitted: usize,
        /// Particles to place.
        requested: usize,
        /// The lattice.
        lattice: Lattice,
        /// Nearest-neighbour spacing in m.
        spacing_m: f64,
    },
    /// More particles than the insertion grid can index.
    #[error("too many particles ({count})")]
    TooManyParticles {
        /// Particles requested.
        count: usize,
    },
    /// Random insertion found no free position for a particle.
    #[error(
        "random insertion placed only {placed} of {requested} particles: particle {particle} (radius {radius_m:.6e} m) found no free position in {attempts} attempts{}",
        if *in_top_layer { " in the top layer" } else { "" }
    )]
    NoFreePosition {
        /// Particles placed before.
        placed: usize,
        /// Particles to place.
        requested: usize,
        /// Index of the particle that found no place.
        particle: usize,
        /// Its radius in m.
        radius_m: f64,
        /// Attempts per particle.
        attempts: usize,
        /// Whether layered insertion had reached its top layer.
        in_top_layer: bool,
    },
}
