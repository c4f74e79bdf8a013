//! The yield of a tolerance case: the probability that a design meets every requirement of the
//! model at every speed of its range, each requirement's own, the per-speed curves, and each
//! requirement's worst margin (mean, σ, the capability index `Cpk = μ/(3σ)` of a margin whose
//! lower specification limit is 0), by each method that gives it.
//!
//! - **Quadrature** ([`crate::quadrature::QuadYield`]): each node is a whole sweep; the
//!   boundary between designs that pass and fail is located along each line; error estimate.
//! - **Monte Carlo** ([`crate::montecarlo::YieldCounts`]): the fraction of samples that pass,
//!   with the 95 % Wilson score interval (Wilson 1927), exact-count merges across shards.
//! - **First order**: the margin linearised at the nominal design,
//!   `P = Φ(β)`, `β = m₀/σ_m`, `σ_m² = ∇mᵀ Σ ∇m` (the mean-value first-order reliability index;
//!   Hasofer & Lind 1974 for its invariant form), per speed. Over a range it gives the
//!   probability at the worst speed, an upper bound on the range's (the events at the speeds
//!   are not independent: the bound is attained when one speed decides), and none for the
//!   requirements that are pass or fail (the branch) or are not a smooth function of the
//!   outputs at the nominal design (stability, where no mode is close to it, has a first-order
//!   margin only through its growth rate, which the local model does not carry).

use crate::model::{Requirement, RequirementKind};
use crate::montecarlo::YieldCounts;
use crate::output::{Output, Quantity};
use crate::propagate::{Method, Study};
use crate::quadrature::{MarginStat, QuadYield};
use crate::requirement::{
    carriers, covers, has_margin, mode_margin, mode_margin_gradient, reaches,
};
use crate::tolerance::Spread;
use statrs::distribution::{ContinuousCDF, Normal};

/// One line of `yield.csv`: the probability of meeting a requirement (or all of them) over its
/// range or at one speed, by one method.
#[derive(Debug, Clone, PartialEq)]
pub struct YieldRow {
    pub case: usize,
    pub method: Method,
    /// The requirement (index into the model's), `None` for all of them.
    pub requirement: Option<usize>,
    /// `None`: over the requirement's range; else at this speed.
    pub speed: Option<f64>,
    pub probability: f64,
    /// Quadrature: ± the error estimate (clamped to [0, 1]); Monte Carlo: 95 % Wilson
    /// interval; first order: the value itself.
    pub ci: (f64, f64),
    /// The worst margin over the range: mean and σ (range rows of requirements with a margin).
    pub margin: Option<(f64, f64)>,
    /// `μ/(3σ)` of the worst margin (where σ > 0).
    pub cpk: Option<f64>,
    /// Samples (Monte Carlo) or nodes (quadrature) behind the row.
    pub evaluations: usize,
    /// Quadrature: does the error estimate meet the requested accuracy (the quadrature's
    /// tolerance, as an absolute error of the probability)? Where not, the rule's largest stage
    /// was reached first.
    pub within_request: Option<bool>,
    /// What the design meets at the target yield (range rows of a requirement).
    pub limit: Option<Limit>,
}

/// What a design with its tolerances as they are meets at the target yield: the inverse
/// questions of a specification. Each as `[estimate, low, high]`: from the probability itself
/// and from the low and high ends of its interval (first order: three times its value).
#[derive(Debug, Clone, PartialEq)]
pub struct Limit {
    /// The highest analysed speed up to which, from the start of the requirement's range on
    /// (beyond its end too), the probability of meeting it at every speed is at least the
    /// target: the largest operating range met. `None`: not even at the range's first speed.
    pub reach: [Option<f64>; 3],
    /// The worst margin over the range met at the target yield: its `1 − target` quantile
    /// (`−∞` where more than `1 − target` of the designs fail without a margin; first order:
    /// the worst speed's `m₀ − z σ`, `Φ(z)` = target); `None` for a pass-or-fail requirement.
    pub margin: Option<[f64; 3]>,
    /// Why the margin or an end of its interval has no value (`±∞` or NaN in `margin`, blank
    /// in `limits.csv`), in words; `None` where every value is a number.
    pub why: Option<String>,
}

impl Limit {
    /// The limit with `why` derived from `margin`'s unbounded parts: `reasons` gives the words
    /// for an estimate of `−∞`, a low end of `−∞` and a high end of `+∞`, in that order.
    fn new(reach: [Option<f64>; 3], margin: Option<[f64; 3]>, reasons: [&str; 3]) -> Limit {
        let why = margin.and_then(|m| {
            let parts: Vec<&str> = [
                !m[0].is_finite(),
                !m[0].is_finite() || !m[1].is_finite(),
                !m[0].is_finite() || !m[2].is_finite(),
            ]
            .iter()
            .zip(reasons)
            .filter(|(bad, _)| **bad)
            .map(|(_, why)| why)
            .collect();
            // An unbounded estimate leaves its interval so: one reason says both.
            let parts = if !m[0].is_finite() {
                vec![parts[0]]
            } else {
                parts
            };
            (!parts.is_empty()).then(|| parts.join("; "))
        });
        Limit { reach, margin, why }
    }

    /// A limit without a margin for `why` (a requirement with one, where no design has it).
    fn without_margin(reach: [Option<f64>; 3], why: &str) -> Limit {
        Limit {
            reach,
            margin: None,
            why: Some(why.to_string()),
        }
    }
}

/// The last speed of the initial run of `prefix` (speed, probability) at or above `target`.
fn reach_of(prefix: impl IntoIterator<Item = (f64, f64)>, target: f64) -> Option<f64> {
    prefix
        .into_iter()
        .take_while(|&(_, p)| p >= target)
        .last()
        .map(|(w, _)| w)
}

/// The reach `[estimate, low, high]` from the per-speed `(speed, probability, (low, high))`.
fn reach(prefix: &[(f64, f64, (f64, f64))], target: f64) -> [Option<f64>; 3] {
    [
        reach_of(prefix.iter().map(|x| (x.0, x.1)), target),
        reach_of(prefix.iter().map(|x| (x.0, x.2.0)), target),
        reach_of(prefix.iter().map(|x| (x.0, x.2.1)), target),
    ]
}

/// The `q` quantile of `sorted` samples with its 95 % distribution-free interval, the order
/// statistics whose ranks the binomial distribution of the count below the quantile gives
/// (e.g. Hahn & Meeker, *Statistical Intervals*, 1991, §5.2): `[estimate, low, high]`, `−∞` /
/// `+∞` where too few samples lie beyond the quantile for an end.
pub fn quantile_interval(sorted: &[f64], q: f64) -> [f64; 3] {
    use statrs::distribution::{Binomial, DiscreteCDF};
    let n = sorted.len();
    let est = crate::montecarlo::sorted_quantile(sorted, q);
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

/// The 95 % Wilson score interval of `k` successes in `n` trials.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054;
    let (none, all) = (k == 0, k == n);
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    // At k = 0 and k = n the ends are 0 and 1 exactly (rounding would leave 10⁻¹⁹).
    (
        if none { 0.0 } else { (c - h).max(0.0) },
        if all { 1.0 } else { (c + h).min(1.0) },
    )
}

fn cpk(mean: f64, std: f64) -> Option<f64> {
    (std > 0.0 && mean.is_finite()).then(|| mean / (3.0 * std))
}

/// The quadrature's rows of case `case` (`nodes` swept), with what the design meets at
/// `target`.
pub fn quadrature_rows(
    case: usize,
    y: &QuadYield,
    reqs: &[Requirement],
    speeds: &[f64],
    nodes: usize,
    target: f64,
) -> Vec<YieldRow> {
    let ci = |(p, e): (f64, f64)| ((p - e).max(0.0), (p + e).min(1.0));
    // Within the request: the probability's error (absolute), and the worst margin's mean and
    // σ errors relative to its σ.
    let within = |(_, e): (f64, f64)| e <= y.request;
    let margin_within = |m: &MarginStat| {
        let allowed = y.request * m.std;
        m.mean_error <= allowed && m.std_error <= allowed
    };
    let mut out = vec![YieldRow {
        case,
        method: Method::Quadrature,
        requirement: None,
        speed: None,
        probability: y.all.0,
        ci: ci(y.all),
        margin: None,
        cpk: None,
        evaluations: nodes,
        within_request: Some(within(y.all)),
        limit: None,
    }];
    for (r, &each) in y.each.iter().enumerate() {
        let margin = y.margins[r].map(|m| (m.mean, m.std));
        let prefix: Vec<(f64, f64, (f64, f64))> = speeds
            .iter()
            .zip(&y.prefix)
            .filter(|(w, _)| reaches(&reqs[r], **w))
            .map(|(&w, p)| (w, p[r].0, ci(p[r])))
            .collect();
        out.push(YieldRow {
            case,
            method: Method::Quadrature,
            requirement: Some(r),
            speed: None,
            probability: each.0,
            ci: ci(each),
            margin,
            cpk: margin.and_then(|(m, s)| cpk(m, s)),
            evaluations: nodes,
            within_request: Some(within(each) && y.margins[r].as_ref().is_none_or(margin_within)),
            limit: Some(match y.margins[r].and_then(|m| m.at_target) {
                Some(t) => Limit::new(
                    reach(&prefix, target),
                    Some([t.estimate, t.low, t.high]),
                    [
                        "more than 1 − target of the designs fail without a margin",
                        "margin_low unbounded: the target plus the probability's error exceeds \
                         the share of designs with a margin",
                        "margin_high unbounded: the target less the probability's error is ≤ 0",
                    ],
                ),
                None if has_margin(&reqs[r]) => Limit::without_margin(
                    reach(&prefix, target),
                    "no design has a margin over the range (every node failed or has no value)",
                ),
                None => Limit::new(reach(&prefix, target), None, [""; 3]),
            }),
        });
    }
    for (i, row) in y.curves.iter().enumerate() {
        for (r, &p) in row.iter().enumerate() {
            if p.0.is_nan() {
                continue;
            }
            out.push(YieldRow {
                case,
                method: Method::Quadrature,
                requirement: Some(r),
                speed: Some(speeds[i]),
                probability: p.0,
                ci: ci(p),
                margin: None,
                cpk: None,
                evaluations: nodes,
                within_request: Some(within(p)),
                limit: None,
            });
        }
    }
    out
}

/// The Monte Carlo's rows of case `case` from the counts of `n` samples and, where the run
/// kept them, every sample's worst margins (sorted, per requirement), with what the design
/// meets at `target`.
pub fn monte_carlo_rows(
    case: usize,
    y: &YieldCounts,
    worst: Option<&[Vec<f64>]>,
    reqs: &[Requirement],
    speeds: &[f64],
    n: usize,
    target: f64,
) -> Vec<YieldRow> {
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

/// A requirement's first-order margin at speed `i`: its nominal value and its gradient over
/// the study's variables, `None` where first order does not apply (see the module
/// documentation) or a derivative is missing.
pub fn linear_margin(study: &Study, req: &Requirement, i: usize) -> Option<(f64, Vec<f64>)> {
    let pt = study.nominal[i].as_ref()?;
    let lm = study.locals[i].as_ref()?;
    let speed = study.speeds[i];
    let index = |q: Quantity, mode: Option<usize>| {
        study
            .outputs
            .iter()
            .position(|o| *o == Output { quantity: q, mode })
    };
    match req.kind {
        RequirementKind::SameBranch | RequirementKind::Stable => None,
        RequirementKind::Transfer { max } => {
            let k = index(Quantity::TransferMagnitude, None)?;
            let g = lm.grad[k].as_ref().ok()?;
            Some((max - lm.value[k], g.iter().map(|x| -x).collect()))
        }
        _ => {
            let c = carriers(pt, None);
            let modes = pt.modes.len();
            let of = |m: usize| mode_margin(req, speed, c[2 * m], c[2 * m + 1]);
            // The mode asked, or the worst at the nominal design.
            let m = match req.mode {
                Some(m) => m,
                None => (0..modes)
                    .filter(|&m| !of(m).is_nan())
                    .min_by(|&a, &b| of(a).total_cmp(&of(b)))?,
            };
            let m0 = of(m);
            let (kw, kz) = (
                index(Quantity::DampedFrequency, Some(m))?,
                index(Quantity::DampingRatio, Some(m))?,
            );
            let (wd, zeta) = (lm.value[kw], lm.value[kz]);
            let (dw, dz) = mode_margin_gradient(req, speed, wd, zeta);
            let gw = if dw == 0.0 {
                None
            } else {
                Some(lm.grad[kw].as_ref().ok()?)
            };
            let gz = if dz == 0.0 {
                None
            } else {
                Some(lm.grad[kz].as_ref().ok()?)
            };
            let g = (0..study.vars.len())
                .map(|v| dw * gw.map_or(0.0, |g| g[v]) + dz * gz.map_or(0.0, |g| g[v]))
                .collect::<Vec<f64>>();
            (m0.is_finite() && g.iter().all(|x| x.is_finite())).then_some((m0, g))
        }
    }
}

/// `σ_m = √(gᵀ Σ g)` under `spread`.
pub fn margin_sigma(g: &[f64], spread: &Spread) -> f64 {
    let n = g.len();
    let mut v = 0.0;
    for a in 0..n {
        for b in 0..n {
            v += g[a] * spread.covariance[(a, b)] * g[b];
        }
    }
    v.max(0.0).sqrt()
}

/// `Φ(m₀/σ)`, 1 or 0 where σ = 0.
fn first_order_probability(m0: f64, sigma: f64) -> f64 {
    if sigma > 0.0 {
        Normal::standard().cdf(m0 / sigma)
    } else if m0 >= 0.0 {
        1.0
    } else {
        0.0
    }
}

/// The first-order rows of case `case`: per speed, and over the range at the worst speed, with
/// what the design meets at the model's target yield (the reach from the running minimum of the
/// per-speed probabilities, an upper bound like the range's probability).
pub fn first_order_rows(study: &Study, case: usize, spread: &Spread) -> Vec<YieldRow> {
    let model = study.model.model();
    let (reqs, target) = (&model.requirements, model.allocation.target_yield);
    let z = Normal::standard().inverse_cdf(target);
    let mut out = Vec::new();
    let mut worst_all: Option<f64> = Some(1.0);
    for (r, req) in reqs.iter().enumerate() {
        let mut worst: Option<(f64, f64, f64)> = None;
        let mut at_target = f64::INFINITY;
        let mut complete = true;
        // (speed, probability of every speed from the range's start up to it), while known.
        let mut prefix: Vec<(f64, f64, (f64, f64))> = Vec::new();
        let mut running = Some(1.0f64);
        for (i, &w) in study.speeds.iter().enumerate() {
            if !reaches(req, w) {
                continue;
            }
            let Some((m0, g)) = linear_margin(study, req, i) else {
                running = None;
                complete &= !covers(req, w);
                continue;
            };
            let s = margin_sigma(&g, spread);
            let p = first_order_probability(m0, s);
            if let Some(x) = running.as_mut() {
                *x = x.min(p);
                prefix.push((w, *x, (*x, *x)));
            }
            if !covers(req, w) {
                continue;
            }
            out.push(YieldRow {
                case,
                method: Method::FirstOrder,
                requirement: Some(r),
                speed: Some(w),
                probability: p,
                ci: (p, p),
                margin: None,
                cpk: None,
                evaluations: 0,
                within_request: None,
                limit: None,
            });
            at_target = at_target.min(m0 - z * s);
            if worst.is_none_or(|x| p < x.0) {
                worst = Some((p, m0, s));
            }
        }
        match worst {
            Some((p, m0, s)) if complete => {
                out.push(YieldRow {
                    case,
                    method: Method::FirstOrder,
                    requirement: Some(r),
                    speed: None,
                    probability: p,
                    ci: (p, p),
                    margin: Some((m0, s)),
                    cpk: cpk(m0, s),
                    evaluations: 0,
                    within_request: None,
                    limit: Some(Limit::new(
                        reach(&prefix, target),
                        Some([at_target; 3]),
                        ["the margin's first-order quantile is unbounded"; 3],
                    )),
                });
                worst_all = worst_all.map(|x| x.min(p));
            }
            _ => worst_all = None,
        }
    }
    if let Some(p) = worst_all
        && !reqs.is_empty()
    {
        out.insert(
            0,
            YieldRow {
                case,
                method: Method::FirstOrder,
                requirement: None,
                speed: None,
                probability: p,
                ci: (p, p),
                margin: None,
                cpk: None,
                evaluations: 0,
                within_request: None,
                limit: None,
            },
        );
    }
    out
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

    #[test]
    fn the_reach_ends_at_the_first_speed_below_the_target() {
        let p = [
            (1.0, 0.99),
            (2.0, 0.95),
            (3.0, 0.91),
            (4.0, 0.85),
            (5.0, 0.95),
        ];
        let rows: Vec<(f64, f64, (f64, f64))> = p
            .iter()
            .map(|&(w, p)| (w, p, (p - 0.02, p + 0.02)))
            .collect();
        let [est, lo, hi] = reach(&rows, 0.9);
        let bits = |x: Option<f64>| x.map(f64::to_bits);
        assert_eq!(bits(est), Some(3f64.to_bits()));
        assert_eq!(bits(lo), Some(2f64.to_bits()));
        assert_eq!(bits(hi), Some(3f64.to_bits()));
        assert_eq!(reach(&rows, 0.999)[0], None);
    }

    #[test]
    fn wilson_interval_matches_its_closed_form() {
        // 81 of 100: the textbook interval [0.7222, 0.8749].
        let (lo, hi) = wilson(81, 100);
        assert!(
            (lo - 0.722_2).abs() < 1e-4 && (hi - 0.874_9).abs() < 1e-4,
            "{lo} {hi}"
        );
        // All pass: the upper end is 1, the lower end n/(n + z²); none pass: the lower end 0.
        let (lo, hi) = wilson(50, 50);
        assert!(hi.to_bits() == 1f64.to_bits());
        assert!(wilson(0, 50).0.to_bits() == 0f64.to_bits());
        assert!((lo - 50.0 / (50.0 + 1.959_963_984_540_054f64.powi(2))).abs() < 1e-12);
    }
}
