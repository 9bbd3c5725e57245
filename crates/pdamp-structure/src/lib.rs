//! # pdamp-structure — the structural level of pdamp [D Sect. 3.3]
//!
//! One or several particle dampers on a vibrating structure:
//!
//! - [`fe`]: built-in finite elements (3D Euler–Bernoulli/Timoshenko beams, hex8 solids, point
//!   masses with rigid offsets, springs, supports) assembling K and M [D Eq. 3.19];
//! - [`matrix_market`]: import of K and M in Matrix Market format with a node/dof map;
//! - [`modal`]: modal reduction $(K - \omega^2 M)\phi = 0$ [D Eq. 3.20–3.22] and the reduced
//!   [`modal::ModalStructure`] (also from direct modal input);
//! - [`integrate`]: Newmark integration of the modal equations with attached equivalent
//!   dampers [D Eq. 3.21, 3.29–3.31];
//! - coupling approach 1 (full DEM, [`dem`]), 2 (effective fields, [`effective::FieldTable`])
//!   and 3 (analytical formulas, [`formulas`]);
//! - analyses: free vibration and log decrement ([`free`], D Eq. 3.40–3.41), sine sweeps, FRF,
//!   resonance-peak damping and the steady-state iteration ([`forced`], D Eq. 3.42–3.50,
//!   Fig. 3.7), modal parameter extraction from FRFs ([`modal_fit`]: rational fraction
//!   polynomial, half-power bandwidth), efficiency and design formulas ([`design`], D Eq. 3.51–3.52, 5.15–5.23);
//! - [`scenario`]: the TOML input of `pdamp structure` and `pdamp couple`.
//!
//! \[D\] is the dissertation on the particle damper design toolchain.

#![forbid(unsafe_code)]
pub mod dem;
pub mod design;
pub mod effective;
pub mod error;
pub use pdamp_fem::linear as fe;
pub mod forced;
pub mod formulas;
pub mod free;
pub mod fuzz;
pub mod integrate;
pub use pdamp_fem::matrix_market;
pub mod modal;
pub mod modal_fit;
pub mod position_study;
pub mod report;
pub mod scenario;
pub mod sparse;
pub mod study;

pub use error::StructureError;
pub use modal::{ModalPoint, ModalStructure, Mode};
