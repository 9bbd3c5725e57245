//! # pdamp-scenario — the DEM scenario
//!
//! A scenario file (TOML, `docs/scenario.md`) describes a DEM run: materials, contact laws,
//! walls on rigid bodies, particle groups, time stepping, output, and the damper and
//! effective-field sections that `pdamp damper` and `pdamp fields` read. This crate owns
//! * the schema and its validation ([`schema`], every error names the key),
//! * the world builder and bed preparation ([`schema::Scenario::build_world`], [`prepare`]),
//! * the cost and memory estimate before anything is allocated ([`estimate`]),
//! * the run driver behind `pdamp run` ([`run`]) and the benchmark behind `pdamp bench`
//!   ([`mod@bench`]),
//! * the provenance and digests of a scenario's outputs ([`provenance`]).
//!
//! The file formats it reads and writes (CSV, VTK, STL, checkpoints, beds) are `pdamp-io`; the
//! physics is `pdamp-dem`. The structure and powder levels keep their own input files in their
//! crates (`pdamp_structure::scenario`, `pdamp_powder::cantilever`), since those schemas are
//! made of the levels' own types.

#![forbid(unsafe_code)]
pub mod bench;
pub mod error;
pub mod examples;
pub mod fuzz;
pub mod prepare;
pub mod provenance;
pub mod restitution;
pub mod run;
pub mod schema;

pub use error::InputError;
pub use schema::estimate;
pub use schema::{Scenario, ScenarioError};
