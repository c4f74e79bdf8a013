//! The Campbell diagram: ω_d of the modes an engine order can reach against speed, with the ±3σ
//! bands of the case with the most toleranced variables, the engine-order lines (each drawn and
//! labelled apart), and where a mode meets one ([`CriticalSpeed`], which the report tabulates):
//! crossing it, or running alongside it without crossing (a near-tangency, which a tolerance
//! can turn into a crossing).

use super::draw::{Band, Line, Style, draw_up_to, palette};
use super::{Display, FrequencyUnit, Plot, series};
use crate::analyze::Analysis;
use crate::modal::ModeClass;
use crate::model::Model;
use crate::output::Quantity;
use crate::table::Method;
use crate::table::Row;
use plotters::prelude::*;

/// A mode meeting an engine-order line.
#[derive(Debug, Clone, Copy)]
pub struct CriticalSpeed {
    pub mode: usize,
    pub order: f64,
    /// rad/s: where `ω_d(Ω) = order·Ω` (a crossing), or where the mode comes closest to the line
    /// (a near-tangency).
    pub speed: f64,
    /// σ of the crossing speed under the Campbell diagram's case ([`campbell_case`]; first
    /// order: σ_ωd / |order − dω_d/dΩ|); NaN for a near-tangency, which has no crossing speed.
    pub std: f64,
    pub meeting: Meeting,
}

/// How a mode meets an engine-order line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Meeting {
    /// `ω_d − order·Ω` changes sign between two speeds.
    Crossing,
    /// No crossing, but the mode comes within [`NEAR`] of the line (`gap`: the smallest
    /// `(ω_d − order·Ω)/ω_d`, signed), or within 3σ of its ω_d (`within_3_sigma`): a
    /// tolerance, or a speed step finer than the sweep's, can make it a crossing.
    Tangency { gap: f64, within_3_sigma: bool },
}

/// The relative distance from an engine-order line below which a mode that does not cross it
/// counts as meeting it: 1 %, a tenth of the separation margins API 684 asks of a critical
/// speed, so closer than any design would mean to run.
pub const NEAR: f64 = 0.01;

/// The tolerance case whose bands the Campbell diagram shows and whose σ its critical speeds
/// carry: the one `d` chooses ([`Display::campbell_case`]), else the one with the most
/// toleranced variables (the whole design's spread), the first of those where several tie.
pub fn campbell_case(a: &Analysis, d: Display) -> usize {
    match d.campbell_case {
        Some(c) if c < a.cases.len() => c,
        _ => (0..a.cases.len())
            .rev()
            .max_by_key(|&c| a.cases[c].tolerances.len())
            .unwrap_or(0),
    }
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

/// Where `ω_d` of one mode (rows of the `analytic` method, NaN where the mode is rigid) crosses
/// `order × Ω`, with σ of the crossing speed (first order in σ of ω_d: σ_ωd / |order −
/// dω_d/dΩ|); and where it comes near the line without crossing (a local least distance,
/// interior or at an end of the speeds, within [`NEAR`] or 3σ).
fn meetings(rows: &[&Row], mode: usize, order: f64) -> Vec<CriticalSpeed> {
    let mut out = Vec::new();
    let gap = |r: &Row| r.mean - order * r.speed;
    for w in rows.windows(2) {
        let (f0, f1) = (gap(w[0]), gap(w[1]));
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
                meeting: Meeting::Crossing,
            });
        }
    }
    // Near-tangencies: local least |gap| on a stretch the mode does not cross (its neighbours
    // on the same side of the line).
    let n = rows.len();
    for i in 0..n {
        let r = rows[i];
        let g = gap(r);
        if !(g.is_finite() && r.mean > 0.0) {
            continue;
        }
        let beside = |j: Option<usize>| {
            j.and_then(|j| rows.get(j))
                .map(|o| gap(o))
                .filter(|v| v.is_finite())
        };
        let (before, after) = (beside(i.checked_sub(1)), beside(Some(i + 1)));
        let least = before.is_none_or(|b| b * g > 0.0 && b.abs() > g.abs())
            && after.is_none_or(|a| a * g > 0.0 && a.abs() >= g.abs());
        if !least || (before.is_none() && after.is_none()) {
            continue;
        }
        let within_3_sigma = g.abs() <= 3.0 * r.std;
        if g.abs() <= NEAR * r.mean || within_3_sigma {
            out.push(CriticalSpeed {
                mode,
                order,
                speed: r.speed,
                std: f64::NAN,
                meeting: Meeting::Tangency {
                    gap: g / r.mean,
                    within_3_sigma,
                },
            });
        }
    }
    out
}

/// The modes a Campbell diagram shows: those an engine order reaches within the speeds
/// analysed (nominal ω_d at or below `reach` at some speed) or that meet an order line, and the
/// lowest mode that is not rigid where none is (so that the diagram shows how far the modes
/// lie above the orders).
fn shown(a: &Analysis, modes: usize, reach: f64, meeting: &[CriticalSpeed]) -> Vec<usize> {
    let points: Vec<_> = a.nominal.iter().flatten().collect();
    let oscillates = |m: usize| {
        points
            .iter()
            .filter_map(move |p| p.modes.get(m))
            .filter(|md| md.class != ModeClass::Rigid && md.damped_frequency > 0.0)
    };
    let mut out: Vec<usize> = (0..modes)
        .filter(|&m| {
            oscillates(m).any(|md| md.damped_frequency <= reach)
                || meeting.iter().any(|c| c.mode == m)
        })
        .collect();
    if out.is_empty()
        && let Some(m) = (0..modes).find(|&m| oscillates(m).next().is_some())
    {
        out.push(m);
    }
    out
}

/// The lowest modes that get their own band and σ plots whatever their frequency.
pub const LOWEST_PLOTTED: usize = 6;

/// The modes whose outputs get their own plots: the [`LOWEST_PLOTTED`] lowest, and every
/// mode an engine order reaches within the speeds analysed (nominal ω_d within [`NEAR`] of the
/// highest order at the top speed somewhere: the modes the Campbell diagram is about). A
/// 42-mode rotor's axial and high bending modes, far above every excitation, are in the tables
/// only (each plotted they were some 340 files).
pub fn plotted_modes(model: &Model, a: &Analysis) -> Vec<usize> {
    let modes = (a.nominal.iter().flatten())
        .map(|p| p.modes.len())
        .next()
        .unwrap_or(0);
    let top = (a.nominal.iter().flatten()).fold(0.0f64, |t, p| t.max(p.speed.abs()));
    let highest = orders(model).last().copied().unwrap_or(1.0);
    let reach = (1.0 + NEAR) * highest * top;
    (0..modes)
        .filter(|&m| {
            m < LOWEST_PLOTTED
                || (a.nominal.iter().flatten()).any(|p| {
                    p.modes.get(m).is_some_and(|md| {
                        md.class != ModeClass::Rigid && md.damped_frequency <= reach
                    })
                })
        })
        .collect()
}

/// Campbell diagram: nominal ω_d of the modes an engine order reaches ([`shown`]) with ±3σ
/// (the [`campbell_case`], the automatic `analytic` choice, so the bands stay right through
/// changes of class; no line where a mode is rigid), the engine-order lines (each its own
/// dash, labelled at its end on the frame) and the speeds where a mode meets one, marked.
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
    let case = campbell_case(a, d);
    let orders = orders(model);
    let speeds: Vec<f64> = a.nominal.iter().flatten().map(|p| p.speed).collect();
    let (lo, hi) = match (speeds.first(), speeds.last()) {
        (Some(&lo), Some(&hi)) => (lo, hi),
        _ => return (None, Vec::new()),
    };
    let highest = orders.last().copied().unwrap_or(1.0);
    let reach = highest * hi.max(lo.abs());
    // A mode's ω_d against speed, NaN where the nominal design has it rigid (no frequency).
    let rigid: std::collections::HashSet<(usize, u64)> = (a.nominal.iter().flatten())
        .flat_map(|p| {
            (p.modes.iter().enumerate())
                .filter(|(_, md)| md.class == ModeClass::Rigid)
                .map(|(m, _)| (m, p.speed.to_bits()))
        })
        .collect();
    let rows_of = |m: usize| -> Vec<Row> {
        series(
            a,
            case,
            Quantity::DampedFrequency,
            Some(m),
            Method::Analytic,
        )
        .into_iter()
        .map(|r| {
            let mut r = r.clone();
            if rigid.contains(&(m, r.speed.to_bits())) {
                (r.mean, r.std) = (f64::NAN, f64::NAN);
            }
            r
        })
        .collect()
    };
    let all: Vec<Vec<Row>> = (0..modes).map(rows_of).collect();
    let mut critical: Vec<CriticalSpeed> = Vec::new();
    for (m, rows) in all.iter().enumerate() {
        let refs: Vec<&Row> = rows.iter().collect();
        for &o in &orders {
            critical.extend(meetings(&refs, m, o));
        }
    }
    let drawn = shown(a, modes, reach, &critical);
    // The frequency axis: up to the highest order at the top speed, or the shown modes' bands.
    let mut top = reach;
    for &m in &drawn {
        top = (all[m].iter())
            .map(|r| r.mean + 3.0 * r.std)
            .filter(|v| v.is_finite())
            .fold(top, f64::max);
    }
    let top = 1.05 * top;
    // Each line named by its mode's shape at the middle of the speeds (its dominant
    // coordinate, and its whirl where a spin turns it).
    let what = a.middle_point().map_or_else(Vec::new, |pt| {
        crate::scene::descriptions(model, &model.nominal(), pt)
    });
    let mut lines = Vec::new();
    let mut bands = Vec::new();
    for &m in &drawn {
        let rows = &all[m];
        let color = palette(m);
        bands.push(Band {
            name: String::new(),
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
    lines.extend(order_lines(&orders, (lo, hi), top, d));
    let marks = |kind: bool| -> Vec<(f64, f64)> {
        (critical.iter())
            .filter(|c| drawn.contains(&c.mode) && (c.meeting == Meeting::Crossing) == kind)
            .map(|c| (c.speed * xs, c.order * c.speed * ys))
            .collect()
    };
    let (crossings, tangencies) = (marks(true), marks(false));
    if !crossings.is_empty() {
        lines.push(Line::new("critical speeds (crossings)", crossings, RED).styled(Style::Marks));
    }
    if !tangencies.is_empty() {
        let amber = RGBColor(230, 150, 0);
        lines.push(
            Line::new("near-tangencies (within 1 % or 3σ)", tangencies, amber).styled(Style::Marks),
        );
    }
    critical.sort_by(|a, b| a.speed.total_cmp(&b.speed));
    let above = (0..modes)
        .filter(|m| !drawn.contains(m) && all[*m].iter().any(|r| r.mean.is_finite()))
        .count();
    let case_name = a.cases.get(case).map_or("", |c| c.name.as_str());
    let title = format!("{}: Campbell diagram (case {case_name})", model.name);
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    let ylabel = match d.frequency {
        FrequencyUnit::RadPerSecond => "damped natural frequency ω_d (rad/s)".to_string(),
        u => format!("damped natural frequency ({})", u.symbol()),
    };
    let plot = draw_up_to(&title, &xlabel, &ylabel, &lines, &bands, Some(top * ys))
        .ok()
        .map(|svg| Plot {
            stem: "campbell".into(),
            caption: format!(
                "Damped natural frequency of the modes against speed, each with its ±3σ band \
                 (shaded; case {case_name}, the one with the most toleranced variables; \
                 analytic), the engine orders {} (each its own dash, labelled where it leaves \
                 the axes), in red the critical speeds where a mode crosses one and in amber \
                 where a mode comes within 1 % (or within its 3σ) of one without crossing: a \
                 tolerance can make those crossings. The critical speeds are listed with their \
                 σ in the report. Each mode is named by its shape at the middle speed: its \
                 dominant coordinate, and FW or BW where it whirls forward or backward about a \
                 spinning joint's axis. No line is drawn where a mode is rigid.{}",
                orders
                    .iter()
                    .map(|o| format!("{o}×Ω"))
                    .collect::<Vec<_>>()
                    .join(", "),
                if above > 0 {
                    format!(
                        " {above} higher mode(s), above what {highest}×Ω reaches at the top \
                         speed, are left out (their rows are in tolerance.csv)."
                    )
                } else {
                    String::new()
                }
            ),
            title,
            svg,
        });
    (plot, critical)
}

/// The line dash of the `i`-th engine order: solid, dashed, dotted, long dashes.
fn order_style(i: usize) -> Style {
    [
        Style::Solid,
        Style::Dashed,
        Style::Dotted,
        Style::LongDashed,
    ][i % 4]
}

/// The engine-order lines `order × Ω` of the Campbell diagram across the speeds `lo..hi` (rad/s),
/// each ending where it leaves the axes (at the top speed or at `top`, rad/s, the top of the
/// frequency axis) and labelled there.
fn order_lines(orders: &[f64], (lo, hi): (f64, f64), top: f64, d: Display) -> Vec<Line> {
    let (xs, ys) = (
        d.speed.per_rad_per_second(),
        d.frequency.per_rad_per_second(),
    );
    let mut lines = Vec::new();
    for (i, &o) in orders.iter().enumerate() {
        let end = if top > 0.0 { hi.min(top / o) } else { hi };
        if end > lo {
            lines.push(
                Line::new(
                    format!("{o}×Ω"),
                    vec![(lo * xs, o * lo * ys), (end * xs, o * end * ys)],
                    BLACK,
                )
                .styled(order_style(i))
                .labelled(format!("{o}×")),
            );
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::Detail;

    /// Rows of ω_d = `f(Ω)` with σ `std` at the speeds 90, 91, …, 110 rad/s.
    fn rows(f: impl Fn(f64) -> f64, std: f64) -> Vec<Row> {
        (90..=110)
            .map(|s| Row {
                speed: s as f64,
                quantity: Quantity::DampedFrequency,
                mode: Some(0),
                case: 0,
                mean: f(s as f64),
                std,
                missing: None,
                detail: Detail::Analytic {
                    basis: None,
                    quadrature: None,
                },
            })
            .collect()
    }

    fn meet(rows: &[Row]) -> Vec<CriticalSpeed> {
        meetings(&rows.iter().collect::<Vec<_>>(), 0, 1.0)
    }

    #[test]
    fn a_mode_running_alongside_an_order_is_a_near_tangency_and_one_crossing_it_a_crossing() {
        // ω_d = Ω (1.004 + 1e-4 (Ω − 100)²): 0.4 % above 1×Ω at 100 rad/s, never on it.
        let alongside = rows(|s| s * (1.004 + 1e-4 * (s - 100.0).powi(2)), 0.01);
        let m = meet(&alongside);
        assert_eq!(m.len(), 1, "{m:?}");
        assert_eq!(m[0].speed.to_bits(), 100f64.to_bits());
        let Meeting::Tangency {
            gap,
            within_3_sigma,
        } = m[0].meeting
        else {
            panic!("{m:?}")
        };
        assert!((gap - 0.004 / 1.004).abs() < 1e-12, "{gap}");
        assert!(!within_3_sigma);
        assert!(m[0].std.is_nan());
        // 3 % away: not near, unless its σ reaches the line.
        let apart = rows(|s| s * (1.03 + 1e-4 * (s - 100.0).powi(2)), 0.01);
        assert!(meet(&apart).is_empty());
        let m = meet(&rows(|s| s * (1.03 + 1e-4 * (s - 100.0).powi(2)), 1.1));
        assert!(
            matches!(
                m[..],
                [CriticalSpeed {
                    meeting: Meeting::Tangency {
                        within_3_sigma: true,
                        ..
                    },
                    ..
                }]
            ),
            "{m:?}"
        );
        // A mode at 100.5 rad/s crosses 1×Ω at 100.5, with σ_ωd / |1 − 0|.
        let m = meet(&rows(|_| 100.5, 0.2));
        assert_eq!(m.len(), 1, "{m:?}");
        assert_eq!(m[0].meeting, Meeting::Crossing);
        assert!((m[0].speed - 100.5).abs() < 1e-12 && (m[0].std - 0.2).abs() < 1e-12);
    }
}
