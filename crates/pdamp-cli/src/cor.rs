//! `pdamp cor`: coefficient of restitution ε(v) of a sphere hitting a wall (or an identical
//! sphere) from an impact model of `pdamp-impact` [D Chap. 4].
//!
//! Writes to `--out DIR`:
//! - `cor.csv`: `velocity_m_s,restitution,contact_time_s,max_force_n` (first impacts, velocity
//!   increasing) — the ε(v) table of the `gonthier-table` contact law;
//! - `gonthier_table.toml`: the same table as a ready `normal = { law = "gonthier-table", … }`;
//! - `cor_all.csv`: every impact (with `--repeat N`) and the energy split;
//! - `force_v<V>_i<K>.csv` (FE): contact force histories `time_s,force_n`;
//! - `cor.png` / `cor.svg`: ε over v.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use pdamp_impact::study::{CorError, CorModel, check_cor_request, checked_cor_curve};
use pdamp_impact::{CorPoint, FeOptions, MaterialSet, MeshDensity, Partner};
use pdamp_plot::{Axis, LinePlot, Marker, Series, line_plot};

/// Arguments of `pdamp cor`.
#[derive(Args)]
pub struct CorArgs {
    /// Sphere radius, m.
    #[arg(long)]
    sphere_radius_m: f64,
    /// Sphere material (s235, al6060, saa9579 or a name from --materials).
    #[arg(long)]
    sphere: String,
    /// Wall material, or `sphere` for an identical sphere (head-on, relative velocity).
    #[arg(long)]
    wall: String,
    /// Impact velocities, m/s, comma separated.
    #[arg(long, value_delimiter = ',', required = true)]
    velocities_m_s: Vec<f64>,
    /// Impact model.
    #[arg(long, value_enum, default_value_t = ModelArg::Fe)]
    model: ModelArg,
    /// FE mesh density.
    #[arg(long, value_enum, default_value_t = MeshArg::Medium)]
    mesh: MeshArg,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// TOML file with `[materials.NAME]` tables (added to the built-ins).
    #[arg(long)]
    materials: Option<PathBuf>,
    /// Impacts on the same spot per velocity (FE: hardening carried over).
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Thornton limiting pressure p_y / σ_y (1.6 = first yield).
    #[arg(long, default_value_t = 1.6)]
    thornton_pressure_factor: f64,
    /// Replace the results of an earlier run in --out (exactly the files it wrote).
    #[arg(long)]
    overwrite: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
    Fe,
    Hertz,
    Thornton,
    Viscoelastic,
}

#[derive(Clone, Copy, ValueEnum)]
enum MeshArg {
    Coarse,
    Medium,
    Fine,
}

/// A library error as the command line says it: the input by its flag.
fn flag_error(e: CorError) -> anyhow::Error {
    match e.key {
        "result" => anyhow::anyhow!("{}", e.message),
        key => anyhow::anyhow!("--{} {}", key.replace('_', "-"), e.message),
    }
}

/// Runs `pdamp cor`.
pub fn run(a: CorArgs) -> Result<()> {
    let traced = crate::Traced::start(a.materials.as_deref(), 0);
    let set = match &a.materials {
        Some(p) => {
            let text =
                std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
            MaterialSet::from_toml_str(&text)?
        }
        None => MaterialSet::builtins(),
    };
    let sphere = set.get(&a.sphere)?;
    let partner = if a.wall.eq_ignore_ascii_case("sphere") {
        Partner::Sphere
    } else {
        Partner::Wall(set.get(&a.wall)?)
    };
    let model = impact_model(&a);
    // Checked before the output directory is opened: a bad input leaves nothing behind.
    let vs = check_cor_request(a.sphere_radius_m, &a.velocities_m_s, model, a.repeat)
        .map_err(flag_error)?;
    let inputs: Vec<&std::path::Path> = a.materials.as_deref().into_iter().collect();
    let mut dir = crate::outputs::open_out(
        &a.out,
        false,
        a.overwrite,
        None,
        &[
            "cor.csv",
            "gonthier_table.toml",
            "cor_all.csv",
            "cor.png",
            "cor.svg",
            "provenance.json",
            "input.toml",
        ],
        &inputs,
    )?;
    let start = std::time::Instant::now();
    let bar = crate::progress::Progress::new();
    let pts = checked_cor_curve(
        &sphere,
        &partner,
        a.sphere_radius_m,
        &a.velocities_m_s,
        model,
        a.repeat,
        &|done, total| bar.count("impacts", done, total),
    );
    bar.finish();
    // The library names the input; the command line prints it as its flag.
    let pts = pts.map_err(flag_error)?;
    let elapsed = start.elapsed().as_secs_f64();

    let first: Vec<_> = pts.iter().filter(|p| p.impact == 1).collect();
    write_first_impacts(&a.out, &first)?;
    write_every_impact(&a.out, &pts)?;
    plot_cor(&a, &sphere.name, &vs, &pts)?;
    traced.write(&a.out)?;
    dir.set_status(pdamp_io::output_dir::RunStatus::Finished);
    dir.close()?;
    let fe_times: Vec<f64> = pts
        .iter()
        .filter_map(|p| p.fe.as_ref().map(|r| r.wall_time_s))
        .collect();
    let summary = serde_json::json!({
        "out": a.out.display().to_string(),
        "points": pts.len(),
        "wall_time_s": elapsed,
        "mean_run_time_per_impact_s": if fe_times.is_empty() { f64::NAN } else { fe_times.iter().sum::<f64>() / fe_times.len() as f64 },
        "velocity_m_s": first.iter().map(|p| p.velocity_m_s).collect::<Vec<_>>(),
        "restitution": first.iter().map(|p| p.restitution).collect::<Vec<_>>(),
    });
    println!("{}", serde_json::to_string_pretty(&summary)?);
    Ok(())
}

/// The impact model of the arguments (the FE model with its mesh density).
fn impact_model(a: &CorArgs) -> CorModel {
    let density = match a.mesh {
        MeshArg::Coarse => MeshDensity::Coarse,
        MeshArg::Medium => MeshDensity::Medium,
        MeshArg::Fine => MeshDensity::Fine,
    };
    match a.model {
        ModelArg::Fe => CorModel::Fe(FeOptions::with_density(density)),
        ModelArg::Hertz => CorModel::Hertz,
        ModelArg::Thornton => CorModel::Thornton {
            pressure_factor: a.thornton_pressure_factor,
        },
        ModelArg::Viscoelastic => CorModel::Viscoelastic,
    }
}

/// `cor.csv` (the first impacts, the ε(v) table) and `gonthier_table.toml` (the same table as a
/// `gonthier-table` normal law, ε clipped to (0, 1]).
fn write_first_impacts(out: &Path, first: &[&CorPoint]) -> Result<()> {
    pdamp_io::csv::write_csv_atomic(
        out.join("cor.csv"),
        &[
            "velocity_m_s",
            "restitution",
            "contact_time_s",
            "max_force_n",
        ],
        first.iter().map(|p| {
            [
                p.velocity_m_s,
                p.restitution,
                p.contact_time_s,
                p.max_force_n,
            ]
        }),
    )?;
    // DEM table: ε clipped to (0, 1] as the gonthier-table law requires
    let mut toml = String::from(
        "# ε(v) from `pdamp cor`; paste into [contact] or a [[contact.pairs]] entry of a scenario\n",
    );
    let list = |f: &dyn Fn(&CorPoint) -> f64| {
        first
            .iter()
            .map(|p| format!("{:?}", f(p)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        toml,
        "normal = {{ law = \"gonthier-table\", impact_velocities_m_s = [{}], restitutions = [{}] }}",
        list(&|p| p.velocity_m_s),
        list(&|p| p.restitution.clamp(1e-6, 1.0))
    );
    pdamp_io::atomic::write_atomic(out.join("gonthier_table.toml"), toml.as_bytes())?;
    Ok(())
}

/// `cor_all.csv` (every impact with the FE energy split) and the FE force histories
/// `force_v<V>_i<K>.csv`.
fn write_every_impact(out: &Path, pts: &[CorPoint]) -> Result<()> {
    pdamp_io::csv::write_csv_atomic(
        out.join("cor_all.csv"),
        &[
            "velocity_m_s",
            "impact",
            "restitution",
            "contact_time_s",
            "max_force_n",
            "max_overlap_m",
            "initial_energy_j",
            "sphere_rigid_kinetic_j",
            "sphere_vibration_j",
            "wall_kinetic_j",
            "wall_stored_j",
            "plastic_sphere_j",
            "plastic_wall_j",
            "viscous_sphere_j",
            "viscous_wall_j",
            "energy_balance_error_j",
            "elements",
            "time_steps",
            "run_time_s",
        ],
        pts.iter().map(|p| {
            let mut row = vec![
                p.velocity_m_s,
                p.impact as f64,
                p.restitution,
                p.contact_time_s,
                p.max_force_n,
            ];
            match &p.fe {
                Some(r) => {
                    let e = &r.energy;
                    row.extend([
                        r.max_overlap_m,
                        e.initial_j,
                        e.sphere_rigid_kinetic_j,
                        e.sphere_vibration_j,
                        e.wall_kinetic_j,
                        e.wall_stored_j,
                        e.plastic_sphere_j,
                        e.plastic_wall_j,
                        e.viscous_sphere_j,
                        e.viscous_wall_j,
                        e.balance_error_j,
                        r.elements as f64,
                        r.steps as f64,
                        r.wall_time_s,
                    ]);
                }
                None => row.extend([f64::NAN; 14]),
            }
            row
        }),
    )?;
    for p in pts {
        if let Some(r) = &p.fe {
            pdamp_io::csv::write_csv_atomic(
                out.join(format!("force_v{}_i{}.csv", p.velocity_m_s, p.impact)),
                &["time_s", "force_n"],
                r.force_history.iter().map(|&(t, f)| [t, f]),
            )?;
        }
    }
    Ok(())
}

/// `cor.png` / `cor.svg`: ε over v, one series per impact number (a log velocity axis where
/// the velocities span more than a factor 20).
fn plot_cor(a: &CorArgs, sphere_name: &str, vs: &[f64], pts: &[CorPoint]) -> Result<()> {
    let mut plot = LinePlot::new(
        if vs.len() > 1 && vs[vs.len() - 1] / vs[0] > 20.0 {
            Axis::log("impact velocity (m/s)")
        } else {
            Axis::linear("impact velocity (m/s)")
        },
        Axis::linear("coefficient of restitution (-)").with_limits(0.0, 1.05),
    );
    plot.title = format!(
        "{} sphere r = {} mm on {}",
        sphere_name,
        a.sphere_radius_m * 1e3,
        a.wall
    );
    for k in 1..=a.repeat.max(1) {
        let (x, y): (Vec<f64>, Vec<f64>) = pts
            .iter()
            .filter(|p| p.impact == k)
            .map(|p| (p.velocity_m_s, p.restitution))
            .unzip();
        let label = if k == 1 {
            "first impact".to_string()
        } else {
            format!("impact {k}")
        };
        plot.series
            .push(Series::new(label, x, y).with_marker(Marker::Circle));
    }
    line_plot(a.out.join("cor"), &plot)?;
    Ok(())
}
