//! The package's exceptions and how the library's errors become them.

use modaltol::request::{RequestError, Setting};
use modaltol::settings::ThreadsError;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    _modaltol,
    ModelError,
    PyValueError,
    "The model is invalid; `file`, `line`, `column` (1-based, or None) say where."
);
pyo3::create_exception!(
    _modaltol,
    SolveError,
    PyRuntimeError,
    "A computation failed at the operating point asked for (no equilibrium, a singular \
     mass matrix, …); the message says why."
);

/// A model error as `ModelError`, carrying its place.
pub(crate) fn model_error(py: Python<'_>, e: modaltol::model::ModelError) -> PyErr {
    let err = ModelError::new_err(e.to_string());
    let v = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail.
    let _ = v.setattr("file", e.file.clone());
    let _ = v.setattr("line", e.line);
    let _ = v.setattr("column", e.column);
    let _ = v.setattr("reason", e.message.clone());
    err
}

/// Bad arguments (names, ranges): `ValueError`.
pub(crate) fn bad(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A refused analysis request in the package's spelling (the keyword's name): `ValueError`,
/// or `RuntimeError` where the operating system refuses the threads.
pub(crate) fn refused(e: RequestError) -> PyErr {
    match e {
        RequestError::Threads(t @ ThreadsError::Refused { .. }) => {
            PyRuntimeError::new_err(format!("threads: {t}"))
        }
        RequestError::NoSpeeds | RequestError::ModelSpeeds(_) => bad(e.to_string()),
        e => {
            let name = match e.setting() {
                Setting::Speeds => "speeds:",
                Setting::Cases => "cases:",
                Setting::Samples => "samples",
                Setting::Sobol => "sobol",
                Setting::QuadratureTolerance => "quadrature_tolerance",
                Setting::QuadratureNodes => "quadrature_nodes",
                Setting::Threads => "threads",
                Setting::Shard => "shard",
                Setting::TargetYield => "target_yield",
            };
            bad(format!("{name} {e}"))
        }
    }
}
