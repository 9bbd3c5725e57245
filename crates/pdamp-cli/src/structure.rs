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
}

/// Runs `pdamp structure …`.
pub fn run_structure(args: StructureArgs) -> Result<()> {
    match args.action {
        StructureAction::Modes { structure, out } => {
            let traced = crate::Traced::start(Some(&structure), 0);
            let s = pdamp_structure::report::run_modes(&structure, &out).map_err(|e| anyhow!(e))?;
            traced.write(&out)?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("modes.csv").display());
            Ok(())
        }
        StructureAction::OptimizeLayers { study, out } => {
            let traced = crate::Traced::start(Some(&study), 0);
            let s = pdamp_structure::study::run_layer_study_file(&study, &out)
                .map_err(|e| anyhow!(e))?;
            traced.write(&out)?;
            println!("{}", serde_json::to_string_pretty(&s)?);
            eprintln!("wrote {}", out.join("study.csv").display());
            Ok(())
        }
        StructureAction::DamperPositions { study, out } => {
            let traced = crate::Traced::start(Some(&study), 0);
            let s = pdamp_structure::position_study::run_position_study_file(&study, &out)
                .map_err(|e| anyhow!(e))?;
            traced.write(&out)?;
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
            if !(frequency_hz > 0.0 && particle_radius_m > 0.0 && particles_per_line > 0.0) {
                return Err(anyhow!(
                    "--frequency-hz, --particle-radius-m and --particles-per-line must be > 0"
                ));
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
    traced.write(&args.out)?;
    println!("{}", serde_json::to_string_pretty(&s)?);
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
