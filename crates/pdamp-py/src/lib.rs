//! The extension module `pdamp._pdamp` of the Python package `pdamp` (issue 28): the library
//! (not the CLI binary) from Python, with the GIL released, Ctrl-C turned into a clean stop
//! (`KeyboardInterrupt`) and progress handed to a Python callback.
//!
//! * `scenario`: scenarios from files and dicts, validated with the command line's messages;
//! * `world`: a DEM world stepped from Python with zero-copy numpy views and driven bodies;
//! * `levels`: damper points, effective fields, coupled structures, structural modes, powder
//!   cavities, restitution curves and single impacts;
//! * `detach`: how library work runs under Python.
//!
//! The Python side (`python/pdamp/__init__.py`) turns the JSON results into dicts, numpy arrays
//! and pandas DataFrames.

mod detach;
mod levels;
mod scenario;
mod world;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _pdamp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "ScenarioError",
        m.py().get_type::<scenario::ScenarioError>(),
    )?;
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<world::PyWorld>()?;
    m.add_function(wrap_pyfunction!(levels::run, m)?)?;
    m.add_function(wrap_pyfunction!(levels::fields, m)?)?;
    m.add_function(wrap_pyfunction!(levels::couple, m)?)?;
    m.add_function(wrap_pyfunction!(levels::structure_modes, m)?)?;
    m.add_function(wrap_pyfunction!(levels::powder_run, m)?)?;
    m.add_function(wrap_pyfunction!(levels::cor, m)?)?;
    m.add_function(wrap_pyfunction!(levels::impact, m)?)?;
    m.add_function(wrap_pyfunction!(levels::horizontal_formulas, m)?)?;
    Ok(())
}
