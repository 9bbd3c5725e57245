//! Parameter studies of paper Sect. 3 (Figs. 2–6, Table 1): one cantilever run per value of a
//! parameter, each written to its own sub-directory, plus a combined decay plot, an envelope
//! plot and a Table-1-like `table.csv` (ζ1, ζ2, ζ̄5 per value). Finished runs
//! (`<dir>/summary.json` present) are skipped, so a study can be resumed; each run
//! checkpoints into `<dir>/checkpoint.bin` and, with `resume`, an interrupted run continues
//! from its checkpoint ([`cantilever::run_in_dir`]).

use std::path::Path;

use crate::cantilever::{self, CantileverScenario};
use crate::damping;

/// The varied parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StudyParameter {
    /// ϕ (Fig. 2).
    PackingDensity,
    /// Factor on k_N (Fig. 3).
    StiffnessFactor,
    /// μ (Fig. 4a).
    Friction,
    /// e (Fig. 4b).
    Restitution,
    /// γ [J/m²] at the reference size (Fig. 5).
    SurfaceEnergy,
    /// D50 [m] (Sect. 3.2); time step scaled ∝ D50.
    D50,
    /// Gravity direction (Fig. 6): values 0 = upright, 1 = upside down, 2 = horizontal.
    Orientation,
}

impl StudyParameter {
    /// Name used in file names.
    pub fn name(&self) -> &'static str {
        match self {
            Self::PackingDensity => "packing_density",
            Self::StiffnessFactor => "stiffness_factor",
            Self::Friction => "friction",
            Self::Restitution => "restitution",
            Self::SurfaceEnergy => "surface_energy_j_m2",
            Self::D50 => "d50_m",
            Self::Orientation => "orientation",
        }
    }

    /// The scenario with the parameter set to `v`.
    pub fn apply(&self, base: &CantileverScenario, v: f64) -> Result<CantileverScenario, String> {
        let mut s = base.clone();
        let p = s
            .powder
            .as_mut()
            .ok_or("the study needs a [powder] section")?;
        match self {
            Self::PackingDensity => p.prep.packing_density = v,
            Self::StiffnessFactor => p.law.normal_stiffness_n_m *= v,
            Self::Friction => p.law.friction = v,
            Self::Restitution => p.law.restitution = v,
            Self::SurfaceEnergy => p.law.surface_energy_j_m2 = v,
            Self::D50 => {
                let f = v / p.d50_m;
                p.d50_m = v;
                s.run.time_step_s *= f;
            }
            Self::Orientation => {
                s.run.gravity_m_s2 = match v as i64 {
                    0 => [0.0, 0.0, -9.81],
                    1 => [0.0, 0.0, 9.81],
                    2 => [-9.81, 0.0, 0.0],
                    _ => {
                        return Err(
                            "orientation values: 0 upright, 1 upside down, 2 horizontal".into()
                        );
                    }
                }
            }
        }
        s.validate()?;
        Ok(s)
    }
}

/// One row of the study table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StudyRow {
    /// Parameter value.
    pub value: f64,
    /// Table-1 ratios.
    pub damping: damping::TableOneRatios,
    /// Particles.
    pub particles: usize,
    /// Wall time of preparation + coupled run [s].
    pub wall_time_s: f64,
}

/// Runs the study into `out` and returns the table; `options` are passed to every run that
/// is not finished yet (checkpoint interval; `resume` continues an interrupted run from its
/// checkpoint).
pub fn run_study(
    base: &CantileverScenario,
    param: StudyParameter,
    values: &[f64],
    out: &Path,
    options: cantilever::RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Vec<StudyRow>, String> {
    let mut rows = Vec::new();
    let mut decay = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("tip displacement x (mm)"),
    );
    let mut env = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("peak |x| (mm)"),
    );
    for (q, &v) in values.iter().enumerate() {
        let sc = param.apply(base, v)?;
        let dir = out.join(format!("{}_{}", param.name(), v));
        let t_rel = sc.load.rise_s + sc.load.hold_s;
        let (t, x, row) = if dir.join("summary.json").exists() {
            let (_, data) =
                pdamp_io::csv::read_csv_f64(dir.join("tip.csv")).map_err(|e| e.to_string())?;
            let t: Vec<f64> = data.iter().map(|r| r[0]).collect();
            let x: Vec<f64> = data.iter().map(|r| r[1]).collect();
            let js: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(dir.join("summary.json")).map_err(|e| e.to_string())?,
            )
            .map_err(|e| e.to_string())?;
            let wall = js["result"]["wall_time_s"].as_f64().unwrap_or(0.0)
                + js["result"]["prep"]["wall_time_s"].as_f64().unwrap_or(0.0);
            let particles = js["result"]["particles"].as_u64().unwrap_or(0) as usize;
            let d = damping::table_one(&t, &x, t_rel);
            (
                t,
                x,
                StudyRow {
                    value: v,
                    damping: d,
                    particles,
                    wall_time_s: wall,
                },
            )
        } else {
            // the stage names the run; the fraction is the stage's own (stages restart at 0)
            let n = values.len();
            let mut prog = |stage: &str, f: f64| {
                let label = format!("run {}/{n} ({} = {v}): {stage}", q + 1, param.name());
                progress(&label, f)
            };
            let r = cantilever::run_in_dir(&sc, &dir, options, &mut prog)?;
            let wall = r.wall_time_s + r.prep.as_ref().map_or(0.0, |p| p.wall_time_s);
            (
                r.time_s.clone(),
                r.tip_m.clone(),
                StudyRow {
                    value: v,
                    damping: r.damping,
                    particles: r.particles,
                    wall_time_s: wall,
                },
            )
        };
        let label = format!("{} = {v}", param.name());
        decay.series.push(pdamp_plot::Series::new(
            label.clone(),
            t.iter().map(|s| s * 1e3).collect(),
            x.iter().map(|s| s * 1e3).collect(),
        ));
        let ext = damping::local_extrema(&t, &x, t_rel);
        env.series.push(pdamp_plot::Series::new(
            label,
            ext.iter().map(|&i| t[i] * 1e3).collect(),
            ext.iter().map(|&i| x[i].abs() * 1e3).collect(),
        ));
        rows.push(row);
    }
    let nan = f64::NAN;
    let table: Vec<[f64; 6]> = rows
        .iter()
        .map(|r| {
            [
                r.value,
                r.damping.zeta_1.unwrap_or(nan),
                r.damping.zeta_2.unwrap_or(nan),
                r.damping.zeta_5.unwrap_or(nan),
                r.particles as f64,
                r.wall_time_s,
            ]
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(
        out.join("table.csv"),
        &[
            param.name(),
            "zeta_1",
            "zeta_2",
            "zeta_5",
            "particles",
            "wall_time_s",
        ],
        table,
    )
    .map_err(|e| e.to_string())?;
    pdamp_plot::line_plot(out.join("decay"), &decay).map_err(|e| e.to_string())?;
    pdamp_plot::line_plot(out.join("envelope"), &env).map_err(|e| e.to_string())?;
    Ok(rows)
}
