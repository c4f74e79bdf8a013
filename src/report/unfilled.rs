//! What an analysis left without an answer, told to the user: the rows without a value grouped
//! by case, method, output and reason ([`unfilled`], for `summary.json` and the report), the
//! same in a few lines for stderr, and the Monte Carlo samples that were not physically
//! admissible. Its own file because three outputs (stderr, JSON, HTML) say it.

use super::accuracy::{bounds, output_name, speed_range};
use crate::analyze::Analysis;
use crate::output::Quantity;
use crate::table::Method;

/// Rows of one method for one output and case that have no value, for one reason.
#[derive(Debug, Clone)]
pub struct Unfilled {
    pub case: usize,
    pub method: Method,
    pub quantity: Quantity,
    pub mode: Option<usize>,
    pub reason: String,
    /// The speeds (rad/s) of those rows, in the rows' order.
    pub speeds: Vec<f64>,
}

/// Every row without a value, grouped by case, method, output and reason, in the rows' order.
pub fn unfilled(a: &Analysis) -> Vec<Unfilled> {
    let mut out: Vec<Unfilled> = Vec::new();
    for r in &a.rows {
        let Some(m) = &r.missing else { continue };
        let reason = m.to_string();
        let same = |u: &Unfilled| {
            u.case == r.case
                && u.method == r.method()
                && u.quantity == r.quantity
                && u.mode == r.mode
                && u.reason == reason
        };
        match out.iter_mut().find(|u| same(u)) {
            Some(u) => u.speeds.push(r.speed),
            None => out.push(Unfilled {
                case: r.case,
                method: r.method(),
                quantity: r.quantity,
                mode: r.mode,
                reason,
                speeds: vec![r.speed],
            }),
        }
    }
    out
}

/// Groups of [`unfilled`] shown on stderr at most (`summary.json` and the report list all).
const UNFILLED_LINES: usize = 12;

/// The rows without a value in a few lines: per method and reason, how many rows, which
/// outputs and speeds (empty when every row has a value).
pub fn unfilled_lines(a: &Analysis) -> Vec<String> {
    let groups = unfilled(a);
    // Per (method, reason): rows, outputs, speed range, cases.
    let mut merged: Vec<(Method, String, usize, Vec<String>, f64, f64)> = Vec::new();
    for u in &groups {
        let output = output_name(u.quantity, u.mode);
        let (lo, hi) = bounds(&u.speeds);
        match merged
            .iter_mut()
            .find(|x| x.0 == u.method && x.1 == u.reason)
        {
            Some(x) => {
                x.2 += u.speeds.len();
                if !x.3.contains(&output) {
                    x.3.push(output);
                }
                x.4 = x.4.min(lo);
                x.5 = x.5.max(hi);
            }
            None => merged.push((
                u.method,
                u.reason.clone(),
                u.speeds.len(),
                vec![output],
                lo,
                hi,
            )),
        }
    }
    let mut lines: Vec<String> = merged
        .iter()
        .take(UNFILLED_LINES)
        .map(|(method, reason, rows, outputs, lo, hi)| {
            let speeds = speed_range((*lo, *hi));
            format!(
                "{}: {rows} row(s) without a value ({}; {speeds}): {reason}",
                method.as_str(),
                outputs.join(", ")
            )
        })
        .collect();
    if merged.len() > UNFILLED_LINES {
        lines.push(format!(
            "… and {} more groups of rows without a value (summary.json lists them all)",
            merged.len() - UNFILLED_LINES
        ));
    }
    lines
}

/// Warnings of a Monte Carlo whose samples crossed a physical limit, one line per case and
/// reason (empty when none did).
pub fn inadmissible_warnings(a: &Analysis) -> Vec<String> {
    let mut out = Vec::new();
    for (ci, t) in a.inadmissible.iter().enumerate() {
        let done = a.samples_done.get(ci).copied().unwrap_or(0);
        for (reason, n, v) in t {
            out.push(format!(
                "case '{}': {n} of {done} Monte Carlo samples are not physically admissible ({reason}, e.g. {v:e}); they count as failed at every speed",
                a.cases[ci].name
            ));
        }
    }
    out
}
