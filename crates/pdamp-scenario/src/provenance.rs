//! Where an output of a DEM scenario comes from: its `provenance.json`
//! ([`pdamp_io::provenance::Provenance`]) and the digests that key checkpoints and stored results
//! ([`scenario_digest`], [`scenario_content_digest`]).

use crate::schema::Scenario;
use pdamp_io::provenance::Provenance;
use std::path::Path;

/// Provenance of a run of `scenario` by this process.
pub fn of(scenario: &Scenario) -> Provenance {
    Provenance::with_digest(
        &scenario.title,
        scenario_digest(scenario),
        scenario.simulation.seed,
    )
}

/// Writes `dir/scenario.toml` (canonical) and `dir/provenance.json` of a run of `scenario` by
/// this process ([`of`]), atomically.
pub fn write(scenario: &Scenario, dir: &Path) -> Result<(), std::io::Error> {
    of(scenario).write_with_copy(dir, "scenario.toml", &scenario.to_toml())
}

/// Digest identifying a scenario in checkpoints and outputs (of its canonical TOML).
pub fn scenario_digest(scenario: &Scenario) -> String {
    pdamp_io::checkpoint::digest(scenario.to_toml().as_bytes())
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
            |b| pdamp_io::checkpoint::digest(&b),
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
    pdamp_io::checkpoint::digest((scenario.to_toml() + &files).as_bytes())
}
