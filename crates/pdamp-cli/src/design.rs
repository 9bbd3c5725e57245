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
    /// Replace the results of an earlier run in DIR (exactly the files it wrote).
    #[arg(long)]
    overwrite: bool,
}

/// What `pdamp design` writes.
const OUTPUTS: [&str; 15] = [
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
    } = args;
    let traced = crate::Traced::start(Some(&study), 0);
    let s = crate::structure::in_out_dir(&out, false, overwrite, &OUTPUTS, &study, || {
        let s = pdamp_optimizer::run_design_study_file_with(&study, &out, &mut |m| {
            eprintln!("pdamp design: {m}")
        })
        .map_err(|e| anyhow!(e))?;
        traced.write(&out)?;
        Ok(s)
    })?;
    println!("{}", serde_json::to_string_pretty(&s["best"])?);
    eprintln!("wrote {}", out.join("report.md").display());
    Ok(())
}
