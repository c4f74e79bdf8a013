//! The CSV tables of an analysis: `tolerance.csv` (mean and σ per speed, output, case and
//! method, with Monte Carlo's intervals, the quadrature's quantiles and error estimates and the
//! variance shares) and `probabilities.csv` (the probability of each change of character).

use super::opt;
use crate::analyze::Analysis;
use crate::model::Model;

/// Header of `tolerance.csv`.
pub fn tolerance_header(model: &Model, a: &Analysis) -> Vec<String> {
    let mut h: Vec<String> = [
        "speed",
        "quantity",
        "mode",
        "case",
        "method",
        "mean",
        "std",
        "mean_ci_low",
        "mean_ci_high",
        "std_ci_low",
        "std_ci_high",
        "samples",
        "failed",
        "class_changed",
        "basis",
        "q05",
        "q50",
        "q95",
        "mean_error",
        "std_error",
        "within_request",
        "partial",
        "reason",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    h.extend(
        a.vars
            .iter()
            .map(|&b| format!("share:{}", model.parameters[b].name)),
    );
    h
}

/// Rows of `tolerance.csv`: one per (speed, quantity, mode, case, method). Empty cells where a
/// method gives no answer (its `reason` says why: an output not differentiable there, a
/// rigid-body mode's damping ratio) or a column does not apply.
/// `partial` (a column of every row) says the run was interrupted: the Monte Carlo rows cover
/// fewer samples than asked.
pub fn tolerance_rows(a: &Analysis, partial: bool) -> Vec<Vec<String>> {
    a.rows
        .iter()
        .map(|r| {
            let mut v = vec![
                r.speed.to_string(),
                r.quantity.as_str().to_string(),
                r.mode.map_or(String::new(), |m| (m + 1).to_string()),
                a.cases[r.case].name.clone(),
                r.method().as_str().to_string(),
                opt(Some(r.mean)),
                opt(Some(r.std)),
            ];
            match &r.mc() {
                Some(m) => v.extend([
                    opt(Some(m.mean_ci.0)),
                    opt(Some(m.mean_ci.1)),
                    opt(Some(m.std_ci.0)),
                    opt(Some(m.std_ci.1)),
                    m.n.to_string(),
                    m.failed.to_string(),
                    m.class_changed.to_string(),
                ]),
                None => v.extend(std::iter::repeat_n(String::new(), 7)),
            }
            v.push(r.basis().map_or(String::new(), |m| m.as_str().to_string()));
            match r.quantiles() {
                Some(q) => v.extend(q.map(|x| opt(Some(x)))),
                None => v.extend(std::iter::repeat_n(String::new(), 3)),
            }
            match r.errors() {
                Some((em, es)) => v.extend([opt(Some(em)), opt(Some(es))]),
                None => v.extend(std::iter::repeat_n(String::new(), 2)),
            }
            v.push(r.within_request().map_or(String::new(), |w| w.to_string()));
            v.push(partial.to_string());
            v.push(r.missing.as_ref().map_or(String::new(), |m| m.to_string()));
            match &r.shares() {
                Some(s) => v.extend(s.iter().map(|x| opt(Some(*x)))),
                None => v.extend(std::iter::repeat_n(String::new(), a.vars.len())),
            }
            v
        })
        .collect()
}

/// Header of `probabilities.csv`.
pub const PROBABILITY_HEADER: [&str; 8] = [
    "speed",
    "case",
    "method",
    "event",
    "mode",
    "probability",
    "ci_low",
    "ci_high",
];

/// Rows of `probabilities.csv`: one per (speed, case, method, event, mode); `mode` (1-based)
/// for `overdamped` only. The interval is the quadrature's probability ± its error estimate,
/// or the Monte Carlo's 95 % Wilson score interval.
pub fn probability_rows(a: &Analysis) -> Vec<Vec<String>> {
    a.probabilities
        .iter()
        .map(|p| {
            vec![
                p.speed.to_string(),
                a.cases[p.case].name.clone(),
                p.method.as_str().to_string(),
                p.event.as_str().to_string(),
                p.mode.map_or(String::new(), |m| (m + 1).to_string()),
                p.probability.to_string(),
                p.ci.0.to_string(),
                p.ci.1.to_string(),
            ]
        })
        .collect()
}
