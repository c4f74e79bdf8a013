//! `Model.sensitivity`: the sensitivities at one speed.

use crate::NativeModel;
use crate::convert::{self, table};
use crate::errors::SolveError;
use modaltol::report;
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::Options;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Sensitivities at one speed (the CLI's `sensitivity --format csv` columns).
pub(crate) fn sensitivity<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speed: f64,
    wrt: Option<Vec<String>>,
    transfer: Option<&str>,
    derivatives: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let wrt = model.wrt(wrt)?;
    let tf = model.transfer(transfer)?;
    let how = convert::derivatives(derivatives)?;
    let rows = py.detach(|| -> PyResult<Vec<Vec<String>>> {
        let pt = model.point(speed, &Options::single())?;
        let p = model.model.model().nominal();
        let at = tf.map(|t| TransferAt::at_speed(&t, speed));
        let s = DesignPoint::new(&model.model, &p, &pt)
            .with_transfer(at)
            .sensitivities(&wrt, how)
            .map_err(|e| SolveError::new_err(format!("sensitivities at {speed:?} rad/s: {e}")))?;
        let why = report::transfer_defect_at(&pt, at.as_ref());
        let shown = report::SensitivityReport {
            model: model.m(),
            point: &pt,
            sensitivity: &s,
            no_transfer: why,
        };
        Ok(shown.rows())
    })?;
    table(py, &report::SENSITIVITY_HEADER, &rows)
}
