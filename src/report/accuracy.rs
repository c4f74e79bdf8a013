//! The quadrature rows whose error estimates exceed the requested accuracy: the refinement
//! reached its finest grid first. They keep their values (with their error estimates); this
//! says plainly which they are, in `summary.json`, the report and on stderr.

use crate::analyze::Analysis;
use crate::output::Quantity;
use crate::table::Method;

/// Quadrature rows of one case and output whose error estimates exceed the request.
#[derive(Debug, Clone)]
pub struct Outside {
    pub case: usize,
    pub quantity: Quantity,
    /// 0-based mode, `None` for |H|.
    pub mode: Option<usize>,
    /// The speeds of those rows (rad/s).
    pub speeds: Vec<f64>,
}

/// Every quadrature row outside the requested accuracy, grouped by case and output, in the
/// rows' order.
pub fn outside_request(a: &Analysis) -> Vec<Outside> {
    let mut out: Vec<Outside> = Vec::new();
    for r in &a.rows {
        if r.method() != Method::Quadrature || r.within_request() != Some(false) {
            continue;
        }
        let same = |o: &Outside| o.case == r.case && o.quantity == r.quantity && o.mode == r.mode;
        match out.iter_mut().find(|o| same(o)) {
            Some(o) => o.speeds.push(r.speed),
            None => out.push(Outside {
                case: r.case,
                quantity: r.quantity,
                mode: r.mode,
                speeds: vec![r.speed],
            }),
        }
    }
    out
}

/// Quadrature yield rows of one case and requirement (`None`: all together) whose error
/// estimates exceed the request: over the range (`None`) or at speeds.
#[derive(Debug, Clone)]
pub struct YieldOutside {
    pub case: usize,
    pub requirement: Option<usize>,
    pub speeds: Vec<Option<f64>>,
}

/// Every quadrature yield row outside the requested accuracy, grouped by case and requirement.
pub fn yield_outside_request(a: &Analysis) -> Vec<YieldOutside> {
    let mut out: Vec<YieldOutside> = Vec::new();
    for y in &a.yields {
        if y.method != crate::table::Method::Quadrature || y.within_request != Some(false) {
            continue;
        }
        match out
            .iter_mut()
            .find(|o| o.case == y.case && o.requirement == y.requirement)
        {
            Some(o) => o.speeds.push(y.speed),
            None => out.push(YieldOutside {
                case: y.case,
                requirement: y.requirement,
                speeds: vec![y.speed],
            }),
        }
    }
    out
}

/// The output's name in words (`damped_frequency of mode 2`).
pub(super) fn output_name(quantity: Quantity, mode: Option<usize>) -> String {
    mode.map_or(quantity.as_str().to_string(), |m| {
        format!("{} of mode {}", quantity.as_str(), m + 1)
    })
}

/// The lowest and highest of `speeds`.
pub(super) fn bounds(speeds: &[f64]) -> (f64, f64) {
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}

/// Speeds from `lo` to `hi` in words.
pub(super) fn speed_range((lo, hi): (f64, f64)) -> String {
    if lo.to_bits() == hi.to_bits() {
        format!("at {lo} rad/s")
    } else {
        format!("between {lo} and {hi} rad/s")
    }
}

/// One line per case: how many quadrature rows are outside the requested accuracy, and for
/// which outputs (empty when every row meets it).
pub fn outside_request_lines(a: &Analysis) -> Vec<String> {
    let groups = outside_request(a);
    (0..a.cases.len())
        .filter_map(|case| {
            let of: Vec<&Outside> = groups.iter().filter(|o| o.case == case).collect();
            if of.is_empty() {
                return None;
            }
            let rows: usize = of.iter().map(|o| o.speeds.len()).sum();
            let outputs: Vec<String> = of
                .iter()
                .take(4)
                .map(|o| {
                    format!(
                        "{} {}",
                        output_name(o.quantity, o.mode),
                        speed_range(bounds(&o.speeds))
                    )
                })
                .collect();
            let more = if of.len() > 4 {
                format!(" and {} more outputs", of.len() - 4)
            } else {
                String::new()
            };
            // How far off: the largest error estimate (of the mean or σ) as a share of σ.
            let worst = (a.rows.iter())
                .filter(|r| r.case == case && r.method() == Method::Quadrature)
                .filter(|r| r.within_request() == Some(false) && r.std > 0.0)
                .filter_map(|r| {
                    let q = r.detail.quadrature()?;
                    Some((q.errors.0.max(q.errors.1) / r.std, r))
                })
                .filter(|(e, _)| e.is_finite())
                .max_by(|x, y| x.0.total_cmp(&y.0));
            let far = worst.map_or(String::new(), |(e, r)| {
                format!(
                    ". The largest error estimate is {:.2} σ ({} at {} rad/s)",
                    e,
                    output_name(r.quantity, r.mode),
                    r.speed
                )
            });
            let swept = a.quadrature_rules.get(case).map_or(0, |r| r.1);
            Some(format!(
                "case '{}': the quadrature's error estimate exceeds the requested accuracy at \
                 {rows} row(s) (within_request = false in tolerance.csv): {}{more}{far}. Those \
                 values are the finest rule's within the node budget ({swept} nodes swept); to \
                 tighten them allow more nodes (--quadrature-nodes), or read the Monte Carlo's \
                 95 % intervals beside them (--samples)",
                a.cases[case].name,
                outputs.join("; ")
            ))
        })
        .chain(yield_outside_lines(a))
        .collect()
}

/// One line per case whose quadrature yield rows miss the requested accuracy.
fn yield_outside_lines(a: &Analysis) -> Vec<String> {
    let groups = yield_outside_request(a);
    (0..a.cases.len())
        .filter_map(|case| {
            let of: Vec<&YieldOutside> = groups.iter().filter(|o| o.case == case).collect();
            if of.is_empty() {
                return None;
            }
            let rows: usize = of.iter().map(|o| o.speeds.len()).sum();
            Some(format!(
                "case '{}': the quadrature's yield error estimate exceeds the requested \
                 accuracy at {rows} row(s) (within_request = false in yield.csv)",
                a.cases[case].name
            ))
        })
        .collect()
}
