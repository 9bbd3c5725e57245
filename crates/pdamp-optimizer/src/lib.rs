//! # pdamp-optimizer — from a structure and a target to a verified particle damper
//!
//! `pdamp design STUDY.toml --out DIR` answers the designer's inverse question: *which damper,
//! where, and how much damping will it give?* The study names the structure (any model pdamp
//! reduces: beam FE, Matrix Market, modal input), the objective (the smallest amplitude after a
//! time T of a free decay, or the largest damping ratio of chosen modes over an amplitude
//! range), the design space (points, container lengths, particle materials and radii, layers
//! and particle numbers) and the constraints (bed mass, clearance).
//!
//! The search is multi-fidelity ([`fidelity`], [`search`]): the envelope model screens the
//! space, the modal time simulation with the formula dampers verifies a budget of designs with
//! a local search, and the report ([`report`]) compares the levels on every verified design,
//! checks the best design's robustness to detuning and writes a ready-to-run scenario for each
//! listed design. With `[verification] field_designs = N` the best N designs, each with every
//! wall coating of the study, get the effective fields of their DEM beds ([`effective_fields`],
//! approach 2, stored and reused) and are ranked by the structure's response with those fields;
//! with `dem_designs = N` the best N listed designs are run with coupled DEM ([`dem`],
//! approach 1: free decays, or for the forced objectives a slow sine sweep through each
//! resonance, [`resonance_sweep`]). Both on an ensemble of dropped beds: the report gives the objective's mean and
//! 95 % confidence interval beside the formulas' value.
//!
//! \[D\] is the dissertation on the particle damper design toolchain.

#![forbid(unsafe_code)]

pub mod dem;
mod design_scenario;
pub mod effective_fields;
mod error;
pub mod fidelity;
pub mod report;
pub mod resonance_sweep;
pub mod search;
pub mod space;
pub mod spec;
pub mod study;

pub use error::DesignError;
pub use space::{Choice, Design, Space};
pub use study::DesignStudy;

use std::path::Path;

/// Loads a study file, runs the search and writes every output to `out`.
///
/// # Errors
/// Input errors naming the key, solver errors, output errors.
pub fn run_design_study_file(path: &Path, out: &Path) -> Result<serde_json::Value, DesignError> {
    run_design_study_file_with(path, out, &mut |_| {})
}

/// [`run_design_study_file`] that reports its phases (`progress` gets one line per phase).
///
/// # Errors
/// See [`run_design_study_file`].
pub fn run_design_study_file_with(
    path: &Path,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<serde_json::Value, DesignError> {
    let started = std::time::Instant::now();
    let study = DesignStudy::load(path)?;
    let space = Space::new(&study);
    progress(&format!(
        "screening {:.0} designs, then time simulations",
        space.size()
    ));
    let outcome = search::run_search(&space)?;
    report::write_outputs(
        &space,
        &outcome,
        out,
        started.elapsed().as_secs_f64(),
        progress,
    )
}
