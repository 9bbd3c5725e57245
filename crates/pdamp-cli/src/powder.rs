//! `pdamp powder …`: two-way coupled DEM–FEM for powder-filled cavities (library:
//! `pdamp-powder`, scenario keys and results in docs/powder.md).

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::{Args, Subcommand, ValueEnum};
use pdamp_powder::cantilever::{self, CantileverScenario};
use pdamp_powder::study::{self, StudyParameter};

/// Arguments of `pdamp powder`.
#[derive(Args)]
pub struct PowderArgs {
    #[command(subcommand)]
    action: PowderAction,
}

#[derive(Clone, Copy, ValueEnum)]
enum ParamArg {
    PackingDensity,
    StiffnessFactor,
    Friction,
    Restitution,
    SurfaceEnergy,
    D50,
    Orientation,
}

#[derive(Subcommand)]
enum PowderAction {
    /// Prepares the powder and runs the coupled cantilever; writes DIR/tip.csv, envelope.csv,
    /// energy.csv, summary.json (ζ1, ζ2, ζ̄5 of paper Table 1, iterations, wall time), tip.png.
    Run {
        /// Cantilever scenario (TOML, examples/powder_cantilever_*.toml).
        scenario: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Run on K independently prepared powder beds (seeds seed + 1 000 003 k) in
        /// DIR/packing_KKK/ and write DIR/ensemble.json (mean, std and 95 % CI of ζ1, ζ2, ζ̄5)
        /// and DIR/table.csv; resumable.
        #[arg(long, default_value_t = 1)]
        packings: usize,
        #[command(flatten)]
        ck: CheckpointArgs,
        /// `--backend slurm` (with --packings K): the packings as a sweep of Slurm array
        /// jobs (docs/cluster.md).
        #[command(flatten)]
        backend: crate::sweep::BackendArgs,
    },
    /// One cantilever run per value of a parameter (paper Figs. 2–6, Table 1); writes
    /// DIR/<param>_<value>/…, DIR/table.csv, DIR/decay.png, DIR/envelope.png. Resumable.
    Study {
        /// Base scenario.
        scenario: PathBuf,
        /// Varied parameter (orientation: 0 upright, 1 upside down, 2 horizontal).
        #[arg(long, value_enum)]
        parameter: ParamArg,
        /// Comma-separated values (SI; stiffness-factor multiplies k_N).
        #[arg(long, value_delimiter = ',', required = true)]
        values: Vec<f64>,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Run every value on K independently prepared powder beds (DIR/<param>_<value>/
        /// packing_KKK/); DIR/ensemble.csv gets the mean, std and 95 % CI of ζ1, ζ2, ζ̄5 per
        /// value.
        #[arg(long, default_value_t = 1)]
        packings: usize,
        #[command(flatten)]
        ck: CheckpointArgs,
        /// `--backend slurm`: every run (value and packing) a task of a sweep of Slurm array
        /// jobs (docs/cluster.md).
        #[command(flatten)]
        backend: crate::sweep::BackendArgs,
    },
    /// Eigenfrequencies of the empty beam of a scenario against Timoshenko beam theory.
    Modes {
        /// Scenario (only [beam] is used).
        scenario: PathBuf,
        /// Number of modes.
        #[arg(long, default_value_t = 4)]
        count: usize,
    },
}

/// The study parameter of a command-line choice.
fn param_of(p: ParamArg) -> StudyParameter {
    match p {
        ParamArg::PackingDensity => StudyParameter::PackingDensity,
        ParamArg::StiffnessFactor => StudyParameter::StiffnessFactor,
        ParamArg::Friction => StudyParameter::Friction,
        ParamArg::Restitution => StudyParameter::Restitution,
        ParamArg::SurfaceEnergy => StudyParameter::SurfaceEnergy,
        ParamArg::D50 => StudyParameter::D50,
        ParamArg::Orientation => StudyParameter::Orientation,
    }
}

/// A sweep continues by itself (every task resumes its checkpoint) and is started again by
/// deleting its directory: `--resume` and `--overwrite` do not apply.
fn refuse_with_slurm(ck: &CheckpointArgs) -> Result<()> {
    if ck.resume || ck.overwrite {
        return Err(anyhow!(
            "--backend slurm continues a sweep in DIR by itself (`pdamp sweep resubmit DIR`); --resume and --overwrite do not apply (delete DIR to start again)"
        ));
    }
    Ok(())
}

/// Checkpointing of `powder run` and of every run of `powder study`.
#[derive(Args, Clone, Copy)]
struct CheckpointArgs {
    /// Continue from DIR/checkpoint.bin (of a study: inside the interrupted run), written every
    /// --checkpoint-interval-s, after the preparation and on Ctrl-C; the results equal those of
    /// an uninterrupted run.
    #[arg(long)]
    resume: bool,
    /// Wall-clock seconds between checkpoints (0 = only on Ctrl-C/SIGTERM).
    #[arg(long, default_value_t = 60.0)]
    checkpoint_interval_s: f64,
    /// Replace the results of an earlier run in DIR (exactly the files it wrote; of a study:
    /// every run folder, also one of another scenario).
    #[arg(long, conflicts_with = "resume")]
    overwrite: bool,
}

/// What `pdamp powder run` and `study` write (checked for links and inputs).
pub(crate) const OUTPUTS: [&str; 16] = [
    "particles.pvd",
    "vtk",
    "tip.csv",
    "envelope.csv",
    "energy.csv",
    "summary.json",
    "tip.png",
    "tip.svg",
    "table.csv",
    "ensemble.json",
    "ensemble.csv",
    "decay.png",
    "envelope.png",
    "checkpoint.bin",
    "provenance.json",
    "input.toml",
];

impl CheckpointArgs {
    fn options(self) -> Result<cantilever::RunOptions> {
        if !(self.checkpoint_interval_s >= 0.0 && self.checkpoint_interval_s.is_finite()) {
            return Err(anyhow!(
                "--checkpoint-interval-s must be finite and ≥ 0 (0 = only on Ctrl-C/SIGTERM), got {}",
                self.checkpoint_interval_s
            ));
        }
        Ok(
            cantilever::RunOptions::new(self.checkpoint_interval_s, self.resume)
                .cancelled_by(crate::cancel()),
        )
    }
}

fn load(path: &PathBuf) -> Result<CantileverScenario> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    CantileverScenario::from_toml(&text).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// Opens the output directory of a command that continues its finished runs (a study, an
/// ensemble) unless `--overwrite` starts again.
fn open_continuing(
    out: &std::path::Path,
    ck: CheckpointArgs,
    scenario: &std::path::Path,
) -> Result<pdamp_io::output_dir::OutputDir> {
    Ok(pdamp_io::output_dir::OutputDir::open(
        out,
        if ck.overwrite {
            pdamp_io::output_dir::OutputMode::Overwrite
        } else {
            pdamp_io::output_dir::OutputMode::Continue
        },
        &OUTPUTS,
        &[scenario],
    )?)
}

/// Runs `pdamp powder …`.
pub fn run(args: PowderArgs) -> Result<()> {
    let bar = crate::progress::Progress::new();
    let mut progress = |stage: &str, f: f64| bar.set(stage, f);
    match args.action {
        PowderAction::Run {
            scenario,
            out,
            packings,
            ck,
            backend,
        } if backend.backend == Some(crate::sweep::Backend::Slurm) => {
            refuse_with_slurm(&ck)?;
            if packings < 2 {
                return Err(anyhow!(
                    "--backend slurm runs the packings of an ensemble as a sweep: give --packings K (K ≥ 2); a single run is one job (`sbatch --wrap \"pdamp powder run …\"`)"
                ));
            }
            bar.finish();
            crate::sweep::create_powder(
                &scenario,
                &out,
                crate::sweep::PowderSweep::Ensemble { packings },
            )?;
            crate::sweep::submit(&out, &backend)?;
        }
        PowderAction::Run { backend, .. } | PowderAction::Study { backend, .. }
            if backend.any_slurm_option()
                && backend.backend != Some(crate::sweep::Backend::Slurm) =>
        {
            return Err(anyhow!(
                "the Slurm options (--partition, --throttle, …) need --backend slurm"
            ));
        }
        PowderAction::Study {
            scenario,
            parameter,
            values,
            out,
            packings,
            ck,
            backend,
        } if backend.backend == Some(crate::sweep::Backend::Slurm) => {
            refuse_with_slurm(&ck)?;
            bar.finish();
            crate::sweep::create_powder(
                &scenario,
                &out,
                crate::sweep::PowderSweep::Study {
                    parameter: param_of(parameter).name().to_string(),
                    values,
                    packings,
                },
            )?;
            crate::sweep::submit(&out, &backend)?;
        }
        PowderAction::Run {
            scenario,
            out,
            packings,
            ck,
            ..
        } if packings != 1 => {
            let sc = load(&scenario)?;
            let traced = crate::Traced::start(Some(&scenario), study::seed_of(&sc));
            let options = ck.options()?;
            // An ensemble continues its finished packings (each checked against its scenario).
            let mut dir = open_continuing(&out, ck, &scenario)?;
            let e = study::run_ensemble(&sc, packings, &out, options, &mut progress)
                .map_err(anyhow::Error::msg)
                .and_then(|r| traced.write(&out).map(|()| r));
            dir.set_outcome(&e);
            dir.close()?;
            let e = e?;
            bar.finish();
            println!("{}", serde_json::to_string_pretty(&e)?);
            eprintln!("wrote {}", out.join("ensemble.json").display());
        }
        PowderAction::Run {
            scenario, out, ck, ..
        } => {
            let sc = load(&scenario)?;
            let traced = crate::Traced::start(Some(&scenario), study::seed_of(&sc));
            let options = ck.options()?;
            let mut dir = crate::outputs::open_out(
                &out,
                ck.resume,
                ck.overwrite,
                Some(pdamp_io::checkpoint::CHECKPOINT_FILE),
                &OUTPUTS,
                &[scenario.as_path()],
            )?;
            let r = cantilever::run_in_dir(&sc, &out, options, &mut progress)
                .map_err(anyhow::Error::msg)
                .and_then(|r| traced.write(&out).map(|()| r));
            dir.set_outcome(&r);
            dir.close()?;
            let r = r?;
            bar.finish();
            println!("{}", serde_json::to_string_pretty(&r)?);
            eprintln!("wrote {}", out.display());
        }
        PowderAction::Study {
            scenario,
            parameter,
            values,
            out,
            packings,
            ck,
            ..
        } => {
            let sc = load(&scenario)?;
            let traced = crate::Traced::start(Some(&scenario), study::seed_of(&sc));
            let options = ck.options()?;
            let p = param_of(parameter);
            // A study continues its finished runs (each checked against its scenario).
            let mut dir = open_continuing(&out, ck, &scenario)?;
            let rows =
                study::run_study_packings(&sc, p, &values, packings, &out, options, &mut progress)
                    .map_err(anyhow::Error::msg)
                    .and_then(|r| traced.write(&out).map(|()| r));
            dir.set_outcome(&rows);
            dir.close()?;
            let rows = rows?;
            bar.finish();
            println!("{}", serde_json::to_string_pretty(&rows)?);
            eprintln!("wrote {}", out.join("table.csv").display());
        }
        PowderAction::Modes { scenario, count } => {
            let sc = load(&scenario)?;
            let f = cantilever::empty_beam_modes(&sc.beam, count).map_err(anyhow::Error::msg)?;
            let timo = cantilever::timoshenko_reference(&sc.beam);
            bar.finish();
            println!(
                "{}",
                serde_json::to_string_pretty(
                    &serde_json::json!({ "frequencies_hz": f, "timoshenko_f1_hz": timo, "dofs": 3 * sc.beam.mesh().nodes.len() })
                )?
            );
        }
    }
    Ok(())
}
