//! The yield of the model's requirements: `yield.csv`, its part of `summary.json` and the
//! report's first section (each requirement's probability by each method beside the target,
//! pass or fail, its worst margin and capability index).

use crate::analyze::Analysis;
use crate::margins::unit;
use crate::model::{Model, Requirement};
use crate::table::Method;
use crate::table::YieldRow;
use serde_json::{Value, json};

/// Header of `yield.csv`.
pub const YIELD_HEADER: [&str; 19] = [
    "case",
    "method",
    "requirement",
    "kind",
    "mode",
    "speed_from",
    "speed_to",
    "speed",
    "probability",
    "ci_low",
    "ci_high",
    "target",
    "meets_target",
    "margin_unit",
    "margin_mean",
    "margin_std",
    "cpk",
    "evaluations",
    "within_request",
];

/// The requirement in words (for the report).
pub fn describe(r: &Requirement) -> String {
    let what = r.kind.describe(&modes_read(r));
    match r.speeds {
        Some((a, b)) => format!("{what}, for {a} ≤ Ω ≤ {b} rad/s"),
        None => format!("{what}, at every speed"),
    }
}

/// The mode(s) a requirement reads, in words.
fn modes_read(r: &Requirement) -> String {
    r.mode
        .map_or("every mode".to_string(), |m| format!("mode {}", m + 1))
}

/// Does a probability with interval `ci` meet `target`: `yes` where the interval is above
/// it, `no` where below, `undecided` where it holds it.
pub fn verdict(ci: (f64, f64), target: f64) -> &'static str {
    if ci.0 >= target {
        "yes"
    } else if ci.1 < target {
        "no"
    } else {
        "undecided"
    }
}

/// A number for JSON: `null` where it is not finite (JSON has no infinities).
fn finite_or_null(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn opt(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or(String::new(), |x| x.to_string())
}

/// The transfer function's unit, for the margins of `transfer` requirements.
pub(in crate::report) fn transfer_unit(model: &Model) -> String {
    model
        .analysis
        .transfer
        .as_ref()
        .map_or(String::new(), |t| model.transfer_unit(t))
}

/// Rows of `yield.csv`: per case and method, all requirements together
/// (`requirement = all`), then each over its range, then each per speed.
pub fn yield_rows(model: &Model, a: &Analysis) -> Vec<Vec<String>> {
    let target = model.allocation.target_yield;
    let tu = transfer_unit(model);
    a.yields
        .iter()
        .map(|y| {
            let r = y.requirement.map(|r| &model.requirements[r]);
            let range = |end: fn((f64, f64)) -> f64| {
                r.and_then(|r| r.speeds)
                    .map_or(String::new(), |s| end(s).to_string())
            };
            vec![
                a.cases[y.case].name.clone(),
                y.method.as_str().to_string(),
                r.map_or("all".to_string(), |r| r.name.clone()),
                r.map_or(String::new(), |r| r.kind.name().to_string()),
                r.and_then(|r| r.mode)
                    .map_or(String::new(), |m| (m + 1).to_string()),
                range(|s| s.0),
                range(|s| s.1),
                y.speed.map_or(String::new(), |w| w.to_string()),
                y.probability.to_string(),
                y.ci.0.to_string(),
                y.ci.1.to_string(),
                target.to_string(),
                if y.speed.is_none() && y.method != Method::FirstOrder {
                    verdict(y.ci, target).to_string()
                } else if y.speed.is_none() {
                    // First order over a range is an upper bound: it can only say no.
                    if y.probability < target {
                        "no"
                    } else {
                        "undecided"
                    }
                    .to_string()
                } else {
                    String::new()
                },
                r.filter(|_| y.margin.is_some())
                    .map_or(String::new(), |r| unit(r, &tu)),
                opt(y.margin.map(|m| m.0)),
                opt(y.margin.map(|m| m.1)),
                opt(y.cpk),
                y.evaluations.to_string(),
                y.within_request.map_or(String::new(), |w| w.to_string()),
            ]
        })
        .collect()
}

/// The yield part of `summary.json`: the target and, per case, method and requirement (or all),
/// the probability over the range with its interval and verdict.
pub fn yield_summary(model: &Model, a: &Analysis) -> Value {
    let target = model.allocation.target_yield;
    json!({
        "target_yield": target,
        "requirements": model.requirements.iter().map(|r| json!({
            "name": r.name, "kind": r.kind.name(), "mode": r.mode.map(|m| m + 1),
            "speeds": r.speeds.map(|s| [s.0, s.1]), "description": describe(r)})).collect::<Vec<_>>(),
        "results": a.yields.iter().filter(|y| y.speed.is_none()).map(|y: &YieldRow| json!({
            "case": a.cases[y.case].name, "method": y.method.as_str(),
            "requirement": y.requirement.map_or("all".to_string(), |r| model.requirements[r].name.clone()),
            "probability": y.probability, "ci": [y.ci.0, y.ci.1],
            "meets_target": verdict(y.ci, target),
            "margin_mean": y.margin.map(|m| m.0), "margin_std": y.margin.map(|m| m.1),
            "cpk": y.cpk,
            "at_target": y.limit.as_ref().map(|l| json!({
                "reach": l.reach, "margin": l.margin.map(|m| m.map(finite_or_null)),
                "reason": l.why,
            }))})).collect::<Vec<_>>(),
    })
}

/// Header of `limits.csv`.
pub const LIMITS_HEADER: [&str; 16] = [
    "case",
    "method",
    "requirement",
    "kind",
    "target",
    "speed_from",
    "speed_to",
    "reach",
    "reach_low",
    "reach_high",
    "margin_unit",
    "margin_at_target",
    "margin_low",
    "margin_high",
    "tightest",
    "reason",
];

/// The tightest requirement of `r`'s kind that designs meet at the target yield, in words,
/// from the worst margin met at it (`q`, in the margin's unit): each kind's bound moved by `q`.
pub fn tightest(r: &Requirement, q: f64, transfer_unit: &str) -> String {
    if q.is_nan() {
        return String::new();
    }
    if q == f64::NEG_INFINITY {
        return "none: more than 1 − target of the designs fail without a margin".into();
    }
    r.kind.tightest(&modes_read(r), q, transfer_unit)
}

/// Rows of `limits.csv`: per case, method and requirement, what the design with the case's
/// tolerances meets at the target yield: the highest speed up to which (from its range's
/// start) it holds, and the worst margin met, with the tightest requirement of its kind.
pub fn limit_rows(model: &Model, a: &Analysis) -> Vec<Vec<String>> {
    let target = model.allocation.target_yield;
    let tu = transfer_unit(model);
    let speed = |w: Option<f64>| w.map_or(String::new(), |w| w.to_string());
    a.yields
        .iter()
        .filter_map(|y| Some((y, y.limit.as_ref()?, &model.requirements[y.requirement?])))
        .map(|(y, l, r)| {
            // An unbounded or missing end is blank; `reason` says why.
            let m = |k: usize| {
                l.margin
                    .filter(|m| m[k].is_finite())
                    .map_or(String::new(), |m| m[k].to_string())
            };
            vec![
                a.cases[y.case].name.clone(),
                y.method.as_str().to_string(),
                r.name.clone(),
                r.kind.name().to_string(),
                target.to_string(),
                speed(r.speeds.map(|s| s.0)),
                speed(r.speeds.map(|s| s.1)),
                speed(l.reach[0]),
                speed(l.reach[1]),
                speed(l.reach[2]),
                l.margin.map_or(String::new(), |_| unit(r, &tu)),
                m(0),
                m(1),
                m(2),
                l.margin.map_or(String::new(), |m| tightest(r, m[0], &tu)),
                l.why.clone().unwrap_or_default(),
            ]
        })
        .collect()
}

/// Header of `sobol.csv`.
pub const SOBOL_HEADER: [&str; 14] = [
    "case",
    "target",
    "speed",
    "quantity",
    "mode",
    "variable",
    "first",
    "first_ci_low",
    "first_ci_high",
    "total",
    "total_ci_low",
    "total_ci_high",
    "derivative_bound",
    "rows",
];

/// Rows of `sobol.csv`: per case, target (an output at a speed, or a requirement's worst
/// margin: `margin:<name>`) and variable.
pub fn sobol_rows(model: &Model, a: &Analysis) -> Vec<Vec<String>> {
    use crate::table::Target;
    a.sobol
        .iter()
        .map(|(case, s)| {
            let (target, speed, quantity, mode) = match s.target {
                Target::Output(i, o) => {
                    let out = a.outputs[o];
                    (
                        "output".to_string(),
                        a.speeds[i].to_string(),
                        out.quantity.as_str().to_string(),
                        out.mode.map_or(String::new(), |m| (m + 1).to_string()),
                    )
                }
                Target::Margin(r) => (
                    format!("margin:{}", model.requirements[r].name),
                    String::new(),
                    String::new(),
                    String::new(),
                ),
            };
            vec![
                a.cases[*case].name.clone(),
                target,
                speed,
                quantity,
                mode,
                model.parameters[a.vars[s.variable]].name.clone(),
                s.first.to_string(),
                s.first_ci.0.to_string(),
                s.first_ci.1.to_string(),
                s.total.to_string(),
                s.total_ci.0.to_string(),
                s.total_ci.1.to_string(),
                opt(s.bound),
                s.rows.to_string(),
            ]
        })
        .collect()
}
