//! The levels of the toolchain from Python, each on the library with the GIL released: a damper
//! point and the effective field (D Part II), the coupled structure (D Part III), structural
//! modes, powder-filled cavities (P), restitution curves and single impacts (D Part I).

use crate::detach::{Progress, detached};
use crate::scenario::PyScenario;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A `RuntimeError` of an I/O failure.
fn io_err(e: std::io::Error) -> PyErr {
    PyRuntimeError::new_err(e.to_string())
}

/// Columns of a CSV file as numpy arrays (a dict, column name → float64 array).
fn columns<'py>(
    py: Python<'py>,
    header: &[String],
    rows: &[Vec<f64>],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, name) in header.iter().enumerate() {
        let col: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        let a: Bound<'py, PyArray1<f64>> = col.into_pyarray(py);
        d.set_item(name, a)?;
    }
    Ok(d)
}

/// A plain scenario run to files (`pdamp run SCENARIO.toml --out OUT`: settling, the main run,
/// `energy.csv`, VTK snapshots, `summary.json`); returns the text of `summary.json`. A damper
/// scenario runs its excitation point (prepares the bed, excites the container, evaluates the
/// complex power), as the command line does — Python's `damper_point`.
#[pyfunction]
#[pyo3(signature = (scenario, out, threads = None, progress = None))]
pub(crate) fn run(
    py: Python<'_>,
    scenario: &PyScenario,
    out: PathBuf,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    std::fs::create_dir_all(&out).map_err(io_err)?;
    let (sc, base) = (&scenario.inner, &scenario.base_dir);
    let pool = crate::detach::pool(threads)?;
    detached(py, &pool, progress.as_ref(), |p: &Progress| {
        let options = pdamp_scenario::run::RunOptions::new(0.0, false).cancelled_by(&p.cancel);
        if sc.damper.is_some() {
            pdamp_design::report::run_damper_scenario_with(sc, base, &out, options, |phase, f| {
                p.set(phase, f)
            })?;
        } else {
            pdamp_scenario::run::run_scenario(sc, base, &out, options, |phase, f| p.set(phase, f))?;
        }
        Ok(std::fs::read_to_string(out.join("summary.json"))?)
    })
}

/// The effective field of a damper scenario over its `[fields]` grid (`pdamp fields`): writes
/// `fields.csv`, the maps and the resumable store into `out`; returns the columns of
/// `fields.csv` as numpy arrays (a dict, column name → array).
#[pyfunction]
#[pyo3(signature = (scenario, out, threads = None, progress = None))]
pub(crate) fn fields<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    out: PathBuf,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    std::fs::create_dir_all(&out).map_err(io_err)?;
    let (sc, base) = (&scenario.inner, &scenario.base_dir);
    let pool = crate::detach::pool(threads)?;
    let (header, rows) = detached(py, &pool, progress.as_ref(), |p: &Progress| {
        pdamp_design::report::run_fields_scenario_on(
            sc,
            base,
            &out,
            pdamp_design::PointEngine::Cpu(pdamp_design::ThreadSplit::default()),
            |f| p.set("settling", f),
            |done, total| p.set("points", done as f64 / total.max(1) as f64),
            &p.cancel,
        )?;
        Ok(pdamp_io::csv::read_csv_f64(out.join("fields.csv"))?)
    })?;
    columns(py, &header, &rows)
}

/// A particle damper coupled to a structure (`pdamp couple SCENARIO.toml --out OUT`: full DEM,
/// effective fields or formulas; free decay, sweeps or FRFs): writes every output of the command
/// line into `out` and returns the text of `summary.json`. `resume` continues from the
/// checkpoint in `out` (`checkpoint_interval_s` of wall time between checkpoints, 0: only on a
/// stop).
#[pyfunction]
#[pyo3(signature = (path, out, threads = None, resume = false, checkpoint_interval_s = 0.0, progress = None))]
pub(crate) fn couple(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    threads: Option<usize>,
    resume: bool,
    checkpoint_interval_s: f64,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    pdamp_structure::scenario::CoupleScenario::load(&path)
        .map_err(|e| crate::scenario::ScenarioError::new_err(e.to_string()))?;
    if !(checkpoint_interval_s.is_finite() && checkpoint_interval_s >= 0.0) {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "checkpoint_interval_s must be a finite number of seconds >= 0, got {checkpoint_interval_s}"
        )));
    }
    std::fs::create_dir_all(&out).map_err(io_err)?;
    let options = pdamp_scenario::run::RunOptions::new(checkpoint_interval_s, resume);
    let pool = crate::detach::pool(threads)?;
    let v = detached(py, &pool, progress.as_ref(), |p: &Progress| {
        let v = pdamp_structure::report::run_couple(
            &path,
            &out,
            options.cancelled_by(&p.cancel),
            &mut |f| p.set("running", f),
        )?;
        p.set("running", 1.0);
        Ok(v)
    })?;
    serde_json::to_string(&v).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// Natural frequencies and modes of a structure file (`pdamp structure modes`): writes
/// `modes.csv` into `out` and returns the summary's text.
#[pyfunction]
#[pyo3(signature = (path, out))]
pub(crate) fn structure_modes(py: Python<'_>, path: PathBuf, out: PathBuf) -> PyResult<String> {
    pdamp_structure::scenario::load_structure(&path)
        .map_err(|e| crate::scenario::ScenarioError::new_err(e.to_string()))?;
    let pool = crate::detach::pool(Some(1))?;
    let v = detached(py, &pool, None, |_: &Progress| {
        Ok(pdamp_structure::report::run_modes(&path, &out)?)
    })?;
    serde_json::to_string(&v).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// A powder-filled cavity, two-way coupled DEM–FEM (`pdamp powder run SCENARIO.toml --out
/// OUT`, P): preparation, excitation and free decay; with `packings` K > 1 an ensemble of K
/// random packings (`--packings K`: `ensemble.json` with mean and 95 % confidence intervals).
/// Returns the text of the run's (or the ensemble's) result.
#[pyfunction]
#[pyo3(signature = (path, out, packings = 1, threads = None, resume = false, checkpoint_interval_s = 0.0, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn powder_run(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    packings: usize,
    threads: Option<usize>,
    resume: bool,
    checkpoint_interval_s: f64,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    use pdamp_powder::cantilever::{CantileverScenario, RunOptions, run_in_dir};
    let text = std::fs::read_to_string(&path)
        .map_err(|e| crate::scenario::ScenarioError::new_err(format!("{}: {e}", path.display())))?;
    let sc = CantileverScenario::from_toml(&text)
        .and_then(|sc| sc.validate().map(|()| sc))
        .map_err(|e| crate::scenario::ScenarioError::new_err(format!("{}: {e}", path.display())))?;
    if packings == 0 {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "packings must be at least 1",
        ));
    }
    std::fs::create_dir_all(&out).map_err(io_err)?;
    let options = RunOptions::new(checkpoint_interval_s, resume);
    let pool = crate::detach::pool(threads)?;
    detached(py, &pool, progress.as_ref(), |p: &Progress| {
        let mut tick = |phase: &str, f: f64| p.set(phase, f);
        let json = if packings == 1 {
            serde_json::to_string(&run_in_dir(
                &sc,
                &out,
                options.cancelled_by(&p.cancel),
                &mut tick,
            )?)
        } else {
            serde_json::to_string(&pdamp_powder::study::run_ensemble(
                &sc,
                packings,
                &out,
                options.cancelled_by(&p.cancel),
                &mut tick,
            )?)
        };
        Ok(json?)
    })
}

/// A `ValueError` naming the keyword argument at fault.
fn input_error(key: &str, message: &str) -> PyErr {
    if key == "result" {
        return pyo3::exceptions::PyValueError::new_err(message.to_string());
    }
    pyo3::exceptions::PyValueError::new_err(format!("{key} {message}"))
}

/// The coefficient of restitution ε(v) of a sphere hitting a wall or an identical sphere
/// (`pdamp cor`, D Chap. 4): returns the impacts' columns `velocity_m_s`, `impact`,
/// `restitution`, `contact_time_s`, `max_force_n` (first impacts and repeats, velocity
/// increasing) as numpy arrays.
#[pyfunction]
#[pyo3(signature = (sphere, wall, sphere_radius_m, velocities_m_s, model = "fe", mesh = "medium", repeat = 1, thornton_pressure_factor = 1.6, materials = None, threads = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn cor<'py>(
    py: Python<'py>,
    sphere: &str,
    wall: &str,
    sphere_radius_m: f64,
    velocities_m_s: Vec<f64>,
    model: &str,
    mesh: &str,
    repeat: usize,
    thornton_pressure_factor: f64,
    materials: Option<PathBuf>,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use pdamp_impact::study::{CorModel, checked_cor_curve};
    use pdamp_impact::{FeOptions, MaterialSet, MeshDensity, Partner};
    let set = match &materials {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| input_error("materials", &format!("{}: {e}", p.display())))?;
            MaterialSet::from_toml_str(&text)
                .map_err(|e| input_error("materials", &format!("{}: {e}", p.display())))?
        }
        None => MaterialSet::builtins(),
    };
    let sphere = set
        .get(sphere)
        .map_err(|e| input_error("sphere", &e.to_string()))?;
    let partner = if wall.eq_ignore_ascii_case("sphere") {
        Partner::Sphere
    } else {
        Partner::Wall(
            set.get(wall)
                .map_err(|e| input_error("wall", &e.to_string()))?,
        )
    };
    let density = match mesh {
        "coarse" => MeshDensity::Coarse,
        "medium" => MeshDensity::Medium,
        "fine" => MeshDensity::Fine,
        _ => {
            return Err(input_error(
                "mesh",
                &format!("must be coarse, medium or fine, got {mesh:?}"),
            ));
        }
    };
    let model = match model {
        "fe" => CorModel::Fe(FeOptions::with_density(density)),
        "hertz" => CorModel::Hertz,
        "thornton" => CorModel::Thornton {
            pressure_factor: thornton_pressure_factor,
        },
        "viscoelastic" => CorModel::Viscoelastic,
        _ => {
            return Err(input_error(
                "model",
                &format!("must be fe, hertz, thornton or viscoelastic, got {model:?}"),
            ));
        }
    };
    let pool = crate::detach::pool(threads)?;
    let pts = detached(py, &pool, progress.as_ref(), |p: &Progress| {
        Ok(checked_cor_curve(
            &sphere,
            &partner,
            sphere_radius_m,
            &velocities_m_s,
            model,
            repeat,
            &|done, total| p.set("impacts", done as f64 / total.max(1) as f64),
        ))
    })?
    .map_err(|e| input_error(e.key, &e.message))?;
    let header: Vec<String> = [
        "velocity_m_s",
        "impact",
        "restitution",
        "contact_time_s",
        "max_force_n",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<Vec<f64>> = pts
        .iter()
        .map(|p| {
            vec![
                p.velocity_m_s,
                p.impact as f64,
                p.restitution,
                p.contact_time_s,
                p.max_force_n,
            ]
        })
        .collect();
    columns(py, &header, &rows)
}

/// One head-on impact of a sphere on a rigid wall or an identical sphere with the DEM's contact
/// laws (`pdamp impact`), against Hertz theory (D Eq. 4.8, 2.80): returns the result's text.
#[pyfunction]
#[pyo3(signature = (radius_m, youngs_modulus_pa, poisson_ratio, density_kg_m3, velocity_m_s, partner = "wall", law = "hertz", restitution = 1.0, stiffness_n_m = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn impact(
    py: Python<'_>,
    radius_m: f64,
    youngs_modulus_pa: f64,
    poisson_ratio: f64,
    density_kg_m3: f64,
    velocity_m_s: f64,
    partner: &str,
    law: &str,
    restitution: f64,
    stiffness_n_m: Option<f64>,
) -> PyResult<String> {
    use pdamp_dem::impact::{ImpactLaw, ImpactRequest, Partner, checked_head_on_impact};
    let partner = match partner {
        "wall" => Partner::Wall,
        "sphere" => Partner::Sphere,
        _ => {
            return Err(input_error(
                "partner",
                &format!("must be wall or sphere, got {partner:?}"),
            ));
        }
    };
    let names: Vec<&str> = ImpactLaw::ALL.iter().map(|(n, _)| *n).collect();
    let law = ImpactLaw::from_name(law).ok_or_else(|| {
        input_error(
            "law",
            &format!("must be one of {}, got {law:?}", names.join(", ")),
        )
    })?;
    let req = ImpactRequest {
        partner,
        radius_m,
        material: pdamp_dem::Material::new(
            "material",
            density_kg_m3,
            youngs_modulus_pa,
            poisson_ratio,
        ),
        law,
        restitution,
        stiffness_n_m,
        velocity_m_s,
    };
    let r = py
        .detach(|| checked_head_on_impact(&req))
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    serde_json::to_string(&r).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The combined analytical model of a horizontally excited damper [D Eq. 6.12]: η̄ and
/// m̄_bed/m_bed at each amplitude for frequency `frequency_hz` — rolling (scattered Eq. 5.3,
/// collect-and-collide Eq. 5.10, mass Eq. 5.14) for A < g, bouncing (scattered Eq. 6.3,
/// collect-and-collide Eq. 6.8 with 6.6) for A ≥ g. Returns the columns `amplitude_m`,
/// `effective_loss_factor`, `effective_mass_ratio` as numpy arrays.
#[pyfunction]
#[pyo3(signature = (amplitudes_m, frequency_hz, rolling_clearance_m, bouncing_clearance_m, bouncing_mass_ratio = 1.0))]
pub(crate) fn horizontal_formulas<'py>(
    py: Python<'py>,
    amplitudes_m: Vec<f64>,
    frequency_hz: f64,
    rolling_clearance_m: f64,
    bouncing_clearance_m: f64,
    bouncing_mass_ratio: f64,
) -> PyResult<Bound<'py, PyDict>> {
    use pdamp_structure::formulas::{HorizontalDamper, RollingDamper};
    let positive = [
        ("frequency_hz", frequency_hz),
        ("bouncing_mass_ratio", bouncing_mass_ratio),
    ];
    if let Some((k, v)) = positive.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        return Err(input_error(k, &format!("must be finite and > 0, got {v}")));
    }
    for (k, v) in [
        ("rolling_clearance_m", rolling_clearance_m),
        ("bouncing_clearance_m", bouncing_clearance_m),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(input_error(
                k,
                &format!("must be finite and >= 0 m, got {v}"),
            ));
        }
    }
    if let Some(x) = amplitudes_m.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(input_error(
            "amplitudes_m",
            &format!("must all be finite and > 0 m, got {x}"),
        ));
    }
    let d = HorizontalDamper {
        rolling: RollingDamper {
            bed_mass_kg: 1.0,
            clearance_m: rolling_clearance_m,
            smoothing_log_width: None,
        },
        bouncing_clearance_m,
        bouncing_mass_ratio,
    };
    let omega = 2.0 * std::f64::consts::PI * frequency_hz;
    let rows: Vec<Vec<f64>> = amplitudes_m
        .iter()
        .map(|&x| {
            let (eta, m) = d.loss_factor_and_mass_ratio(x, omega);
            vec![x, eta, m]
        })
        .collect();
    let header: Vec<String> = [
        "amplitude_m",
        "effective_loss_factor",
        "effective_mass_ratio",
    ]
    .map(String::from)
    .to_vec();
    columns(py, &header, &rows)
}
