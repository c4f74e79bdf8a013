//! `Model.allocate`: tolerance allocation to the target yield.

use crate::NativeModel;
use crate::convert::{interruptible, table};
use crate::errors::bad;
use modaltol::cancel::Cancel;
use modaltol::model::SpeedRange;
use modaltol::report;
use modaltol::settings;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Tolerance allocation (see `modaltol::allocate`): `allocation.csv`'s table and
/// `allocation.json`'s text.
pub(crate) fn allocate<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speeds: Option<String>,
    target_yield: Option<f64>,
    case: Option<String>,
    quadrature_tolerance: f64,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.m();
    settings::quadrature_tolerance(quadrature_tolerance)
        .map_err(|e| bad(format!("quadrature_tolerance {e}")))?;
    let threads = threads.map(|n| usize::try_from(n).unwrap_or(0));
    settings::threads(threads).map_err(|e| bad(format!("threads {e}")))?;
    let range = match speeds {
        Some(s) => SpeedRange::parse(&s).map_err(|e| bad(format!("speeds: {e}")))?,
        None => m
            .analysis
            .speed
            .ok_or_else(|| bad("no speeds given and the model has no [analysis] speed"))?,
    };
    settings::analysis_speeds(range.len()).map_err(|e| bad(format!("speeds: {e}")))?;
    let grid: Vec<f64> = range.speeds().collect();
    m.check_requirement_speeds(&grid)
        .map_err(|e| bad(format!("speeds: {e}")))?;
    let target = settings::target_yield(target_yield.unwrap_or(m.allocation.target_yield))
        .map_err(|e| bad(format!("target_yield {e}")))?;
    let start = match case.as_deref().or(m.allocation.case.as_deref()) {
        Some(n) => m
            .analysis
            .cases
            .iter()
            .find(|c| c.name == n)
            .cloned()
            .ok_or_else(|| bad(format!("case: no tolerance case '{n}' in the model")))?,
        None => modaltol::model::Case::from_parameters(m),
    };
    let opt = modaltol::allocate::AllocateOptions {
        speeds: m.judged_speeds(&grid),
        case: start,
        target,
        costs: Vec::new(),
        quadrature: modaltol::quadrature::QuadOptions {
            tolerance: quadrature_tolerance,
        },
        threads,
        cancel: Cancel::new(),
    };
    let model = &*model.model;
    let a = interruptible(py, &opt.cancel, || {
        modaltol::allocate::allocate(model, &opt, &|_| {})
    })?
    .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item(
        "allocation",
        table(
            py,
            &report::ALLOCATION_HEADER,
            &report::allocation_rows(m, &a),
        )?,
    )?;
    d.set_item(
        "summary",
        serde_json::to_string(&report::allocation_json(m, &a)).expect("a JSON value"),
    )?;
    Ok(d)
}
