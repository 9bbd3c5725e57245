//! # pdamp-io — files in and out of pdamp
//!
//! Scenario files (TOML), meshes (STL), results (CSV, JSON) and ParaView output (VTK XML).
//! Every output file is written atomically (write to a temporary file, then rename).

#![forbid(unsafe_code)]
pub mod atomic;
pub mod bed;
pub mod bed_formats;
pub mod bench;
pub mod checkpoint;
pub mod csv;
pub mod error;
pub mod examples;
pub mod fuzz;
pub mod output_dir;
pub mod prepare;
pub mod provenance;
pub mod restitution;
pub mod run;
pub mod scenario;
pub mod stl;
pub mod vtk;

pub use error::InputError;
// The estimate of a scenario lives at `scenario::estimate`; `pdamp_io::estimate` stays its path.
pub use scenario::estimate;
