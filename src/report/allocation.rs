//! The result of a tolerance allocation: `allocation.csv` (per variable), `allocation.json`
//! (the target, the rounds of search and verification, the costs) and the table printed.

use crate::allocate::Allocation;
use crate::model::Model;
use serde_json::{Value, json};
use std::fmt::Write;

/// Header of `allocation.csv`.
pub const ALLOCATION_HEADER: [&str; 11] = [
    "parameter",
    "nominal",
    "distribution",
    "tolerance_before",
    "tolerance_after",
    "relative_before",
    "relative_after",
    "max",
    "at_max",
    "cost_before",
    "cost_after",
];

/// Rows of `allocation.csv`: per variable, the case's tolerance and the allocated one (± in the
/// parameter's unit, and relative to the nominal value), the largest allowed and the costs.
pub fn allocation_rows(model: &Model, a: &Allocation) -> Vec<Vec<String>> {
    a.variables
        .iter()
        .map(|v| {
            let p = &model.parameters[v.parameter];
            let cost = |t: f64| v.cost.a + v.cost.b / t.powf(v.cost.k);
            let rel = |t: f64| {
                if p.value != 0.0 {
                    (t / p.value.abs()).to_string()
                } else {
                    String::new()
                }
            };
            vec![
                p.name.clone(),
                p.value.to_string(),
                match p.distribution {
                    crate::model::Distribution::Normal => "normal",
                    crate::model::Distribution::Uniform => "uniform",
                }
                .to_string(),
                v.before.to_string(),
                v.after.to_string(),
                rel(v.before),
                rel(v.after),
                v.max.to_string(),
                v.at_bound.to_string(),
                cost(v.before).to_string(),
                cost(v.after).to_string(),
            ]
        })
        .collect()
}

/// `allocation.json`.
pub fn allocation_json(model: &Model, a: &Allocation) -> Value {
    json!({
        "model": model.name,
        "target_yield": a.target,
        "met": a.met,
        "cost_before": a.cost_before,
        "cost_after": a.cost_after,
        "constraints": a.constraints,
        "verified_yield": a.rounds[a.chosen].verified.0,
        "verified_error": a.rounds[a.chosen].verified.1,
        "chosen_round": a.chosen + 1,
        "cost_gap": a.cost_gap,
        "variables": a.variables.iter().map(|v| json!({
            "parameter": model.parameters[v.parameter].name, "tolerance_before": v.before,
            "tolerance_after": v.after, "max": v.max, "at_max": v.at_bound,
            "cost": {"a": v.cost.a, "b": v.cost.b, "k": v.cost.k}})).collect::<Vec<_>>(),
        "rounds": a.rounds.iter().map(|r| json!({
            "beta": r.beta, "predicted_worst_probability": r.predicted,
            "verified_yield": r.verified.0, "verified_error": r.verified.1,
            "quadrature_nodes": r.nodes})).collect::<Vec<_>>(),
        "note": "tolerances are ± values in the parameter's unit (±3σ of a normal variable, the half-width of a uniform one); the verified yield is the quadrature's probability of meeting every requirement at every speed of its range",
    })
}

/// The allocation as a text table.
pub fn allocation_table(model: &Model, a: &Allocation) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<16} {:>12} {:>14} {:>14} {:>9} {:>9}",
        "parameter", "nominal", "tolerance", "allocated", "before %", "after %"
    );
    for v in &a.variables {
        let p = &model.parameters[v.parameter];
        let pct = |t: f64| 100.0 * t / p.value.abs();
        let _ = writeln!(
            s,
            "{:<16} {:>12.6} {:>14.6e} {:>14.6e} {:>9.3} {:>9.3}{}",
            p.name,
            p.value,
            v.before,
            v.after,
            pct(v.before),
            pct(v.after),
            if v.at_bound { "  (at its largest)" } else { "" }
        );
    }
    let r = &a.rounds[a.chosen];
    let _ = writeln!(
        s,
        "cost {:.6} → {:.6}; verified yield {:.6} ± {:.2e} (target {}): {}",
        a.cost_before,
        a.cost_after,
        r.verified.0,
        r.verified.1,
        a.target,
        if a.met { "met" } else { "NOT met" }
    );
    let _ = writeln!(
        s,
        "round {} of {}; {}",
        a.chosen + 1,
        a.rounds.len(),
        match a.cost_gap {
            Some(g) => format!(
                "{:.3} % above the cheapest design found short of the target",
                100.0 * g
            ),
            None => "no design short of the target was tried: the cost is not bracketed".into(),
        }
    );
    s
}
