//! `pdamp structure modes|optimize-layers|damper-positions|coated-wall` and `pdamp couple`: the structural level [D Sect. 3.3] (library:
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
    /// single mode); writes DIR/modes.csv (mode,frequency_hz,damping_ratio,phi_<point>…),
    /// DIR/summary.json and, for a beam, DIR/mode_shapes.png/svg (the first modes' deflection
    /// along the beam, normalised).
    Modes {
        /// Structure file (TOML with a [structure] section).
        structure: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Replace the results of an earlier run in DIR (exactly the files it wrote).
        #[arg(long)]
        overwrite: bool,
    },
    /// Brute-force layer optimisation (D Sect. 5.2.1 / 7.2.3): every combination of particle
    /// numbers per layer simulated in free vibration with the analytical formulas; writes
    /// DIR/study.csv (best first) and DIR/summary.json.
    OptimizeLayers {
        /// Study file (TOML: scenario = "…free analysis…", [study]).
        study: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Replace the results of an earlier run in DIR (exactly the files it wrote).
        #[arg(long)]
        overwrite: bool,
    },
    /// Damper-position study (D Sect. 8.2.3, Fig. 8.27): one equivalent damper (approach 2/3)
    /// moved along a beam, Fig. 3.7 resonance equilibrium per mode and position; writes
    /// DIR/positions.csv, DIR/positions.png/svg and DIR/summary.json.
    DamperPositions {
        /// Study file (TOML: scenario = "…steady_state analysis…", [study] positions).
        study: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Replace the results of an earlier run in DIR (exactly the files it wrote).
        #[arg(long)]
        overwrite: bool,
    },
    /// Coated-wall damper design (D Sect. 8.1.5, Eq. 8.3–8.12): coating Young's modulus and
    /// bouncing clearance for a desired frequency; prints JSON.
    CoatedWall {
        /// Desired frequency f_d of high loss factor at Γ = 1, Hz.
        #[arg(long)]
        frequency_hz: f64,
        /// Particle radius, m.
        #[arg(long)]
        particle_radius_m: f64,
        /// Particle density, kg/m³.
        #[arg(long, default_value_t = 7900.0)]
        particle_density_kg_m3: f64,
        /// Particle Young's modulus, Pa.
        #[arg(long, default_value_t = 208e9)]
        particle_youngs_modulus_pa: f64,
        /// Particle Poisson's ratio.
        #[arg(long, default_value_t = 0.3)]
        particle_poisson_ratio: f64,
        /// Coating Poisson's ratio.
        #[arg(long, default_value_t = 0.5)]
        wall_poisson_ratio: f64,
        /// Particles in one line along the excitation (n_p^line).
        #[arg(long)]
        particles_per_line: f64,
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
    /// Replace the results of an earlier run in DIR (exactly the files it wrote).
    #[arg(long, conflicts_with = "resume")]
    overwrite: bool,
}

/// Runs `work` with `out` opened for it (see [`crate::outputs::open_out`]): the manifest records how it
/// ended; a failure that wrote nothing leaves no directory.
pub(crate) fn in_out_dir<T>(
    out: &std::path::Path,
    resume: bool,
    overwrite: bool,
    outputs: &[&str],
    input: &std::path::Path,
    work: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let mut dir = crate::outputs::open_out(
        out,
        resume,
        overwrite,
        Some(pdamp_io::checkpoint::CHECKPOINT_FILE),
        outputs,
        &[input],
    )?;
    let r = work();
    dir.set_outcome(&r);
    dir.close()?;
    r
}

/// What the structure and coupling commands write.
const OUTPUTS: [&str; 20] = [
    "particles.pvd",
    "vtk",
    "modes.csv",
    "mode_shapes.png",
    "mode_shapes.svg",
    "summary.json",
    "study.csv",
    "positions.csv",
    "positions.png",
    "positions.svg",
    "decay.csv",
    "damping.csv",
    "frf.csv",
    "frf_segments.csv",
    "updates.csv",
    "response.csv",
    "checkpoint.bin",
    "provenance.json",
    "input.toml",
    "failure.json",
];

/// Runs `pdamp structure …`.
pub fn run_structure(args: StructureArgs) -> Result<()> {
    match args.action {
        StructureAction::Modes {
            structure,
            out,
            overwrite,
        } => {
            let traced = crate::Traced::start(Some(&structure), 0);
            let (s, shapes) = in_out_dir(&out, false, overwrite, &OUTPUTS, &structure, || {
                let s =
                    pdamp_structure::report::run_modes(&structure, &out).map_err(|e| anyhow!(e))?;
                let shapes = mode_shape_plot(&structure, &out)?;
                traced.write(&out)?;
                Ok((s, shapes))
            })?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("modes.csv").display());
            match shapes {
                Some(files) => eprintln!("wrote {}", files.png.display()),
                None => eprintln!("note: no mode_shapes.png: {NO_MODE_SHAPES}"),
            }
            Ok(())
        }
        StructureAction::OptimizeLayers {
            study,
            out,
            overwrite,
        } => {
            let traced = crate::Traced::start(Some(&study), 0);
            let s = in_out_dir(&out, false, overwrite, &OUTPUTS, &study, || {
                let s = pdamp_structure::study::run_layer_study_file(&study, &out)
                    .map_err(|e| anyhow!(e))?;
                traced.write(&out)?;
                Ok(s)
            })?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("study.csv").display());
            Ok(())
        }
        StructureAction::DamperPositions {
            study,
            out,
            overwrite,
        } => {
            let traced = crate::Traced::start(Some(&study), 0);
            let s = in_out_dir(&out, false, overwrite, &OUTPUTS, &study, || {
                let s = pdamp_structure::position_study::run_position_study_file(&study, &out)
                    .map_err(|e| anyhow!(e))?;
                traced.write(&out)?;
                Ok(s)
            })?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("positions.csv").display());
            Ok(())
        }
        StructureAction::CoatedWall {
            frequency_hz,
            particle_radius_m,
            particle_density_kg_m3,
            particle_youngs_modulus_pa,
            particle_poisson_ratio,
            wall_poisson_ratio,
            particles_per_line,
        } => {
            let input = pdamp_structure::design::CoatedWallInput {
                design_frequency_hz: frequency_hz,
                particle_radius_m,
                particle_density_kg_m3,
                particle_youngs_modulus_pa,
                particle_poisson_ratio,
                wall_poisson_ratio,
                particles_per_line,
            };
            for (name, v, max) in [
                ("--frequency-hz", frequency_hz, 1e5),
                ("--particle-radius-m", particle_radius_m, 1.0),
                ("--particles-per-line", particles_per_line, 1e6),
                ("--particle-density-kg-m3", particle_density_kg_m3, 1e5),
                (
                    "--particle-youngs-modulus-pa",
                    particle_youngs_modulus_pa,
                    1e13,
                ),
            ] {
                if !(v > 0.0 && v <= max) {
                    return Err(anyhow!("{name} must lie in (0, {max:e}], got {v}"));
                }
            }
            for (name, v) in [
                ("--particle-poisson-ratio", particle_poisson_ratio),
                ("--wall-poisson-ratio", wall_poisson_ratio),
            ] {
                if !(v > -1.0 && v <= 0.5) {
                    return Err(anyhow!("{name} must lie in (-1, 0.5], got {v}"));
                }
            }
            let d = pdamp_structure::design::coated_wall_design(&input);
            println!(
                "{}",
                serde_json::to_string_pretty(&serde_json::json!({"input": input, "design": d}))?
            );
            Ok(())
        }
    }
}

/// Modes plotted in `mode_shapes.png`.
const PLOTTED_MODES: usize = 6;
/// Most beam nodes sampled for the mode shapes.
const SHAPE_NODES: usize = 401;

/// Mode shapes of a beam along its axis.
#[derive(Debug, Clone)]
struct BeamModeShapes {
    /// Positions of the sampled nodes along the beam, m.
    positions_m: Vec<f64>,
    /// Per mode: frequency (Hz), the dof shown, and its values at the nodes normalised so
    /// that the largest magnitude is +1.
    modes: Vec<(f64, &'static str, Vec<f64>)>,
}

/// The mode shapes of a `[structure.beam]` along the beam axis, `Ok(None)` for other
/// structures: the structure is reduced again with a point at every node (at most
/// [`SHAPE_NODES`], evenly picked, the ends included) for the translations uy (and, without
/// `planar`, uz, ux and the torsion rotx), the same eigenproblem as `modes.csv`. Each mode
/// shows the translation of largest amplitude (rotx for a pure torsion mode).
fn beam_mode_shapes(structure: &std::path::Path) -> Result<Option<BeamModeShapes>> {
    use pdamp_structure::scenario::{PointSpec, load_structure};
    let file = load_structure(structure).map_err(|e| anyhow!(e))?;
    let Some(beam) = &file.structure.beam else {
        return Ok(None);
    };
    let (_, positions) = beam.model().map_err(|e| anyhow!(e))?;
    let step = positions.len().div_ceil(SHAPE_NODES).max(1);
    let mut nodes: Vec<usize> = (0..positions.len()).step_by(step).collect();
    if nodes.last() != Some(&(positions.len() - 1)) {
        nodes.push(positions.len() - 1);
    }
    let dofs: &[&'static str] = if beam.planar {
        &["uy"]
    } else {
        &["uy", "uz", "ux", "rotx"]
    };
    let mut spec = file.structure.clone();
    let positions = &positions;
    spec.points = nodes
        .iter()
        .flat_map(|&i| {
            dofs.iter().map(move |d| PointSpec {
                name: format!("node{i}_{d}"),
                position_m: Some(positions[i]),
                node: None,
                dof: d.to_string(),
            })
        })
        .collect();
    let base = structure.parent().unwrap_or(std::path::Path::new("."));
    let built = spec.build(base).map_err(|e| anyhow!(e))?;
    let m = &built.modal;
    let n_dof = dofs.len();
    let modes = m
        .modes
        .iter()
        .enumerate()
        .take(PLOTTED_MODES)
        .map(|(k, mode)| {
            let values = |d: usize| -> Vec<f64> {
                (0..nodes.len())
                    .map(|j| m.points[j * n_dof + d].shape[k])
                    .collect()
            };
            let peak = |v: &[f64]| v.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
            let translations = dofs.iter().take_while(|d| **d != "rotx").count();
            let best_t = (0..translations)
                .max_by(|a, b| peak(&values(*a)).total_cmp(&peak(&values(*b))))
                .unwrap_or(0);
            let d = if dofs.len() > translations
                && peak(&values(best_t)) < 1e-9 * peak(&values(translations))
            {
                translations
            } else {
                best_t
            };
            let mut v = values(d);
            let at_peak = v
                .iter()
                .copied()
                .max_by(|a, b| a.abs().total_cmp(&b.abs()))
                .unwrap_or(0.0);
            if at_peak != 0.0 {
                v.iter_mut().for_each(|x| *x /= at_peak);
            }
            (mode.frequency_hz, dofs[d], v)
        })
        .collect();
    Ok(Some(BeamModeShapes {
        positions_m: nodes.iter().map(|&i| positions[i]).collect(),
        modes,
    }))
}

/// Why [`mode_shape_plot`] draws nothing for a structure without node coordinates.
const NO_MODE_SHAPES: &str = "the structure is not a [structure.beam] and has no node coordinates (single_mode, \
     modal and matrix_market models); modes.csv holds the shapes at the named points";

/// Writes `DIR/mode_shapes.png/svg` for a beam (see [`beam_mode_shapes`]): one line per mode,
/// its frequency in the legend. `Ok(None)` when the structure has no node coordinates
/// (single mode, modal input, Matrix Market: `modes.csv` has φ at the named points; see
/// [`NO_MODE_SHAPES`]).
fn mode_shape_plot(
    structure: &std::path::Path,
    out: &std::path::Path,
) -> Result<Option<pdamp_plot::PlotFiles>> {
    use pdamp_plot::{Axis, LinePlot, Series, line_plot};
    let Some(shapes) = beam_mode_shapes(structure)? else {
        return Ok(None);
    };
    let planar = shapes.modes.iter().all(|m| m.1 == "uy");
    let mut plot = LinePlot::new(
        Axis::linear("position along the beam x (m)"),
        Axis::linear(if planar {
            "deflection u_y, normalised (-)"
        } else {
            "displacement, normalised (-)"
        }),
    );
    plot.title = format!(
        "mode shapes, {}",
        structure
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    for (k, (f, dof, v)) in shapes.modes.iter().enumerate() {
        let label = if planar {
            format!("mode {}: {} Hz", k + 1, frequency_label(*f))
        } else {
            format!("mode {}: {} Hz ({dof})", k + 1, frequency_label(*f))
        };
        plot.series
            .push(Series::new(label, shapes.positions_m.clone(), v.clone()));
    }
    Ok(Some(line_plot(out.join("mode_shapes"), &plot)?))
}

/// A frequency with four significant digits.
fn frequency_label(f: f64) -> String {
    let r: f64 = format!("{f:.3e}").parse().unwrap_or(f);
    pdamp_plot::format_number(r)
}

/// Runs `pdamp couple`.
pub fn run_couple(args: CoupleArgs) -> Result<()> {
    let traced = crate::Traced::start(Some(&args.scenario), 0);
    let bar = crate::progress::Progress::new();
    if !(args.checkpoint_interval_s.is_finite() && args.checkpoint_interval_s >= 0.0) {
        return Err(anyhow!(
            "--checkpoint-interval-s must be a finite number of seconds >= 0 (0 = only on Ctrl-C), got {}",
            args.checkpoint_interval_s
        ));
    }
    let options = pdamp_scenario::run::RunOptions::new(args.checkpoint_interval_s, args.resume)
        .cancelled_by(crate::cancel());
    let s = in_out_dir(
        &args.out,
        args.resume,
        args.overwrite,
        &OUTPUTS,
        &args.scenario,
        || {
            let s =
                pdamp_structure::report::run_couple(&args.scenario, &args.out, options, &mut |f| {
                    bar.set("running", f)
                })
                .map_err(|e| anyhow!(e))?;
            traced.write(&args.out)?;
            Ok(s)
        },
    )?;
    bar.finish();
    println!("{}", serde_json::to_string_pretty(&s)?);
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mode 1 of the clamped–free Euler–Bernoulli beam of examples/structure_cantilever_small.toml
    /// against the closed form φ(ξ) = cosh βξ − cos βξ − σ(sinh βξ − sin βξ), βL = 1.8751,
    /// σ = (cosh βL + cos βL)/(sinh βL + sin βL), normalised to 1 at the tip: within 1e-3 at
    /// x = L/4, L/2, 3L/4 and L (20 cubic elements; measured 5e-12).
    #[test]
    fn cantilever_mode_one_matches_closed_form() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/structure_cantilever_small.toml");
        let shapes = beam_mode_shapes(&path).unwrap().expect("a beam");
        assert_eq!(shapes.modes.len(), 4);
        assert!((shapes.positions_m[0]).abs() < 1e-15);
        assert!((shapes.positions_m.last().unwrap() - 1.0).abs() < 1e-12);
        let (f1, dof, v) = &shapes.modes[0];
        assert_eq!(*dof, "uy");
        assert!((f1 - 8.355).abs() < 0.01, "f1 = {f1}");
        let bl: f64 = 1.875_104_068_711_961;
        let sigma = (bl.cosh() + bl.cos()) / (bl.sinh() + bl.sin());
        let phi = |xi: f64| {
            let b = bl * xi;
            b.cosh() - b.cos() - sigma * (b.sinh() - b.sin())
        };
        let mut worst: f64 = 0.0;
        for xi in [0.25, 0.5, 0.75, 1.0] {
            let j = shapes
                .positions_m
                .iter()
                .position(|x| (x - xi).abs() < 1e-9)
                .expect("a node there");
            let exact = phi(xi) / phi(1.0);
            worst = worst.max((v[j] - exact).abs());
        }
        eprintln!("cantilever mode 1: largest deviation from the closed form {worst:.2e}");
        assert!(worst < 1e-3, "{worst}");
        assert!((v[0]).abs() < 1e-12, "clamped end");
        // Mode 2 has one node inside the span (sign change).
        let v2 = &shapes.modes[1].2;
        let changes = v2[1..].windows(2).filter(|w| w[0] * w[1] < 0.0).count();
        assert_eq!(changes, 1);
    }
}
