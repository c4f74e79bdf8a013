//! The report's table of where first order (the paper's method) is off: per case and output,
//! the speed ranges where first order's σ is more than 10 % off the quadrature's, and the worst
//! of those speeds.

use super::esc;
use crate::analyze::Analysis;
use crate::model::Model;
use crate::output::Quantity;
use crate::plots::Display;
use crate::table::Method;
use std::fmt::Write;

/// Per case and output: the speeds where first order's σ is more than 10 % off the
/// quadrature's (where the quadrature's σ is at least 2 % of its largest: below that a
/// relative error says nothing), as ranges in the display units, and the worst of them.
pub(super) fn first_order_table(model: &Model, a: &Analysis, d: Display) -> String {
    let whose = if model.paper_example().is_some() {
        " (the paper's method)"
    } else {
        ""
    };
    let f = d.speed.per_rad_per_second();
    let mut h = format!(
        "<h2>Where first order{whose} is off</h2><p>First order's σ against the \
         quadrature's, where the quadrature's σ is at least 2 % of its largest over the speeds \
         (where σ passes near zero a relative error says nothing).</p><table><tr><th>case</th>\
         <th>output</th><th>speeds ({}) where first order's σ is &gt; 10 % off the \
         quadrature's</th><th>worst</th></tr>",
        d.speed.symbol()
    );
    let mut outputs: Vec<(Quantity, Option<usize>)> = a
        .rows
        .iter()
        .filter(|r| r.method() == Method::Quadrature && r.quantity != Quantity::DampingRatio)
        .map(|r| (r.quantity, r.mode))
        .collect();
    outputs.sort_by_key(|o| (o.0 as u8, o.1));
    outputs.dedup();
    let mut any = false;
    for (ci, c) in a.cases.iter().enumerate() {
        for &(q, mode) in &outputs {
            let off = crate::plots::first_order_off(a, ci, q, mode);
            let mut ranges: Vec<(f64, f64)> = Vec::new();
            let mut open = false;
            for &(w, v) in &off {
                if v.is_finite() {
                    match (open, ranges.last_mut()) {
                        (true, Some(r)) => r.1 = w,
                        _ => ranges.push((w, w)),
                    }
                }
                open = v.is_finite();
            }
            if ranges.is_empty() {
                continue;
            }
            any = true;
            // The worst over the speeds flagged (σ not near zero there).
            let worst = (off.iter())
                .filter(|(_, v)| v.is_finite())
                .filter_map(|&(w, _)| {
                    let at = |m: Method| {
                        a.rows.iter().find(|r| {
                            r.case == ci
                                && r.quantity == q
                                && r.mode == mode
                                && r.method() == m
                                && r.speed.to_bits() == w.to_bits()
                        })
                    };
                    let (quad, first) = (at(Method::Quadrature)?, at(Method::FirstOrder)?);
                    Some(((first.std - quad.std).abs() / quad.std, w))
                })
                .filter(|x| x.0.is_finite())
                .fold((0.0f64, f64::NAN), |m, x| if x.0 > m.0 { x } else { m });
            let label = mode.map_or(q.as_str().to_string(), |m| {
                format!("{} mode {}", q.as_str(), m + 1)
            });
            let text: Vec<String> = ranges
                .iter()
                .map(|(a, b)| {
                    if a.to_bits() == b.to_bits() {
                        format!("{:.3}", a * f)
                    } else {
                        format!("{:.3}–{:.3}", a * f, b * f)
                    }
                })
                .collect();
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td style=\"text-align:left\">{}</td><td>{:.0} % at {:.3}</td></tr>",
                esc(&c.name),
                label,
                text.join(", "),
                100.0 * worst.0,
                worst.1 * f
            );
        }
    }
    if !any {
        h.push_str("<tr><td colspan=\"4\">first order is within 10 % of the quadrature's σ at every speed</td></tr>");
    }
    h.push_str("</table>");
    h
}
