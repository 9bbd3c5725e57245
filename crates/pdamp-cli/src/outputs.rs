//! The output directory of the commands: what they write into it, opening it (fresh, resumed
//! or overwritten) and the inputs no output may replace.

use anyhow::{Context, Result, bail};

/// Files and folders the DEM commands write into their output directory (checked for
/// symbolic links and for inputs they would replace before anything is written).
pub(crate) const RUN_OUTPUTS: [&str; 25] = [
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
pub(crate) fn copy_input(out: &std::path::Path, input: &std::path::Path) -> Result<()> {
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
pub(crate) fn scenario_inputs(
    scenario: &std::path::Path,
    sc: &pdamp_scenario::schema::Scenario,
) -> Vec<std::path::PathBuf> {
    let base = scenario
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default();
    std::iter::once(scenario.to_path_buf())
        .chain(sc.referenced_files().into_iter().map(|f| base.join(f)))
        .collect()
}
