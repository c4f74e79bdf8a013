//! The report's specification sections: the yield of each requirement against the target,
//! what the design meets at the target yield (the largest operating range, the worst margin
//! and the tightest requirement of its kind), and which tolerance matters (Sobol indices).

use super::{esc, sig};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::report::yields::transfer_unit;
use std::fmt::Write;

/// The specification first: per requirement (and all together), per case and method, the
/// probability of meeting it over its range beside the target yield, its verdict, and the worst
/// margin's mean, σ and Cpk.
pub(super) fn specification(h: &mut String, model: &Model, a: &Analysis) {
    if model.requirements.is_empty() {
        return;
    }
    let target = model.allocation.target_yield;
    let _ = writeln!(
        h,
        "<h2 id=\"specification\">Specification: yield against the target {}</h2>\
<p>The probability that a design meets each requirement at every analysed speed of its range, and all of them together (<code>yield.csv</code>, with the per-speed curves). Quadrature: ± its error estimate; Monte Carlo: 95 % Wilson interval; first order: at the worst speed, an upper bound. <b>meets</b> is <i>yes</i> where the whole interval is at or above the target, <i>no</i> where below, <i>undecided</i> where it holds the target.</p>\
<table><tr><th>requirement</th><th>case</th><th>method</th><th>yield</th><th>interval</th><th>meets</th><th>worst margin, mean ± σ</th><th>C<sub>pk</sub></th></tr>",
        target_text(target)
    );
    let tu = transfer_unit(model);
    let mut rows: Vec<&crate::table::YieldRow> =
        a.yields.iter().filter(|y| y.speed.is_none()).collect();
    rows.sort_by_key(|y| (y.requirement.map_or(0, |r| r + 1), y.case));
    for y in rows {
        let (name, what, unit) = match y.requirement {
            Some(r) => {
                let r = &model.requirements[r];
                (
                    r.name.clone(),
                    crate::report::describe(r),
                    unit_in_words(r, &tu),
                )
            }
            None => (
                "all".to_string(),
                "every requirement".to_string(),
                String::new(),
            ),
        };
        let verdict = if y.method == crate::table::Method::FirstOrder {
            if y.probability < target {
                "no"
            } else {
                "undecided"
            }
        } else {
            crate::report::verdict(y.ci, target)
        };
        let colour = match verdict {
            "yes" => "#1a7f37",
            "no" => "#cf222e",
            _ => "#9a6700",
        };
        let _ = writeln!(
            h,
            "<tr><td title=\"{}\"><b>{}</b><br><small>{}</small></td><td>{}</td><td>{}</td><td>{}</td><td>[{}, {}]</td><td style=\"color:{colour}\"><b>{verdict}</b></td><td>{}</td><td>{}</td></tr>",
            esc(&what),
            esc(&name),
            esc(&what),
            esc(&a.cases[y.case].name),
            y.method.as_str(),
            sig(y.probability),
            sig(y.ci.0),
            sig(y.ci.1),
            y.margin.map_or("–".into(), |(m, s)| format!(
                "{} ± {} {}",
                sig(m),
                sig(s),
                esc(&unit)
            )),
            y.cpk.map_or("–".into(), sig),
        );
    }
    let _ = writeln!(h, "</table>");
}

/// Which tolerance matters: per case, the Sobol indices of each requirement's worst margin
/// and of every output at the speed where its σ by the analytic method is largest, largest
/// total index first.
pub(super) fn sobol_table(h: &mut String, model: &Model, a: &Analysis) {
    use crate::table::Target;
    for (case, why) in &a.sobol_refused {
        let _ = writeln!(
            h,
            "<p><b>Note:</b> no Sobol indices for case {}: {}</p>",
            esc(&a.cases[*case].name),
            esc(why)
        );
    }
    if a.sobol.is_empty() {
        return;
    }
    let _ = writeln!(
        h,
        "<h2 id=\"sobol\">Which tolerance matters: Sobol indices</h2>\
<p>First-order index S (the share of the variance a variable causes alone) and total index S<sub>T</sub> (with its interactions), 95 % jackknife intervals, pick-freeze Monte Carlo (Saltelli 2010); the derivative bound on S<sub>T</sub> from the exact gradients (Sobol &amp; Kucherenko 2009); the first-order variance share of the Taylor method beside it where the target is an output. Every speed and output in <code>sobol.csv</code>; here each requirement's worst margin and each output at the speed of its largest σ.</p>\
<table><tr><th>case</th><th>target</th><th>variable</th><th>S</th><th>S<sub>T</sub></th><th>bound on S<sub>T</sub></th><th>first-order share</th></tr>"
    );
    let shown = crate::plots::sobol_shown(a);
    for (case, s) in shown {
        let target = s
            .target
            .describe(&model.requirements, &a.speeds, &a.outputs, sig);
        let share = match s.target {
            Target::Output(i, o) => a
                .rows
                .iter()
                .find(|r| {
                    r.case == *case
                        && r.method() == crate::table::Method::FirstOrder
                        && r.speed.to_bits() == a.speeds[i].to_bits()
                        && r.quantity == a.outputs[o].quantity
                        && r.mode == a.outputs[o].mode
                })
                .and_then(|r| r.shares())
                .map(|sh| sig(sh[s.variable])),
            Target::Margin(_) => None,
        };
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{} [{}, {}]</td><td>{} [{}, {}]</td><td>{}</td><td>{}</td></tr>",
            esc(&a.cases[*case].name),
            esc(&target),
            esc(&model.parameters[a.vars[s.variable]].name),
            sig(s.first),
            sig(s.first_ci.0),
            sig(s.first_ci.1),
            sig(s.total),
            sig(s.total_ci.0),
            sig(s.total_ci.1),
            s.bound.map_or("–".into(), sig),
            share.unwrap_or_else(|| "–".into()),
        );
    }
    let _ = writeln!(h, "</table>");
}

/// What the design meets at the target yield, per requirement, case and method: the highest
/// speed up to which it holds from its range's start (with the ends from the interval), the
/// worst margin met and the tightest requirement of its kind in words.
pub(super) fn limits_table(h: &mut String, model: &Model, a: &Analysis) {
    let mut rows: Vec<&crate::table::YieldRow> =
        a.yields.iter().filter(|y| y.limit.is_some()).collect();
    if rows.is_empty() {
        return;
    }
    rows.sort_by_key(|y| (y.requirement, y.case));
    let target = model.allocation.target_yield;
    let _ = writeln!(
        h,
        "<h3 id=\"at-target\">What the design meets at the target yield {}</h3>\
<p>With the tolerances as they are: the <b>largest operating range</b>, the highest analysed speed up to which (from the start of the requirement's range, beyond its end too) a design meets the requirement at every speed with probability ≥ the target, and in brackets the same from the interval's low and high ends; and the <b>worst margin met</b> at the target yield (its 1 − target quantile over the designs, with its interval), i.e. the tightest requirement of its kind the designs meet. Negative: the requirement must be relaxed by that much. First order: from the linearised margin at each speed, an estimate. In <code>limits.csv</code>.</p>\
<table><tr><th>requirement</th><th>case</th><th>method</th><th>range met up to (rad/s)</th><th>worst margin met</th><th>tightest met</th></tr>",
        target_text(target)
    );
    let tu = transfer_unit(model);
    let speed = |w: Option<f64>| w.map_or("none".to_string(), sig);
    for y in rows {
        let (Some(l), Some(r)) = (y.limit.as_ref(), y.requirement) else {
            continue;
        };
        let r = &model.requirements[r];
        let reach = if y.method == crate::table::Method::FirstOrder {
            speed(l.reach[0])
        } else {
            format!(
                "{} [{}, {}]",
                speed(l.reach[0]),
                speed(l.reach[1]),
                speed(l.reach[2])
            )
        };
        // An unbounded end reads "unbounded"; the reason follows, as in limits.csv.
        let num = |x: f64| {
            if x.is_finite() {
                sig(x)
            } else {
                "unbounded".to_string()
            }
        };
        let mut margin = l.margin.map_or("–".into(), |m| {
            let u = unit_in_words(r, &tu);
            if y.method == crate::table::Method::FirstOrder {
                format!("{} {}", num(m[0]), esc(&u))
            } else {
                format!("{} [{}, {}] {}", num(m[0]), num(m[1]), num(m[2]), esc(&u))
            }
        });
        if let Some(why) = &l.why {
            margin.push_str(&format!("<br><small>{}</small>", esc(why)));
        }
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&r.name),
            esc(&a.cases[y.case].name),
            y.method.as_str(),
            reach,
            margin,
            esc(&l
                .margin
                .map_or(String::new(), |m| crate::report::tightest(r, m[0], &tu))),
        );
    }
    let _ = writeln!(h, "</table>");
}

/// The target yield as written in a heading: to six figures, in full where that would read 0
/// or 1 (a target of 1 − 10⁻¹² is not 1.00000).
/// A requirement's margin unit as a reader writes it after a number: none for a dimensionless
/// margin (the CSV files keep the SI `1`).
fn unit_in_words(r: &crate::model::Requirement, transfer: &str) -> String {
    let u = crate::margins::unit(r, transfer);
    if u == "1" { String::new() } else { u }
}

fn target_text(target: f64) -> String {
    let short = sig(target);
    if short == "1" || short == "0" || short.parse::<f64>().is_ok_and(|x| x <= 0.0 || x >= 1.0) {
        target.to_string()
    } else {
        short
    }
}
