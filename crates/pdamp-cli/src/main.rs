//! `pdamp` — particle damper simulation and design from the command line.
//!
//! A thin layer: every command parses its arguments, calls one library function and reports.

#![forbid(unsafe_code)]
// The argument docs are the `--help` texts (TOML sections such as [fields], file patterns such
// as DIR/<param>_<value>), written for the terminal, not for rustdoc.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use anyhow::{Context, Result, bail};
use cli::{Cli, Command, cli_command, negative_values};
use dem_commands::{Device, cmd_fields, cmd_run, cmd_settle};
use pdamp_dem::time_loop::CancelToken;

mod bench;
mod check;
mod cli;
mod cor;
mod dem_commands;
mod design;
#[cfg(feature = "gpu")]
mod gpu;
mod impact;
mod outputs;
mod powder;
mod progress;
mod structure;
mod sweep;
mod validate;

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

/// The process's stop request: Ctrl-C / SIGTERM cancel it ([`on_signal`]); every long run of a
/// command is handed it (`RunOptions::cancelled_by`, `Damper::cancelled_by`, …).
pub(crate) fn cancel() -> &'static CancelToken {
    static CANCEL: std::sync::OnceLock<CancelToken> = std::sync::OnceLock::new();
    CANCEL.get_or_init(CancelToken::new)
}

/// Ctrl-C / SIGTERM: inside a run that stops cleanly (its loop has armed [`cancel`]) the first
/// signal asks it to write a checkpoint and stop; otherwise, or on a second signal, the process
/// ends at once with status 130.
fn on_signal() {
    let c = cancel();
    if c.is_armed() && !c.is_cancelled() {
        c.cancel();
        eprintln!("\nstopping after the next checkpoint (press Ctrl-C again to abort at once)");
    } else {
        std::process::exit(130);
    }
}

fn main() -> std::process::ExitCode {
    // Ctrl-C / SIGTERM: long runs write a checkpoint and stop (see `--resume`).
    let _ = ctrlc::set_handler(on_signal);
    match run_cli() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            if format!("{e}").starts_with(pdamp_io::checkpoint::INTERRUPTED) {
                std::process::ExitCode::from(130)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}

/// The error and its causes, joined by ": " like `{:#}`, each cause only where its text is not
/// printed already: library errors carry their cause in their message (`"output: {source}"`)
/// and some also expose it as `source()`; it is printed once.
fn error_text(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
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
    pdamp_scenario::estimate::set_force(cli.force);
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
                pdamp_scenario::run::RunOptions::new(checkpoint_interval_s, resume)
                    .cancelled_by(cancel()),
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
        Command::Check { scenario } => check::cmd_check(&scenario),
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
                pdamp_scenario::examples::shaken_box(particles, duration_s).to_toml()
            );
            Ok(())
        }
        Command::Impact(args) => impact::run(args),
        Command::Cor(args) => cor::run(args),
        Command::Structure(args) => structure::run_structure(args),
        Command::Couple(args) => structure::run_couple(args),
        Command::Design(args) => design::run(args),
        Command::Powder(args) => powder::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Validate(args) => validate::run(args),
    }
}

#[cfg(test)]
mod tests {
    use super::error_text;

    /// An error that prints its cause and also returns it as `source()`.
    #[derive(Debug)]
    struct Wrapping {
        source: std::io::Error,
    }

    impl std::fmt::Display for Wrapping {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "output: {}", self.source)
        }
    }

    impl std::error::Error for Wrapping {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.source)
        }
    }

    #[test]
    fn a_cause_in_the_message_is_printed_once() {
        let e = anyhow::Error::new(Wrapping {
            source: std::io::Error::other("disk full"),
        })
        .context("writing fields.csv");
        assert_eq!(error_text(&e), "writing fields.csv: output: disk full");
        // `{:#}` would have printed it twice.
        assert_eq!(
            format!("{e:#}"),
            "writing fields.csv: output: disk full: disk full"
        );
        // A cause not in the message is kept.
        let e = anyhow::Error::new(std::io::Error::other("no space")).context("saving");
        assert_eq!(error_text(&e), "saving: no space");
    }
}
