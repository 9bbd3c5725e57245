//! Where an output comes from: `provenance.json` in every output directory (next to the
//! `scenario.toml` copy) names the pdamp version, the command line, the scenario digest, the
//! seed and the thread count, so every figure can be traced and reproduced. This module is the
//! file format; the provenance of a DEM scenario and the scenario digests that key checkpoints
//! and stored results are `pdamp_scenario::provenance`.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// Contents of `provenance.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// pdamp version that wrote the outputs.
    pub pdamp_version: String,
    /// Command line (program arguments).
    pub command: Vec<String>,
    /// Scenario title.
    pub scenario_title: String,
    /// Digest of the canonical scenario (FNV-1a 64 of `scenario.toml`).
    pub scenario_digest: String,
    /// Random seed of the scenario.
    pub seed: u64,
    /// Worker threads (results do not depend on it; see docs/reliability.md).
    pub threads: usize,
    /// Start of the run, seconds since the Unix epoch (UTC).
    pub started_unix_s: u64,
}

impl Provenance {
    /// Provenance of a run by this process of an input whose title, digest and seed the caller
    /// knows (a DEM scenario: `pdamp_scenario::provenance::of`).
    pub fn with_digest(title: &str, digest: String, seed: u64) -> Self {
        Self {
            pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
            command: std::env::args().collect(),
            scenario_title: title.to_string(),
            scenario_digest: digest,
            seed,
            threads: rayon::current_num_threads(),
            started_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        }
    }

    /// Provenance of a command whose input is not a DEM scenario — a structure, coupling, study
    /// or powder file (`input` is its text), or command-line options only (`input = None`,
    /// e.g. `pdamp cor`). The digest is that of the input's bytes (of the command line without
    /// an input file); `seed` is the input's seed (0 where it has none).
    pub fn of_input(title: &str, input: Option<&str>, seed: u64) -> Self {
        let digest = match input {
            Some(text) => crate::checkpoint::digest(text.as_bytes()),
            None => {
                let command: Vec<String> = std::env::args().skip(1).collect();
                crate::checkpoint::digest(command.join(" ").as_bytes())
            }
        };
        Self::with_digest(title, digest, seed)
    }

    /// Writes `dir/provenance.json` and, when there is an input file, a verbatim copy of it as
    /// `dir/input.toml`, atomically.
    pub fn write_input(&self, dir: &Path, input: Option<&str>) -> Result<(), std::io::Error> {
        std::fs::create_dir_all(dir)?;
        if let Some(text) = input {
            crate::atomic::write_atomic(dir.join("input.toml"), text.as_bytes())?;
        }
        let json = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        crate::atomic::write_atomic(dir.join("provenance.json"), json.as_bytes())
    }

    /// Writes `dir/<copy_name>` (the input as the run read it, e.g. a canonical
    /// `scenario.toml`) and `dir/provenance.json`, atomically.
    pub fn write_with_copy(
        &self,
        dir: &Path,
        copy_name: &str,
        text: &str,
    ) -> Result<(), std::io::Error> {
        std::fs::create_dir_all(dir)?;
        crate::atomic::write_atomic(dir.join(copy_name), text.as_bytes())?;
        let json = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        crate::atomic::write_atomic(dir.join("provenance.json"), json.as_bytes())
    }
}
