//! The shares plot of a case with several design variables (the paper's Fig. 12): each
//! variable's share of the first-order variance of mode 1's ω_d against speed, which says which
//! tolerance to tighten where.

use super::draw::{Line, draw, palette};
use super::{Display, Plot, series};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::output::Quantity;
use crate::table::Method;

/// Shares of the first-order variance of mode 1's ω_d in case `ci` against speed (`xlabel`), in
/// per cent; `None` where there is nothing to draw.
pub(super) fn shares(
    model: &Model,
    a: &Analysis,
    ci: usize,
    d: Display,
    xlabel: &str,
) -> Option<Plot> {
    let case = &a.cases[ci];
    let xs = d.speed.per_rad_per_second();
    let rows = series(
        a,
        ci,
        Quantity::DampedFrequency,
        Some(0),
        Method::FirstOrder,
    );
    let lines: Vec<Line> = a
        .vars
        .iter()
        .enumerate()
        .filter(|(_, b)| case.tolerances.iter().any(|t| t.0 == **b))
        .map(|(k, &b)| {
            Line::new(
                model.parameters[b].name.clone(),
                rows.iter()
                    .map(|r| (r.speed * xs, r.shares().map_or(f64::NAN, |s| 100.0 * s[k])))
                    .collect(),
                palette(k),
            )
        })
        .collect();
    let title = format!(
        "{}: share of the variance of ω_d (mode 1), case {}",
        model.name, case.name
    );
    draw(&title, xlabel, "share of variance (%)", &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("shares_{}", case.name),
            caption: format!(
                "Each design variable's share of the first-order variance of mode 1's \
                 ω_d, case {}: which tolerance to tighten at each speed.",
                case.name
            ),
            title,
            svg,
        })
}
