//! The report's numeric summary, "σ where it matters": per case, σ of the first modes' outputs
//! and of |H| by every method at the speeds that matter, and how the methods agree there.

use super::{esc, short, sig};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::output::{Output, Quantity};
use crate::plots::{CriticalSpeed, Display, Meeting};
use crate::table::McStat;
use crate::table::Method;
use crate::table::Row;
use std::fmt::Write;

/// The modes the summary covers: the first three.
const MODES: usize = 3;

/// A row of a case's table: the output, where (in words) and the speed (rad/s) of the rows it
/// shows.
type Place = (Quantity, Option<usize>, String, f64);

/// The numeric summary of an analysis, per case: for the first modes' ω_d and ζ and for |H|,
/// σ by every method where it matters (the speed of the largest σ, the critical speeds of the
/// 1×Ω line, the |H| peak), and how the methods agree there: first order against the answer,
/// and whether the answer lies inside Monte Carlo's 95 % interval of σ.
pub(super) fn summary_table(
    model: &Model,
    a: &Analysis,
    critical: &[CriticalSpeed],
    d: Display,
) -> String {
    let outputs = outputs(a);
    let mut h = format!(
        "<h2>Summary: σ where it matters</h2><p>Per case, σ of each output by every method at \
         the speed of its largest σ, at the critical speeds (1×Ω) and at the |H| peak. \
         “±3σ, % of mean” is the answer's spread (three standard deviations, the band that \
         holds 99.73 % of a normal output) relative to its mean. “first order vs answer” is \
         first order's σ against the answer's (analytic); “Monte Carlo agrees” says whether \
         the answer lies inside Monte Carlo's 95 % interval of σ; neither is given where σ is \
         below what the evaluation resolves (–). Speeds in {}.</p>",
        d.speed.symbol()
    );
    for (ci, c) in a.cases.iter().enumerate() {
        let case = Case { a, ci };
        let places = case.places(&outputs, critical, d);
        if places.is_empty() {
            continue;
        }
        let _ = write!(
            h,
            "<h3>case {}</h3><table><tr><th>output</th><th>where</th><th>speed</th><th>mean</th>\
             <th>σ analytic (the answer)</th><th>±3σ, % of mean</th><th>σ first order</th><th>σ second order</th>\
             <th>σ Monte Carlo [95 %]</th><th>first order vs answer</th><th>Monte Carlo agrees</th></tr>",
            esc(&c.name)
        );
        for place in places {
            case.row(&mut h, model, place, d);
        }
        h.push_str("</table>");
    }
    h
}

/// The outputs the summary shows, modes first: the answer's (analytic) outputs of the first
/// [`MODES`] modes and |H|, ζ only where its mean or σ is resolved somewhere
/// ([`Analysis::resolved`]: an undamped system's ζ is 0 with σ 0, up to rounding, everywhere).
fn outputs(a: &Analysis) -> Vec<Output> {
    let mut outputs: Vec<Output> = a
        .rows
        .iter()
        .filter(|r| r.method() == Method::Analytic)
        .filter(|r| r.mode.is_none_or(|m| m < MODES))
        .map(|r| Output {
            quantity: r.quantity,
            mode: r.mode,
        })
        .collect();
    outputs.sort_by_key(|o| (o.mode, o.quantity as u8));
    outputs.dedup();
    outputs.retain(|o| o.quantity != Quantity::DampingRatio || a.resolved(o.quantity, o.mode));
    outputs
}

/// An output's name in the table, with its unit in the display units `d` and its mode.
fn label(model: &Model, d: Display, q: Quantity, mode: Option<usize>) -> String {
    let name = match q {
        Quantity::DampedFrequency => format!("ω_d ({})", d.frequency.symbol()),
        Quantity::DampingRatio => "ζ".into(),
        Quantity::TransferMagnitude => match &model.analysis.transfer {
            Some(t) => format!("|H| ({})", model.transfer_unit(t)),
            None => "|H|".into(),
        },
    };
    mode.map_or(name.clone(), |m| format!("{name}, mode {}", m + 1))
}

/// A number of the table, or `–` where there is none.
fn num(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite()).map_or("–".to_string(), sig)
}

/// The rows of one case of the analysis.
struct Case<'a> {
    a: &'a Analysis,
    ci: usize,
}

impl<'a> Case<'a> {
    /// The row of method `m` for an output at the speed `w` (the same speed, bit for bit).
    fn find(&self, q: Quantity, mode: Option<usize>, m: Method, w: f64) -> Option<&'a Row> {
        let ci = self.ci;
        self.a.rows.iter().find(|r| {
            r.case == ci
                && r.quantity == q
                && r.mode == mode
                && r.method() == m
                && r.speed.to_bits() == w.to_bits()
        })
    }

    /// The answer's rows (analytic, with a finite σ) of an output.
    fn answers(&self, q: Quantity, mode: Option<usize>) -> Vec<&'a Row> {
        let ci = self.ci;
        self.a
            .rows
            .iter()
            .filter(|r| r.case == ci && r.quantity == q && r.mode == mode)
            .filter(|r| r.method() == Method::Analytic && r.std.is_finite())
            .collect()
    }

    /// Where the table shows the outputs: each at the speed of its largest σ, the first
    /// modes' ω_d at the critical speeds of the 1×Ω line (the nearest speed computed), |H| at
    /// its peak.
    fn places(&self, outputs: &[Output], critical: &[CriticalSpeed], d: Display) -> Vec<Place> {
        let fs = d.speed.per_rad_per_second();
        let mut places: Vec<Place> = Vec::new();
        for &Output { quantity: q, mode } in outputs {
            if let Some(r) = self
                .answers(q, mode)
                .into_iter()
                .max_by(|x, y| x.std.total_cmp(&y.std))
            {
                places.push((q, mode, "largest σ".into(), r.speed));
            }
        }
        for cs in critical.iter().filter(|c| {
            c.order.to_bits() == 1f64.to_bits() && c.mode < MODES && c.meeting == Meeting::Crossing
        }) {
            let rows = self.answers(Quantity::DampedFrequency, Some(cs.mode));
            if let Some(r) = rows.iter().min_by(|x, y| {
                (x.speed - cs.speed)
                    .abs()
                    .total_cmp(&(y.speed - cs.speed).abs())
            }) {
                places.push((
                    Quantity::DampedFrequency,
                    Some(cs.mode),
                    format!("critical speed {:.4}", cs.speed * fs),
                    r.speed,
                ));
            }
        }
        if let Some(r) = self
            .answers(Quantity::TransferMagnitude, None)
            .into_iter()
            .max_by(|x, y| x.mean.total_cmp(&y.mean))
        {
            places.push((
                Quantity::TransferMagnitude,
                None,
                "|H| peak".into(),
                r.speed,
            ));
        }
        places
    }

    /// One row of the table: the output's mean and σ by every method at `place`, and how the
    /// methods agree there.
    fn row(&self, h: &mut String, model: &Model, place: Place, d: Display) {
        let (q, mode, place, w) = place;
        let fs = d.speed.per_rad_per_second();
        let ys = if q == Quantity::DampedFrequency {
            d.frequency.per_rad_per_second()
        } else {
            1.0
        };
        let get = |m: Method| self.find(q, mode, m, w);
        let answer = get(Method::Analytic);
        let sa = answer.map(|r| r.std);
        let sf = get(Method::FirstOrder).map(|r| r.std);
        let mc = get(Method::MonteCarlo).and_then(|r| r.mc());
        // Where the answer's σ is below what the evaluation resolves, the methods' σ are
        // rounding: no comparison.
        let resolved = answer.is_some_and(|r| r.std > q.resolution(r.mean, r.std));
        let (vs, agrees) = if resolved {
            (first_order_vs(sa, sf), monte_carlo_agrees(sa, mc))
        } else {
            ("–".to_string(), "–")
        };
        let spread = answer
            .filter(|r| r.mean != 0.0 && r.std.is_finite())
            .map_or("–".to_string(), |r| {
                format!("±{} %", short(300.0 * r.std / r.mean.abs()))
            });
        let mc_text = mc.map_or("–".to_string(), |m| {
            format!(
                "{} [{}, {}]",
                num(Some(m.std * ys)),
                num(Some(m.std_ci.0 * ys)),
                num(Some(m.std_ci.1 * ys))
            )
        });
        let _ = write!(
            h,
            "<tr><td style=\"text-align:left\">{}</td><td style=\"text-align:left\">{}</td><td>{:.4}</td><td>{}</td><td>{}</td><td>{spread}</td><td>{}</td><td>{}</td><td>{}</td><td>{vs}</td><td>{agrees}</td></tr>",
            esc(&label(model, d, q, mode)),
            esc(&place),
            w * fs,
            num(answer.map(|r| r.mean * ys)),
            num(sa.map(|s| s * ys)),
            num(sf.map(|s| s * ys)),
            num(get(Method::SecondOrder).map(|r| r.std * ys)),
            mc_text,
        );
    }
}

/// First order's σ `sf` against the answer's `sa`, in per cent (`–` where either is missing or
/// the answer's is zero).
fn first_order_vs(sa: Option<f64>, sf: Option<f64>) -> String {
    sa.zip(sf)
        .filter(|(a, f)| *a > 0.0 && a.is_finite() && f.is_finite())
        .map_or("–".to_string(), |(a, f)| {
            // No "-0 %": a difference that rounds to nothing is 0.
            let pct = (100.0 * (f - a) / a).round();
            format!("{:+.0} %", if pct == 0.0 { 0.0 } else { pct })
        })
}

/// Whether the answer's σ `sa` lies inside Monte Carlo's 95 % interval of σ (`–` where either
/// is missing).
fn monte_carlo_agrees(sa: Option<f64>, mc: Option<McStat>) -> &'static str {
    sa.zip(mc).map_or("–", |(s, m)| {
        if s >= m.std_ci.0 && s <= m.std_ci.1 {
            "yes"
        } else {
            "no"
        }
    })
}
