//! The command line: the `pdamp` arguments and subcommands (clap), with negative numbers
//! accepted as option values.

use crate::dem_commands::{Device, PointArgs};
use crate::{bench, cor, design, impact, powder, structure, sweep, validate};
use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "pdamp",
    version,
    about = "Particle damper simulation and design toolkit"
)]
pub(crate) struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    pub(crate) threads: Option<usize>,
    /// Run even beyond the soft limits of the estimate (available memory, output size,
    /// frames, rows, a month of run time); the limits of the machine stay.
    #[arg(long, global = true)]
    pub(crate) force: bool,
    /// No progress output (bars on a terminal, lines every few seconds elsewhere).
    #[arg(long, global = true)]
    pub(crate) quiet: bool,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Run a DEM scenario from a TOML file; writes summary.json, energy.csv and VTK files.
    Run {
        /// Scenario file (TOML); `builtin:shaken-box` runs the built-in example.
        scenario: String,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Continue from DIR/checkpoint.bin (written every --checkpoint-interval-s and on
        /// Ctrl-C); the results equal those of an uninterrupted run.
        #[arg(long)]
        resume: bool,
        /// Replace the results of an earlier run in DIR (exactly the files it wrote).
        #[arg(long, conflicts_with = "resume")]
        overwrite: bool,
        /// Wall-clock seconds between checkpoints (0 = only on Ctrl-C).
        #[arg(long, default_value_t = 60.0)]
        checkpoint_interval_s: f64,
        #[command(flatten)]
        point: PointArgs,
    },
    /// Effective fields of a damper scenario over its [fields] grid (resumable): writes
    /// DIR/fields.csv and PNG/SVG maps of η̄, m̄_bed/m_bed and the dissipated energy.
    Fields {
        /// Scenario file (TOML) with [damper] and [fields] sections.
        scenario: PathBuf,
        /// Output directory (finished points in DIR/points/ are reused).
        #[arg(long)]
        out: PathBuf,
        /// Where the points run: `cpu` (points in parallel on the threads) or `gpu` (the
        /// pending points as batches of worlds on the GPU backend; beds are prepared on the CPU).
        #[arg(long, value_enum, default_value_t = Device::Cpu)]
        device: Device,
        /// Start again: remove the points and maps of an earlier run in DIR first.
        #[arg(long)]
        overwrite: bool,
        /// `--backend slurm`: the field as a sweep of Slurm array jobs (docs/cluster.md);
        /// `pdamp sweep status|collect DIR` follow and collect it.
        #[command(flatten)]
        backend: sweep::BackendArgs,
    },
    /// Sweeps: a field's points (and packings) as tasks run here or as Slurm array jobs —
    /// new, submit, status, resubmit, collect (docs/cluster.md).
    Sweep {
        #[command(subcommand)]
        command: sweep::SweepCommand,
    },
    /// Prepare the bed of a scenario (drop-down and settling) and save it: DIR/bed.pdbed (exact
    /// continuation, `placement = { method = "file", path = "DIR/bed.pdbed" }`), bed.csv,
    /// bed.data (LAMMPS/LIGGGHTS read_data), bed.vtp and summary.json with its statistics.
    Settle {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Packing index k of an ensemble (seed = simulation.seed + 1 000 003 k).
        #[arg(long, default_value_t = 0)]
        packing: usize,
        /// Replace the results of an earlier run in DIR (exactly the files it wrote).
        #[arg(long)]
        overwrite: bool,
    },
    /// Load, validate and build a scenario without running it; prints what would run as JSON
    /// (particles, masses, shortest contact time, time-step ratio, damper grid).
    Check {
        /// Scenario file (TOML).
        scenario: PathBuf,
    },
    /// Print a shell completion script: `pdamp completions bash > ~/.local/share/bash-completion/completions/pdamp`
    /// (zsh: into a folder of `$fpath` as `_pdamp`; fish: `~/.config/fish/completions/pdamp.fish`).
    Completions {
        /// Shell.
        shell: clap_complete::Shell,
    },
    /// Print the built-in example scenario as TOML.
    Example {
        /// Number of particles.
        #[arg(long, default_value_t = 2000)]
        particles: usize,
        /// Shaking duration, s.
        #[arg(long, default_value_t = 0.5)]
        duration_s: f64,
    },
    /// Single head-on impact; prints measured and Hertz-theory values as JSON.
    Impact(impact::ImpactArgs),
    /// Coefficient of restitution ε(v) from impact models (FE, Hertz, Thornton, viscoelastic);
    /// writes DIR/cor.csv (velocity_m_s,restitution,contact_time_s,max_force_n), a gonthier-table
    /// snippet and a plot.
    Cor(cor::CorArgs),
    /// Structural level: `pdamp structure modes STRUCTURE.toml` writes modes.csv.
    Structure(structure::StructureArgs),
    /// Particle dampers coupled to a structure (full DEM, effective fields or formulas): free
    /// decay (decay.csv, damping.csv), sweeps or steady-state FRFs (frf.csv), summary.json, plots.
    Couple(structure::CoupleArgs),
    /// Design optimiser: from a structure and a target to a verified damper (envelope screening,
    /// time-simulation verification); writes DIR/designs.csv, report.md, summary.json, plots and
    /// ready-to-run scenarios/design_N.toml (docs/design.md).
    Design(design::DesignArgs),
    /// Powder-filled cavities, two-way coupled DEM–FEM (docs/powder.md): run, study, modes.
    Powder(powder::PowderArgs),
    /// Shaken-box benchmark; prints particle-timesteps per second as JSON.
    Bench(bench::BenchArgs),
    /// pdamp against the numbers of the dissertation and the DEM–FEM paper: writes
    /// validation.md and validation.csv (docs/validation.md is its output).
    Validate(validate::ValidateArgs),
}

/// `pdamp` with `--opt -1` accepted as a value in every subcommand (clap takes `-1` for an
/// option otherwise and asks for `--opt=-1`); a negative value where none is allowed gets the
/// option's own range error.
pub(crate) fn cli_command() -> clap::Command {
    fn negative_numbers(cmd: clap::Command) -> clap::Command {
        let names: Vec<String> = cmd
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect();
        names
            .into_iter()
            .fold(cmd.allow_negative_numbers(true), |c, n| {
                c.mut_subcommand(n, negative_numbers)
            })
    }
    negative_numbers(<Cli as clap::CommandFactory>::command())
}

/// `--opt -1e-3` → `--opt=-1e-3`: an option followed by a negative number (or a comma list of
/// numbers starting with one) takes it as its value; clap alone reads `-1e-3` as short flags.
pub(crate) fn negative_values(args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let is_negative_number = |a: &std::ffi::OsString| {
        a.to_str().is_some_and(|s| {
            s.starts_with('-')
                && s.split(',')
                    .all(|x| !x.is_empty() && x.trim().parse::<f64>().is_ok())
        })
    };
    let mut out: Vec<std::ffi::OsString> = Vec::with_capacity(args.len());
    let mut it = args.into_iter().peekable();
    while let Some(a) = it.next() {
        let is_long = a
            .to_str()
            .is_some_and(|s| s.starts_with("--") && s.len() > 2 && !s.contains('='));
        match it.peek() {
            Some(next) if is_long && is_negative_number(next) => {
                let mut joined = a;
                joined.push("=");
                joined.push(it.next().unwrap_or_default());
                out.push(joined);
            }
            _ => out.push(a),
        }
    }
    out
}
