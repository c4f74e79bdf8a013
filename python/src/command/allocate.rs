//! `Model.allocate`: tolerance allocation to the target yield.

use crate::NativeModel;
use crate::convert::{interruptible, table};
use crate::errors::{bad, refused};
use modaltol::cancel::Cancel;
use modaltol::model::SpeedRange;
use modaltol::report;
use modaltol::request::{AllocateRequest, RequestError, Speeds};
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
    (quadrature_tolerance, quadrature_nodes): (f64, Option<i64>),
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.m();
    let request = AllocateRequest {
        speeds: match speeds {
            Some(s) => {
                Speeds::Range(SpeedRange::parse(&s).map_err(|e| bad(format!("speeds: {e}")))?)
            }
            None => Speeds::Model,
        },
        case,
        target_yield,
        quadrature_tolerance,
        // A negative count is refused as any count out of range.
        quadrature_nodes: quadrature_nodes
            .map(|n| {
                settings::quadrature_nodes(n).map_err(|e| bad(format!("quadrature_nodes {e}")))
            })
            .transpose()?,
        threads: threads.map(|n| usize::try_from(n).unwrap_or(0)),
        ..AllocateRequest::default()
    };
    // The keyword is `case` (one case), where an analysis takes `cases`.
    let opt = request.resolve(m, Cancel::new()).map_err(|e| match e {
        RequestError::Cases(why) => bad(format!("case: {why}")),
        e => refused(e),
    })?;
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
