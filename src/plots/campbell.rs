//! The Campbell diagram: ω_d of every mode against speed with ±3σ bands of the first case, the
//! engine-order lines, and the critical speeds where a mode crosses one ([`CriticalSpeed`],
//! which the report tabulates).

use super::draw::{Band, Line, Style, draw, palette};
use super::{Display, Plot, series};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::output::Quantity;
use crate::table::Method;
use crate::table::Row;
use plotters::prelude::*;

/// A mode crossing an engine-order line: `ω_d(Ω) = order·Ω`.
#[derive(Debug, Clone, Copy)]
pub struct CriticalSpeed {
    pub mode: usize,
    pub order: f64,
    /// rad/s.
    pub speed: f64,
    /// σ of the critical speed under the first case (first order): σ_ωd / |order − dω_d/dΩ|.
    pub std: f64,
}

/// The engine orders drawn on the Campbell diagram: 1, 2, 3 and the model's transfer order.
fn orders(model: &Model) -> Vec<f64> {
    let mut o = vec![1.0, 2.0, 3.0];
    if let Some(t) = model.analysis.transfer
        && !o.contains(&t.order)
        && t.order > 0.0
    {
        o.push(t.order);
    }
    o.sort_by(f64::total_cmp);
    o
}

/// Where `ω_d` of one mode (rows of the `analytic` method) crosses `order × Ω`, with σ of the
/// crossing speed (first order in σ of ω_d: σ_ωd / |order − dω_d/dΩ|).
fn crossings(rows: &[&Row], mode: usize, order: f64) -> Vec<CriticalSpeed> {
    let mut out = Vec::new();
    for w in rows.windows(2) {
        let (f0, f1) = (
            w[0].mean - order * w[0].speed,
            w[1].mean - order * w[1].speed,
        );
        if f0.is_finite() && f1.is_finite() && f0 * f1 < 0.0 && w[0].mean > 0.0 && w[1].mean > 0.0 {
            let t = f0 / (f0 - f1);
            let speed = w[0].speed + t * (w[1].speed - w[0].speed);
            let slope = (w[1].mean - w[0].mean) / (w[1].speed - w[0].speed);
            let sd = w[0].std + t * (w[1].std - w[0].std);
            out.push(CriticalSpeed {
                mode,
                order,
                speed,
                std: sd / (order - slope).abs(),
            });
        }
    }
    out
}

/// Campbell diagram: nominal ω_d of every mode with ±3σ (first case, the automatic `analytic`
/// choice, so the bands stay right through changes of class), the engine-order lines (cut at
/// the top of the modes) and the critical speeds where a mode crosses one, marked.
pub(super) fn campbell(
    model: &Model,
    a: &Analysis,
    modes: usize,
    d: Display,
) -> (Option<Plot>, Vec<CriticalSpeed>) {
    let (xs, ys) = (
        d.speed.per_rad_per_second(),
        d.frequency.per_rad_per_second(),
    );
    let mut lines = Vec::new();
    let mut bands = Vec::new();
    let mut critical = Vec::new();
    let orders = orders(model);
    let mut top = 0.0f64;
    // Each line named by its mode's shape at the middle of the speeds (its dominant
    // coordinate, and its whirl where a spin turns it).
    let middle = a.middle_point();
    let what = middle.map_or_else(Vec::new, |pt| {
        crate::scene::descriptions(model, &model.nominal(), pt)
    });
    for m in 0..modes {
        let rows = series(a, 0, Quantity::DampedFrequency, Some(m), Method::Analytic);
        let color = palette(m);
        for &o in &orders {
            critical.extend(crossings(&rows, m, o));
        }
        top = rows
            .iter()
            .map(|r| r.mean + 3.0 * r.std)
            .filter(|v| v.is_finite())
            .fold(top, f64::max);
        bands.push(Band {
            name: format!("mode {} ± 3σ", m + 1),
            lower: rows
                .iter()
                .map(|r| (r.speed * xs, (r.mean - 3.0 * r.std).max(0.0) * ys))
                .collect(),
            upper: rows
                .iter()
                .map(|r| (r.speed * xs, (r.mean + 3.0 * r.std) * ys))
                .collect(),
            color,
        });
        // FW / BW: forward and backward whirl, as rotordynamics' Campbell diagrams say it.
        let name = match what.get(m).filter(|w| !w.is_empty()) {
            Some(w) => format!(
                "mode {} ({})",
                m + 1,
                w.replace("forward whirl", "FW")
                    .replace("backward whirl", "BW")
            ),
            None => format!("mode {}", m + 1),
        };
        lines.push(Line::new(
            name,
            rows.iter().map(|r| (r.speed * xs, r.mean * ys)).collect(),
            color,
        ));
    }
    lines.extend(order_lines(a, &orders, top, d));
    if !critical.is_empty() {
        lines.push(
            Line::new(
                "critical speeds (crossings)",
                critical
                    .iter()
                    .map(|c| (c.speed * xs, c.order * c.speed * ys))
                    .collect(),
                RED,
            )
            .styled(Style::Marks),
        );
    }
    critical.sort_by(|a, b| a.speed.total_cmp(&b.speed));
    let case = a.cases.first().map_or("", |c| c.name.as_str());
    let title = format!("{}: Campbell diagram (case {case})", model.name);
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    let ylabel = format!("ω_d ({})", d.frequency.symbol());
    let plot = draw(&title, &xlabel, &ylabel, &lines, &bands)
        .ok()
        .map(|svg| Plot {
            stem: "campbell".into(),
            caption: format!(
                "Damped natural frequency of every mode against speed with its ±3σ band (case \
                 {case}, analytic), the engine orders 1×, 2×, 3×Ω{} and, in red, the critical \
                 speeds where a mode crosses one (listed with their σ above). Each mode is named \
                 by its shape at the middle speed: its dominant coordinate, and FW or BW where \
                 it whirls forward or backward about a spinning joint's axis.",
                model
                    .analysis
                    .transfer
                    .filter(|t| ![1.0, 2.0, 3.0].contains(&t.order))
                    .map_or(String::new(), |t| format!(" and the model's {}×Ω", t.order))
            ),
            title,
            svg,
        });
    (plot, critical)
}

/// The engine-order lines `order × Ω` of the Campbell diagram across the speeds of the analysis
/// (1× solid, the others dashed), each cut where it rises above the modes' range (`top`, rad/s;
/// not cut where `top` is 0).
fn order_lines(a: &Analysis, orders: &[f64], top: f64, d: Display) -> Vec<Line> {
    let (xs, ys) = (
        d.speed.per_rad_per_second(),
        d.frequency.per_rad_per_second(),
    );
    let mut lines = Vec::new();
    let speeds: Vec<f64> = a.nominal.iter().flatten().map(|p| p.speed).collect();
    if let (Some(&lo), Some(&hi)) = (speeds.first(), speeds.last()) {
        for &o in orders {
            // Cut where the line leaves the modes' range, so that it does not squash them.
            let end = if top > 0.0 { hi.min(top / o) } else { hi };
            if end > lo {
                lines.push(
                    Line::new(
                        format!("{o}×Ω"),
                        vec![(lo * xs, o * lo * ys), (end * xs, o * end * ys)],
                        BLACK,
                    )
                    .styled(if o.to_bits() == 1f64.to_bits() {
                        Style::Solid
                    } else {
                        Style::Dashed
                    }),
                );
            }
        }
    }
    lines
}
