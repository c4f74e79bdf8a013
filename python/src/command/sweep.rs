//! `Model.sweep`: the speed sweep's table.

use crate::NativeModel;
use crate::convert::{self, interruptible, table};
use modaltol::cancel::Cancel;
use modaltol::nominal_sweep::NominalSweep;
use modaltol::report::{self, SweepColumns};
use modaltol::settings;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The keywords of `Model.sweep` (the Python wrapper passes them all, as a dict).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct SweepKeywords {
    transfer: Option<String>,
    sensitivity: bool,
    wrt: Option<Vec<String>>,
    derivatives: String,
    independent: Option<Vec<String>>,
    branch: String,
}

/// The speed sweep's table (the CLI's `sweep` columns).
pub(crate) fn sweep<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speeds: Option<&Bound<'py, PyAny>>,
    options: SweepKeywords,
) -> PyResult<Bound<'py, PyDict>> {
    let SweepKeywords {
        transfer,
        sensitivity,
        wrt,
        derivatives,
        independent,
        branch,
    } = options;
    let (transfer, derivatives, branch) = (transfer.as_deref(), &*derivatives, &*branch);
    let m = model.m();
    let tf = model.transfer(transfer)?;
    let cols = SweepColumns {
        transfer: tf.is_some(),
        wrt: if sensitivity {
            model.wrt(wrt)?
        } else {
            Vec::new()
        },
    };
    let columns = report::sweep_header(m, &cols).len();
    let w = model.speeds_or_model(speeds, &|n| {
        settings::table(n.saturating_mul(m.dof().max(1)), columns)
    })?;
    let opt = model.options_on(independent, branch)?;
    let how = convert::derivatives(derivatives)?;
    let cancel = Cancel::new();
    let model = &*model.model;
    let rows = interruptible(py, &cancel, || {
        let mut study = NominalSweep::new(model, opt, tf, cols.wrt.clone(), how);
        let mut rows = Vec::new();
        for &speed in &w {
            if cancel.is_cancelled() {
                break;
            }
            let (r, extras) = study.step(speed);
            rows.extend(report::sweep_rows(model.model(), &cols, speed, &r, &extras));
        }
        rows
    })?;
    table(py, &report::sweep_header(m, &cols), &rows)
}
