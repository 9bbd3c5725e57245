//! Parameter studies of paper Sect. 3 (Figs. 2–6, Table 1): one cantilever run per value of a
//! parameter, each written to its own sub-directory, plus a combined decay plot, an envelope
//! plot and a Table-1-like `table.csv` (ζ1, ζ2, ζ̄5 per value, with the period, the
//! preparation's settled and final packing density, whether the plate compressed the bed, the
//! energy closure and the wall times). Finished runs (`<dir>/summary.json` present) are
//! reused, so a study can be resumed — but only if they belong to the same scenario: every
//! `summary.json` stores the digest of its run's canonical scenario (the study's scenario with
//! the parameter applied), and a run directory holding results or a checkpoint of a different
//! scenario is refused before anything runs ([`StudyError::ForeignRun`]). Each run
//! checkpoints into `<dir>/checkpoint.bin` and, with `resume`, an interrupted run continues
//! from its checkpoint ([`cantilever::run_in_dir`]).
//!
//! **Ensembles** (`packings` > 1): a powder bed is one random packing, and a chaotic granular
//! damper gives another decay on every packing, so a damping ratio is reported as the mean
//! over K independently prepared beds with its 95 % confidence interval (Student's t,
//! [`pdamp_design::ensemble::EnsembleStat`]). Packing k is prepared with the seed
//! [`pdamp_scenario::prepare::packing_seed`]`(seed, k)` (packing 0 is the scenario's own seed) and
//! runs in `packing_KKK/` ([`run_ensemble`]; in a study, below each value's folder), resumable
//! like every run.

use std::path::{Path, PathBuf};

use crate::cantilever::{self, CantileverError, CantileverScenario};
use crate::damping;
use pdamp_design::ensemble::EnsembleStat;
use serde::Serialize;

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
    /// D50 \[m\] (Sect. 3.2); time step scaled ∝ D50.
    D50,
    /// Gravity direction (Fig. 6): values 0 = upright, 1 = upside down, 2 = horizontal.
    Orientation,
}

impl StudyParameter {
    /// Every parameter, in the order of the paper's figures.
    pub const ALL: [StudyParameter; 7] = [
        Self::PackingDensity,
        Self::StiffnessFactor,
        Self::Friction,
        Self::Restitution,
        Self::SurfaceEnergy,
        Self::D50,
        Self::Orientation,
    ];

    /// The parameter with this [`StudyParameter::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

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

    /// The scenario with the parameter set to `v` (validated; the error names the value).
    pub fn apply(
        &self,
        base: &CantileverScenario,
        v: f64,
    ) -> Result<CantileverScenario, StudyError> {
        self.apply_unnamed(base, v)
            .map_err(|source| StudyError::Value {
                parameter: self.name(),
                value: v,
                source: Box::new(source),
            })
    }

    fn apply_unnamed(
        &self,
        base: &CantileverScenario,
        v: f64,
    ) -> Result<CantileverScenario, ValueError> {
        if !v.is_finite() {
            return Err(ValueError::NotFinite);
        }
        let mut s = base.clone();
        let p = s.powder.as_mut().ok_or(ValueError::NoPowder)?;
        match self {
            Self::PackingDensity => p.prep.packing_density = v,
            Self::StiffnessFactor => {
                if !(v > 0.0) {
                    return Err(ValueError::StiffnessFactor);
                }
                p.law.normal_stiffness_n_m *= v
            }
            Self::Friction => p.law.friction = v,
            Self::Restitution => p.law.restitution = v,
            Self::SurfaceEnergy => p.law.surface_energy_j_m2 = v,
            Self::D50 => {
                if !(v > 0.0) {
                    return Err(ValueError::D50);
                }
                let f = v / p.d50_m;
                p.d50_m = v;
                s.run.time_step_s *= f;
            }
            Self::Orientation => {
                s.run.gravity_m_s2 = match v {
                    0.0 => [0.0, 0.0, -9.81],
                    1.0 => [0.0, 0.0, 9.81],
                    2.0 => [-9.81, 0.0, 0.0],
                    _ => {
                        return Err(ValueError::Orientation);
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
    /// Packing (0 without an ensemble).
    pub packing: usize,
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
    /// Wall time of preparation + coupled run \[s\].
    pub wall_time_s: f64,
}

impl StudyRow {
    /// The row of a finished run.
    fn of(value: f64, packing: usize, r: &cantilever::CantileverResult) -> Self {
        StudyRow {
            value,
            packing,
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
pub const TABLE_COLUMNS: [&str; 17] = [
    "zeta_1",
    "zeta_2",
    "zeta_5",
    "period_s",
    "particles",
    "settled_packing_density",
    "packing_density",
    "compressed",
    "plate_force_n",
    "plate_force_before_handover_n",
    "top_gap_m",
    "max_relative_overlap",
    "energy_closure",
    "mean_coupling_iterations",
    "prep_wall_time_s",
    "run_wall_time_s",
    "wall_time_s",
];

/// One line of `table.csv`: the parameter value (or, in an ensemble, the packing), then
/// [`TABLE_COLUMNS`].
fn table_line(first: f64, r: &StudyRow) -> [f64; 18] {
    let nan = f64::NAN;
    let prep = r.prep.as_ref();
    let prep_wall = prep.map_or(0.0, |p| p.wall_time_s);
    [
        first,
        r.damping.zeta_1.unwrap_or(nan),
        r.damping.zeta_2.unwrap_or(nan),
        r.damping.zeta_5.unwrap_or(nan),
        r.damping.period_s.unwrap_or(nan),
        r.particles as f64,
        prep.map_or(nan, |p| p.settled_packing_density),
        prep.map_or(nan, |p| p.packing_density),
        prep.map_or(nan, |p| f64::from(u8::from(p.compressed))),
        prep.map_or(nan, |p| p.plate_force_n),
        prep.map_or(nan, |p| p.plate_force_before_handover_n),
        prep.map_or(nan, |p| p.top_gap_m),
        prep.map_or(nan, |p| p.max_relative_overlap),
        r.energy_closure,
        r.mean_iterations,
        prep_wall,
        r.wall_time_s - prep_wall,
        r.wall_time_s,
    ]
}

/// Why a value of the varied parameter is refused ([`StudyParameter::apply`]).
#[derive(Debug, thiserror::Error)]
pub enum ValueError {
    /// The value is not a finite number.
    #[error("values must be finite numbers")]
    NotFinite,
    /// The scenario has no powder to vary.
    #[error("the study needs a [powder] section")]
    NoPowder,
    /// A stiffness factor ≤ 0.
    #[error("the stiffness factor must be positive")]
    StiffnessFactor,
    /// A D50 ≤ 0.
    #[error("d50_m must be positive")]
    D50,
    /// An orientation other than 0, 1 or 2.
    #[error("orientation values: 0 upright, 1 upside down, 2 horizontal")]
    Orientation,
    /// The scenario with the value applied is invalid.
    #[error(transparent)]
    Scenario(#[from] CantileverError),
}

/// Why a study refuses to run or fails.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A run directory holds results (or an interrupted run) of another scenario.
    #[error(
        "{dir} holds {what} of a different scenario (digest {found} vs {expected}); use another --out or remove it"
    )]
    ForeignRun {
        /// The run directory.
        dir: PathBuf,
        /// `results` or `an interrupted run`.
        what: &'static str,
        /// Digest stored there.
        found: String,
        /// Digest of this study's scenario for the value.
        expected: String,
    },
    /// A run directory's summary cannot be read.
    #[error("{path}: {why}; remove the run directory {dir} to compute it again")]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The run directory.
        dir: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// A value of the varied parameter is refused.
    #[error("--values: {parameter} = {value}: {source}")]
    Value {
        /// Name of the parameter ([`StudyParameter::name`]).
        parameter: &'static str,
        /// The value.
        value: f64,
        /// Why.
        source: Box<ValueError>,
    },
    /// No value to run.
    #[error("--values: give at least one value")]
    NoValues,
    /// Zero packings per value.
    #[error("--packings must be at least 1")]
    NoPackings,
    /// An ensemble of fewer than 2 packings.
    #[error("--packings: an ensemble needs at least 2 packings, got {0}")]
    TooFewPackings(usize),
    /// An ensemble of a scenario without powder.
    #[error("packings: an ensemble needs a [powder] section (the empty beam has no bed)")]
    NoPowder,
    /// A negative or non-finite checkpoint interval.
    #[error("--checkpoint-interval-s: must be finite and ≥ 0, got {0}")]
    CheckpointInterval(f64),
    /// A finished run's `summary.json` has neither a digest nor a readable scenario.
    #[error("no scenario_digest and no readable scenario ({0})")]
    NoDigest(#[source] serde_json::Error),
    /// A finished run's `tip.csv` lacks columns.
    #[error(
        "{path}: needs the columns time_s and tip_displacement_m; remove {dir} to compute it again"
    )]
    TipColumns {
        /// The file.
        path: PathBuf,
        /// The run directory.
        dir: PathBuf,
    },
    /// A finished run's `summary.json` cannot be read.
    #[error("{source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A finished run's `summary.json` is no JSON.
    #[error("{source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The decoding error.
        source: serde_json::Error,
    },
    /// `ensemble.json` could not be encoded.
    #[error("{0}")]
    Encode(#[source] serde_json::Error),
    /// An output file could not be written.
    #[error("{source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A run failed (or its scenario is invalid).
    #[error(transparent)]
    Cantilever(#[from] CantileverError),
    /// A CSV file could not be read or written.
    #[error(transparent)]
    Csv(#[from] pdamp_io::csv::CsvError),
    /// A plot could not be written.
    #[error(transparent)]
    Plot(#[from] pdamp_plot::PlotError),
}

/// Digest of the scenario a finished run's `summary.json` belongs to: its `scenario_digest`
/// field, or (summaries written before the field existed) the digest of the scenario stored
/// in it.
pub fn summary_digest(js: &serde_json::Value) -> Result<String, StudyError> {
    if let Some(d) = js["scenario_digest"].as_str() {
        return Ok(d.to_string());
    }
    let sc: CantileverScenario =
        serde_json::from_value(js["scenario"].clone()).map_err(StudyError::NoDigest)?;
    Ok(cantilever::scenario_digest(&sc)?)
}

/// Scenario digest in the header of a checkpoint file (read without decoding the body);
/// `None` if the bytes are no pdamp checkpoint.
pub fn checkpoint_digest(bytes: &[u8]) -> Option<String> {
    // MAGIC (8), format u32, then strings as u64 length + bytes (bincode, fixint, LE)
    let mut at = 8 + 4;
    if bytes.get(..8)? != b"PDAMPCK\0" {
        return None;
    }
    let mut string = || -> Option<String> {
        let n = u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?) as usize;
        let s = bytes.get(at + 8..(at + 8).checked_add(n)?)?;
        at += 8 + n;
        String::from_utf8(s.to_vec()).ok()
    };
    let _version = string()?;
    string()
}

/// Refuses a run directory that holds results or a checkpoint of another scenario than the
/// one with digest `expected`; `Ok(true)` if it holds finished results of this scenario.
fn check_run_dir(dir: &Path, expected: &str) -> Result<bool, StudyError> {
    let summary = dir.join("summary.json");
    let foreign = |what, found: String| StudyError::ForeignRun {
        dir: dir.to_path_buf(),
        what,
        found,
        expected: expected.to_string(),
    };
    if summary.exists() {
        let unreadable = |why: String| StudyError::Unreadable {
            path: summary.clone(),
            dir: dir.to_path_buf(),
            why,
        };
        let text = std::fs::read_to_string(&summary).map_err(|e| unreadable(e.to_string()))?;
        let js: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| unreadable(e.to_string()))?;
        let found = summary_digest(&js).map_err(|e| unreadable(e.to_string()))?;
        if found != expected {
            return Err(foreign("results", found));
        }
        return Ok(true);
    }
    if let Ok(bytes) = std::fs::read(dir.join(pdamp_io::checkpoint::CHECKPOINT_FILE))
        && let Some(found) = checkpoint_digest(&bytes)
        && found != expected
    {
        return Err(foreign("an interrupted run", found));
    }
    Ok(false)
}

/// The tip history of a finished run (`tip.csv`: time, displacement).
fn read_tip(dir: &Path) -> Result<(Vec<f64>, Vec<f64>), StudyError> {
    let path = dir.join("tip.csv");
    let (_, data) = pdamp_io::csv::read_csv_f64(&path)?;
    if data.iter().any(|r| r.len() < 2) {
        return Err(StudyError::TipColumns {
            path,
            dir: dir.to_path_buf(),
        });
    }
    Ok((
        data.iter().map(|r| r[0]).collect(),
        data.iter().map(|r| r[1]).collect(),
    ))
}

/// The scenario of packing `k`: the powder prepared with [`pdamp_scenario::prepare::packing_seed`].
pub fn with_packing(base: &CantileverScenario, k: usize) -> Result<CantileverScenario, StudyError> {
    let mut s = base.clone();
    let p = s.powder.as_mut().ok_or(StudyError::NoPowder)?;
    p.prep.seed = pdamp_scenario::prepare::packing_seed(p.prep.seed, k);
    Ok(s)
}

/// Folder of packing `k` below an ensemble's directory.
pub fn packing_dir(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("packing_{k:03}"))
}

/// Mean, spread and 95 % confidence interval of the Table-1 ratios and the packing density
/// over the members of an ensemble.
#[derive(Debug, Clone, Serialize)]
pub struct PowderEnsemble {
    /// Number of packings K.
    pub packings: usize,
    /// Preparation seed of every packing.
    pub seeds: Vec<u64>,
    /// ζ1 over the packings.
    pub zeta_1: EnsembleStat,
    /// ζ2 over the packings.
    pub zeta_2: EnsembleStat,
    /// ζ̄5 over the packings.
    pub zeta_5: EnsembleStat,
    /// Settled packing density of the preparations.
    pub settled_packing_density: EnsembleStat,
    /// Final packing density of the preparations.
    pub packing_density: EnsembleStat,
    /// Every member, in packing order.
    pub members: Vec<StudyRow>,
}

impl PowderEnsemble {
    /// The statistics of `members` (packing order).
    pub fn of(members: Vec<StudyRow>, seeds: Vec<u64>) -> Self {
        let stat = |f: &dyn Fn(&StudyRow) -> Option<f64>| {
            EnsembleStat::of(
                &members
                    .iter()
                    .map(|r| f(r).unwrap_or(f64::NAN))
                    .collect::<Vec<_>>(),
            )
        };
        PowderEnsemble {
            packings: members.len(),
            seeds,
            zeta_1: stat(&|r| r.damping.zeta_1),
            zeta_2: stat(&|r| r.damping.zeta_2),
            zeta_5: stat(&|r| r.damping.zeta_5),
            settled_packing_density: stat(&|r| r.prep.as_ref().map(|p| p.settled_packing_density)),
            packing_density: stat(&|r| r.prep.as_ref().map(|p| p.packing_density)),
            members,
        }
    }
}

/// Columns of `ensemble.csv` of a study with packings: per value, K and for ζ1, ζ2, ζ̄5 the
/// mean, the standard deviation and the 95 % CI half-width.
pub const ENSEMBLE_COLUMNS: [&str; 10] = [
    "packings",
    "zeta_1_mean",
    "zeta_1_std",
    "zeta_1_ci95_half_width",
    "zeta_2_mean",
    "zeta_2_std",
    "zeta_2_ci95_half_width",
    "zeta_5_mean",
    "zeta_5_std",
    "zeta_5_ci95_half_width",
];

fn ensemble_line(value: f64, e: &PowderEnsemble) -> [f64; 11] {
    let s = |x: &EnsembleStat| [x.mean, x.std, x.ci95_half_width];
    let (a, b, c) = (s(&e.zeta_1), s(&e.zeta_2), s(&e.zeta_5));
    [
        value,
        e.packings as f64,
        a[0],
        a[1],
        a[2],
        b[0],
        b[1],
        b[2],
        c[0],
        c[1],
        c[2],
    ]
}

/// One run of a study or an ensemble — what a task of a sweep runs (issue 27): the value of the
/// varied parameter, the packing, the scenario with both applied, its folder and a label.
#[derive(Debug, Clone)]
pub struct StudyRun {
    /// Value of the varied parameter (an ensemble: the packing index).
    pub value: f64,
    /// Packing index.
    pub packing: usize,
    /// The scenario of this run.
    pub scenario: CantileverScenario,
    /// Its folder (summary.json, tip.csv, … when finished; checkpoint.bin while running).
    pub dir: PathBuf,
    /// For people (`packing_density = 0.6, packing 1`).
    pub label: String,
}

/// The runs of [`run_study_packings`] in its order (values, then packings), with their folders
/// below `out`; every value is applied (and checked) here.
pub fn study_runs(
    base: &CantileverScenario,
    param: StudyParameter,
    values: &[f64],
    packings: usize,
    out: &Path,
) -> Result<Vec<StudyRun>, StudyError> {
    if values.is_empty() {
        return Err(StudyError::NoValues);
    }
    if packings == 0 {
        return Err(StudyError::NoPackings);
    }
    let mut runs = Vec::with_capacity(values.len() * packings);
    for &v in values {
        let sc = param.apply(base, v)?;
        let dir = out.join(format!("{}_{}", param.name(), v));
        let label = format!("{} = {v}", param.name());
        if packings == 1 {
            runs.push(StudyRun {
                value: v,
                packing: 0,
                scenario: sc,
                dir,
                label,
            });
        } else {
            for k in 0..packings {
                runs.push(StudyRun {
                    value: v,
                    packing: k,
                    scenario: with_packing(&sc, k)?,
                    dir: packing_dir(&dir, k),
                    label: format!("{label}, packing {k}"),
                });
            }
        }
    }
    Ok(runs)
}

/// The runs of [`run_ensemble`]: packing k in `out/packing_KKK/`.
pub fn ensemble_runs(
    base: &CantileverScenario,
    packings: usize,
    out: &Path,
) -> Result<Vec<StudyRun>, StudyError> {
    if packings < 2 {
        return Err(StudyError::TooFewPackings(packings));
    }
    (0..packings)
        .map(|k| {
            Ok(StudyRun {
                value: k as f64,
                packing: k,
                scenario: with_packing(base, k)?,
                dir: packing_dir(out, k),
                label: format!("packing {k}"),
            })
        })
        .collect()
}

impl StudyRun {
    /// Whether its folder holds the finished results of its scenario (`Ok(false)`: nothing,
    /// or an interrupted run of it); a folder of another scenario or an unreadable summary is
    /// an error that names it.
    pub fn finished(&self) -> Result<bool, StudyError> {
        let digest = cantilever::scenario_digest(&self.scenario)?;
        check_run_dir(&self.dir, &digest)
    }

    /// Runs it in its folder unless finished, continuing an interrupted run from its checkpoint
    /// (written every `checkpoint_interval_s` and when `cancel` is cancelled — the CLI's
    /// SIGTERM —, so a preempted or cancelled task loses at most that much).
    pub fn run(
        &self,
        checkpoint_interval_s: f64,
        cancel: &pdamp_dem::time_loop::CancelToken,
        progress: &mut dyn FnMut(&str, f64),
    ) -> Result<bool, StudyError> {
        if self.finished()? {
            return Ok(false);
        }
        let resume = self
            .dir
            .join(pdamp_io::checkpoint::CHECKPOINT_FILE)
            .is_file();
        cantilever::run_in_dir(
            &self.scenario,
            &self.dir,
            cantilever::RunOptions::new(checkpoint_interval_s, resume).cancelled_by(cancel),
            progress,
        )?;
        Ok(true)
    }
}

/// One planned run: scenario, folder, whether it has finished, its label.
struct PlannedRun {
    value: f64,
    packing: usize,
    scenario: CantileverScenario,
    dir: PathBuf,
    finished: bool,
    label: String,
}

/// Checks `dir` against `sc` ([`check_run_dir`]).
fn plan_run(
    value: f64,
    packing: usize,
    sc: CantileverScenario,
    dir: PathBuf,
    label: String,
) -> Result<PlannedRun, StudyError> {
    let digest = cantilever::scenario_digest(&sc)?;
    let finished = check_run_dir(&dir, &digest)?;
    Ok(PlannedRun {
        value,
        packing,
        scenario: sc,
        dir,
        finished,
        label,
    })
}

/// Runs (or reads back, when finished) the planned runs in order; returns their tip histories
/// and rows, and draws them into the decay and envelope plots of `out`.
fn run_planned(
    plan: Vec<PlannedRun>,
    out: &Path,
    options: cantilever::RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Vec<StudyRow>, StudyError> {
    if !(options.checkpoint_interval_s >= 0.0 && options.checkpoint_interval_s.is_finite()) {
        return Err(StudyError::CheckpointInterval(
            options.checkpoint_interval_s,
        ));
    }
    let mut rows = Vec::new();
    let mut decay = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("tip displacement x (mm)"),
    );
    let mut env = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("peak |x| (mm)"),
    );
    let n = plan.len();
    for (q, run) in plan.into_iter().enumerate() {
        let sc = &run.scenario;
        let t_rel = sc.load.rise_s + sc.load.hold_s;
        let (t, x, row) = if run.finished {
            let (t, x) = read_tip(&run.dir)?;
            let path = run.dir.join("summary.json");
            let text = std::fs::read_to_string(&path).map_err(|source| StudyError::Read {
                path: path.clone(),
                source,
            })?;
            let js: serde_json::Value =
                serde_json::from_str(&text).map_err(|source| StudyError::Json { path, source })?;
            let res = &js["result"];
            let f = |k: &str| res[k].as_f64().unwrap_or(f64::NAN);
            let prep: Option<crate::prep::PrepReport> =
                serde_json::from_value(res["prep"].clone()).unwrap_or(None);
            let row = StudyRow {
                value: run.value,
                packing: run.packing,
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
            let mut prog = |stage: &str, f: f64| {
                let label = format!("run {}/{n} ({}): {stage}", q + 1, run.label);
                progress(&label, f)
            };
            let r = cantilever::run_in_dir(sc, &run.dir, options.clone(), &mut prog)?;
            let row = StudyRow::of(run.value, run.packing, &r);
            (r.time_s, r.tip_m, row)
        };
        decay.series.push(pdamp_plot::Series::new(
            run.label.clone(),
            t.iter().map(|s| s * 1e3).collect(),
            x.iter().map(|s| s * 1e3).collect(),
        ));
        let ext = damping::local_extrema(&t, &x, t_rel);
        env.series.push(pdamp_plot::Series::new(
            run.label,
            ext.iter().map(|&i| t[i] * 1e3).collect(),
            ext.iter().map(|&i| x[i].abs() * 1e3).collect(),
        ));
        rows.push(row);
    }
    pdamp_plot::line_plot(out.join("decay"), &decay)?;
    pdamp_plot::line_plot(out.join("envelope"), &env)?;
    Ok(rows)
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
) -> Result<Vec<StudyRow>, StudyError> {
    run_study_packings(base, param, values, 1, out, options, progress)
}

/// [`run_study`] on `packings` beds per value (module docs): with `packings` > 1 each value's
/// folder holds `packing_KKK/`, `table.csv` has a `packing` column after the value, and
/// `ensemble.csv` ([`ENSEMBLE_COLUMNS`]) the mean and 95 % CI of ζ1, ζ2, ζ̄5 per value.
pub fn run_study_packings(
    base: &CantileverScenario,
    param: StudyParameter,
    values: &[f64],
    packings: usize,
    out: &Path,
    options: cantilever::RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Vec<StudyRow>, StudyError> {
    // every value is validated and every existing run directory checked before any run
    let plan = study_runs(base, param, values, packings, out)?
        .into_iter()
        .map(|r| plan_run(r.value, r.packing, r.scenario, r.dir, r.label))
        .collect::<Result<Vec<_>, _>>()?;
    let rows = run_planned(plan, out, options, progress)?;
    let mut header = vec![param.name()];
    if packings > 1 {
        header.push("packing");
    }
    header.extend(TABLE_COLUMNS);
    let lines = rows.iter().map(|r| {
        let line = table_line(r.value, r);
        if packings > 1 {
            let mut l = vec![r.value, r.packing as f64];
            l.extend_from_slice(&line[1..]);
            l
        } else {
            line.to_vec()
        }
    });
    pdamp_io::csv::write_csv_atomic(out.join("table.csv"), &header, lines)?;
    if packings > 1 {
        let mut header = vec![param.name()];
        header.extend(ENSEMBLE_COLUMNS);
        let seeds: Vec<u64> = (0..packings)
            .map(|k| with_packing(base, k).map_or(0, |s| seed_of(&s)))
            .collect();
        let lines: Vec<[f64; 11]> = rows
            .chunks(packings)
            .map(|c| ensemble_line(c[0].value, &PowderEnsemble::of(c.to_vec(), seeds.clone())))
            .collect();
        pdamp_io::csv::write_csv_atomic(out.join("ensemble.csv"), &header, lines)?;
    }
    Ok(rows)
}

/// Seed of the powder preparation (0 without powder).
pub fn seed_of(sc: &CantileverScenario) -> u64 {
    sc.powder.as_ref().map_or(0, |p| p.prep.seed)
}

/// `pdamp powder run --packings K`: the scenario on K independently prepared beds in
/// `out/packing_KKK/` (module docs); writes `table.csv` (`packing` and [`TABLE_COLUMNS`]),
/// `ensemble.json` ([`PowderEnsemble`]), `decay` and `envelope` plots. Resumable.
pub fn run_ensemble(
    base: &CantileverScenario,
    packings: usize,
    out: &Path,
    options: cantilever::RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<PowderEnsemble, StudyError> {
    let runs = ensemble_runs(base, packings, out)?;
    let seeds: Vec<u64> = runs.iter().map(|r| seed_of(&r.scenario)).collect();
    let plan = runs
        .into_iter()
        .map(|r| plan_run(r.value, r.packing, r.scenario, r.dir, r.label))
        .collect::<Result<Vec<_>, _>>()?;
    let rows = run_planned(plan, out, options, progress)?;
    let mut header = vec!["packing"];
    header.extend(TABLE_COLUMNS);
    pdamp_io::csv::write_csv_atomic(
        out.join("table.csv"),
        &header,
        rows.iter().map(|r| table_line(r.packing as f64, r)),
    )?;
    let e = PowderEnsemble::of(rows, seeds);
    let json = serde_json::to_string_pretty(&e).map_err(StudyError::Encode)?;
    let path = out.join("ensemble.json");
    pdamp_io::atomic::write_atomic(&path, json.as_bytes())
        .map_err(|source| StudyError::Write { path, source })?;
    Ok(e)
}
