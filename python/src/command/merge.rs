//! `modaltol.merge`: shards of one run merged as the command line merges them.

use crate::NativeModel;
use crate::command::analyze::{analysis_dict, run_analysis};
use crate::convert::unit;
use crate::errors::{bad, refused};
use modaltol::cancel::Cancel;
use modaltol::plots::Display;
use modaltol::request::{Request, Resolved, Speeds};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The keywords of `merge` (Python's `modaltol.merge`): the cases the shards were run with and
/// the result directory with its display units.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct MergeKeywords {
    cases: Option<Vec<String>>,
    target_yield: Option<f64>,
    threads: Option<i64>,
    output: Option<PathBuf>,
    speed_unit: String,
    frequency_unit: String,
    campbell_case: Option<String>,
}

/// Merges shards `(name, text)` of one run of this model exactly as the CLI's `merge` does
/// (refusing what it refuses): the tables of `analyze`, and the result directory with
/// `output`.
pub(crate) fn merge<'py>(
    model: &NativeModel,
    py: Python<'py>,
    shards: Vec<(String, String)>,
    options: MergeKeywords,
) -> PyResult<Bound<'py, PyDict>> {
    let MergeKeywords {
        cases,
        target_yield,
        threads,
        output,
        speed_unit,
        frequency_unit,
        campbell_case,
    } = options;
    let m = model.m();
    let mut display = Display {
        speed: unit(&speed_unit, "speed_unit")?,
        frequency: unit(&frequency_unit, "frequency_unit")?,
        campbell_case: None,
    };
    let request = Request {
        speeds: Speeds::Model,
        cases: cases.unwrap_or_default(),
        samples: None,
        seed: None,
        sampling: None,
        monte_carlo: true,
        quadrature: true,
        quadrature_tolerance: 1e-3,
        quadrature_nodes: None,
        threads: threads.map(|n| usize::try_from(n).unwrap_or(0)),
        shard: None,
        sobol: None,
        target_yield,
    };
    let Resolved {
        options: base,
        target_yield,
        ..
    } = request
        .check()
        .and_then(|r| r.resolve(m, Cancel::new()))
        .map_err(refused)?;
    display.campbell_case = super::analyze::campbell(campbell_case.as_deref(), &base.cases)?;
    let gathered =
        modaltol::shard::verify(m, &base.cases, shards).map_err(|e| bad(e.to_string()))?;
    let (opt, mc) =
        modaltol::shard::merged_options(&gathered.run, gathered.states, base).map_err(bad)?;
    let dir = model.result_dir(&output)?;
    let targeted = model.targeted(target_yield);
    let model = &*targeted;
    let mut a = run_analysis(py, model, &opt)?;
    // The Monte Carlo's time is the shards', not the fold's.
    if gathered.monte_carlo_seconds.is_some() {
        a.monte_carlo_seconds = gathered.monte_carlo_seconds;
    }
    let used = opt
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    analysis_dict(py, model, &a, Some(&mc), used, dir, display)
}
