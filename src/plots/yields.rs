//! The yield curves of a case: the probability of meeting each requirement at each speed of
//! its range, by the quadrature (lines), Monte Carlo (dots) and first order (dashes).

use super::draw::{Line, Style, draw, palette};
use super::{Display, Plot};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::table::Method;

/// The per-speed probability of each requirement of case `case`; `None` without requirements.
pub(super) fn yield_curves(model: &Model, a: &Analysis, case: usize, d: Display) -> Option<Plot> {
    if model.requirements.is_empty() {
        return None;
    }
    let xs = d.speed.per_rad_per_second();
    let mut lines = Vec::new();
    for (r, req) in model.requirements.iter().enumerate() {
        for (method, style) in [
            (Method::Quadrature, Style::Solid),
            (Method::MonteCarlo, Style::Dots),
            (Method::FirstOrder, Style::Dashed),
        ] {
            let pts: Vec<(f64, f64)> = a
                .yields
                .iter()
                .filter(|y| y.case == case && y.method == method && y.requirement == Some(r))
                .filter_map(|y| y.speed.map(|w| (w * xs, 100.0 * y.probability)))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let name = format!("{}, {}", req.name, method.as_str());
            lines.push(Line::new(name, pts, palette(r)).styled(style));
        }
    }
    if lines.is_empty() {
        return None;
    }
    let title = format!(
        "{}: probability of meeting each requirement, case {}",
        model.name, a.cases[case].name
    );
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    draw(&title, &xlabel, "probability (%)", &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("yield_{}", a.cases[case].name),
            caption: format!(
                "Probability that a design meets each requirement at each speed of its range, case \
                 {} (target {} %): quadrature (lines), Monte Carlo (dots), first order (dashes). \
                 The yield over the range, every speed at once, is in the specification table \
                 and yield.csv.",
                a.cases[case].name,
                super::percent(model.allocation.target_yield)
            ),
            title,
            svg,
        })
}
