//! The yield by the quadrature: the probability that a design meets every requirement at every
//! speed of its range, each requirement's own, the per-speed probabilities and the worst
//! margins' moments, integrated along the lines of the case's rule.
//!
//! Every node is a whole sweep, so a requirement over a speed range is a property of the node
//! and of the points between nodes: at each speed the carriers are interpolated between nodes
//! exactly as for the moments ([`super::line::Context::pieces`]), and each requirement's margin
//! at each speed is a function of `t` along the line. The line is cut at every boundary of a
//! speed's pieces and into sub-intervals no longer than [`STEP`]; where a margin changes sign
//! across a sub-interval its zero is found by bisection; between those zeros which
//! requirements are met is constant, and the normal mass of each piece is exact. The yield is
//! then a line integral of an indicator with located jumps (the preintegration of Griewank,
//! Kuo, Leövey & Sloan 2018), its error estimated as the moments' are: the node grid against
//! every other node, and the transverse rule against its check.
//!
//! The worst margin met at the target yield `Y` is the root `q` of `P(M ≥ q) = Y`: the same
//! integral with every margin moved by `q`, so that its precision is the probability's
//! ([`at_target`]). The root is bracketed and found by regula falsi on `Φ⁻¹(P)` (nearly linear
//! in `q` for a nearly normal margin), with a bisection wherever two steps did not halve the
//! bracket (the safeguard of Brent's and Dekker's methods; Brent, *Algorithms for Minimization
//! without Derivatives*, 1973, ch. 4); the interval is the pair of roots at `Y ± e`, `e` the
//! probability's error estimate there: every `q` whose probability is within the error of `Y`.

mod line;
mod stage;
mod tally;
mod target;

use super::rules::{Rule, Stage};
use super::sums::ErrorParts;
use super::{NodeData, Reference};
use crate::margins::{covers, reaches};
use crate::model::Requirement;
use stage::Source;
use statrs::distribution::{ContinuousCDF, Normal};
use tally::{Layout, Tally};
use target::{Root, find_roots};

/// Longest sub-interval of a line (in standard deviations) across which a margin's sign is
/// taken from its ends: a quarter of the finest node spacing.
const STEP: f64 = 0.1875;

/// The root of `P(M ≥ q) = Y` is taken as found where `P` is this fraction of the request
/// (or of `Y` or `1 − Y`, where smaller) from `Y`, or the bracket is at rounding: well inside
/// the error the answer states.
const ROOT_FRACTION: f64 = 1e-3;

/// The least error claimed for a probability: across the lines the rules' outermost nodes lie
/// 4 to 6 σ out, so the tails beyond (10⁻⁹ of the mass beyond 6 σ) enter through the
/// interpolated carriers only; probabilities within 10⁻¹¹ of 1 were seen 5·10⁻¹² off where the
/// estimate said 10⁻¹³.
const PROBABILITY_FLOOR: f64 = 1e-10;

/// Integrations at most per root of `P(M ≥ q) = Y` (bracketing and refining; the bracket
/// grows by doubling from the margin's σ, so 40 reach 10¹² σ).
const ROOT_ITERATIONS: usize = 60;

/// The yield of one case by the quadrature, with error estimates (absolute).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadYield {
    /// The error requested of every probability (absolute): a row whose error estimate
    /// exceeds it is outside the request.
    pub request: f64,
    /// Every requirement met at every speed of its range.
    pub all: (f64, f64),
    /// Per requirement: probability and error.
    pub each: Vec<(f64, f64)>,
    /// Per requirement: the worst margin over its range, mean and σ with their errors, `None`
    /// for a pass-or-fail requirement or where no design has one.
    pub margins: Vec<Option<MarginStat>>,
    /// `[speed][requirement]`: probability of meeting it at that speed and its error; NaN
    /// outside its range.
    pub curves: Vec<Vec<(f64, f64)>>,
    /// `[speed][requirement]`: probability of meeting it at every speed from its range's
    /// start up to that one (beyond the range's end too: the operating range it holds over),
    /// and its error; NaN below the range.
    pub prefix: Vec<Vec<(f64, f64)>>,
}

/// Mean and σ of a requirement's worst margin over its range, with error estimates, and the
/// margin met at the target yield.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarginStat {
    pub mean: f64,
    pub std: f64,
    pub mean_error: f64,
    pub std_error: f64,
    /// The margin met at the target yield, `None` until the quadrature has sought it (after its
    /// last stage).
    pub at_target: Option<AtTarget>,
}

/// The worst margin met at the target yield `Y`: `q` with `P(M ≥ q) = Y`, and the roots at
/// `Y + e` (`low`) and `Y − e` (`high`), `e` the probability's error estimate. `−∞` where
/// that many designs do not reach a margin (more than `1 − Y` fail without one), `+∞` where
/// `Y − e ≤ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtTarget {
    pub estimate: f64,
    pub low: f64,
    pub high: f64,
    /// The probability's error estimate at the estimate.
    pub probability_error: f64,
}

/// What the yield integration needs besides the nodes: the requirements, their nominal
/// worst margins (the shift of the moments), the offsets their margins are moved by and the
/// target yield.
#[derive(Clone)]
pub(super) struct Requirements<'a> {
    pub list: &'a [Requirement],
    /// The error requested of each probability (absolute).
    pub request: f64,
    pub speeds: &'a [f64],
    pub shift: Vec<f64>,
    /// Each requirement is met where its margin is at least this (0 but while the margin met
    /// at the target is sought).
    pub offset: Vec<f64>,
    pub target: f64,
    /// Are the worst margins' moments integrated (5-point Gauss–Legendre on every piece)? Not
    /// while the margin met at the target is sought: its probabilities alone are read.
    pub moments: bool,
}

/// The yield at `stage` with its error estimates' parts (the margins met at the target are
/// left to [`final_yield`]).
pub(super) fn evaluate_yield(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    reqs: &Requirements,
) -> (QuadYield, ErrorParts) {
    yield_on(&Source::new(store, rule, stage), nominal, reqs)
}

/// The yield at `stage` (the last) with every margin's [`AtTarget`].
pub(super) fn final_yield(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    reqs: &Requirements,
) -> QuadYield {
    let source = Source::new(store, rule, stage);
    let (mut y, _) = yield_on(&source, nominal, reqs);
    at_target(&source, nominal, reqs, &mut y);
    y
}

/// The yield integrated on `source`, with its error estimates' parts.
fn yield_on(source: &Source, nominal: &Reference, reqs: &Requirements) -> (QuadYield, ErrorParts) {
    let l = Layout {
        reqs: reqs.list.len(),
        speeds: source.speeds(),
    };
    let tallies = source.tallies(nominal, reqs, l);
    let mut parts = ErrorParts::default();
    let mut prob = |k: usize| -> (f64, f64) {
        let (p, e) = tallies.probability(l, k);
        parts.along = parts.along.max(e.along);
        parts.across = parts.across.max(e.across);
        p
    };
    let all = prob(l.all());
    let each: Vec<(f64, f64)> = (0..l.reqs).map(|r| prob(l.each(r))).collect();
    let mut per_speed = |within: fn(&Requirement, f64) -> bool,
                         at: fn(&Layout, usize, usize) -> usize|
     -> Vec<Vec<(f64, f64)>> {
        (0..l.speeds)
            .map(|i| {
                (0..l.reqs)
                    .map(|r| {
                        if within(&reqs.list[r], reqs.speeds[i]) {
                            prob(at(&l, i, r))
                        } else {
                            (f64::NAN, f64::NAN)
                        }
                    })
                    .collect()
            })
            .collect()
    };
    let curves = per_speed(covers, Layout::curve);
    let prefix = per_speed(reaches, Layout::prefix);
    let (fine, rough) = (&tallies.fine, &tallies.rough);
    let margins = (0..l.reqs)
        .map(|r| {
            let shift = reqs.shift[r];
            let (mean, std) = fine.moments(l, r, shift)?;
            let (rm, rs) = rough.moments(l, r, shift).unwrap_or((f64::NAN, f64::NAN));
            let cm = tallies
                .across
                .error(&|t: &Tally| t.moments(l, r, shift).map(|m| m.0));
            let cs = tallies
                .across
                .error(&|t: &Tally| t.moments(l, r, shift).map(|m| m.1));
            let finite = |e: f64| if e.is_finite() { e } else { f64::INFINITY };
            Some(MarginStat {
                mean,
                std,
                mean_error: finite(2.0 * (mean - rm).abs() + cm),
                std_error: finite(2.0 * (std - rs).abs() + cs),
                at_target: None,
            })
        })
        .collect();
    (
        QuadYield {
            request: reqs.request,
            all,
            each,
            margins,
            curves,
            prefix,
        },
        parts,
    )
}

/// Fills every margin's [`AtTarget`] from the lines of `source`: the roots of
/// `P(M_r ≥ q) = Y`, then of `Y ± e` with `e` the probability's error estimate at the first
/// root.
fn at_target(source: &Source, nominal: &Reference, reqs: &Requirements, y: &mut QuadYield) {
    let n = reqs.list.len();
    let with_margin: Vec<usize> = (0..n).filter(|&r| y.margins[r].is_some()).collect();
    if with_margin.is_empty() {
        return;
    }
    let target = reqs.target;
    let seek = Seeker::new(source, nominal, reqs);
    // From the normal quantile of the margin's moments, on the scale of its σ.
    let z = Normal::standard().inverse_cdf((1.0 - target).clamp(1e-300, 1.0 - 1e-16));
    let first: Vec<(usize, f64, f64, f64)> = with_margin
        .iter()
        .map(|&r| {
            let m = y.margins[r].expect("a margin");
            (r, target, m.mean + m.std * z, m.std)
        })
        .collect();
    let roots = seek.solve(&first);
    let estimates: Vec<f64> = roots.iter().map(|r| r.found.expect("found")).collect();
    let errors = seek.errors(&with_margin, &estimates);
    // The ends start where the slope of P at the estimate puts them, `∓ e / |P'|`.
    let ends: Vec<(usize, f64, f64, f64)> = with_margin
        .iter()
        .zip(&errors)
        .zip(&roots)
        .flat_map(|((&r, &e), root)| {
            let q = root.found.filter(|q| q.is_finite()).unwrap_or(0.0);
            let std = y.margins[r].map_or(0.0, |m| m.std);
            let step = root.slope().map_or(std, |s| e / s).max(1e-12 * std);
            [
                (r, target + e, q - step, step),
                (r, target - e, q + step, step),
            ]
        })
        .collect();
    let ends = seek.solve(&ends);
    for (k, &r) in with_margin.iter().enumerate() {
        let m = y.margins[r].as_mut().expect("a margin");
        // The ends hold the estimate (at an atom of the margin, the three roots meet to
        // rounding: ω_d = 0 for every overdamped design).
        let q = estimates[k];
        m.at_target = Some(AtTarget {
            estimate: q,
            low: ends[2 * k].found.expect("found").min(q),
            high: ends[2 * k + 1].found.expect("found").max(q),
            probability_error: errors[k],
        });
    }
}

/// What the roots of the margins' probabilities at given levels are sought on: the lines of
/// `source` (their tallies without the margins' moments) and each requirement's probability of
/// having a margin at all (`P(M ≥ q)` for `q → −∞`).
struct Seeker<'a> {
    source: &'a Source<'a>,
    nominal: &'a Reference<'a>,
    reqs: Requirements<'a>,
    reached: Tally,
    l: Layout,
}

impl<'a> Seeker<'a> {
    fn new(source: &'a Source, nominal: &'a Reference, reqs: &Requirements<'a>) -> Self {
        let n = reqs.list.len();
        let l = Layout {
            reqs: n,
            speeds: source.speeds(),
        };
        let reqs = Requirements {
            moments: false,
            ..reqs.clone()
        };
        let reached = source.fine(
            nominal,
            &Requirements {
                offset: vec![f64::NEG_INFINITY; n],
                ..reqs.clone()
            },
            l,
        );
        Seeker {
            source,
            nominal,
            reqs,
            reached,
            l,
        }
    }

    /// Each sought root as (requirement, target probability, start, scale); several at once
    /// share an integration: the requirements are repeated, each copy with its own offset.
    fn solve(&self, goals: &[(usize, f64, f64, f64)]) -> Vec<Root> {
        let (reqs, l) = (&self.reqs, self.l);
        let list: Vec<Requirement> = goals.iter().map(|g| reqs.list[g.0].clone()).collect();
        let lg = Layout {
            reqs: goals.len(),
            speeds: l.speeds,
        };
        let moved = |offset: &[f64]| Requirements {
            list: &list,
            offset: offset.to_vec(),
            shift: goals.iter().map(|g| reqs.shift[g.0]).collect(),
            ..reqs.clone()
        };
        let roots = goals
            .iter()
            .map(|&(r, p, start, scale)| {
                let reached = self.reached.ratio(l, l.each(r));
                Root::new(p, reached, start, scale, reqs.request)
            })
            .collect::<Vec<_>>();
        find_roots(roots, |q| {
            let t = self.source.fine(self.nominal, &moved(q), lg);
            (0..goals.len()).map(|k| t.ratio(lg, lg.each(k))).collect()
        })
    }

    /// The probability's error estimate at each requirement's `estimates` (of those
    /// `with_margin`; 0 where the estimate is not finite).
    fn errors(&self, with_margin: &[usize], estimates: &[f64]) -> Vec<f64> {
        let (reqs, l) = (&self.reqs, self.l);
        let mut offset = vec![0.0; reqs.list.len()];
        for (&r, &q) in with_margin.iter().zip(estimates) {
            offset[r] = if q.is_finite() { q } else { 0.0 };
        }
        let tallies = self.source.tallies(
            self.nominal,
            &Requirements {
                offset,
                ..reqs.clone()
            },
            l,
        );
        with_margin
            .iter()
            .zip(estimates)
            .map(|(&r, q)| {
                if q.is_finite() {
                    tallies.probability(l, l.each(r)).0.1
                } else {
                    0.0
                }
            })
            .collect()
    }
}
