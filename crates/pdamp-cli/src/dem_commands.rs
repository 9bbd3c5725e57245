//! The DEM commands: `pdamp run` (a scenario), `pdamp fields` (the effective fields of a damper
//! scenario) and `pdamp settle` (a bed prepared and saved), with their shared arguments.

use crate::outputs::{RUN_OUTPUTS, copy_input, open_out, scenario_inputs};
use crate::progress;
use anyhow::{Result, anyhow, bail};
use clap::ValueEnum;
use std::path::PathBuf;

/// Where DEM steps run.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Device {
    /// The CPU engine (pdamp-dem).
    Cpu,
    /// The GPU backend (pdamp-gpu).
    Gpu,
}

/// Excitation of a damper scenario given on the command line (overrides `[damper]`).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub(crate) struct PointArgs {
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
    pub(crate) fn apply(&self, sc: &mut pdamp_scenario::schema::Scenario) -> Result<()> {
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

pub(crate) fn cmd_run(
    scenario: &str,
    out: &std::path::Path,
    options: pdamp_scenario::run::RunOptions,
    overwrite: bool,
    point: PointArgs,
) -> Result<()> {
    let (mut sc, base) = if scenario == "builtin:shaken-box" {
        (
            pdamp_scenario::examples::shaken_box(2000, 0.5),
            PathBuf::from("."),
        )
    } else {
        let path = PathBuf::from(scenario);
        // Everything is checked (and the world built once) before any output is written.
        let (sc, _) = pdamp_scenario::schema::Scenario::load_and_build(&path)?;
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
        let s = pdamp_scenario::run::run_scenario(&sc, &base, out, options, tick)
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

pub(crate) fn cmd_fields(
    scenario: &std::path::Path,
    out: &std::path::Path,
    device: Device,
    overwrite: bool,
) -> Result<()> {
    let (sc, world) = pdamp_scenario::schema::Scenario::load_and_build(scenario)?;
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
    pdamp_scenario::estimate::Estimate::of(&sc, points, rayon::current_num_threads())
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
        crate::cancel(),
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

pub(crate) fn cmd_settle(
    scenario: &std::path::Path,
    out: &std::path::Path,
    packing: usize,
    overwrite: bool,
) -> Result<()> {
    let (sc, _) = pdamp_scenario::schema::Scenario::load_and_build(scenario)?;
    let sc = pdamp_scenario::prepare::scenario_for_packing(&sc, packing);
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
    let s = pdamp_scenario::prepare::settle_scenario(
        &sc,
        &base,
        out,
        &mut |phase, f| bar.set(phase, f),
        crate::cancel(),
    );
    dir.set_outcome(&s);
    dir.close()?;
    let s = s.map_err(anyhow::Error::msg)?;
    bar.finish();
    println!("{}", serde_json::to_string_pretty(&s)?);
    Ok(())
}
