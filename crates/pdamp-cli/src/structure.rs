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
    /// single mode); writes DIR/modes.csv (mode,frequency_hz,damping_ratio,phi_<point>…) and
    /// DIR/summary.json.
    Modes {
        /// Structure file (TOML with a [structure] section).
        structure: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "out/structure")]
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

/// Runs `work` with `out` opened for it (see [`crate::open_out`]): the manifest records how it
/// ended; a failure that wrote nothing leaves no directory.
fn in_out_dir<T>(
    out: &std::path::Path,
    resume: bool,
    overwrite: bool,
    outputs: &[&str],
    input: &std::path::Path,
    work: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let mut dir = crate::open_out(
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
const OUTPUTS: [&str; 16] = [
    "modes.csv",
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
            let s = in_out_dir(&out, false, overwrite, &OUTPUTS, &structure, || {
                let s =
                    pdamp_structure::report::run_modes(&structure, &out).map_err(|e| anyhow!(e))?;
                traced.write(&out)?;
                Ok(s)
            })?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("modes.csv").display());
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
    let options = pdamp_io::run::RunOptions {
        checkpoint_interval_s: args.checkpoint_interval_s,
        resume: args.resume,
    };
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
