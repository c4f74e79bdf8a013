//! `summary.json` of an analysis: the model, cases, speeds, timings (beside the paper's for
//! its two examples, [`paper_timings`]), the largest probabilities, the Monte Carlo's settings
//! and failures, and every row without a value. Its own file because it condenses the whole
//! run into one document.

use super::{outside_request, unfilled, yield_outside_request};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::montecarlo::McOptions;
use serde_json::{Value, json};

/// Per case, method, event and mode: the largest probability over the speeds and where it is.
fn probability_summary(a: &Analysis) -> Vec<Value> {
    let mut out: Vec<Value> = Vec::new();
    let mut keys: Vec<(usize, &str, &str, Option<usize>)> = a
        .probabilities
        .iter()
        .map(|p| (p.case, p.method.as_str(), p.event.as_str(), p.mode))
        .collect();
    keys.sort();
    keys.dedup();
    for (case, method, event, mode) in keys {
        let rows = a.probabilities.iter().filter(|p| {
            p.case == case
                && p.method.as_str() == method
                && p.event.as_str() == event
                && p.mode == mode
        });
        let (mut best, mut at, mut any) = (0.0f64, None, 0usize);
        for p in rows {
            if p.probability > 0.0 {
                any += 1;
            }
            if p.probability > best {
                (best, at) = (p.probability, Some(p.speed));
            }
        }
        out.push(
            json!({"case": a.cases[case].name, "method": method, "event": event,
                        "mode": mode.map(|m| m + 1), "max_probability": best, "at_speed": at,
                        "speeds_with_nonzero_probability": any}),
        );
    }
    out
}

/// The paper's timings (Kim & Yoo 2007, Tables 1–2: analytic s, Monte Carlo s, ratio) when the
/// model is one of its two examples ([`Model::paper_example`]).
pub fn paper_timings(model: &Model) -> Option<(&'static str, f64, f64, f64)> {
    match model.paper_example()? {
        "pendulum" => Some(("pendulum", 0.703, 448.281, 638.0)),
        _ => Some(("governor", 2.188, 2525.375, 1154.0)),
    }
}

/// `summary.json` of an analysis: model, cases, timings (beside the paper's for its two
/// examples), failures.
pub fn summary_json(model: &Model, a: &Analysis, mc: Option<&McOptions>, threads: usize) -> Value {
    let cases: Vec<Value> = a
        .cases
        .iter()
        .map(|c| {
            json!({"name": c.name, "tolerances": c.tolerances.iter().map(|(b, t)| {
                let p = &model.parameters[*b];
                json!({"parameter": p.name, "nominal": p.value, "tolerance": t.absolute(p.value),
                       "distribution": p.distribution})
            }).collect::<Vec<_>>(), "correlated": c.correlation.is_some()})
        })
        .collect();
    let speeds: Vec<f64> = {
        let mut s: Vec<f64> = a.rows.iter().map(|r| r.speed).collect();
        s.dedup();
        s
    };
    let mc_failed: usize = a.rows.iter().filter_map(|r| r.mc().map(|m| m.failed)).sum();
    let mut summary = json!({
        "model": model.name,
        "file": model.file,
        "units": {"speed": "rad/s", "damped_frequency": "rad/s", "damping_ratio": "1", "time": "s"},
        "speeds": {"count": a.nominal.len(), "from": speeds.first(), "to": speeds.last()},
        "design_variables": a.vars.iter().map(|&b| model.parameters[b].name.clone()).collect::<Vec<_>>(),
        "cases": cases,
        "methods": ["first_order", "second_order", "invariant", "quadrature", "analytic", "monte_carlo"],
        "analytic_seconds": a.analytic_seconds,
        "first_order_seconds": a.first_order_seconds,
        "second_order_seconds": a.second_order_seconds,
        "quadrature_seconds": a.quadrature_seconds,
        "quadrature": a.quadrature_seconds.map(|t| json!({"seconds": t,
            "cases": a.cases.iter().zip(&a.quadrature_rules).map(|(c, (rule, nodes))|
                json!({"case": c.name, "rule": rule, "nodes_swept": nodes})).collect::<Vec<_>>()})),
        "probabilities": probability_summary(a),
        "yield": (!model.requirements.is_empty()).then(|| super::yield_summary(model, a)),
        "monte_carlo": mc.map(|m| json!({"samples": m.samples, "seed": m.seed, "sampling": m.sampling, "threads": threads,
                                          "seconds": a.monte_carlo_seconds, "failed_sample_points": mc_failed,
                                          "samples_done": a.samples_done, "partial": a.interrupted(m.samples),
                                          "inadmissible_samples": inadmissible_summary(a)})),
        "partial": a.cancelled() || mc.is_some_and(|m| a.interrupted(m.samples)),
        "ratio_monte_carlo_to_analytic": a.monte_carlo_seconds.map(|m| m / a.analytic_seconds),
        "ratio_monte_carlo_to_quadrature": a.monte_carlo_seconds.zip(a.quadrature_seconds).map(|(m, q)| m / q),
        "paper": paper_timings(model).map(|(example, analytic, mc, ratio)| json!({
            "note": "Kim & Yoo (2007), Tables 1–2, 2007 hardware, 3000 samples",
            "example": example, "analytic_seconds": analytic, "monte_carlo_seconds": mc, "ratio": ratio})),
        "failures": a.failures.iter().map(|(w, m)| json!({"speed": w, "message": m})).collect::<Vec<_>>(),
        "quadrature_outside_request": outside_request(a).iter().map(|o| json!({
            "case": a.cases[o.case].name, "quantity": o.quantity.as_str(), "mode": o.mode.map(|m| m + 1),
            "rows": o.speeds.len(), "speeds": o.speeds})).collect::<Vec<_>>(),
        "quadrature_yield_outside_request": yield_outside_request(a).iter().map(|o| json!({
            "case": a.cases[o.case].name,
            "requirement": o.requirement.map_or("all".to_string(), |r| model.requirements[r].name.clone()),
            "rows": o.speeds.len(), "speeds": o.speeds})).collect::<Vec<_>>(),
        "sobol_refused": a.sobol_refused.iter().map(|(case, why)| json!({
            "case": a.cases[*case].name, "reason": why})).collect::<Vec<_>>(),
        "unfilled": unfilled(a).iter().map(|u| json!({
            "case": a.cases[u.case].name, "method": u.method.as_str(), "quantity": u.quantity.as_str(),
            "mode": u.mode.map(|m| m + 1), "reason": u.reason, "rows": u.speeds.len(),
            "speeds": u.speeds})).collect::<Vec<_>>(),
    });
    // The paper's timings for its own examples only: no `paper` key in another model's summary.
    if let Some(o) = summary.as_object_mut().filter(|o| o["paper"].is_null()) {
        o.remove("paper");
    }
    summary
}

/// Per case, the Monte Carlo samples that are not physically admissible, by reason.
fn inadmissible_summary(a: &Analysis) -> Vec<serde_json::Value> {
    a.cases
        .iter()
        .zip(&a.inadmissible)
        .map(|(c, t)| {
            json!({"case": c.name, "samples": t.iter().map(|x| x.1).sum::<usize>(),
                   "reasons": t.iter().map(|(r, n, v)| json!({"reason": r, "samples": n, "first_value": v})).collect::<Vec<_>>()})
        })
        .collect()
}
