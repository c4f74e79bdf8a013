//! The band plot of one output of a case (the paper's Figs. 2, 5, 8, 10): the answer's mean ± σ
//! as a shaded band, every method's mean, the paper's first-order band dashed, and red marks
//! where first order's σ is more than 10 % off the quadrature's ([`first_order_off`], public
//! because the report lists the same speeds).

use super::draw::{Band, Line, Style, draw};
use super::{Output, Plot, method_color, scale, series, unit};
use crate::analyze::Analysis;
use crate::output::Quantity;
use crate::table::Method;
use plotters::prelude::*;

/// Mean ± σ of the output `o` against speed (`xlabel`); `None` where there is nothing to draw.
pub(super) fn band(o: &Output, xlabel: &str) -> Option<Plot> {
    let (model, case, q, d) = (o.model, o.case(), o.q, o.d);
    let (tag, label) = (o.tag(), o.label());
    let (xs, ys) = (d.speed.per_rad_per_second(), scale(q, d));
    // ω_d and |H| cannot be negative: bands stop at zero.
    let floor = if q == Quantity::DampingRatio {
        f64::NEG_INFINITY
    } else {
        0.0
    };
    // Mean ± σ: the answer as a band, every method's mean, first order's ± σ dashed.
    let answer = o.rows(Method::Analytic);
    let bands = vec![Band {
        name: "analytic mean ± σ (the answer)".into(),
        lower: o.pts(&answer, &|r| (r.mean - r.std).max(floor)),
        upper: o.pts(&answer, &|r| r.mean + r.std),
        color: method_color(Method::Analytic),
    }];
    let mut lines = means(o, floor);
    // The speeds where first order's σ is more than 10 % off the quadrature's.
    let off = first_order_off(o.a, o.ci, q, o.mode);
    if off.iter().any(|p| p.1.is_finite()) {
        lines.push(
            Line::new(
                "first order σ > 10 % off",
                off.iter().map(|&(x, y)| (x * xs, y * ys)).collect(),
                RED,
            )
            .styled(Style::Marks),
        );
    }
    let title = format!("{}: {label}, case {}", model.name, case.name);
    draw(&title, xlabel, &unit(model, q, d), &lines, &bands)
        .ok()
        .map(|svg| Plot {
            stem: format!("band_{}_{}{tag}", case.name, q.as_str()),
            caption: format!(
                "Mean ± σ of {label} against speed for case {}. The shaded band is the \
                 answer to read (analytic); dashed lines are first order's band{}; red dots \
                 mark the speeds where first order's σ is more than 10 % off.",
                case.name,
                if model.paper_example().is_some() {
                    " (the paper's method)"
                } else {
                    ""
                }
            ),
            title,
            svg,
        })
}

/// The mean lines of a band plot: every method's mean but second order's and the invariant's
/// (Monte Carlo's as dots), and first order's mean ± σ dashed, its lower line stopping at
/// `floor`.
fn means(o: &Output, floor: f64) -> Vec<Line> {
    let mut lines = Vec::new();
    for m in o.methods() {
        if m == Method::SecondOrder || m == Method::Invariant {
            continue;
        }
        let rows = o.rows(m);
        let style = if m == Method::MonteCarlo {
            Style::Dots
        } else {
            Style::Solid
        };
        lines.push(
            Line::new(
                format!("{} mean", m.as_str()),
                o.pts(&rows, &|r| r.mean),
                method_color(m),
            )
            .styled(style),
        );
        if m == Method::FirstOrder {
            lines.push(
                Line::new(
                    "first_order mean ± σ",
                    o.pts(&rows, &|r| r.mean + r.std),
                    method_color(m),
                )
                .styled(Style::Dashed),
            );
            lines.push(
                Line::new(
                    "",
                    o.pts(&rows, &|r| (r.mean - r.std).max(floor)),
                    method_color(m),
                )
                .styled(Style::Dashed),
            );
        }
    }
    lines
}

/// Speeds where first order's σ is more than 10 % off the quadrature's (the quadrature's σ
/// at least 2 % of its largest): `(speed, first-order mean)` there, NaN elsewhere.
pub fn first_order_off(
    a: &Analysis,
    case: usize,
    q: Quantity,
    mode: Option<usize>,
) -> Vec<(f64, f64)> {
    let quad = series(a, case, q, mode, Method::Quadrature);
    let first = series(a, case, q, mode, Method::FirstOrder);
    let largest = quad.iter().map(|r| r.std).fold(0.0f64, f64::max);
    quad.iter()
        .map(|r| {
            let f = first
                .iter()
                .find(|f| f.speed.to_bits() == r.speed.to_bits());
            let off = f.is_some_and(|f| {
                r.std >= 0.02 * largest && ((f.std - r.std).abs() > 0.1 * r.std || f.std.is_nan())
            });
            (
                r.speed,
                if off {
                    f.map_or(f64::NAN, |f| f.mean)
                } else {
                    f64::NAN
                },
            )
        })
        .collect()
}
