//! Formatting of results: CSV rows, JSON documents and text tables. Builds strings and values;
//! writing them anywhere is the CLI's business.
//!
//! Units: speeds and frequencies in rad/s, angles in rad, translations in m, drive forces in
//! N·m (revolute) or N (prismatic), damping ratios dimensionless.
//!
//! One submodule per thing formatted: the results of the commands `check`, `modal`, `sweep`,
//! `sensitivity` and `frf`; an analysis's CSV tables (`tolerance`), its `summary.json`
//! (`summary`), what it left without a value (`unfilled`) and its HTML page (`html`). This
//! module holds what several of them share (the cells of a mode, a failed point's rows, how a
//! number that is not there is written) and re-exports every public item, so that callers
//! name them `report::…`.

mod accuracy;
mod allocation;
mod check;
mod frf;
mod html;
mod modal;
mod peaks;
mod sensitivity;
mod summary;
mod sweep;
mod tolerance;
mod unfilled;
mod yields;

pub use accuracy::{
    Outside, YieldOutside, outside_request, outside_request_lines, yield_outside_request,
};
pub use allocation::{ALLOCATION_HEADER, allocation_json, allocation_rows, allocation_table};
pub use check::{check_report, check_summary, solved_warnings};
pub use frf::{frf_header, frf_rows};
pub use html::{Extra, MODES_DRAWN, report_html};
pub use modal::{
    body_shapes, display_shape, modal_json, modal_table, modes_failed_rows, modes_header,
    modes_rows,
};
pub use peaks::{PEAK_HEADER, peak_rows};
pub use sensitivity::{SENSITIVITY_HEADER, SensitivityReport, elasticity, transfer_defect_at};
pub use summary::{paper_timings, summary_json};
pub use sweep::{SweepColumns, sweep_header, sweep_rows};
pub use tolerance::{PROBABILITY_HEADER, probability_rows, tolerance_header, tolerance_rows};
pub use unfilled::{Unfilled, inadmissible_warnings, unfilled, unfilled_lines};
pub use yields::{
    LIMITS_HEADER, SOBOL_HEADER, YIELD_HEADER, describe, limit_rows, sobol_rows, tightest, verdict,
    yield_rows, yield_summary,
};

use crate::modal::Mode;
use crate::model::Model;
use crate::sweep::{Point, PointError};

/// `x` with `decimals` decimals, or `–` where it is undefined (the damping ratio of a
/// rigid-body mode).
fn fixed(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "–".into()
    }
}

fn opt(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or(String::new(), |x| x.to_string())
}

/// A row's message: its parts that are there, joined.
fn message<'a>(parts: impl IntoIterator<Item = Option<&'a str>>) -> String {
    parts.into_iter().flatten().collect::<Vec<_>>().join("; ")
}

/// The columns every per-mode table starts with: where, which mode, its character and roots.
const MODE_COLUMNS: [&str; 10] = [
    "speed",
    "mode",
    "status",
    "damped_frequency",
    "natural_frequency",
    "damping_ratio",
    "eigen_re",
    "eigen_im",
    "eigen2_re",
    "eigen2_im",
];

/// The cells of [`MODE_COLUMNS`] for mode `i` (0-based) of a point at `speed`.
fn mode_cells(speed: f64, i: usize, m: &Mode) -> Vec<String> {
    vec![
        speed.to_string(),
        (i + 1).to_string(),
        m.class.as_str().to_string(),
        m.damped_frequency.to_string(),
        m.natural_frequency.to_string(),
        opt(Some(m.damping_ratio)),
        m.root.lambda.re.to_string(),
        m.root.lambda.im.to_string(),
        m.partner.lambda.re.to_string(),
        m.partner.lambda.im.to_string(),
    ]
}

/// A failed point's rows, `ncols` wide: one per degree of freedom, status `failed`, the
/// reason in the last column (`message`).
fn failed_rows(model: &Model, ncols: usize, speed: f64, e: &PointError) -> Vec<Vec<String>> {
    (0..model.dof().max(1))
        .map(|i| {
            let mut r = vec![String::new(); ncols];
            r[0] = speed.to_string();
            r[1] = (i + 1).to_string();
            r[2] = "failed".into();
            r[ncols - 1] = e.to_string();
            r
        })
        .collect()
}

/// What a point's rows say beside their numbers: which branch and why where it is not simply
/// the stable equilibrium reached, then any note (a change of stability).
fn point_message(p: &Point, transfer: Option<&str>) -> String {
    let branch = (p.branch.as_str() != "stable").then(|| p.branch.to_string());
    message([branch.as_deref(), p.note.as_deref(), transfer])
}
