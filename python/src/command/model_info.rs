//! What a model holds: its parameters and coordinates as tables.

use crate::NativeModel;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The parameters: name, nominal value, tolerance (absolute, in the parameter's unit; NaN
/// where none), distribution.
pub(crate) fn parameters<'py>(
    model: &NativeModel,
    py: Python<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.m();
    let d = PyDict::new(py);
    d.set_item(
        "name",
        m.parameters
            .iter()
            .map(|p| p.name.clone())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "value",
        m.parameters.iter().map(|p| p.value).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "tolerance",
        m.parameters
            .iter()
            .map(|p| p.tolerance.map_or(f64::NAN, |t| t.absolute(p.value)))
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "distribution",
        m.parameters
            .iter()
            .map(|p| match p.distribution {
                modaltol::model::Distribution::Normal => "normal",
                modaltol::model::Distribution::Uniform => "uniform",
            })
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// The generalised coordinates: name, unit, driven.
pub(crate) fn coordinates<'py>(
    model: &NativeModel,
    py: Python<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.m();
    let d = PyDict::new(py);
    d.set_item(
        "name",
        m.coordinates
            .iter()
            .map(|c| c.name.clone())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "unit",
        m.coordinates
            .iter()
            .map(|c| c.unit.symbol())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "driven",
        m.coordinates.iter().map(|c| c.driven).collect::<Vec<_>>(),
    )?;
    Ok(d)
}
