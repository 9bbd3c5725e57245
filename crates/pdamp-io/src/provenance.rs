//! Where an output comes from: `provenance.json` in every output directory (next to the
//! `scenario.toml` copy) names the pdamp version, the command line, the scenario digest, the
//! seed and the thread count, so every figure can be traced and reproduced. The scenario
//! digests that key checkpoints and stored results live here too ([`scenario_digest`],
//! [`scenario_content_digest`]).

use crate::scenario::Scenario;
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
    /// Provenance of a run of `scenario` by this process.
    pub fn of(scenario: &crate::scenario::Scenario) -> Self {
        Self {
            pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
            command: std::env::args().collect(),
            scenario_title: scenario.title.clone(),
            scenario_digest: scenario_digest(scenario),
            seed: scenario.simulation.seed,
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
        let command: Vec<String> = std::env::args().collect();
        let digest = match input {
            Some(text) => crate::checkpoint::digest(text.as_bytes()),
            None => crate::checkpoint::digest(command[1..].join(" ").as_bytes()),
        };
        Self {
            pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
            command,
            scenario_title: title.to_string(),
            scenario_digest: digest,
            seed,
            threads: rayon::current_num_threads(),
            started_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        }
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

    /// Writes `dir/scenario.toml` (canonical) and `dir/provenance.json`, atomically.
    pub fn write(
        &self,
        scenario: &crate::scenario::Scenario,
        dir: &Path,
    ) -> Result<(), std::io::Error> {
        std::fs::create_dir_all(dir)?;
        crate::atomic::write_atomic(dir.join("scenario.toml"), scenario.to_toml().as_bytes())?;
        let json = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        crate::atomic::write_atomic(dir.join("provenance.json"), json.as_bytes())
    }
}

/// Digest identifying a scenario in checkpoints and outputs (of its canonical TOML).
pub fn scenario_digest(scenario: &Scenario) -> String {
    crate::checkpoint::digest(scenario.to_toml().as_bytes())
}

/// The content of every file the scenario reads ([`Scenario::referenced_files`], relative to
/// `base_dir`) as TOML comment lines `# file <path>: <digest of its bytes>` (`unreadable`
/// where it cannot be read), so that a checkpoint or a stored result is never continued with
/// a changed mesh or bed behind an unchanged path.
pub fn referenced_files_digest(scenario: &Scenario, base_dir: &Path) -> String {
    let mut s = String::new();
    for f in scenario.referenced_files() {
        let d = std::fs::read(base_dir.join(&f)).map_or_else(
            |_| "unreadable".to_string(),
            |b| crate::checkpoint::digest(&b),
        );
        s.push_str(&format!("# file {}: {d}\n", f.display()));
    }
    s
}

/// Digest of a scenario together with the content of the files it reads (checkpoints and
/// stored results of runs are keyed by it).
pub fn scenario_content_digest(scenario: &Scenario, base_dir: &Path) -> String {
    let files = referenced_files_digest(scenario, base_dir);
    if files.is_empty() {
        return scenario_digest(scenario);
    }
    crate::checkpoint::digest((scenario.to_toml() + &files).as_bytes())
}
