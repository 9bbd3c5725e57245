//! Cohesive powder DEM of paper Sect. 2.1: contact law ([`law`]), particles and velocity Verlet
//! ([`powder`]), pair list ([`neighbor`]), walls ([`wall`]) and size distributions ([`psd`]).

pub mod law;
pub mod neighbor;
pub mod powder;
pub mod psd;
pub mod wall;

pub use law::PowderLaw;
pub use neighbor::NeighborList;
pub use powder::{Powder, PowderLedger};
pub use psd::{LogNormal, Rng};
pub use wall::{PlaneWall, WallSlots};
