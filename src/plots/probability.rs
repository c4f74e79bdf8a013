//! The probability plot of a case: the probability of each change of character (a mode
//! overdamped, the equilibrium unstable, another branch) against speed, quadrature and Monte
//! Carlo.

use super::draw::{Line, Style, draw, palette};
use super::{Display, Plot};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::table::Method;

/// Probabilities of character of one case against speed, quadrature and Monte Carlo (a colour
/// per event, solid for the quadrature and dots for Monte Carlo); `None` when every
/// probability stays below 0.1 %.
pub(super) fn probabilities(
    model: &Model,
    a: &Analysis,
    case: usize,
    modes: usize,
    d: Display,
) -> Option<Plot> {
    use crate::table::Event;
    let mut events: Vec<(Event, Option<usize>)> =
        (0..modes).map(|m| (Event::Overdamped, Some(m))).collect();
    events.extend([(Event::Unstable, None), (Event::OtherBranch, None)]);
    let xs = d.speed.per_rad_per_second();
    let mut lines = Vec::new();
    for (k, &(event, mode)) in events.iter().enumerate() {
        for method in [Method::Quadrature, Method::MonteCarlo] {
            let pts: Vec<(f64, f64)> = a
                .probabilities
                .iter()
                .filter(|p| {
                    p.case == case && p.event == event && p.mode == mode && p.method == method
                })
                .map(|p| (p.speed * xs, 100.0 * p.probability))
                .collect();
            // Below 0.1 % at every speed: left to probabilities.csv (far-tail noise otherwise).
            if pts.iter().all(|p| p.1 < 0.1) {
                continue;
            }
            let name = match mode {
                Some(m) => format!("{} mode {}, {}", event.as_str(), m + 1, method.as_str()),
                None => format!("{}, {}", event.as_str(), method.as_str()),
            };
            let style = if method == Method::MonteCarlo {
                Style::Dots
            } else {
                Style::Solid
            };
            lines.push(Line::new(name, pts, palette(k)).styled(style));
        }
    }
    if lines.is_empty() {
        return None;
    }
    let title = format!(
        "{}: probability of a change of character, case {}",
        model.name, a.cases[case].name
    );
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    draw(&title, &xlabel, "probability (%)", &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("probability_{}", a.cases[case].name),
            caption: format!(
                "Probability that a mode is overdamped, that the equilibrium is unstable or that a \
                 design sits on another equilibrium branch, case {}: quadrature (lines, ± its \
                 error estimate in probabilities.csv) and Monte Carlo (dots, 95 % Wilson \
                 intervals there).",
                a.cases[case].name
            ),
            title,
            svg,
        })
}
