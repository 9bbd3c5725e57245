//! Parameter studies of paper Sect. 3 (Figs. 2–6, Table 1): one cantilever run per value of a
//! parameter, each written to its own sub-directory, plus a combined decay plot, an envelope
//! plot and a Table-1-like `table.csv` (ζ1, ζ2, ζ̄5 per value, with the period, the
//! preparation's settled and final packing density, whether the plate compressed the bed, the
//! energy closure and the wall times). Finished runs
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
    /// Preparation report (settled and final packing density, compression, plate force).
    pub prep: Option<crate::prep::PrepReport>,
    /// Energy closure of the coupled run (largest drift of the balance / largest stored energy).
    pub energy_closure: f64,
    /// Mean fixed-point iterations per coupled step.
    pub mean_iterations: f64,
    /// Wall time of preparation + coupled run [s].
    pub wall_time_s: f64,
}

impl StudyRow {
    /// The row of a finished run.
    fn of(value: f64, r: &cantilever::CantileverResult) -> Self {
        StudyRow {
            value,
            damping: r.damping,
            particles: r.particles,
            prep: r.prep.clone(),
            energy_closure: r.energy_closure,
            mean_iterations: r.mean_iterations,
            wall_time_s: r.wall_time_s + r.prep.as_ref().map_or(0.0, |p| p.wall_time_s),
        }
    }
}

/// Columns of `table.csv` (units in the names; `compressed` is 1 or 0).
pub const TABLE_COLUMNS: [&str; 15] = [
    "zeta_1",
    "zeta_2",
    "zeta_5",
    "period_s",
    "particles",
    "settled_packing_density",
    "packing_density",
    "compressed",
    "plate_force_n",
    "max_relative_overlap",
    "energy_closure",
    "mean_coupling_iterations",
    "prep_wall_time_s",
    "run_wall_time_s",
    "wall_time_s",
];

/// One line of `table.csv`: the parameter value, then [`TABLE_COLUMNS`].
fn table_line(r: &StudyRow) -> [f64; 16] {
    let nan = f64::NAN;
    let prep = r.prep.as_ref();
    let prep_wall = prep.map_or(0.0, |p| p.wall_time_s);
    [
        r.value,
        r.damping.zeta_1.unwrap_or(nan),
        r.damping.zeta_2.unwrap_or(nan),
        r.damping.zeta_5.unwrap_or(nan),
        r.damping.period_s.unwrap_or(nan),
        r.particles as f64,
        prep.map_or(nan, |p| p.settled_packing_density),
        prep.map_or(nan, |p| p.packing_density),
        prep.map_or(nan, |p| f64::from(u8::from(p.compressed))),
        prep.map_or(nan, |p| p.plate_force_n),
        prep.map_or(nan, |p| p.max_relative_overlap),
        r.energy_closure,
        r.mean_iterations,
        prep_wall,
        r.wall_time_s - prep_wall,
        r.wall_time_s,
    ]
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
            let res = &js["result"];
            let f = |k: &str| res[k].as_f64().unwrap_or(f64::NAN);
            let prep: Option<crate::prep::PrepReport> =
                serde_json::from_value(res["prep"].clone()).unwrap_or(None);
            let row = StudyRow {
                value: v,
                damping: damping::table_one(&t, &x, t_rel),
                particles: res["particles"].as_u64().unwrap_or(0) as usize,
                energy_closure: f("energy_closure"),
                mean_iterations: f("mean_iterations"),
                wall_time_s: f("wall_time_s") + prep.as_ref().map_or(0.0, |p| p.wall_time_s),
                prep,
            };
            (t, x, row)
        } else {
            // the stage names the run; the fraction is the stage's own (stages restart at 0)
            let n = values.len();
            let mut prog = |stage: &str, f: f64| {
                let label = format!("run {}/{n} ({} = {v}): {stage}", q + 1, param.name());
                progress(&label, f)
            };
            let r = cantilever::run_in_dir(&sc, &dir, options, &mut prog)?;
            let row = StudyRow::of(v, &r);
            (r.time_s, r.tip_m, row)
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
    let mut header = vec![param.name()];
    header.extend(TABLE_COLUMNS);
    pdamp_io::csv::write_csv_atomic(out.join("table.csv"), &header, rows.iter().map(table_line))
        .map_err(|e| e.to_string())?;
    pdamp_plot::line_plot(out.join("decay"), &decay).map_err(|e| e.to_string())?;
    pdamp_plot::line_plot(out.join("envelope"), &env).map_err(|e| e.to_string())?;
    Ok(rows)
}
