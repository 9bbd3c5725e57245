//! `pdamp structure modes` and `pdamp couple`: the structural level [D Sect. 3.3] (library:
//! `pdamp-structure`, inputs in docs/structure.md).

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::{Args, Subcommand};

/// Arguments of `pdamp structure`.
#[derive(Args)]
pub struct StructureArgs {
    #[command(subcommand)]
    action: StructureAction,
}

#[derive(Subcommand)]
enum StructureAction {
    /// Builds and reduces a structure (beam FE, Matrix Market import, direct modal input or a
    /// single mode); writes DIR/modes.csv (mode,frequency_hz,damping_ratio,phi_<point>…) and
    /// DIR/summary.json.
    Modes {
        /// Structure file (TOML with a [structure] section).
        structure: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "out/structure")]
        out: PathBuf,
    },
}

/// Arguments of `pdamp couple`.
#[derive(Args)]
pub struct CoupleArgs {
    /// Coupling scenario (TOML: structure, [[dampers]], [analysis]).
    scenario: PathBuf,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Continue a full-DEM coupling (approach 1) from DIR/checkpoint.bin; the result equals an
    /// uninterrupted run.
    #[arg(long)]
    resume: bool,
    /// Wall-clock seconds between checkpoints of a full-DEM coupling (0 = only on Ctrl-C).
    #[arg(long, default_value_t = 60.0)]
    checkpoint_interval_s: f64,
}

/// Runs `pdamp structure …`.
pub fn run_structure(args: StructureArgs) -> Result<()> {
    match args.action {
        StructureAction::Modes { structure, out } => {
            let s = pdamp_structure::report::run_modes(&structure, &out).map_err(|e| anyhow!(e))?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("modes.csv").display());
            Ok(())
        }
    }
}

/// Runs `pdamp couple`.
pub fn run_couple(args: CoupleArgs) -> Result<()> {
    let bar = indicatif::ProgressBar::new(1000);
    let options = pdamp_io::run::RunOptions {
        checkpoint_interval_s: args.checkpoint_interval_s,
        resume: args.resume,
    };
    let s = pdamp_structure::report::run_couple(&args.scenario, &args.out, options, &mut |f| {
        bar.set_position((f * 1000.0) as u64)
    })
    .map_err(|e| anyhow!(e))?;
    bar.finish_and_clear();
    println!("{}", serde_json::to_string_pretty(&s)?);
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
