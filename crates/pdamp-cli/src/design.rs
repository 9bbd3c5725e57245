//! `pdamp design STUDY.toml --out DIR`: the design optimiser (library: `pdamp-optimizer`,
//! study file in docs/design.md).

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;

/// Arguments of `pdamp design`.
#[derive(Args)]
pub struct DesignArgs {
    /// Study file (TOML: scenario = "…free analysis…", [objective], [damper], [[materials]],
    /// [constraints], [search]).
    study: PathBuf,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Replace the results of an earlier run in DIR (exactly the files it wrote, the stored
    /// effective fields in DIR/fields included).
    #[arg(long)]
    overwrite: bool,
    /// Continue an earlier run in DIR: the search runs again (seconds) and every effective-field
    /// point stored in DIR/fields is reused; the coupled-DEM runs are made again.
    #[arg(long)]
    resume: bool,
}

/// What `pdamp design` writes.
const OUTPUTS: [&str; 17] = [
    "fields",
    "fields.csv",
    "dem",
    "dem.csv",
    "designs.csv",
    "summary.json",
    "report.md",
    "robustness.csv",
    "damping_curve.csv",
    "damping.png",
    "damping.svg",
    "decay.png",
    "decay.svg",
    "scenarios",
    "provenance.json",
    "input.toml",
    "failure.json",
];

/// Runs `pdamp design`.
pub fn run(args: DesignArgs) -> Result<()> {
    let DesignArgs {
        study,
        out,
        overwrite,
        resume,
    } = args;
    use pdamp_io::output_dir::{OutputDir, OutputMode};
    let mode = match (resume, overwrite) {
        (true, true) => anyhow::bail!("--resume and --overwrite exclude each other"),
        (true, false) => OutputMode::Continue,
        (false, true) => OutputMode::Overwrite,
        (false, false) => OutputMode::Fresh,
    };
    let traced = crate::Traced::start(Some(&study), 0);
    let mut dir = OutputDir::open(&out, mode, &OUTPUTS, &[study.as_path()])?;
    let s: Result<serde_json::Value> = (|| {
        let s = pdamp_optimizer::run_design_study_file_with(&study, &out, &mut |m| {
            eprintln!("pdamp design: {m}")
        })
        .map_err(|e| anyhow!(e))?;
        traced.write(&out)?;
        Ok(s)
    })();
    dir.set_outcome(&s);
    dir.close()?;
    let s = s?;
    println!("{}", serde_json::to_string_pretty(&s["best"])?);
    eprintln!("wrote {}", out.join("report.md").display());
    Ok(())
}
