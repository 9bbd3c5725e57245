//! Particle generation: size distributions, container regions and initial placements
//! ([D sec. 2.1, Fig. 2.2]).
//!
//! * [`SizeDistribution`] — monodisperse, uniform in radius, or (truncated) log-normal in diameter
//!   as in [P Table A.2] (D50 = 1.0 mm, σ = 0.2707, r ∈ [0.353414, 0.707385] mm).
//! * [`Region`] — the volume to fill (axis-aligned box or arbitrary cylinder).
//! * Placements: [`grid_packing`] (simple cubic) and [`tight_packing`] (hexagonal close packing)
//!   filled layer by layer from the bottom ([D Fig. 2.2a]); [`random_insertion`] over the whole
//!   volume ([D Fig. 2.2c]) or layer by layer ([D Fig. 2.2d], via [`Layering`]).
//!
//! Drop-down settling ([D Fig. 2.2b]) is done by the simulation pipeline, not here.
//! All generators are deterministic: the same inputs (and seed) give bit-identical output.

mod error;
mod insertion;
mod lattice;
mod order;
mod region;
mod size;

pub use error::PackingError;
pub(crate) use insertion::CellGrid;
pub use insertion::{Layering, random_insertion, random_insertion_clear_of};
pub use lattice::{grid_packing, lattice_sites, tight_packing};
pub use order::{LAYER_TILE_CELLS, layer_order, morton_order};
pub use region::{Region, orthonormal_frame};
pub use size::{SizeDistribution, normal_cdf, normal_quantile};

/// Lattice of a regular packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lattice {
    /// Simple cubic grid (solid fraction π/6 ≈ 0.524 for equal spheres).
    SimpleCubic,
    /// Hexagonal close packing, triangular layers stacked ABAB (π/(3√2) ≈ 0.740).
    Hcp,
    /// Face-centred cubic, triangular layers stacked ABC (π/(3√2) ≈ 0.740).
    Fcc,
}

#[cfg(test)]
mod tests;
