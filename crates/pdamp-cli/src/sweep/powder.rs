//! The `powder-study` and `powder-ensemble` kinds of sweep: one task per coupled DEM–FEM run
//! (value and packing), checkpointed in its folder.

use super::{absolute, install};
use anyhow::{Context, Result};
use pdamp_sweep::{SweepManifest, Task};
use std::path::Path;

/// Kind names of powder sweeps.
pub(super) const POWDER_STUDY_KIND: &str = "powder-study";
pub(super) const POWDER_ENSEMBLE_KIND: &str = "powder-ensemble";

/// What a powder sweep runs besides its scenario (kept in the manifest's `parameters`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub(crate) enum PowderSweep {
    /// `pdamp powder study`: one run per value (and packing).
    Study {
        /// [`pdamp_powder::study::StudyParameter::name`].
        parameter: String,
        /// Its values.
        values: Vec<f64>,
        /// Packings per value.
        packings: usize,
    },
    /// `pdamp powder run --packings K`.
    Ensemble {
        /// K.
        packings: usize,
    },
}

impl PowderSweep {
    fn kind(&self) -> &'static str {
        match self {
            PowderSweep::Study { .. } => POWDER_STUDY_KIND,
            PowderSweep::Ensemble { .. } => POWDER_ENSEMBLE_KIND,
        }
    }

    /// The runs below `dir`, in the order of the local command.
    pub(super) fn runs(
        &self,
        base: &pdamp_powder::cantilever::CantileverScenario,
        dir: &Path,
    ) -> Result<Vec<pdamp_powder::study::StudyRun>> {
        let runs = match self {
            PowderSweep::Study {
                parameter,
                values,
                packings,
            } => {
                let p = pdamp_powder::study::StudyParameter::from_name(parameter)
                    .with_context(|| format!("unknown study parameter '{parameter}'"))?;
                pdamp_powder::study::study_runs(base, p, values, *packings, dir)
            }
            PowderSweep::Ensemble { packings } => {
                pdamp_powder::study::ensemble_runs(base, *packings, dir)
            }
        };
        runs.map_err(anyhow::Error::msg)
    }
}

/// Makes (or opens) the sweep of a powder study or ensemble of `scenario` in `out`: one task
/// per run (value and packing), each checkpointed in its own folder.
pub(crate) fn create_powder(
    scenario: &Path,
    out: &Path,
    what: PowderSweep,
) -> Result<SweepManifest> {
    let text = std::fs::read_to_string(scenario)
        .with_context(|| format!("reading {}", scenario.display()))?;
    let base = pdamp_powder::cantilever::CantileverScenario::from_toml(&text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", scenario.display()))?;
    let runs = what.runs(&base, Path::new(""))?;
    let source = absolute(scenario);
    let manifest = SweepManifest {
        format: pdamp_sweep::SWEEP_FORMAT,
        pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
        kind: what.kind().into(),
        title: source
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned()),
        base_dir: source.parent().map(|p| p.to_path_buf()).unwrap_or_default(),
        scenario_source: source,
        scenario_digest: pdamp_powder::cantilever::scenario_digest(&base)
            .map_err(anyhow::Error::msg)?,
        parameters: serde_json::to_value(&what)?,
        tasks: runs
            .iter()
            .enumerate()
            .map(|(index, r)| Task {
                index,
                label: r.label.clone(),
                needs: vec![],
                result: r.dir.join("summary.json"),
                error: r.dir.join("error.txt"),
            })
            .collect(),
    };
    install(
        scenario,
        out,
        manifest,
        &[scenario.to_path_buf()],
        &crate::powder::OUTPUTS,
    )
}

/// Collects a powder study or ensemble: the tables, plots and ensemble statistics of the local
/// command, read from the finished runs.
pub(super) fn collect_powder(
    dir: &Path,
    base: &pdamp_powder::cantilever::CantileverScenario,
    what: &PowderSweep,
) -> Result<()> {
    let mut out_dir = pdamp_io::output_dir::OutputDir::open(
        dir,
        pdamp_io::output_dir::OutputMode::Continue,
        &crate::powder::OUTPUTS,
        &[],
    )?;
    // Every run is finished (checked above): nothing runs, everything is read back.
    let options = pdamp_powder::cantilever::RunOptions::new(0.0, false);
    let result: Result<serde_json::Value> = match what {
        PowderSweep::Study {
            parameter,
            values,
            packings,
        } => pdamp_powder::study::StudyParameter::from_name(parameter)
            .ok_or_else(|| anyhow::anyhow!("unknown study parameter '{parameter}'"))
            .and_then(|p| {
                pdamp_powder::study::run_study_packings(
                    base,
                    p,
                    values,
                    *packings,
                    dir,
                    options,
                    &mut |_, _| {},
                )
                .map_err(anyhow::Error::msg)
            })
            .map(|rows| serde_json::to_value(rows).unwrap_or_default()),
        PowderSweep::Ensemble { packings } => {
            pdamp_powder::study::run_ensemble(base, *packings, dir, options, &mut |_, _| {})
                .map_err(anyhow::Error::msg)
                .map(|e| serde_json::to_value(e).unwrap_or_default())
        }
    };
    out_dir.set_outcome(&result);
    out_dir.close()?;
    println!("{}", serde_json::to_string_pretty(&result?)?);
    Ok(())
}
