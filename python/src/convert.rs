//! Between Python and the library: arguments read (speeds, units, derivatives), tables handed
//! over as dicts of typed columns, and long calls run without the GIL and stopped by Ctrl-C.

use crate::errors::bad;
use modaltol::cancel::Cancel;
use modaltol::model::SpeedRange;
use modaltol::plots::FrequencyUnit;
use modaltol::sensitivity::Derivatives;
use modaltol::settings;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::Mutex;
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

/// Runs `work` on a worker thread with the GIL released; Ctrl-C cancels `cancel`, waits for
/// the worker to stop at its next check and raises `KeyboardInterrupt`.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    std::thread::scope(|s| {
        let (tx, rx) = channel();
        let rx = Mutex::new(rx);
        s.spawn(move || {
            let _ = tx.send(work());
        });
        loop {
            let got = py.detach(|| {
                rx.lock()
                    .expect("unpoisoned")
                    .recv_timeout(Duration::from_millis(50))
            });
            match got {
                Ok(v) => return Ok(v),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        cancel.cancel();
                        let _ = py.detach(|| rx.lock().expect("unpoisoned").recv());
                        return Err(e);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "modaltol: internal error (the computation stopped without a result)",
                    ));
                }
            }
        }
    })
}

/// A table (header and string cells, as the CLI writes them) as a dict of typed columns: a
/// column whose cells all read `true`/`false` is bool; one whose cells all read as integers is
/// int; one whose non-empty cells all read `true`/`false` holds bools and None (a flag that
/// applies to some rows only, like `within_request`); one whose non-empty cells all read as
/// numbers is float (empty cells NaN); any other is str (empty cells None). The CLI's cells
/// are shortest round-trip decimals, so the floats are the library's bit for bit.
pub(crate) fn table<'py>(
    py: Python<'py>,
    header: &[impl AsRef<str>],
    rows: &[Vec<String>],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (j, name) in header.iter().enumerate() {
        let cells: Vec<&str> = rows.iter().map(|r| r[j].as_str()).collect();
        let ints: Option<Vec<i64>> = cells.iter().map(|c| c.parse().ok()).collect();
        let floats: Option<Vec<f64>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(f64::NAN)
                } else {
                    c.parse().ok()
                }
            })
            .collect();
        let bools: Option<Vec<bool>> = cells.iter().map(|c| c.parse().ok()).collect();
        // `true`/`false` where the column applies, empty where it does not.
        let some_bools: Option<Vec<Option<bool>>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(None)
                } else {
                    c.parse().ok().map(Some)
                }
            })
            .collect();
        let column = match (ints, floats, bools) {
            (_, _, Some(b)) if !cells.is_empty() => PyList::new(py, b)?,
            (Some(i), _, _) if !cells.is_empty() => PyList::new(py, i)?,
            _ if some_bools.is_some() && cells.iter().any(|c| !c.is_empty()) => {
                PyList::new(py, some_bools.unwrap_or_default())?
            }
            (_, Some(f), _) if cells.iter().any(|c| !c.is_empty()) || cells.is_empty() => {
                PyList::new(py, f)?
            }
            _ => PyList::new(
                py,
                cells
                    .iter()
                    .map(|c| (!c.is_empty()).then_some(*c))
                    .collect::<Vec<_>>(),
            )?,
        };
        out.set_item(name.as_ref(), column)?;
    }
    Ok(out)
}

/// How many speeds (or frequencies) a call may take: a check of their number
/// ([`settings::table`], [`settings::analysis_speeds`]), made before they are.
pub(crate) type Fits<'a> = &'a dyn Fn(usize) -> Result<(), String>;

/// Speeds from `"FROM:TO:STEP"` or a sequence of numbers, as many as `fits` allows.
pub(crate) fn speeds(spec: &Bound<'_, PyAny>, what: &str, fits: Fits<'_>) -> PyResult<Vec<f64>> {
    let v: Vec<f64> = if let Ok(s) = spec.extract::<String>() {
        let r = SpeedRange::parse(&s).map_err(|e| bad(format!("{what}: {e}")))?;
        range(&r, what, fits)?
    } else {
        // Refused by its length before its numbers are made into Python floats (30 million of
        // them take seconds); an array is then converted by its own `tolist`, in C.
        if let Ok(n) = spec.len() {
            fits(n).map_err(|e| bad(format!("{what}: {e}")))?;
        }
        let values = match spec.hasattr("tolist") {
            Ok(true) => spec.call_method0("tolist")?,
            _ => spec.clone(),
        };
        values
            .extract()
            .map_err(|_| bad(format!("{what}: expected \"FROM:TO:STEP\" or numbers")))?
    };
    let v = settings::values(v).map_err(|e| bad(format!("{what}: {e}")))?;
    fits(v.len()).map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(v)
}

/// The points of a range, as many as `fits` allows.
pub(crate) fn range(r: &SpeedRange, what: &str, fits: Fits<'_>) -> PyResult<Vec<f64>> {
    fits(r.len()).map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(r.speeds().collect())
}

/// A display unit for the plots and report.
pub(crate) fn unit(name: &str, what: &str) -> PyResult<FrequencyUnit> {
    match name {
        "rad/s" => Ok(FrequencyUnit::RadPerSecond),
        "hz" | "Hz" => Ok(FrequencyUnit::Hertz),
        "rpm" => Ok(FrequencyUnit::Rpm),
        _ => Err(bad(format!(
            "{what} must be \"rad/s\", \"hz\" or \"rpm\", got {name:?}"
        ))),
    }
}

pub(crate) fn derivatives(how: &str) -> PyResult<Derivatives> {
    match how {
        "ad" => Ok(Derivatives::Exact),
        "fd" => Ok(Derivatives::FiniteDifference),
        _ => Err(bad(format!(
            "derivatives must be \"ad\" (exact) or \"fd\" (finite differences), got {how:?}"
        ))),
    }
}
