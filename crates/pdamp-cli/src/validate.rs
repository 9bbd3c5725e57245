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
    /// Only the rows whose id starts with one of these prefixes (comma separated, e.g.
    /// `ch4.fe,ch8.tab8_3`); with --full their simulations run.
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
}

/// Runs `pdamp validate`: writes the table and prints its counts as JSON.
pub(crate) fn run(a: ValidateArgs) -> Result<()> {
    let tier = if a.full { Tier::Full } else { Tier::Quick };
    // every --only prefix must select a row (a typo would silently write an empty table)
    let ids: Vec<&str> = pdamp_validation::targets().iter().map(|t| t.id).collect();
    for p in &a.only {
        if !ids.iter().any(|id| id.starts_with(p.as_str())) {
            anyhow::bail!(
                "--only {p}: no row id starts with '{p}' (ids start with ch4. … ch8. or paper.; \
                 docs/validation.md lists them)"
            );
        }
    }
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
    let keep = |t: &pdamp_validation::Target| {
        a.only.is_empty() || a.only.iter().any(|p| t.id.starts_with(p.as_str()))
    };
    let rows = pdamp_validation::run_where(tier, &ctx, keep);
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
