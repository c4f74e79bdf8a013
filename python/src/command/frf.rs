//! `Model.frf`: the frequency response at one speed.

use crate::NativeModel;
use crate::convert::{self, interruptible, table};
use crate::errors::{SolveError, bad};
use modaltol::cancel::Cancel;
use modaltol::report;
use modaltol::sensitivity::DesignPoint;
use modaltol::settings;
use modaltol::sweep::Options;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Frequency response at one speed (the CLI's `frf` columns).
pub(crate) fn frf<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speed: f64,
    freq: &Bound<'py, PyAny>,
    transfer: Option<&str>,
    wrt: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let tf = match transfer {
        Some(s) => Some(
            model
                .m()
                .parse_response(s)
                .map_err(|e| bad(format!("transfer {s:?}: {e}")))?,
        ),
        None => model.m().analysis.transfer,
    }
    .ok_or_else(|| {
        bad("frf needs transfer=\"input=NAME,output=NAME\" (the model has no [analysis] transfer)")
    })?;
    let wrt = model.wrt(wrt)?;
    let header = report::frf_header(model.m(), &wrt);
    let freqs = convert::speeds(freq, "freq", &|n| settings::table(n, header.len()))?;
    let cancel = Cancel::new();
    let rows = interruptible(py, &cancel, || -> PyResult<Vec<Vec<String>>> {
        let pt = model.point(speed, &Options::single())?;
        let p = model.model.model().nominal();
        // Stops at the frequency after a Ctrl-C (`interruptible` then raises).
        let freqs = freqs.into_iter().take_while(|_| !cancel.is_cancelled());
        let r = DesignPoint::new(&model.model, &p, &pt)
            .frequency_response((tf.input, tf.output), &wrt, freqs)
            .map_err(|e| SolveError::new_err(format!("sensitivities at {speed:?} rad/s: {e}")))?;
        Ok(report::frf_rows(&pt.linear, &r))
    })??;
    table(py, &header, &rows)
}
