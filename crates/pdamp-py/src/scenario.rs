//! Scenarios from Python: read from files, built from dicts, validated with the messages of the
//! command line ([`ScenarioError`] names the key and its line).

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
pub(crate) struct PyScenario {
    pub(crate) inner: pdamp_scenario::schema::Scenario,
    pub(crate) base_dir: PathBuf,
}

fn scenario_error(path: &Path, text: Option<&str>, message: String) -> PyErr {
    ScenarioError::new_err(
        pdamp_scenario::schema::ScenarioError::invalid(path, text, message).to_string(),
    )
}

/// Parses and validates TOML text as the command line does (`source` names it in messages).
fn parse(text: &str, base_dir: &Path, source: &Path) -> PyResult<pdamp_scenario::schema::Scenario> {
    let sc = pdamp_scenario::schema::Scenario::from_toml_in(text, base_dir)
        .map_err(|m| scenario_error(source, Some(text), m.to_string()))?;
    sc.validate()
        .map_err(|m| scenario_error(source, Some(text), m.to_string()))?;
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
        let inner = pdamp_scenario::schema::Scenario::load(&path)
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
