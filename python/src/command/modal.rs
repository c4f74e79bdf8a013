//! `Model.modal`: the equilibrium, M̂, Ĉ, K̂ and the modes at one speed.

use crate::NativeModel;
use crate::convert::table;
use crate::errors::SolveError;
use modaltol::program::Tier;
use modaltol::report;
use modaltol::sweep::Options;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Equilibrium, M̂, Ĉ, K̂ and the modes at one speed.
pub(crate) fn modal<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speed: f64,
    independent: Option<Vec<String>>,
    branch: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let opt = Options {
        tier: Tier::Few,
        ..model.options_on(independent, branch)?
    };
    let pt = py.detach(|| model.point(speed, &opt))?;
    let m = model.m();
    let d = PyDict::new(py);
    let matrix = |a: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..a.nrows())
            .map(|i| (0..a.ncols()).map(|j| a[(i, j)]).collect())
            .collect()
    };
    d.set_item("M", matrix(&pt.linear.m))?;
    d.set_item("C", matrix(&pt.linear.c))?;
    d.set_item("K", matrix(&pt.linear.k))?;
    let names = |v: &[usize]| {
        v.iter()
            .map(|&i| m.coordinates[i].name.clone())
            .collect::<Vec<_>>()
    };
    d.set_item("independent", names(&pt.linear.independent))?;
    d.set_item("free", names(&m.free()))?;
    let q = PyDict::new(py);
    for (c, v) in m.coordinates.iter().zip(&pt.equilibrium.q) {
        q.set_item(&c.name, v)?;
    }
    d.set_item("q", q)?;
    let drive = PyDict::new(py);
    for &i in &m.driven() {
        drive.set_item(&m.coordinates[i].name, pt.equilibrium.drive_force[i])?;
    }
    d.set_item("drive", drive)?;
    d.set_item("iterations", pt.equilibrium.iterations)?;
    d.set_item("note", pt.note.clone())?;
    d.set_item("branch", pt.branch.as_str())?;
    d.set_item("branch_reason", pt.branch.to_string())?;
    d.set_item(
        "modes",
        table(
            py,
            &report::modes_header(m),
            &report::modes_rows(m, &model.model.model().nominal(), &pt)
                .map_err(|e| SolveError::new_err(e.to_string()))?,
        )?,
    )?;
    Ok(d)
}
