//! `pdamp validate`: pdamp against the numbers of its references, as `validation.md` and
//! `validation.csv` (the table of `pdamp_validation`; docs/validation.md is its output).

use anyhow::Result;
use clap::Args;
use pdamp_validation::{Tier, report};
use std::path::PathBuf;

// The arguments of `pdamp validate` (the command's help is the variant's doc in `Command`).
#[derive(Args)]
pub(crate) struct ValidateArgs {
    /// Only the quick rows (closed forms, about a second); the default.
    #[arg(long, conflicts_with = "full")]
    quick: bool,
    /// Every registered row, simulations included.
    #[arg(long)]
    full: bool,
    /// Output directory (validation.md, validation.csv, provenance.json).
    #[arg(long)]
    out: PathBuf,
    /// Replace the results of an earlier run in OUT.
    #[arg(long)]
    overwrite: bool,
}

/// Runs `pdamp validate`: writes the table and prints its counts as JSON.
pub(crate) fn run(a: ValidateArgs) -> Result<()> {
    let tier = if a.full { Tier::Full } else { Tier::Quick };
    let traced = crate::Traced::start(None, 0);
    let mut dir = crate::outputs::open_out(
        &a.out,
        false,
        a.overwrite,
        None,
        &["validation.md", "validation.csv", "provenance.json"],
        &[],
    )?;
    let start = std::time::Instant::now();
    let rows = pdamp_validation::run(tier);
    let command = if a.full {
        "pdamp validate --full"
    } else {
        "pdamp validate --quick"
    };
    report::write(&a.out, &rows, tier, command)?;
    traced.write(&a.out)?;
    dir.set_status(pdamp_io::output_dir::RunStatus::Finished);
    dir.close()?;
    let (reproduced, not_reproduced, failed, not_run) = report::counts(&rows);
    let summary = serde_json::json!({
        "out": a.out.display().to_string(),
        "rows": rows.len(),
        "reproduced": reproduced,
        "not_reproduced": not_reproduced,
        "failed": failed,
        "not_run": not_run,
        "wall_time_s": start.elapsed().as_secs_f64(),
    });
    println!("{}", serde_json::to_string_pretty(&summary)?);
    Ok(())
}
