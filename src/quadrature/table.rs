//! The quadrature's rows: mean, σ, quantiles and error estimates of every output, the
//! probabilities of each change of character, and the yield with what the design meets at the
//! target.

use super::{MarginStat, QuadResult, QuadYield};
use crate::margins::{has_margin, reaches};
use crate::output::{Missing, Quantity};
use crate::propagate::{Study, Tabulate};
use crate::table::{
    Detail, Limit, Method, ProbabilityRow, QuadDetail, Row, Tables, YieldRow, cpk, reach,
};
use crate::tolerance::{LocalModel, Spread};

/// `None`: the run was cancelled before the quadrature started.
impl Tabulate for Option<QuadResult> {
    fn tabulate(self, study: &Study, case: usize, _spread: &Spread, tables: &mut Tables) {
        let Some(q) = self else {
            return;
        };
        tables.quadrature_rules.push((q.rule.clone(), q.nodes));
        if let Some(y) = &q.yields {
            tables.yields.extend(yield_rows(study, case, y, q.nodes));
        }
        for (si, lm) in study.locals.iter().enumerate() {
            let Some(lm) = lm else {
                continue;
            };
            for (k, o) in lm.outputs.iter().enumerate() {
                let stat = q.stats[si]
                    .get(k)
                    .copied()
                    .flatten()
                    .ok_or_else(|| missing(lm, k));
                let detail = stat.as_ref().ok().map(|q| QuadDetail {
                    quantiles: q.quantiles,
                    errors: (q.mean_error, q.std_error),
                    within_request: q.within_request,
                });
                let stat = stat.map(|q| (q.mean, q.std));
                let row = Row::new(study.speeds[si], case, o, stat, Detail::Quadrature(detail));
                tables.row(si, k, row);
            }
        }
        for (si, ps) in q.probabilities.iter().enumerate() {
            if study.nominal[si].is_none() {
                continue;
            }
            for p in ps {
                tables.probabilities.push(ProbabilityRow {
                    speed: study.speeds[si],
                    case,
                    method: Method::Quadrature,
                    event: p.event,
                    mode: p.mode,
                    probability: p.probability,
                    ci: (
                        (p.probability - p.error).max(0.0),
                        (p.probability + p.error).min(1.0),
                    ),
                });
            }
        }
    }
}

/// Why the quadrature has no value for output `k`: the output has none at the nominal point
/// either (the damping ratio of a rigid-body mode), or no node gave one.
fn missing(lm: &LocalModel, k: usize) -> Missing {
    match (lm.outputs[k].quantity, lm.outputs[k].mode, &lm.grad[k]) {
        (Quantity::DampingRatio, Some(_), Err(e @ Missing::RigidDamping { .. })) => e.clone(),
        (Quantity::TransferMagnitude, _, Err(e @ Missing::TransferUnbounded)) => e.clone(),
        _ => Missing::NoValue,
    }
}

/// The quadrature's rows of case `case` (`nodes` swept), with what the design meets at the
/// model's target yield.
fn yield_rows(study: &Study, case: usize, y: &QuadYield, nodes: usize) -> Vec<YieldRow> {
    let m = study.model.model();
    let (reqs, speeds) = (&m.requirements, &study.speeds);
    let target = m.allocation.target_yield;
    let ci = |(p, e): (f64, f64)| ((p - e).max(0.0), (p + e).min(1.0));
    // Within the request: the probability's error (absolute), and the worst margin's mean and
    // σ errors relative to its σ.
    let within = |(_, e): (f64, f64)| e <= y.request;
    let margin_within = |m: &MarginStat| {
        let allowed = y.request * m.std;
        m.mean_error <= allowed && m.std_error <= allowed
    };
    let mut out = vec![YieldRow {
        case,
        method: Method::Quadrature,
        requirement: None,
        speed: None,
        probability: y.all.0,
        ci: ci(y.all),
        margin: None,
        cpk: None,
        evaluations: nodes,
        within_request: Some(within(y.all)),
        limit: None,
    }];
    for (r, &each) in y.each.iter().enumerate() {
        let margin = y.margins[r].map(|m| (m.mean, m.std));
        let prefix: Vec<(f64, f64, (f64, f64))> = speeds
            .iter()
            .zip(&y.prefix)
            .filter(|(w, _)| reaches(&reqs[r], **w))
            .map(|(&w, p)| (w, p[r].0, ci(p[r])))
            .collect();
        out.push(YieldRow {
            case,
            method: Method::Quadrature,
            requirement: Some(r),
            speed: None,
            probability: each.0,
            ci: ci(each),
            margin,
            cpk: margin.and_then(|(m, s)| cpk(m, s)),
            evaluations: nodes,
            within_request: Some(within(each) && y.margins[r].as_ref().is_none_or(margin_within)),
            limit: Some(match y.margins[r].and_then(|m| m.at_target) {
                Some(t) => Limit::new(
                    reach(&prefix, target),
                    Some([t.estimate, t.low, t.high]),
                    [
                        "more than 1 − target of the designs fail without a margin",
                        "margin_low unbounded: the target plus the probability's error exceeds \
                         the share of designs with a margin",
                        "margin_high unbounded: the target less the probability's error is ≤ 0",
                    ],
                ),
                None if has_margin(&reqs[r]) => Limit::without_margin(
                    reach(&prefix, target),
                    "no design has a margin over the range (every node failed or has no value)",
                ),
                None => Limit::new(reach(&prefix, target), None, [""; 3]),
            }),
        });
    }
    for (i, row) in y.curves.iter().enumerate() {
        for (r, &p) in row.iter().enumerate() {
            if p.0.is_nan() {
                continue;
            }
            out.push(YieldRow {
                case,
                method: Method::Quadrature,
                requirement: Some(r),
                speed: Some(speeds[i]),
                probability: p.0,
                ci: ci(p),
                margin: None,
                cpk: None,
                evaluations: nodes,
                within_request: Some(within(p)),
                limit: None,
            });
        }
    }
    out
}
