//! The Monte Carlo's rows: mean and σ of every output with their 95 % intervals and sample
//! quantiles, the probabilities of each change of character with 95 % Wilson score intervals,
//! and the yield with what the design meets at the target (from the kept worst margins'
//! distribution-free quantile intervals).

use super::{McRun, YieldCounts};
use crate::margins::{covers, has_margin, reaches};
use crate::modal::ModeClass;
use crate::output::{Missing, Output, Quantity};
use crate::propagate::{Study, Tabulate};
use crate::sweep::Point;
use crate::table::{
    Detail, Event, Limit, McStat, Method, ProbabilityRow, Row, Tables, YieldRow, cpk, reach, wilson,
};
use crate::tolerance::Spread;

/// A shard's state is not tabulated: it is the run's result ([`McRun::into_shard`]).
impl Tabulate for McRun {
    fn tabulate(self, study: &Study, case: usize, _spread: &Spread, tables: &mut Tables) {
        let r = match self {
            McRun::NotStarted => {
                tables.samples_done.push(0);
                return;
            }
            McRun::Shard(_) => return,
            McRun::Done(r) => r,
        };
        let done = r.samples;
        tables.samples_done.push(done);
        if let Some(y) = &r.fold.total_yields() {
            let worst = r.worst_margins.as_deref();
            tables
                .yields
                .extend(yield_rows(study, case, y, worst, done));
        }
        tables.inadmissible.push(r.inadmissible);
        for (si, stats) in r.stats.iter().enumerate() {
            let Some(pt) = &study.nominal[si] else {
                continue;
            };
            if done < 2 {
                continue;
            }
            let speed = study.speeds[si];
            for p in probabilities(speed, case, &study.outputs, stats) {
                tables.probabilities.push(p);
            }
            for (k, (o, st)) in study.outputs.iter().zip(stats).enumerate() {
                tables.row(si, k, row(speed, case, pt, o, st));
            }
        }
    }
}

/// The row of output `o` at `speed` (whose nominal point is `pt`); a row without a value says
/// why.
fn row(speed: f64, case: usize, pt: &Point, o: &Output, st: &McStat) -> Row {
    Row {
        speed,
        quantity: o.quantity,
        mode: o.mode,
        case,
        mean: st.mean,
        std: st.std,
        missing: if !st.mean.is_finite() {
            Some(no_value(pt, o))
        } else {
            (!st.std.is_finite()).then_some(Missing::OneSample)
        },
        detail: Detail::MonteCarlo(*st),
    }
}

/// Why a sampling method has no value for output `o` at a speed whose nominal point is `pt`:
/// the output has none there either (the damping ratio of a rigid-body mode), or no sample
/// gave one.
fn no_value(pt: &Point, o: &Output) -> Missing {
    match (
        o.quantity,
        o.mode.and_then(|m| pt.modes.get(m).map(|x| (m, x))),
    ) {
        (Quantity::DampingRatio, Some((mode, m))) if m.class == ModeClass::Rigid => {
            Missing::RigidDamping { mode }
        }
        _ => Missing::NoValue,
    }
}

/// The probabilities of character at one speed from the event counts of its statistics, with
/// 95 % Wilson score intervals.
fn probabilities(
    speed: f64,
    case: usize,
    outs: &[Output],
    stats: &[McStat],
) -> Vec<ProbabilityRow> {
    let mut v = Vec::new();
    let mut push = |event, mode, count: usize, st: &McStat| {
        let n = st.n + st.failed;
        if n == 0 {
            return;
        }
        let p = count as f64 / n as f64;
        v.push(ProbabilityRow {
            speed,
            case,
            method: Method::MonteCarlo,
            event,
            mode,
            probability: p,
            ci: wilson(count, n),
        });
    };
    for (o, st) in outs.iter().zip(stats) {
        if o.quantity == Quantity::DampedFrequency {
            push(Event::Overdamped, o.mode, st.overdamped, st);
        }
    }
    if let Some(st) = stats.first() {
        push(Event::Unstable, None, st.unstable, st);
        push(Event::OtherBranch, None, st.other_branch, st);
    }
    v
}

/// The Monte Carlo's rows of case `case` from the counts of `n` samples and, where the run
/// kept them, every sample's worst margins (sorted, per requirement), with what the design
/// meets at the model's target yield.
fn yield_rows(
    study: &Study,
    case: usize,
    y: &YieldCounts,
    worst: Option<&[Vec<f64>]>,
    n: usize,
) -> Vec<YieldRow> {
    let m = study.model.model();
    let (reqs, speeds) = (&m.requirements, &study.speeds);
    let target = m.allocation.target_yield;
    let p = |k: usize| if n > 0 { k as f64 / n as f64 } else { f64::NAN };
    let mut out = vec![YieldRow {
        case,
        method: Method::MonteCarlo,
        requirement: None,
        speed: None,
        probability: p(y.all),
        ci: wilson(y.all, n),
        margin: None,
        cpk: None,
        evaluations: n,
        within_request: None,
        limit: None,
    }];
    for (r, &k) in y.each.iter().enumerate() {
        let margin = has_margin(&reqs[r])
            .then(|| y.margins[r].mean_std())
            .filter(|m| m.0.is_finite());
        let prefix: Vec<(f64, f64, (f64, f64))> = speeds
            .iter()
            .enumerate()
            .filter(|(_, w)| reaches(&reqs[r], **w))
            .map(|(i, &w)| {
                let k = y.prefix[i * reqs.len() + r];
                (w, p(k), wilson(k, n))
            })
            .collect();
        let kept = worst
            .and_then(|w| w.get(r))
            .filter(|w| has_margin(&reqs[r]) && !w.is_empty());
        let at_target = kept.map(|w| quantile_interval(w, 1.0 - target));
        out.push(YieldRow {
            case,
            method: Method::MonteCarlo,
            requirement: Some(r),
            speed: None,
            probability: p(k),
            ci: wilson(k, n),
            margin,
            cpk: margin.and_then(|(m, s)| cpk(m, s)),
            evaluations: n,
            within_request: None,
            limit: Some(if has_margin(&reqs[r]) && kept.is_none() {
                Limit::without_margin(
                    reach(&prefix, target),
                    "the run has no sample's margin (none kept, or no sample)",
                )
            } else {
                Limit::new(
                    reach(&prefix, target),
                    at_target,
                    [
                        "more than 1 − target of the samples fail without a margin",
                        "margin_low unbounded: too few samples below the 1 − target quantile \
                         for its 95 % interval",
                        "margin_high unbounded: too few samples above the 1 − target quantile \
                         for its 95 % interval",
                    ],
                )
            }),
        });
    }
    for (i, &w) in speeds.iter().enumerate() {
        for (r, req) in reqs.iter().enumerate() {
            if !covers(req, w) {
                continue;
            }
            let k = y.curves[i * reqs.len() + r];
            out.push(YieldRow {
                case,
                method: Method::MonteCarlo,
                requirement: Some(r),
                speed: Some(w),
                probability: p(k),
                ci: wilson(k, n),
                margin: None,
                cpk: None,
                evaluations: n,
                within_request: None,
                limit: None,
            });
        }
    }
    out
}

/// The `q` quantile of `sorted` samples with its 95 % distribution-free interval, the order
/// statistics whose ranks the binomial distribution of the count below the quantile gives
/// (e.g. Hahn & Meeker, *Statistical Intervals*, 1991, §5.2): `[estimate, low, high]`, `−∞` /
/// `+∞` where too few samples lie beyond the quantile for an end.
pub fn quantile_interval(sorted: &[f64], q: f64) -> [f64; 3] {
    use statrs::distribution::{Binomial, DiscreteCDF};
    let n = sorted.len();
    let est = super::sorted_quantile(sorted, q);
    let Ok(b) = Binomial::new(q.clamp(0.0, 1.0), n as u64) else {
        return [est, f64::NEG_INFINITY, f64::INFINITY];
    };
    // P(X(l) ≤ ξ) = P(B ≥ l): the largest l with P(B ≤ l − 1) ≤ 2.5 %.
    let lower = (1..=n)
        .take_while(|&l| b.cdf(l as u64 - 1) <= 0.025)
        .last()
        .map_or(f64::NEG_INFINITY, |l| sorted[l - 1]);
    // P(X(u) ≥ ξ) = P(B ≤ u − 1): the smallest u with P(B ≤ u − 1) ≥ 97.5 %.
    let upper = (1..=n)
        .find(|&u| b.cdf(u as u64 - 1) >= 0.975)
        .map_or(f64::INFINITY, |u| sorted[u - 1]);
    // The estimate interpolates between order statistics: the interval's ends hold it.
    [est, lower.min(est), upper.max(est)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_interval_takes_the_binomial_order_statistics() {
        // The median of 100: the textbook ranks 40 and 61 (e.g. Conover, Practical
        // Nonparametric Statistics, Table A3).
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let [est, lo, hi] = quantile_interval(&v, 0.5);
        assert!((est - 50.5).abs() < 1e-12);
        assert!(lo.to_bits() == 40f64.to_bits() && hi.to_bits() == 61f64.to_bits());
        // The 0.27 % quantile of 1000 samples: 2.7 expected below, too few for a lower end.
        let v: Vec<f64> = (1..=1000).map(f64::from).collect();
        let [_, lo, hi] = quantile_interval(&v, 0.0027);
        assert!(
            lo == f64::NEG_INFINITY && hi.is_finite() && hi > 2.0,
            "{lo} {hi}"
        );
    }

    /// The probabilities' intervals end exactly at 0 where no sample had the event and at 1
    /// where every one had it (the Wilson formula rounded to 2.8e-17 and 0.9999999999999999
    /// for 203 of the counts 0 and n below 400, as `probabilities.csv` used to show).
    #[test]
    fn probabilities_of_no_and_of_every_sample_have_exact_interval_ends() {
        let out = [Output {
            quantity: Quantity::DampedFrequency,
            mode: Some(0),
        }];
        for n in [7, 9, 10, 12, 399] {
            let st = McStat {
                n,
                overdamped: 0,
                unstable: n,
                ..McStat::default()
            };
            let rows = probabilities(1.0, 0, &out, &[st]);
            let of = |e: Event| rows.iter().find(|r| r.event == e).expect("a row").ci;
            assert_eq!(of(Event::Overdamped).0.to_bits(), 0f64.to_bits(), "n = {n}");
            assert_eq!(of(Event::Unstable).1.to_bits(), 1f64.to_bits(), "n = {n}");
            assert!(of(Event::Overdamped).1 > 0.0 && of(Event::Unstable).0 < 1.0);
        }
    }
}
