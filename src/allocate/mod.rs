//! Tolerance allocation: the tolerances of a case's variables that minimise a manufacturing
//! cost and still meet the requirements at a target yield, verified by the quadrature.
//!
//! **The search** uses the requirements' exact first-order margins at every speed of their
//! ranges ([`crate::taylor::yields::linear_margin`]): with the variables independent and the tolerance
//! `T_k` their ±3σ (normal; `±√3σ` uniform), the margin `j`'s σ is
//! `σ_j² = Σ_k (g_jk s_k T_k)²`, `s_k = 1/3` or `1/√3`, and each margin must keep the
//! reliability index `m₀_j / σ_j ≥ β` (Hasofer & Lind 1974; at the mean point, the classical
//! root-sum-square stack-up of Chase & Greenwood 1988). The cost is Chase & Greenwood's
//! `Σ_k a_k + b_k / T_k^{e_k}`. In `u_k = T_k²` the constraints are linear and the cost convex,
//! so the problem is a separable convex programme. Its KKT conditions give each `u_k` in
//! closed form from the multipliers: `u_k = (e_k b_k / (2 Σ_j λ_j A_jk))^{2/(e_k+2)}` (clamped to
//! the largest tolerance allowed), `A_jk = (g_jk s_k)²`, which for one active constraint is the
//! textbook `T_k ∝ (e_k b_k / S_k²)^{1/(e_k+2)}`. The multipliers maximise the concave dual,
//! here by exact coordinate ascent (each `λ_j` set so that its constraint holds with equality, or
//! 0 where it is slack; Bertsekas, *Nonlinear Programming*, §6.3).
//!
//! **The verification**: the allocated tolerances are a new tolerance case whose yield (every
//! requirement, including those without a first-order margin) is computed by the quadrature
//! through the whole nonlinear pipeline, with its error estimate. The first-order `β` is only a
//! start: the nonlinear yield of its design falls short of the target or exceeds it. So `β` is
//! searched for (`BetaSearch`) as the root of the verified yield (less its error) at the
//! target, until the design meeting it costs at most [`COST_GAP`] more than one falling short
//! (at most [`MAX_ROUNDS`] rounds), and the result says how close it came
//! ([`Allocation::cost_gap`]). The result states the verified yield, never only the model's
//! prediction.

mod problem;
mod search;

pub use search::COST_GAP;

use problem::Problem;
use search::BetaSearch;

use crate::analyze::{AnalyzeOptions, analyze};
use crate::cancel::Cancel;
use crate::compiled::Compiled;
use crate::margins::covers;
use crate::model::{Case, Cost, Distribution, Tolerance};
use crate::propagate::Study;
use crate::quadrature::QuadOptions;
use crate::table::Method;
use crate::taylor::yields::linear_margin;
use statrs::distribution::{ContinuousCDF, Normal};

/// Rounds of search and verification at most.
pub const MAX_ROUNDS: usize = 12;

/// The default largest tolerance, as a multiple of the case's.
pub const DEFAULT_MAX_FACTOR: f64 = 10.0;

/// One linear constraint of the search: `Σ_k A_k u_k ≤ c` (margin `j` at one speed).
#[derive(Debug, Clone)]
pub struct Constraint {
    pub requirement: usize,
    pub speed: f64,
    /// The nominal margin and its gradient over the case's variables.
    pub margin: f64,
    pub gradient: Vec<f64>,
}

/// One variable's allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct Allocated {
    /// Parameter index.
    pub parameter: usize,
    /// The case's tolerance and the allocated one (absolute, parameter's unit).
    pub before: f64,
    pub after: f64,
    /// The largest tolerance allowed, and whether the allocation sits there (no requirement
    /// limits the variable further).
    pub max: f64,
    pub at_bound: bool,
    pub cost: Cost,
}

/// One round: the reliability index searched with, and the verified yield.
#[derive(Debug, Clone, PartialEq)]
pub struct Round {
    pub beta: f64,
    /// The first-order prediction of the worst constraint's probability.
    pub predicted: f64,
    /// The quadrature's yield of every requirement, and its error estimate.
    pub verified: (f64, f64),
    pub nodes: usize,
}

/// The result of [`allocate`].
#[derive(Debug, Clone)]
pub struct Allocation {
    pub target: f64,
    pub variables: Vec<Allocated>,
    /// Total cost of the case's tolerances and of the allocated ones.
    pub cost_before: f64,
    pub cost_after: f64,
    pub rounds: Vec<Round>,
    /// The round whose design is the result: the cheapest verified to meet the target, else
    /// the last.
    pub chosen: usize,
    /// The verified yield meets the target (within its error estimate: `verified − error ≥
    /// target`)?
    pub met: bool,
    /// How close the cost is to the optimum of the search's family: the relative cost above
    /// the cheapest design found short of the target (`None` where the search found none short
    /// of it, or none meeting it).
    pub cost_gap: Option<f64>,
    /// The constraints of the search (per requirement and speed).
    pub constraints: usize,
    /// The allocated tolerances as a case named `allocated`.
    pub case: Case,
}

/// Why an allocation cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AllocateError {
    #[error("the case has no toleranced variable to allocate")]
    NoVariables,
    #[error("the model has no [[requirements]] to allocate for")]
    NoRequirements,
    #[error(
        "no requirement has a first-order margin to search with (stability and the branch are only verified)"
    )]
    NoMargins,
    #[error(
        "the nominal design does not meet requirement '{requirement}' at {speed} rad/s (margin {margin}): no tolerance can"
    )]
    NominalFails {
        requirement: String,
        speed: f64,
        margin: f64,
    },
    #[error("correlated variables are not allocated (the case gives a correlation matrix)")]
    Correlated,
    #[error("the nominal sweep failed at every speed: {0}")]
    NoSweep(String),
    #[error(
        "a cost is given for '{0}', which the case does not tolerance: it has nothing to allocate"
    )]
    CostWithoutTolerance(String),
    #[error(
        "the cost of '{parameter}' overflows at tolerance {tolerance} (b/T^k beyond floating \
         point): costs are relative, give smaller b or k"
    )]
    CostOverflow { parameter: String, tolerance: f64 },
}

/// σ per unit tolerance: a normal tolerance is ±3σ, a uniform one ±√3σ.
fn sigma_per_tolerance(d: Distribution) -> f64 {
    match d {
        Distribution::Normal => 1.0 / 3.0,
        Distribution::Uniform => 1.0 / 3f64.sqrt(),
    }
}

/// Minimises `Σ b_k u_k^{−e_k/2}` subject to `Σ_k a[j][k] u_k ≤ c[j]` and `u_k ≤ umax_k`: the
/// KKT point by exact coordinate ascent on the dual (see the module documentation).
pub fn solve(b: &[f64], e: &[f64], umax: &[f64], a: &[Vec<f64>], c: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut lambda = vec![0.0; a.len()];
    let primal = |lambda: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|k| {
                let w: f64 = a.iter().zip(lambda).map(|(row, l)| l * row[k]).sum();
                if w > 0.0 {
                    (e[k] * b[k] / (2.0 * w))
                        .powf(2.0 / (e[k] + 2.0))
                        .min(umax[k])
                } else {
                    umax[k]
                }
            })
            .collect()
    };
    let load = |j: usize, u: &[f64]| -> f64 { a[j].iter().zip(u).map(|(x, y)| x * y).sum() };
    for _sweep in 0..10_000 {
        let mut change = 0.0f64;
        for j in 0..a.len() {
            let old = lambda[j];
            lambda[j] = 0.0;
            if load(j, &primal(&lambda)) > c[j] {
                // The load falls as λ_j grows: bracket, then bisect in log λ_j.
                let (mut lo, mut hi) = (1e-300f64, 1.0f64);
                lambda[j] = hi;
                while load(j, &primal(&lambda)) > c[j] && hi < 1e300 {
                    lo = hi;
                    hi *= 16.0;
                    lambda[j] = hi;
                }
                for _ in 0..200 {
                    let mid = (lo * hi).sqrt();
                    lambda[j] = mid;
                    if load(j, &primal(&lambda)) > c[j] {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                    if hi / lo < 1.0 + 1e-15 {
                        break;
                    }
                }
                lambda[j] = hi;
            }
            let scale = old.abs().max(lambda[j].abs());
            if scale > 0.0 {
                change = change.max((lambda[j] - old).abs() / scale);
            }
        }
        if change < 1e-13 {
            break;
        }
    }
    primal(&lambda)
}

/// Settings of [`allocate`].
#[derive(Debug, Clone)]
pub struct AllocateOptions {
    pub speeds: Vec<f64>,
    /// The case whose variables are allocated, and its tolerances to start from.
    pub case: Case,
    pub target: f64,
    /// Cost models replacing the model's `[allocation]` ones (parameter index, cost).
    pub costs: Vec<(usize, Cost)>,
    /// Requested accuracy of the verifying quadrature.
    pub quadrature: QuadOptions,
    pub threads: Option<usize>,
    pub cancel: Cancel,
}

/// The first-order margins of every requirement at every speed of its range, over `vars`.
pub fn constraints(study: &Study) -> Vec<Constraint> {
    let reqs = &study.model.model().requirements;
    let mut out = Vec::new();
    for (r, req) in reqs.iter().enumerate() {
        for (i, &w) in study.speeds.iter().enumerate() {
            if !covers(req, w) {
                continue;
            }
            if let Some((margin, gradient)) = linear_margin(study, req, i) {
                out.push(Constraint {
                    requirement: r,
                    speed: w,
                    margin,
                    gradient,
                });
            }
        }
    }
    out
}

/// Allocates the tolerances of `opt.case`'s variables (see the module documentation);
/// `progress` hears of each round.
pub fn allocate(
    model: &Compiled,
    opt: &AllocateOptions,
    progress: &dyn Fn(&Round),
) -> Result<Allocation, AllocateError> {
    let m = model.model();
    let problem = Problem::new(model, opt)?;
    let Problem {
        vars,
        cons,
        costs,
        before,
        max,
        ..
    } = &problem;
    let mut search = BetaSearch::new(Normal::standard().inverse_cdf(opt.target));
    let mut rounds = Vec::new();
    let mut result = None;
    while let Some(beta) = search.next() {
        let u = problem.allocated(beta);
        let t: Vec<f64> = u.iter().map(|u| u.sqrt()).collect();
        let case = Case {
            name: "allocated".into(),
            tolerances: vars
                .iter()
                .zip(&t)
                .map(|(&v, &t)| (v, Tolerance::Absolute(t)))
                .collect(),
            correlation: None,
        };
        let verified = verify(model, opt, &case);
        let round = Round {
            beta,
            predicted: problem.predicted(&u),
            verified: (verified.0, verified.1),
            nodes: verified.2,
        };
        progress(&round);
        rounds.push(round);
        let met = verified.0 - verified.1 >= opt.target;
        let total: f64 = costs.iter().zip(&t).map(|(c, &t)| c.of(t)).sum();
        search.take(beta, verified.0 - verified.1, opt.target, total);
        // The cheapest design verified to meet the target, else the last.
        let better = match &result {
            None => true,
            Some((_, _, was_met, was, _)) => {
                (met && (!was_met || total < *was)) || !(met || *was_met)
            }
        };
        if better {
            result = Some((t, case, met, total, rounds.len() - 1));
        }
        if opt.cancel.is_cancelled() {
            break;
        }
    }
    let (t, case, met, _, chosen) = result.expect("one round at least");
    if let Some(e) = problem.overflow(m, &t) {
        return Err(e);
    }
    let variables: Vec<Allocated> = vars
        .iter()
        .enumerate()
        .map(|(k, &v)| Allocated {
            parameter: v,
            before: before[k],
            after: t[k],
            max: max[k],
            at_bound: t[k] >= max[k] * (1.0 - 1e-12),
            cost: costs[k],
        })
        .collect();
    Ok(Allocation {
        target: opt.target,
        cost_before: variables.iter().map(|v| v.cost.of(v.before)).sum(),
        cost_after: variables.iter().map(|v| v.cost.of(v.after)).sum(),
        cost_gap: search.cost_gap(),
        variables,
        rounds,
        chosen,
        met,
        constraints: cons.len(),
        case,
    })
}

/// The quadrature's yield of every requirement under `case`: probability, error, nodes.
fn verify(model: &Compiled, opt: &AllocateOptions, case: &Case) -> (f64, f64, usize) {
    let a = analyze(
        model,
        &AnalyzeOptions {
            speeds: opt.speeds.clone(),
            cases: vec![case.clone()],
            quadrature: Some(opt.quadrature),
            monte_carlo: None,
            threads: opt.threads,
            cancel: opt.cancel.clone(),
            ..Default::default()
        },
        &|_, _, _| {},
    );
    a.yields
        .iter()
        .find(|y| y.method == Method::Quadrature && y.requirement.is_none())
        .map_or((f64::NAN, f64::NAN, 0), |y| {
            (y.probability, 0.5 * (y.ci.1 - y.ci.0), y.evaluations)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_constraint_gives_the_lagrange_closed_form() {
        // min Σ b_k/T_k^e_k s.t. Σ S_k² T_k² = C: T_k ∝ (e_k b_k / S_k²)^{1/(e_k+2)} when the
        // exponents are equal.
        let (b, e) = (vec![1.0, 4.0, 0.5], vec![2.0; 3]);
        let s2 = [2.0, 0.3, 5.0];
        let c = 0.7;
        let u = solve(&b, &e, &[1e9; 3], &[s2.to_vec()], &[c]);
        let shape: Vec<f64> = (0..3)
            .map(|k| (e[k] * b[k] / s2[k]).powf(1.0 / (e[k] + 2.0)))
            .collect();
        let scale = (c / (0..3).map(|k| s2[k] * shape[k].powi(2)).sum::<f64>()).sqrt();
        for k in 0..3 {
            let t = u[k].sqrt();
            assert!((t / (scale * shape[k]) - 1.0).abs() < 1e-10, "{t}");
        }
    }

    #[test]
    fn slack_constraints_and_bounds_are_respected() {
        // Two constraints, the second slack; one variable bounded.
        let a = vec![vec![1.0, 1.0], vec![0.1, 0.0]];
        let u = solve(&[1.0, 1.0], &[1.0, 1.0], &[0.2, 10.0], &a, &[1.0, 5.0]);
        assert!((u[0] - 0.2).abs() < 1e-12);
        assert!((u[0] + u[1] - 1.0).abs() < 1e-9);
        // KKT: the cost's slope equals the multiplier's for the free variable only.
        assert!(u.iter().all(|x| *x > 0.0));
    }
}
