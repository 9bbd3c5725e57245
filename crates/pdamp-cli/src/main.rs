//! `pdamp` — particle damper simulation and design from the command line.
//!
//! A thin layer: every command parses its arguments, calls one library function and reports.

#![forbid(unsafe_code)]
// The argument docs are the `--help` texts (TOML sections such as [fields], file patterns such
// as DIR/<param>_<value>), written for the terminal, not for rustdoc.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use anyhow::{Context, Result, anyhow, bail};
use clap::{Parser, Subcommand, ValueEnum};
use pdamp_dem::Material;
use pdamp_dem::impact::{ImpactLaw, ImpactRequest, Partner, checked_head_on_impact};
use std::path::PathBuf;

mod cor;
mod design;
#[cfg(feature = "gpu")]
mod gpu;
mod powder;
mod progress;
mod structure;
mod sweep;

#[derive(Parser)]
#[command(
    name = "pdamp",
    version,
    about = "Particle damper simulation and design toolkit"
)]
struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Run even beyond the soft limits of the estimate (available memory, output size,
    /// frames, rows, a month of run time); the limits of the machine stay.
    #[arg(long, global = true)]
    force: bool,
    /// No progress output (bars on a terminal, lines every few seconds elsewhere).
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
    Impact {
        /// Impact partner.
        #[arg(long, value_enum, default_value_t = PartnerArg::Wall)]
        partner: PartnerArg,
        /// Sphere radius, m.
        #[arg(long)]
        radius_m: f64,
        /// Young's modulus, Pa.
        #[arg(long)]
        youngs_modulus_pa: f64,
        /// Poisson's ratio.
        #[arg(long)]
        poisson_ratio: f64,
        /// Density, kg/m³.
        #[arg(long)]
        density_kg_m3: f64,
        /// Normal contact law.
        #[arg(long, value_enum, default_value_t = LawArg::Hertz)]
        law: LawArg,
        /// Coefficient of restitution (dissipative laws).
        #[arg(long, default_value_t = 1.0)]
        restitution: f64,
        /// Normal stiffness for the linear law, N/m (default: Hertz secant stiffness at max overlap).
        #[arg(long)]
        stiffness_n_m: Option<f64>,
        /// Impact velocity, m/s.
        #[arg(long)]
        velocity_m_s: f64,
    },
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
    Bench {
        /// Number of particles.
        #[arg(long, default_value_t = 8000)]
        particles: usize,
        /// Timed steps.
        #[arg(long, default_value_t = 2000)]
        steps: u64,
        /// Reuse the settled bed stored in this file (settle and store it if missing).
        #[arg(long)]
        settled: Option<PathBuf>,
        /// Also write a LIGGGHTS case of the same run into this folder (bench/peers).
        #[arg(long)]
        export_liggghts: Option<PathBuf>,
        /// Print the energy balance of the timed steps too (peer comparison).
        #[arg(long)]
        peer: bool,
        /// Where the steps run: `cpu` (the reference engine) or `gpu` (the wgpu/Vulkan
        /// backend; lavapipe counts as a GPU driver).
        #[arg(long, value_enum, default_value_t = Device::Cpu)]
        device: Device,
        /// GPU: independent shaken boxes advanced together (the points of a field).
        #[arg(long, default_value_t = 1)]
        batch: usize,
        /// GPU: steps of settling with the boxes at rest before the timed steps (not timed).
        #[arg(long, default_value_t = 10_000)]
        settle_steps: u64,
    },
}

/// Where DEM steps run.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
enum Device {
    /// The CPU engine (pdamp-dem).
    Cpu,
    /// The GPU backend (pdamp-gpu).
    Gpu,
}

/// Excitation of a damper scenario given on the command line (overrides `[damper]`).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
struct PointArgs {
    /// Excitation frequency f, Hz (damper scenarios).
    #[arg(long)]
    frequency_hz: Option<f64>,
    /// Displacement amplitude X, m (damper scenarios; one of X, A, Γ).
    #[arg(long, conflicts_with_all = ["acceleration_m_s2", "intensity"])]
    amplitude_m: Option<f64>,
    /// Acceleration amplitude A, m/s² (damper scenarios).
    #[arg(long, conflicts_with = "intensity")]
    acceleration_m_s2: Option<f64>,
    /// Intensity Γ = A/g (damper scenarios).
    #[arg(long)]
    intensity: Option<f64>,
    /// Independently prepared beds (an ensemble: mean, spread and 95 % confidence interval);
    /// overrides `[damper] packings`.
    #[arg(long)]
    packings: Option<usize>,
}

impl PointArgs {
    fn any(&self) -> bool {
        self.frequency_hz.is_some()
            || self.amplitude_m.is_some()
            || self.acceleration_m_s2.is_some()
            || self.intensity.is_some()
            || self.packings.is_some()
    }

    /// Puts the point into the scenario's `[damper]` and validates it again.
    fn apply(&self, sc: &mut pdamp_io::scenario::Scenario) -> Result<()> {
        if !self.any() {
            return Ok(());
        }
        let Some(d) = sc.damper.as_mut() else {
            bail!(
                "--frequency-hz/--amplitude-m/--acceleration-m-s2/--intensity/--packings need a scenario with a [damper] section"
            );
        };
        if let Some(f) = self.frequency_hz {
            d.frequency_hz = Some(f);
        }
        if let Some(k) = self.packings {
            d.packings = k;
        }
        if self.amplitude_m.is_some()
            || self.acceleration_m_s2.is_some()
            || self.intensity.is_some()
        {
            d.amplitude_m = self.amplitude_m;
            d.acceleration_m_s2 = self.acceleration_m_s2;
            d.intensity = self.intensity;
        }
        sc.validate()
            .map_err(|e| anyhow::anyhow!("command-line excitation: {e}"))
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum PartnerArg {
    Wall,
    Sphere,
}

#[derive(Clone, Copy, ValueEnum)]
enum LawArg {
    Hertz,
    Gonthier,
    LankaraniNikravesh,
    Linear,
    HertzMindlin,
}

/// `provenance.json` (and a copy of the input file as `input.toml`) for a command whose input
/// is not a DEM scenario: call [`Traced::start`] before the work, [`Traced::write`] after it.
pub(crate) struct Traced {
    provenance: pdamp_io::provenance::Provenance,
    input: Option<String>,
}

impl Traced {
    /// Records the start of a command reading `input` (a file) with random seed `seed`.
    pub(crate) fn start(input: Option<&std::path::Path>, seed: u64) -> Self {
        let text = input.and_then(|p| std::fs::read_to_string(p).ok());
        let title = input.map_or_else(String::new, |p| p.display().to_string());
        Self {
            provenance: pdamp_io::provenance::Provenance::of_input(&title, text.as_deref(), seed),
            input: text,
        }
    }

    /// Writes `out/provenance.json` and `out/input.toml`.
    pub(crate) fn write(&self, out: &std::path::Path) -> Result<()> {
        self.provenance
            .write_input(out, self.input.as_deref())
            .with_context(|| format!("writing the provenance into {}", out.display()))
    }
}

fn main() -> std::process::ExitCode {
    // Ctrl-C / SIGTERM: long runs write a checkpoint and stop (see `--resume`).
    let _ = ctrlc::set_handler(pdamp_io::checkpoint::on_signal);
    match run_cli() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            if format!("{e}").starts_with(pdamp_io::checkpoint::INTERRUPTED) {
                std::process::ExitCode::from(130)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}

/// `pdamp` with `--opt -1` accepted as a value in every subcommand (clap takes `-1` for an
/// option otherwise and asks for `--opt=-1`); a negative value where none is allowed gets the
/// option's own range error.
fn cli_command() -> clap::Command {
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
fn negative_values(args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
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

fn run_cli() -> Result<()> {
    let args = negative_values(std::env::args_os().collect());
    let cli = match <Cli as clap::FromArgMatches>::from_arg_matches(
        &cli_command().get_matches_from(args),
    ) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    pdamp_io::estimate::set_force(cli.force);
    progress::set_quiet(cli.quiet);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = match cli.threads {
        Some(0) => bail!("--threads must be >= 1 (leave it out to use all {cores} cores)"),
        Some(t) if t > 4 * cores && t > 16 => bail!(
            "--threads {t} is more than 4 × the {cores} cores of this machine; use at most {} (results do not depend on the thread count)",
            (4 * cores).max(16)
        ),
        Some(t) => t,
        None => 0,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .context("cannot start the thread pool")?;
    // The whole command runs on a worker of the pool: the parallel loops of the time step start
    // on the thread that calls them instead of waking a worker and putting the caller to sleep
    // at every loop (with one thread nothing crosses threads at all).
    rayon::scope(|_| dispatch(cli.command))
}

fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Run {
            scenario,
            out,
            resume,
            overwrite,
            checkpoint_interval_s,
            point,
        } => {
            if !(checkpoint_interval_s.is_finite() && checkpoint_interval_s >= 0.0) {
                bail!(
                    "--checkpoint-interval-s must be a finite number of seconds >= 0 (0 = only on Ctrl-C), got {checkpoint_interval_s}"
                );
            }
            cmd_run(
                &scenario,
                &out,
                pdamp_io::run::RunOptions {
                    checkpoint_interval_s,
                    resume,
                },
                overwrite,
                point,
            )
        }
        Command::Fields {
            scenario,
            out,
            device,
            overwrite,
            backend,
        } => match backend.backend {
            Some(sweep::Backend::Slurm) => {
                if device != Device::Cpu || overwrite {
                    bail!(
                        "--backend slurm runs the points on the CPUs of the cluster's nodes and continues a sweep in DIR; --device gpu and --overwrite do not apply (delete DIR to start again)"
                    );
                }
                sweep::create(&scenario, &out)?;
                sweep::submit(&out, &backend)
            }
            _ => {
                if backend.any_slurm_option() {
                    bail!(
                        "the Slurm options (--partition, --time, --throttle, …) need --backend slurm"
                    );
                }
                cmd_fields(&scenario, &out, device, overwrite)
            }
        },
        Command::Sweep { command } => sweep::dispatch(command),
        Command::Check { scenario } => cmd_check(&scenario),
        Command::Completions { shell } => {
            // Into a buffer first: a closed pipe (`| head`) is not an error worth a panic.
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut cli_command(), "pdamp", &mut script);
            use std::io::Write;
            match std::io::stdout().write_all(&script) {
                Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
                _ => Ok(()),
            }
        }
        Command::Settle {
            scenario,
            out,
            packing,
            overwrite,
        } => cmd_settle(&scenario, &out, packing, overwrite),
        Command::Example {
            particles,
            duration_s,
        } => {
            if !(1..=100_000_000).contains(&particles) {
                bail!("--particles must lie in 1..=100000000, got {particles}");
            }
            if !(duration_s.is_finite() && duration_s >= 0.0) {
                bail!("--duration-s must be a finite time >= 0 in seconds, got {duration_s}");
            }
            print!(
                "{}",
                pdamp_io::examples::shaken_box(particles, duration_s).to_toml()
            );
            Ok(())
        }
        Command::Impact {
            partner,
            radius_m,
            youngs_modulus_pa,
            poisson_ratio,
            density_kg_m3,
            law,
            restitution,
            stiffness_n_m,
            velocity_m_s,
        } => {
            let req = ImpactRequest {
                partner: match partner {
                    PartnerArg::Wall => Partner::Wall,
                    PartnerArg::Sphere => Partner::Sphere,
                },
                radius_m,
                material: Material::new(
                    "material",
                    density_kg_m3,
                    youngs_modulus_pa,
                    poisson_ratio,
                ),
                law: match law {
                    LawArg::Hertz => ImpactLaw::Hertz,
                    LawArg::Gonthier => ImpactLaw::Gonthier,
                    LawArg::LankaraniNikravesh => ImpactLaw::LankaraniNikravesh,
                    LawArg::Linear => ImpactLaw::Linear,
                    LawArg::HertzMindlin => ImpactLaw::HertzMindlin,
                },
                restitution,
                stiffness_n_m,
                velocity_m_s,
            };
            // The library names the input; the command line prints it as its flag.
            let r = checked_head_on_impact(&req).map_err(|e| match e.key {
                "result" | "material" => anyhow!("{}", e.message),
                key => anyhow!("--{} {}", key.replace('_', "-"), e.message),
            })?;
            println!("{}", serde_json::to_string_pretty(&r)?);
            Ok(())
        }
        Command::Cor(args) => cor::run(args),
        Command::Structure(args) => structure::run_structure(args),
        Command::Couple(args) => structure::run_couple(args),
        Command::Design(args) => design::run(args),
        Command::Powder(args) => powder::run(args),
        Command::Bench {
            particles,
            steps,
            settled,
            export_liggghts,
            peer,
            device,
            batch,
            settle_steps,
        } => {
            if device == Device::Gpu {
                #[cfg(feature = "gpu")]
                {
                    if peer || settled.is_some() || export_liggghts.is_some() || batch == 0 {
                        bail!(
                            "--device gpu takes --particles, --steps, --batch (≥ 1) and --settle-steps only"
                        );
                    }
                    let r = gpu::bench(particles, steps, batch, settle_steps)?;
                    println!("{}", serde_json::to_string_pretty(&r)?);
                    return Ok(());
                }
                #[cfg(not(feature = "gpu"))]
                {
                    let _ = (batch, settle_steps);
                    bail!("this pdamp was built without the `gpu` feature");
                }
            }
            if batch != 1 {
                bail!("--batch needs --device gpu");
            }
            bench_limits(particles, steps)?;
            if !peer && settled.is_none() && export_liggghts.is_none() {
                let r = pdamp_io::bench::shaken_box_bench(particles, steps)
                    .map_err(anyhow::Error::msg)?;
                println!(
                    "{}",
                    serde_json::to_string_pretty(&serde_json::json!({
                        "particles": r.particles,
                        "steps": r.steps,
                        "threads": rayon::current_num_threads(),
                        "wall_time_s": r.wall_time_s,
                        "particle_steps_per_s": r.particle_steps_per_s,
                        "neighbor_builds": r.neighbor_builds,
                        "contacts_pp": r.contacts_pp,
                        "settling_wall_time_s": r.settling_wall_time_s,
                    }))?
                );
                return Ok(());
            }
            let mut world = pdamp_io::bench::settled_shaken_box(particles, settled.as_deref())
                .map_err(anyhow::Error::msg)?;
            if let Some(dir) = &export_liggghts {
                pdamp_io::bench::write_liggghts_case(&world, steps, dir)
                    .map_err(anyhow::Error::msg)?;
            }
            let r = pdamp_io::bench::run_peer(&mut world, steps);
            println!("{}", serde_json::to_string_pretty(&r)?);
            Ok(())
        }
    }
}

/// Files and folders the DEM commands write into their output directory (checked for
/// symbolic links and for inputs they would replace before anything is written).
const RUN_OUTPUTS: [&str; 25] = [
    "input.toml",
    "sweep.json",
    "sweep",
    "beds",
    "energy.png",
    "energy.svg",
    "scenario.toml",
    "provenance.json",
    "summary.json",
    "energy.csv",
    "particles.pvd",
    "vtk",
    "checkpoint.bin",
    "bed_statistics.json",
    "failure.json",
    "velocity_fields.csv",
    "trajectories.csv",
    "packings",
    "points",
    "fields.csv",
    "force_displacement.csv",
    "force_time.png",
    "force_time.svg",
    "hysteresis.png",
    "hysteresis.svg",
];

/// `DIR/input.toml`: a verbatim copy of the input file, in every command's output directory
/// (the DEM commands add `scenario.toml`, the scenario as run with every default filled in).
fn copy_input(out: &std::path::Path, input: &std::path::Path) -> Result<()> {
    let bytes = std::fs::read(input).with_context(|| format!("reading {}", input.display()))?;
    pdamp_io::atomic::write_atomic(out.join("input.toml"), &bytes)
        .with_context(|| format!("writing {}", out.join("input.toml").display()))
}

/// Opens the output directory of a command (see [`pdamp_io::output_dir`]): `resume` continues
/// an earlier run that left `checkpoint` in it (with nothing to continue in an empty
/// directory the run starts, with a note; a directory with results but no checkpoint is
/// refused), `overwrite` replaces an earlier run, neither refuses a directory with results.
pub(crate) fn open_out(
    out: &std::path::Path,
    resume: bool,
    overwrite: bool,
    checkpoint: Option<&str>,
    outputs: &[&str],
    inputs: &[&std::path::Path],
) -> Result<pdamp_io::output_dir::OutputDir> {
    use pdamp_io::output_dir::{OutputDir, OutputMode};
    let mode = match (resume, overwrite) {
        (true, true) => bail!("--resume and --overwrite exclude each other"),
        (false, true) => OutputMode::Overwrite,
        (false, false) => OutputMode::Fresh,
        (true, false) => {
            let has_checkpoint = checkpoint.is_some_and(|c| out.join(c).is_file());
            let killed_same = pdamp_io::output_dir::read_manifest(out).is_some_and(|m| {
                m.status == pdamp_io::output_dir::RunStatus::Running
                    && same_command(&m.command, &std::env::args().collect::<Vec<_>>())
            });
            if has_checkpoint {
                OutputMode::Continue
            } else if killed_same {
                // The same command was killed before its first checkpoint: nothing to continue,
                // its partial outputs are replaced by a new run.
                eprintln!(
                    "note: nothing to resume in {} (the run was killed before its first checkpoint): starting it again",
                    out.display()
                );
                OutputMode::Overwrite
            } else {
                // Refused below if there are results; otherwise nothing was started yet.
                match OutputDir::open(out, OutputMode::Fresh, outputs, inputs) {
                    Ok(d) => {
                        eprintln!(
                            "note: nothing to resume in {} (no checkpoint): starting the run",
                            out.display()
                        );
                        return Ok(d);
                    }
                    Err(pdamp_io::output_dir::OutputDirError::HasResults { what, .. }) => {
                        bail!(
                            "--resume: {} holds results ({what}) but no {}: the run was killed before its first checkpoint or cannot be continued; nothing to resume. Use --overwrite to start it again",
                            out.display(),
                            checkpoint.unwrap_or("checkpoint")
                        )
                    }
                    Err(e) => return Err(e.into()),
                }
            }
        }
    };
    Ok(OutputDir::open(out, mode, outputs, inputs)?)
}

/// Whether two command lines run the same command on the same input (the subcommand and the
/// argument after it), whatever their options.
fn same_command(a: &[String], b: &[String]) -> bool {
    const COMMANDS: [&str; 8] = [
        "run",
        "fields",
        "settle",
        "couple",
        "powder",
        "structure",
        "cor",
        "bench",
    ];
    let key = |c: &[String]| {
        c.iter()
            .position(|t| COMMANDS.contains(&t.as_str()))
            .map(|k| (c[k].clone(), c.get(k + 1).cloned()))
    };
    key(a).is_some() && key(a) == key(b)
}

/// The scenario file and the files it reads (meshes, beds): inputs no output may replace.
fn scenario_inputs(
    scenario: &std::path::Path,
    sc: &pdamp_io::scenario::Scenario,
) -> Vec<std::path::PathBuf> {
    let base = scenario
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default();
    std::iter::once(scenario.to_path_buf())
        .chain(sc.referenced_files().into_iter().map(|f| base.join(f)))
        .collect()
}

/// `DIR/energy.png` and `.svg` of a plain run: the terms of the energy ledger over time
/// (kinetic, potential and elastic energy as changes from the start, work of the walls,
/// dissipation and the balance residual W − ΔE − D, which stays at zero in a healthy run).
fn energy_plot(out: &std::path::Path) -> Result<()> {
    use pdamp_plot::{Axis, LinePlot, Series, line_plot};
    let (_, rows) =
        pdamp_io::csv::read_csv_f64(out.join("energy.csv")).map_err(|e| anyhow!("output: {e}"))?;
    let Some(first) = rows.first() else {
        return Ok(());
    };
    let col = |k: usize| -> Vec<f64> { rows.iter().map(|r| r[k]).collect() };
    let delta = |k: usize| -> Vec<f64> { rows.iter().map(|r| r[k] - first[k]).collect() };
    let t = col(0);
    let dissipated: Vec<f64> = rows.iter().map(|r| r[5] + r[6]).collect();
    let residual: Vec<f64> = rows
        .iter()
        .map(|r| r[4] - (r[1] - first[1]) - (r[2] - first[2]) - (r[3] - first[3]) - (r[5] + r[6]))
        .collect();
    let mut plot = LinePlot::new(Axis::linear("time (s)"), Axis::linear("energy (J)"));
    plot.title = "energy ledger".to_string();
    for (label, y) in [
        ("kinetic − initial", delta(1)),
        ("potential − initial", delta(2)),
        ("elastic − initial", delta(3)),
        ("work of the walls", col(4)),
        ("dissipated", dissipated),
        ("balance residual", residual),
    ] {
        plot.series.push(Series::new(label, t.clone(), y));
    }
    line_plot(out.join("energy"), &plot)
        .map(|_| ())
        .map_err(|e| anyhow!("output: {e}"))
}

/// `pdamp bench`: the shaken box's size and length within the machine (see
/// [`pdamp_io::estimate`]).
fn bench_limits(particles: usize, steps: u64) -> Result<()> {
    if particles == 0 || steps == 0 {
        bail!("--particles and --steps must be >= 1");
    }
    let mut sc = pdamp_io::examples::shaken_box(particles.min(1000), 0.0);
    if let Some(g) = sc.particles.first_mut() {
        g.count = Some(particles);
    }
    sc.simulation.duration_s = steps as f64 * sc.simulation.time_step_s;
    sc.output.vtk_interval_s = 0.0;
    sc.output.energy_interval_s = sc.simulation.duration_s.max(1e-12);
    pdamp_io::estimate::Estimate::of(&sc, 1, rayon::current_num_threads())
        .check()
        .map_err(|e| anyhow::anyhow!("--particles/--steps: {e}"))
}

fn cmd_run(
    scenario: &str,
    out: &std::path::Path,
    options: pdamp_io::run::RunOptions,
    overwrite: bool,
    point: PointArgs,
) -> Result<()> {
    let (mut sc, base) = if scenario == "builtin:shaken-box" {
        (
            pdamp_io::examples::shaken_box(2000, 0.5),
            PathBuf::from("."),
        )
    } else {
        let path = PathBuf::from(scenario);
        // Everything is checked (and the world built once) before any output is written.
        let (sc, _) = pdamp_io::scenario::Scenario::load_and_build(&path)?;
        let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        (sc, base)
    };
    point.apply(&mut sc)?;
    let inputs = if scenario == "builtin:shaken-box" {
        Vec::new()
    } else {
        scenario_inputs(std::path::Path::new(scenario), &sc)
    };
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let mut dir = open_out(
        out,
        options.resume,
        overwrite,
        Some(pdamp_io::checkpoint::CHECKPOINT_FILE),
        &RUN_OUTPUTS,
        &inputs,
    )?;
    if scenario != "builtin:shaken-box" {
        copy_input(out, std::path::Path::new(scenario))?;
    }
    let bar = progress::Progress::new();
    let tick = |phase: &str, f: f64| bar.set(phase, f);
    let json = if sc.damper.is_some() {
        if options.resume
            && let Some(text) = pdamp_design::report::finished_damper_summary(&sc, &base, out)
                .map_err(anyhow::Error::msg)?
        {
            dir.set_status(pdamp_io::output_dir::RunStatus::Finished);
            dir.close()?;
            println!("{text}");
            return Ok(());
        }
        let s = pdamp_design::report::run_damper_scenario_with(&sc, &base, out, options, tick);
        dir.set_outcome(&s);
        serde_json::to_string_pretty(&s.map_err(anyhow::Error::msg)?)?
    } else {
        let s = pdamp_io::run::run_scenario(&sc, &base, out, options, tick)
            .map_err(anyhow::Error::msg)
            .and_then(|s| energy_plot(out).map(|()| s));
        dir.set_outcome(&s);
        serde_json::to_string_pretty(&s?)?
    };
    dir.close()?;
    bar.finish();
    println!("{json}");
    Ok(())
}

fn cmd_fields(
    scenario: &std::path::Path,
    out: &std::path::Path,
    device: Device,
    overwrite: bool,
) -> Result<()> {
    let (sc, world) = pdamp_io::scenario::Scenario::load_and_build(scenario)?;
    #[cfg(feature = "gpu")]
    if device == Device::Gpu {
        // Before any bed is prepared: what the GPU kernels lack is said at once.
        pdamp_gpu::check_world(&world).map_err(|e| {
            anyhow::anyhow!(
                "{}: cannot run on the GPU backend: {e}; run it without --device gpu",
                scenario.display()
            )
        })?;
    }
    let _ = &world;
    let Some(spec) = &sc.fields else {
        bail!(
            "{}: `pdamp fields` needs a [fields] section (and [damper])",
            scenario.display()
        );
    };
    let grid = pdamp_design::FieldGrid::from_spec(spec).map_err(anyhow::Error::msg)?;
    let points = grid.frequencies_hz.len() * grid.amplitude_values.len();
    pdamp_io::estimate::Estimate::of(&sc, points, rayon::current_num_threads())
        .check()
        .map_err(|e| {
            anyhow::anyhow!("{}: the field of {points} points: {e}", scenario.display())
        })?;
    let base = scenario
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default();
    let bar = progress::Progress::new();
    #[cfg(feature = "gpu")]
    let gpu = match device {
        Device::Gpu => Some(pdamp_gpu::GpuDevice::open()?),
        Device::Cpu => None,
    };
    #[cfg(feature = "gpu")]
    let engine = match &gpu {
        Some(g) => pdamp_design::PointEngine::Gpu(g),
        None => pdamp_design::PointEngine::Cpu(pdamp_design::ThreadSplit::default()),
    };
    #[cfg(not(feature = "gpu"))]
    let engine = match device {
        Device::Gpu => bail!("this pdamp was built without the `gpu` feature"),
        Device::Cpu => pdamp_design::PointEngine::Cpu(pdamp_design::ThreadSplit::default()),
    };
    // Fields continue point by point (finished points of the same physics are reused).
    let inputs = scenario_inputs(scenario, &sc);
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let mut dir = pdamp_io::output_dir::OutputDir::open(
        out,
        if overwrite {
            pdamp_io::output_dir::OutputMode::Overwrite
        } else {
            pdamp_io::output_dir::OutputMode::Continue
        },
        &RUN_OUTPUTS,
        &inputs,
    )?;
    copy_input(out, scenario)?;
    let start = std::time::Instant::now();
    let outcome = pdamp_design::report::run_fields_scenario_on(
        &sc,
        &base,
        out,
        engine,
        |f| bar.set("settling", f),
        |done, total| bar.count("points", done, total),
    );
    dir.set_outcome(&outcome);
    dir.close()?;
    let outcome = outcome.map_err(anyhow::Error::msg)?;
    bar.finish();
    for (f, x, e) in &outcome.failed {
        eprintln!(
            "warning: point f = {f} Hz, X = {x:.4e} m failed (NaN in fields.csv, retried on the next run): {e}"
        );
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&serde_json::json!({
            "points": outcome.points.len(),
            "reused_points": outcome.reused,
            "failed_points": outcome.failed.iter().map(|(f, x, e)| serde_json::json!({
                "frequency_hz": f, "amplitude_m": x, "error": e
            })).collect::<Vec<_>>(),
            "bed_span_along_direction_m": outcome.bed_span_along_direction_m,
            "wall_time_s": start.elapsed().as_secs_f64(),
            "device": format!("{device:?}").to_lowercase(),
            "fields_csv": out.join("fields.csv"),
        }))?
    );
    Ok(())
}

fn cmd_settle(
    scenario: &std::path::Path,
    out: &std::path::Path,
    packing: usize,
    overwrite: bool,
) -> Result<()> {
    let (sc, _) = pdamp_io::scenario::Scenario::load_and_build(scenario)?;
    let sc = pdamp_io::prepare::scenario_for_packing(&sc, packing);
    let inputs = scenario_inputs(scenario, &sc);
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let mut dir = open_out(
        out,
        false,
        overwrite,
        None,
        &[
            "input.toml",
            "scenario.toml",
            "provenance.json",
            "bed.pdbed",
            "bed.csv",
            "bed.data",
            "bed.vtp",
            "summary.json",
        ],
        &inputs,
    )?;
    copy_input(out, scenario)?;
    let base = scenario
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default();
    let bar = progress::Progress::new();
    let s = pdamp_io::prepare::settle_scenario(&sc, &base, out, &mut |phase, f| bar.set(phase, f));
    dir.set_outcome(&s);
    dir.close()?;
    let s = s.map_err(anyhow::Error::msg)?;
    bar.finish();
    println!("{}", serde_json::to_string_pretty(&s)?);
    Ok(())
}

/// Warnings about a scenario that runs but is unlikely to be what the user wants.
fn scenario_warnings(sc: &pdamp_io::scenario::Scenario, world: &pdamp_dem::World) -> Vec<String> {
    let mut w = Vec::new();
    for b in &world.bodies {
        for wall in &b.walls {
            if let pdamp_dem::walls::Geometry::Mesh(m) = &wall.geometry
                && !m.is_closed()
            {
                w.push(format!(
                    "body '{}', wall '{}': the mesh is not closed (some edge is not shared by exactly two \
                     triangles running along it in opposite directions): particles can leave a container \
                     through the gap; close the mesh if it is meant to hold the bed",
                    b.name, wall.name
                ));
            }
        }
    }
    if sc.damper.is_some() {
        for g in sc.crystal_groups() {
            w.push(format!(
                "particles[{g}].placement.method: a damper bed that starts as a crystal (grid/tight) has another packing \
                 fraction and clearance than a poured bed and moves as a block; the dissertation's beds are drop-downs: \
                 use method = \"drop_down\" (with [settle]) for results to compare with it"
            ));
        }
        if sc.damper.as_ref().is_some_and(|d| d.packings == 1) {
            w.push(
                "damper.packings = 1: one bed is one sample of a chaotic system; set packings >= 3 (or --packings) \
                 for a mean with a 95 % confidence interval"
                    .into(),
            );
        }
    }
    w
}

/// For a TOML file that is not a DEM scenario (no `[simulation]`), the command that reads it.
fn other_scenario_kind(path: &std::path::Path) -> Option<&'static str> {
    let table = std::fs::read_to_string(path)
        .ok()?
        .parse::<toml::Table>()
        .ok()?;
    if table.contains_key("simulation") {
        return None;
    }
    let has = |k: &str| table.contains_key(k);
    Some(
        if has("beam") && has("powder") || has("beam") && has("run") {
            "a powder cantilever scenario: run it with `pdamp powder run FILE --out DIR` (docs/powder.md)"
        } else if has("dampers") || has("analysis") {
            "a structure-with-dampers scenario: run it with `pdamp couple FILE --out DIR` (docs/structure.md)"
        } else if has("study") {
            "a layer study: run it with `pdamp structure optimize-layers FILE --out DIR` (docs/structure.md)"
        } else if has("structure") {
            "a structure: see its modes with `pdamp structure modes FILE --out DIR` (docs/structure.md)"
        } else {
            return None;
        },
    )
}

/// `pdamp check` of a design study (`scenario`, `[objective]`, `[damper]`): every key checked
/// by the optimiser's loader, then the size of the space and the work it implies.
fn check_design_study(path: &std::path::Path) -> Option<Result<()>> {
    let table = std::fs::read_to_string(path)
        .ok()?
        .parse::<toml::Table>()
        .ok()?;
    if !(table.contains_key("objective") && table.contains_key("damper")) {
        return None;
    }
    Some((|| {
        let study = pdamp_optimizer::DesignStudy::load(path).map_err(|e| anyhow!(e))?;
        let space = pdamp_optimizer::Space::new(&study);
        let size = space.size();
        let s = &study.file.search;
        let enumerate = match s.screening {
            pdamp_optimizer::study::Screening::Enumerate => true,
            pdamp_optimizer::study::Screening::Swarm => false,
            pdamp_optimizer::study::Screening::Auto => size <= s.max_enumerated as f64,
        };
        let screened = if enumerate {
            format!("all {size:.0} designs screened with the envelope model")
        } else {
            format!(
                "{size:.3e} designs: a particle swarm over {} categorical choice(s), ≤ {} envelope \
                 evaluations each",
                space.choices().len(),
                s.swarm_particles as u64 * (s.swarm_iterations + 1)
            )
        };
        let verify = s.verifications.map_or_else(
            || "10 % of the screened designs (2 … 60)".to_string(),
            |v| v.to_string(),
        );
        let v = &study.file.verification;
        let dem = if v.dem_designs == 0 {
            String::new()
        } else {
            let per_design = match &study.file.objective {
                pdamp_optimizer::study::ObjectiveSpec::MaxDamping { modes, .. } => modes.len(),
                _ => 1,
            };
            format!(
                "; coupled DEM: {} runs ({} designs × {} packings{}), each one's cost \
                 (particles × steps) printed before it starts{}",
                v.dem_designs * v.packings * per_design,
                v.dem_designs,
                v.packings,
                if per_design > 1 {
                    format!(" × {per_design} modes")
                } else {
                    String::new()
                },
                if v.youngs_modulus_scale < 1.0 {
                    format!(", softened × {}", v.youngs_modulus_scale)
                } else {
                    String::new()
                }
            )
        };
        let fields = if v.field_designs == 0 {
            String::new()
        } else {
            let modes = match &study.file.objective {
                pdamp_optimizer::study::ObjectiveSpec::MinStroke { .. } => 1,
                pdamp_optimizer::study::ObjectiveSpec::MaxDamping { modes, .. }
                | pdamp_optimizer::study::ObjectiveSpec::MinFrfPeak { modes, .. }
                | pdamp_optimizer::study::ObjectiveSpec::MaxResonanceDamping { modes, .. } => {
                    modes.len()
                }
            };
            let designs = v.field_designs * study.file.damper.coatings.len();
            format!(
                "; effective fields: {designs} designs ({} × {} coating(s)) × {modes} mode(s) × \
                 {} amplitudes × {} packings = {} DEM field points of {} cycles (stored points \
                 are reused)",
                v.field_designs,
                study.file.damper.coatings.len(),
                v.field_amplitudes,
                v.packings,
                designs * modes * v.field_amplitudes * v.packings,
                v.field_cycles
            )
        };
        println!(
            "{}: a design study, OK — {screened}; time simulations: {verify}{fields}{dem}; run \
             it with `pdamp design FILE --out DIR` (docs/design.md)",
            path.display()
        );
        Ok(())
    })())
}

fn cmd_check(scenario: &std::path::Path) -> Result<()> {
    if let Some(r) = check_design_study(scenario) {
        return r;
    }
    if let Some(kind) = other_scenario_kind(scenario) {
        bail!(
            "{} is not a DEM scenario (it has no [simulation] table) but {kind}; `pdamp check` \
             checks DEM scenarios (beds, dampers, plain runs)",
            scenario.display()
        );
    }
    let (sc, world) = pdamp_io::scenario::Scenario::load_and_build(scenario)?;
    let p = &world.particles;
    let bed_mass: f64 = p.mass.iter().sum();
    let (rmin, rmax) = p
        .radius
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &r| (a.min(r), b.max(r)));
    let tc = world.min_contact_time_s(sc.simulation.check_impact_velocity_m_s);
    let mut report = serde_json::json!({
        "scenario": scenario,
        "title": sc.title,
        "particles": p.len(),
        "bed_mass_kg": bed_mass,
        "min_radius_m": rmin,
        "max_radius_m": rmax,
        "bodies": world.bodies.iter().map(|b| b.name.clone()).collect::<Vec<_>>(),
        "time_step_s": sc.simulation.time_step_s,
        "shortest_contact_time_s": tc,
        "time_step_over_contact_time": sc.simulation.time_step_s / tc,
        "estimate": pdamp_io::estimate::Estimate::of(
            &sc,
            sc.fields
                .as_ref()
                .and_then(|f| pdamp_design::FieldGrid::from_spec(f).ok())
                .map_or(1, |g| g.frequencies_hz.len() * g.amplitude_values.len()),
            rayon::current_num_threads(),
        ),
        "estimate_for": if sc.fields.is_some() {
            "pdamp fields (every point of the [fields] grid)"
        } else {
            "pdamp run"
        },
        "warnings": scenario_warnings(&sc, &world),
    });
    #[cfg(feature = "gpu")]
    {
        report["gpu_backend"] = match pdamp_gpu::check_world(&world) {
            Ok(()) => serde_json::json!("supported (pdamp fields --device gpu)"),
            Err(e) => serde_json::json!(format!("not supported: {e}")),
        };
    }
    for w in scenario_warnings(&sc, &world) {
        eprintln!("warning: {w}");
    }
    if let Some(d) = &sc.damper {
        report["damper"] = serde_json::json!({
            "container_body": d.container_body,
            "container_mass_kg": d.container_mass_kg,
            "frequency_hz": d.frequency_hz,
            "amplitude_m": d.frequency_hz.and_then(|f| d.amplitude_at(f)),
            "cycles": d.cycles,
            "transient_cycles": d.transient_cycles,
        });
    }
    if let Some(f) = &sc.fields {
        let g = pdamp_design::FieldGrid::from_spec(f).map_err(anyhow::Error::msg)?;
        report["fields"] = serde_json::json!({
            "frequencies_hz": g.frequencies_hz,
            "amplitude_axis": format!("{:?}", g.amplitude_axis),
            "amplitude_values": g.amplitude_values,
            "points": g.frequencies_hz.len() * g.amplitude_values.len(),
        });
    }
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
