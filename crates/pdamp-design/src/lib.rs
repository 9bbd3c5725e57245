//! Design level of pdamp: a single particle damper under harmonic excitation evaluated by the
//! complex power method [D Sect. 3.2], effective fields over frequency × amplitude, motion modes,
//! and reference solutions of idealised damper motions.

#![forbid(unsafe_code)]
pub mod convergence;
pub mod damper;
pub mod ensemble;
mod error;
pub mod event_driven;
pub mod fields;
#[cfg(feature = "gpu")]
pub mod gpu_points;
pub mod motion;
pub mod plots;
pub mod report;

pub use damper::{Damper, PointObserver, PointResult};
pub use error::DesignError;
pub use fields::{FieldGrid, PointEngine, ThreadSplit, run_fields, run_fields_on, run_fields_with};
