//! The σ plot of one output of a case (the paper's Figs. 3, 4, 6, 9, 11): σ against speed by
//! every method, where the methods part showing which to believe.

use super::draw::{Line, Style, draw};
use super::{Output, Plot, method_color, unit};
use crate::table::Method;

/// σ of the output `o` against speed (`xlabel`) by every method that has rows for it (Monte
/// Carlo as dots, second order and the invariant dashed); `None` where there is nothing to
/// draw.
pub(super) fn sigma(o: &Output, xlabel: &str) -> Option<Plot> {
    let (model, case, q, d) = (o.model, o.case(), o.q, o.d);
    let (tag, label) = (o.tag(), o.label());
    let lines: Vec<Line> = o
        .methods()
        .iter()
        .map(|&m| {
            let style = match m {
                Method::MonteCarlo => Style::Dots,
                Method::SecondOrder | Method::Invariant => Style::Dashed,
                _ => Style::Solid,
            };
            Line::new(m.as_str(), o.pts(&o.rows(m), &|r| r.std), method_color(m)).styled(style)
        })
        .collect();
    let title = format!("{}: σ of {label}, case {}", model.name, case.name);
    let ylabel = format!("σ of {}", unit(model, q, d));
    draw(&title, xlabel, &ylabel, &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("std_{}_{}{tag}", case.name, q.as_str()),
            caption: format!(
                "σ of {label} by each method, case {}. Where the methods part, read \
                 analytic (the quadrature: its error estimate is in tolerance.csv); \
                 Monte Carlo scatters by its own sampling error.",
                case.name
            ),
            title,
            svg,
        })
}
