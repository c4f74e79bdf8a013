//! `modaltol._modaltol`: the native half of the Python package `modaltol`.
//!
//! Every computation is the library's, and every table is built by the same functions as the
//! command line's CSV files ([`modaltol::report`]), so a DataFrame and the CLI's file hold the
//! same columns and the same numbers. This module hands tables to Python as dicts of typed
//! columns (float, int or str) and the pure-Python layer (`modaltol/__init__.py`) turns them
//! into pandas DataFrames and numpy arrays.
//!
//! Long calls run on a worker thread with the GIL released; the calling thread waits, looks at
//! Python's signals every 50 ms, and on Ctrl-C cancels the run ([`modaltol::cancel::Cancel`])
//! and raises `KeyboardInterrupt` once the worker has stopped.

mod command;
mod convert;
mod errors;
mod model;

use command::analyze::AnalyzeKeywords;
use command::merge::MergeKeywords;
use command::sweep::SweepKeywords;
use modaltol::compiled::Compiled;
use modaltol::report;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::Arc;

/// A validated model with its equations recorded on first use.
#[pyclass(frozen, module = "modaltol._modaltol")]
pub(crate) struct NativeModel {
    pub(crate) model: Arc<Compiled>,
    /// The file the model was read from, which no output may replace.
    pub(crate) source: Option<PathBuf>,
}

#[pymethods]
impl NativeModel {
    /// Tolerance allocation (see `modaltol::allocate`): `allocation.csv`'s table and
    /// `allocation.json`'s text.
    #[pyo3(signature = (speeds, target_yield, case, quadrature_tolerance, quadrature_nodes, threads))]
    #[allow(clippy::too_many_arguments)]
    fn allocate<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<String>,
        target_yield: Option<f64>,
        case: Option<String>,
        quadrature_tolerance: f64,
        quadrature_nodes: Option<i64>,
        threads: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::allocate::allocate(
            self,
            py,
            speeds,
            target_yield,
            case,
            (quadrature_tolerance, quadrature_nodes),
            threads,
        )
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> String {
        self.m().name.clone()
    }

    /// Degrees of freedom.
    #[getter]
    fn dof(&self) -> usize {
        self.m().dof()
    }

    /// The model's Monte Carlo samples (`[analysis] samples`).
    #[getter]
    fn samples(&self) -> usize {
        self.m().analysis.samples
    }

    /// The parameters: name, nominal value, tolerance (absolute, in the parameter's unit; NaN
    /// where none), distribution.
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        command::model_info::parameters(self, py)
    }

    /// The generalised coordinates: name, unit, driven.
    fn coordinates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        command::model_info::coordinates(self, py)
    }

    /// The names of the tolerance cases an analysis runs by default.
    fn cases(&self) -> Vec<String> {
        self.m()
            .tolerance_cases(&[])
            .map(|c| c.into_iter().map(|c| c.name).collect())
            .unwrap_or_default()
    }

    /// What `modaltol check` prints.
    fn check(&self) -> String {
        report::check_report(&self.model)
    }

    /// The speed sweep's table (the CLI's `sweep` columns).
    #[pyo3(signature = (speeds, options))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<&Bound<'py, PyAny>>,
        options: SweepKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::sweep::sweep(self, py, speeds, options)
    }

    /// Equilibrium, M̂, Ĉ, K̂ and the modes at one speed.
    #[pyo3(signature = (speed, independent=None, branch="stable"))]
    fn modal<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        independent: Option<Vec<String>>,
        branch: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::modal::modal(self, py, speed, independent, branch)
    }

    /// Sensitivities at one speed (the CLI's `sensitivity --format csv` columns).
    #[pyo3(signature = (speed, wrt=None, transfer=None, derivatives="ad"))]
    fn sensitivity<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        wrt: Option<Vec<String>>,
        transfer: Option<&str>,
        derivatives: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::sensitivity::sensitivity(self, py, speed, wrt, transfer, derivatives)
    }

    /// Frequency response at one speed (the CLI's `frf` columns).
    #[pyo3(signature = (speed, freq, transfer=None, wrt=None))]
    fn frf<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        freq: &Bound<'py, PyAny>,
        transfer: Option<&str>,
        wrt: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::frf::frf(self, py, speed, freq, transfer, wrt)
    }

    /// The tolerance analysis (the CLI's `analyze`): tolerance and probability tables and the
    /// summary (JSON text); with `output`, also the CLI's result directory.
    #[pyo3(signature = (speeds, options))]
    fn analyze<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<&Bound<'py, PyAny>>,
        options: AnalyzeKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::analyze::analyze(self, py, speeds, options)
    }

    /// Merges shards `(name, text)` of one run of this model exactly as the CLI's `merge` does
    /// (refusing what it refuses): the tables of `analyze`, and the result directory with
    /// `output`.
    #[pyo3(signature = (shards, options))]
    fn merge<'py>(
        &self,
        py: Python<'py>,
        shards: Vec<(String, String)>,
        options: MergeKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        command::merge::merge(self, py, shards, options)
    }
}

/// The native module.
#[pymodule]
fn _modaltol(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ModelError", m.py().get_type::<errors::ModelError>())?;
    m.add("SolveError", m.py().get_type::<errors::SolveError>())?;
    m.add_class::<NativeModel>()?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_function(wrap_pyfunction!(model::loads, m)?)?;
    Ok(())
}
