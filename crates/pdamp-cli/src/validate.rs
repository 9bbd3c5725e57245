//! `pdamp validate`: pdamp against the numbers of its references, as `validation.md` and
//! `validation.csv` (the table of `pdamp_validation`; docs/validation.md is its output); the
//! runs behind the rows are kept in `OUT/runs/`.

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
    /// Output directory (validation.md, validation.csv, provenance.json, runs/).
    #[arg(long)]
    out: PathBuf,
    /// Replace the results of an earlier run in OUT.
    #[arg(long)]
    overwrite: bool,
    /// The repository's examples folder (default: the one pdamp was built from).
    #[arg(long)]
    examples: Option<PathBuf>,
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
        &["validation.md", "validation.csv", "provenance.json", "runs"],
        &[],
    )?;
    let start = std::time::Instant::now();
    let mut ctx = pdamp_validation::Context::in_repository(&a.out.join("runs"));
    if let Some(e) = &a.examples {
        ctx.examples_dir = e.clone();
    }
    let rows = pdamp_validation::run(tier, &ctx);
    let command = if a.full {
        "pdamp validate --full"
    } else {
        "pdamp validate --quick"
    };
    // A full run's rows take minutes: its wall time goes into the table (the quick table stays
    // the same from run to run, docs/validation.md is compared with it).
    let run_line = a.full.then(|| {
        format!(
            "Wall time of this run: {:.0} s with {} threads.\n",
            start.elapsed().as_secs_f64(),
            rayon::current_num_threads()
        )
    });
    report::write_with(&a.out, &rows, tier, command, run_line.as_deref())?;
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
