//! The report's table of where the paper's first-order method is off: per case and output, the
//! speed ranges where first order's σ is more than 10 % off the quadrature's, and the worst.

use super::esc;
use crate::analyze::Analysis;
use crate::output::Quantity;
use crate::table::Method;
use std::fmt::Write;

/// Per case and output: the speeds where first order's σ is more than 10 % off the
/// quadrature's (where the quadrature's σ is at least 2 % of its largest), as ranges.
pub(super) fn first_order_table(a: &Analysis) -> String {
    let mut h = String::from(
        "<h2>Where the paper's first-order method is off</h2><table><tr><th>case</th><th>output</th><th>speeds (rad/s) where first order's σ is &gt; 10 % off the quadrature's</th><th>worst</th></tr>",
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
            let worst = a
                .rows
                .iter()
                .filter(|r| r.case == ci && r.quantity == q && r.mode == mode)
                .filter(|r| r.method() == Method::Quadrature && r.std > 0.0)
                .filter_map(|r| {
                    a.rows
                        .iter()
                        .find(|f| {
                            f.case == ci
                                && f.quantity == q
                                && f.mode == mode
                                && f.method() == Method::FirstOrder
                                && f.speed.to_bits() == r.speed.to_bits()
                        })
                        .map(|f| ((f.std - r.std).abs() / r.std, r.speed))
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
                        format!("{a:.3}")
                    } else {
                        format!("{a:.3}–{b:.3}")
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
                worst.1
            );
        }
    }
    if !any {
        h.push_str("<tr><td colspan=\"4\">first order is within 10 % of the quadrature's σ at every speed</td></tr>");
    }
    h.push_str("</table>");
    h
}
