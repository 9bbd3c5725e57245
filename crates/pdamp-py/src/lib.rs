//! The extension module `pdamp._pdamp` of the Python package `pdamp` (issue 28): scenarios
//! read, built from Python dicts, validated with the messages of the command line
//! ([`ScenarioError`] with the key and its line), and the damper level — one excitation point,
//! effective fields — run on the library (not on the CLI binary) with the GIL released and
//! Ctrl-C turned into a clean stop (`KeyboardInterrupt`).
//! The Python side (`python/pdamp/__init__.py`) turns the JSON results into dicts, numpy arrays
//! and pandas DataFrames.

use numpy::{IntoPyArray, PyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};
use std::path::{Path, PathBuf};

create_exception!(
    _pdamp,
    ScenarioError,
    PyValueError,
    "A scenario that cannot be read or is invalid; the message names the key (and its line)."
);

/// A validated scenario with the directory its relative paths (meshes, tables, beds) resolve
/// against.
#[pyclass(name = "Scenario", module = "pdamp._pdamp")]
struct PyScenario {
    inner: pdamp_io::scenario::Scenario,
    base_dir: PathBuf,
}

fn scenario_error(path: &Path, text: Option<&str>, message: String) -> PyErr {
    ScenarioError::new_err(
        pdamp_io::scenario::ScenarioError::invalid(path, text, message).to_string(),
    )
}

/// Parses and validates TOML text as the command line does (`source` names it in messages).
fn parse(text: &str, base_dir: &Path, source: &Path) -> PyResult<pdamp_io::scenario::Scenario> {
    let sc = pdamp_io::scenario::Scenario::from_toml_in(text, base_dir)
        .map_err(|m| scenario_error(source, Some(text), m))?;
    sc.validate()
        .map_err(|m| scenario_error(source, Some(text), m))?;
    Ok(sc)
}

/// A Python value (dict, list, str, int, float, bool) as TOML.
fn to_toml(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{key}: keys must be strings")))?;
            let sub = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            if x.is_none() {
                continue;
            }
            t.insert(k, to_toml(&x, &sub)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if let Ok(l) = v.cast::<PyList>() {
        return l
            .iter()
            .enumerate()
            .map(|(i, x)| to_toml(&x, &format!("{key}[{i}]")))
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    if let Ok(items) = v.try_iter() {
        // tuples, numpy arrays: as lists
        return items
            .enumerate()
            .map(|(i, x)| {
                let x = x?;
                match x.extract::<f64>() {
                    Ok(f) if !x.is_instance_of::<PyInt>() => Ok(toml::Value::Float(f)),
                    _ => to_toml(&x, &format!("{key}[{i}]")),
                }
            })
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    Err(PyTypeError::new_err(format!(
        "{key}: a {} cannot be written to a scenario (use dict, list, str, int, float, bool)",
        v.get_type().name()?
    )))
}

/// TOML as Python objects.
fn to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(to_py(py, x)?)?;
            }
            l.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

#[pymethods]
impl PyScenario {
    /// Reads and validates a scenario file (paths in it relative to its folder).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let inner = pdamp_io::scenario::Scenario::load(&path)
            .map_err(|e| ScenarioError::new_err(e.to_string()))?;
        let base_dir = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        Ok(Self { inner, base_dir })
    }

    /// A scenario from TOML text; relative paths resolve against `base_dir` (default: the
    /// working directory).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir = None))]
    fn from_toml(text: &str, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
        let inner = parse(text, &base_dir, Path::new("<toml>"))?;
        Ok(Self { inner, base_dir })
    }

    /// A scenario from a dict shaped like the TOML file (`{"simulation": {...},
    /// "materials": [{...}], ...}`); the same validation and messages as a file.
    #[staticmethod]
    #[pyo3(signature = (d, base_dir = None))]
    fn from_dict(d: &Bound<'_, PyDict>, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let toml::Value::Table(t) = to_toml(d.as_any(), "")? else {
            return Err(PyTypeError::new_err("a scenario is a dict"));
        };
        let text = toml::to_string(&t).map_err(|e| ScenarioError::new_err(e.to_string()))?;
        let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
        let inner = parse(&text, &base_dir, Path::new("<dict>"))?;
        Ok(Self { inner, base_dir })
    }

    /// The scenario as TOML, every default filled in (what `scenario.toml` of a run holds).
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// The scenario as a dict (every default filled in); `Scenario.from_dict` reads it back.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: toml::Table = self
            .inner
            .to_toml()
            .parse()
            .map_err(|e: toml::de::Error| PyRuntimeError::new_err(e.to_string()))?;
        to_py(py, &toml::Value::Table(v))
    }

    /// Title of the scenario.
    #[getter]
    fn title(&self) -> String {
        self.inner.title.clone()
    }

    /// Folder against which relative paths resolve.
    #[getter]
    fn base_dir(&self) -> PathBuf {
        self.base_dir.clone()
    }

    fn __repr__(&self) -> String {
        format!("pdamp.Scenario({:?})", self.inner.title)
    }
}

/// Runs `f` on a pool of `threads` threads (all cores when `None`) with the GIL released; an
/// error of the library becomes a `RuntimeError`. Python's signals are checked every 50 ms while
/// it runs: Ctrl-C (KeyboardInterrupt, in a notebook the stop button) asks the run to stop at its
/// next check ([`pdamp_io::checkpoint::request_stop`]), waits for it, and raises the
/// KeyboardInterrupt.
fn detached<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    f: impl FnOnce() -> Result<T, String> + Send,
) -> PyResult<T> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let mut signal: Option<PyErr> = None;
    let r = std::thread::scope(|s| {
        let run = s.spawn(|| pool.install(f));
        while !run.is_finished() {
            py.detach(|| std::thread::sleep(std::time::Duration::from_millis(50)));
            if signal.is_none()
                && let Err(e) = py.check_signals()
            {
                pdamp_io::checkpoint::request_stop();
                signal = Some(e);
            }
        }
        run.join()
    });
    if let Some(e) = signal {
        pdamp_io::checkpoint::clear_stop();
        return Err(e);
    }
    match r {
        Ok(r) => r.map_err(PyRuntimeError::new_err),
        Err(_) => Err(PyRuntimeError::new_err("the simulation panicked")),
    }
}

/// One excitation point of a damper scenario (`pdamp run DAMPER.toml --out OUT`): prepares the
/// bed, excites the container and writes every output of the command line into `out`; returns
/// the text of `summary.json`.
#[pyfunction]
#[pyo3(signature = (scenario, out, threads = None))]
fn damper_point(
    py: Python<'_>,
    scenario: &PyScenario,
    out: PathBuf,
    threads: Option<usize>,
) -> PyResult<String> {
    std::fs::create_dir_all(&out).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let (sc, base) = (&scenario.inner, &scenario.base_dir);
    detached(py, threads, || {
        pdamp_design::report::run_damper_scenario(sc, base, &out, |_, _| {})?;
        std::fs::read_to_string(out.join("summary.json")).map_err(|e| e.to_string())
    })
}

/// The effective field of a damper scenario over its `[fields]` grid (`pdamp fields`): writes
/// `fields.csv`, the maps and the resumable store into `out`; returns the columns of
/// `fields.csv` as numpy arrays (a dict, column name → array).
#[pyfunction]
#[pyo3(signature = (scenario, out, threads = None))]
fn fields<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    out: PathBuf,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    std::fs::create_dir_all(&out).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let (sc, base) = (&scenario.inner, &scenario.base_dir);
    let (header, rows) = detached(py, threads, || {
        pdamp_design::report::run_fields_scenario(sc, base, &out, |_| {}, |_, _| {})?;
        pdamp_io::csv::read_csv_f64(out.join("fields.csv")).map_err(|e| e.to_string())
    })?;
    let d = PyDict::new(py);
    for (k, name) in header.iter().enumerate() {
        let col: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        let a: Bound<'py, PyArray1<f64>> = col.into_pyarray(py);
        d.set_item(name, a)?;
    }
    Ok(d)
}

/// The extension module.
#[pymodule]
fn _pdamp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ScenarioError", m.py().get_type::<ScenarioError>())?;
    m.add_class::<PyScenario>()?;
    m.add_function(wrap_pyfunction!(damper_point, m)?)?;
    m.add_function(wrap_pyfunction!(fields, m)?)?;
    Ok(())
}
