//! The report's tolerance allocation section (the report of `modaltol allocate`'s design): per
//! variable the starting and the allocated tolerance with their costs, then each round of the
//! search (the reliability index, the first-order prediction, the quadrature's verified yield).

use super::{esc, sig};
use crate::allocate::Allocation;
use crate::model::Model;
use std::fmt::Write;

/// The allocation that made the design.
pub(super) fn allocation_section(h: &mut String, model: &Model, al: &Allocation) {
    let _ = writeln!(
        h,
        "<h2 id=\"allocation\">Tolerance allocation: target yield {}, {}</h2>\
<p>The tolerances that minimise the cost Σ a + b/T<sup>k</sup> while every requirement's first-order margin keeps m₀/σ ≥ β (exact gradients, {} constraints over the requirements and speeds), β raised round by round until the quadrature's yield of every requirement, minus its error estimate, reaches the target. The rest of this report is the allocated design's analysis (case <code>{}</code>). Also in <code>allocation.csv</code> and <code>allocation.json</code>.</p>\
<table><tr><th>parameter</th><th>nominal</th><th>tolerance before (±)</th><th>allocated (±)</th><th>before %</th><th>after %</th><th>largest allowed</th><th>cost before</th><th>cost after</th></tr>",
        sig(al.target),
        if al.met {
            "<span style=\"color:#1a7f37\"><b>met</b></span>"
        } else {
            "<span style=\"color:#cf222e\"><b>NOT met</b></span>"
        },
        al.constraints,
        esc(&al.case.name),
    );
    for v in &al.variables {
        let p = &model.parameters[v.parameter];
        let pct = |t: f64| {
            if p.value != 0.0 {
                sig(100.0 * t / p.value.abs())
            } else {
                "–".into()
            }
        };
        let cost = |t: f64| v.cost.a + v.cost.b / t.powf(v.cost.k);
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td><b>{}</b></td><td>{}</td><td><b>{}</b></td><td>{}{}</td><td>{}</td><td>{}</td></tr>",
            esc(&p.name),
            sig(p.value),
            sig(v.before),
            sig(v.after),
            pct(v.before),
            pct(v.after),
            sig(v.max),
            if v.at_bound { " (reached)" } else { "" },
            sig(cost(v.before)),
            sig(cost(v.after)),
        );
    }
    let _ = writeln!(
        h,
        "<tr><th>total</th><td></td><td></td><td></td><td></td><td></td><td></td><td>{}</td><td><b>{}</b></td></tr></table>",
        sig(al.cost_before),
        sig(al.cost_after)
    );
    let _ = writeln!(
        h,
        "<table><tr><th>round</th><th>β</th><th>first-order prediction (worst constraint)</th><th>verified yield (quadrature)</th><th>nodes</th></tr>"
    );
    for (k, r) in al.rounds.iter().enumerate() {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{} ± {}</td><td>{}</td></tr>",
            k + 1,
            sig(r.beta),
            sig(r.predicted),
            sig(r.verified.0),
            sig(r.verified.1),
            r.nodes
        );
    }
    let _ = writeln!(h, "</table>");
}
