//! A line of `yield.csv`, the yield of a tolerance case: the probability that a design meets every requirement of the
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

use super::method::Method;

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
    pub fn new(reach: [Option<f64>; 3], margin: Option<[f64; 3]>, reasons: [&str; 3]) -> Limit {
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
    pub fn without_margin(reach: [Option<f64>; 3], why: &str) -> Limit {
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
pub fn reach(prefix: &[(f64, f64, (f64, f64))], target: f64) -> [Option<f64>; 3] {
    [
        reach_of(prefix.iter().map(|x| (x.0, x.1)), target),
        reach_of(prefix.iter().map(|x| (x.0, x.2.0)), target),
        reach_of(prefix.iter().map(|x| (x.0, x.2.1)), target),
    ]
}

/// The capability index `μ/(3σ)` of a margin whose lower specification limit is 0 (where
/// σ > 0).
pub fn cpk(mean: f64, std: f64) -> Option<f64> {
    (std > 0.0 && mean.is_finite()).then(|| mean / (3.0 * std))
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
