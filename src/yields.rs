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
use crate::propagate::Study;
use crate::quadrature::QuadYield;
use crate::requirement::{carriers, covers, has_margin, mode_margin, mode_margin_gradient};
use crate::tolerance::Spread;
use statrs::distribution::{ContinuousCDF, Normal};

/// The methods that give a yield, as named in the outputs (those of
/// [`crate::analyze::Method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    FirstOrder,
    Quadrature,
    MonteCarlo,
}

impl Method {
    pub fn as_str(self) -> &'static str {
        match self {
            Method::FirstOrder => "first_order",
            Method::Quadrature => "quadrature",
            Method::MonteCarlo => "monte_carlo",
        }
    }
}

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

/// The quadrature's rows of case `case` (`nodes` swept).
pub fn quadrature_rows(case: usize, y: &QuadYield, speeds: &[f64], nodes: usize) -> Vec<YieldRow> {
    let ci = |(p, e): (f64, f64)| ((p - e).max(0.0), (p + e).min(1.0));
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
    }];
    for (r, &each) in y.each.iter().enumerate() {
        let margin = y.margins[r].map(|m| (m.mean, m.std));
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
            });
        }
    }
    out
}

/// The Monte Carlo's rows of case `case` from the counts of `n` samples.
pub fn monte_carlo_rows(
    case: usize,
    y: &YieldCounts,
    reqs: &[Requirement],
    speeds: &[f64],
    n: usize,
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
    }];
    for (r, &k) in y.each.iter().enumerate() {
        let margin = has_margin(&reqs[r])
            .then(|| y.margins[r].mean_std())
            .filter(|m| m.0.is_finite());
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

/// The first-order rows of case `case`: per speed, and over the range at the worst speed.
pub fn first_order_rows(study: &Study, case: usize, spread: &Spread) -> Vec<YieldRow> {
    let reqs = &study.model.model().requirements;
    let mut out = Vec::new();
    let mut worst_all: Option<f64> = Some(1.0);
    for (r, req) in reqs.iter().enumerate() {
        let mut worst: Option<(f64, f64, f64)> = None;
        let mut complete = true;
        for (i, &w) in study.speeds.iter().enumerate() {
            if !covers(req, w) {
                continue;
            }
            let Some((m0, g)) = linear_margin(study, req, i) else {
                complete = false;
                continue;
            };
            let s = margin_sigma(&g, spread);
            let p = first_order_probability(m0, s);
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
            });
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
            },
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

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
