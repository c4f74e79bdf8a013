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

use super::line::{Context, GL_W, GL_X, Stencil, density, normal_mass};
use super::rules::{Rule, Stage, TENSOR_ORDERS, Transverse};
use super::sums::{ErrorParts, across};
use super::surrogate::{VirtualRule, interpolate};
use super::{NodeData, Reference};
use crate::margins::{State, covers, has_margin, margin, reaches};
use crate::model::Requirement;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

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

/// The additive sums of one line (or a rule): the mass, the mass meeting everything, per
/// requirement the mass meeting it and the worst margin's defined mass and first two moments
/// about `shift`, per speed and requirement the mass meeting it there and from its range's
/// start up to there.
#[derive(Debug, Clone)]
struct Tally {
    v: Vec<f64>,
}

/// Where each part of a [`Tally`] sits.
#[derive(Clone, Copy)]
struct Layout {
    reqs: usize,
    speeds: usize,
}

impl Layout {
    fn len(&self) -> usize {
        2 + 4 * self.reqs + 2 * self.speeds * self.reqs
    }
    fn mass(&self) -> usize {
        0
    }
    fn all(&self) -> usize {
        1
    }
    fn each(&self, r: usize) -> usize {
        2 + r
    }
    /// Defined mass, first and second moment of requirement `r`'s worst margin.
    fn margin(&self, r: usize, k: usize) -> usize {
        2 + self.reqs + 3 * r + k
    }
    fn curve(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + i * self.reqs + r
    }
    fn prefix(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + (self.speeds + i) * self.reqs + r
    }
}

impl Tally {
    fn new(l: Layout) -> Tally {
        Tally {
            v: vec![0.0; l.len()],
        }
    }
    fn add_scaled(&mut self, b: &Tally, w: f64) {
        for (x, y) in self.v.iter_mut().zip(&b.v) {
            *x += w * y;
        }
    }
    fn ratio(&self, l: Layout, k: usize) -> f64 {
        self.v[k] / self.v[l.mass()]
    }
    fn moments(&self, l: Layout, r: usize, shift: f64) -> Option<(f64, f64)> {
        let w = self.v[l.margin(r, 0)];
        (w > 0.0).then(|| {
            let m1 = self.v[l.margin(r, 1)] / w;
            let var = self.v[l.margin(r, 2)] / w - m1 * m1;
            (m1 + shift, var.max(0.0).sqrt())
        })
    }
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

/// The tallies of one stage: on the node grid in use (`fine`) and on every other node of it
/// (`rough`, the along-line error), and what gives the transverse error.
struct Tallies {
    fine: Tally,
    rough: Tally,
    across: Across,
}

/// What the transverse error of a statistic comes from.
enum Across {
    /// One line: none.
    None,
    /// Pairs of estimates whose distances add up (the tensor rule's surrogate against the one
    /// of the order below; the virtual lines' rule against its half).
    Pairs(Vec<(Tally, Tally)>),
    /// Independent replicates of the estimator (the scrambled rule): their Student-t 95 %
    /// half-width.
    Replicates(Vec<Tally>),
}

impl Across {
    /// The transverse error of the statistic `f` (∞ where a part has none).
    fn error(&self, f: &dyn Fn(&Tally) -> Option<f64>) -> f64 {
        let e = match self {
            Across::None => 0.0,
            Across::Pairs(pairs) => pairs
                .iter()
                .map(|(a, b)| match (f(a), f(b)) {
                    (Some(x), Some(y)) => (x - y).abs(),
                    _ => f64::NAN,
                })
                .sum(),
            // The tensor pair is not read for the scrambled rule.
            Across::Replicates(reps) => across(
                Transverse::Scrambled {
                    replicates: reps.len(),
                },
                (&reps[0], &reps[0]),
                reps,
                f,
            ),
        };
        if e.is_nan() { f64::INFINITY } else { e }
    }
}

impl Tallies {
    /// The probability at `k` with its error estimate (the grid's and the transverse rule's),
    /// the error 1 where it has none.
    fn probability(&self, l: Layout, k: usize) -> ((f64, f64), ErrorParts) {
        let p = self.fine.ratio(l, k);
        let along = 2.0 * (p - self.rough.ratio(l, k)).abs();
        let cross = self.across.error(&|t: &Tally| Some(t.ratio(l, k)));
        let err = along + cross;
        (
            (
                p,
                if err.is_finite() {
                    err.max(PROBABILITY_FLOOR)
                } else {
                    1.0
                },
            ),
            ErrorParts {
                along,
                across: cross,
            },
        )
    }
}

/// The per-speed contexts of `store`'s lines.
fn contexts<'a>(store: &'a NodeData, nominal: &'a Reference) -> Vec<Context<'a>> {
    (0..store.speeds)
        .map(|i| Context {
            store,
            speed: i,
            outs: nominal.outs,
            modes: nominal.modes,
            shift: &[],
            branch: nominal.branches[i] as u32,
        })
        .collect()
}

/// `Σ w · tally` over `lines` (line index and weight) of `store` with the nodes at `stride`,
/// the lines in parallel.
fn weighted(
    store: &NodeData,
    nominal: &Reference,
    lines: &[(usize, f64)],
    stride: usize,
    reqs: &Requirements,
    l: Layout,
) -> Tally {
    let contexts = contexts(store, nominal);
    let parts: Vec<(f64, Tally)> = lines
        .par_iter()
        .map(|&(li, w)| (w, line_tally(&contexts, li, stride, reqs, l)))
        .collect();
    let mut sum = Tally::new(l);
    for (w, t) in &parts {
        sum.add_scaled(t, *w);
    }
    sum
}

/// The lines a stage's tallies are integrated on, prepared once for every integration of
/// the stage (the margin at the target integrates many times).
enum Source<'a> {
    /// The tensor rule's surrogate ([`super::surrogate`]): virtual lines interpolated across
    /// the lines in use (`main`), across those of the order below (`check`, at the coarsest
    /// grid), and the main surrogate on the virtual rule's half (`half`).
    Tensor {
        main: NodeData,
        check: NodeData,
        half: NodeData,
        fine_lines: Vec<(usize, f64)>,
        half_lines: Vec<(usize, f64)>,
        stride: usize,
        check_stride: usize,
    },
    /// Real lines (one, or the scrambled replicates): index, weight and replicate.
    Lines {
        store: &'a NodeData,
        used: Vec<(usize, f64, usize)>,
        stride: usize,
        replicates: usize,
    },
}

impl<'a> Source<'a> {
    fn new(store: &'a NodeData, rule: &Rule, stage: Stage) -> Source<'a> {
        let stride = 1 << (rule.levels.last - stage.level);
        match rule.transverse {
            Transverse::Tensor => {
                let check_stride = 1 << (rule.levels.last - rule.levels.first);
                let dims = rule.lines.first().map_or(0, |line| line.y.len());
                let (fine_rule, half_rule) = VirtualRule::for_dims(dims);
                let (main, check) = (stage.per, stage.per - 1);
                let order = |rank: usize| TENSOR_ORDERS[rank];
                let lines_of = |r: &VirtualRule| -> Vec<(usize, f64)> {
                    r.points
                        .iter()
                        .enumerate()
                        .map(|(v, (_, w))| (v, *w))
                        .collect()
                };
                Source::Tensor {
                    main: interpolate(store, rule, main, order(main), stride, &fine_rule),
                    check: interpolate(store, rule, check, order(check), check_stride, &fine_rule),
                    half: interpolate(store, rule, main, order(main), stride, &half_rule),
                    fine_lines: lines_of(&fine_rule),
                    half_lines: lines_of(&half_rule),
                    stride,
                    check_stride,
                }
            }
            _ => {
                let replicates = match rule.transverse {
                    Transverse::Scrambled { replicates } => replicates,
                    _ => 1,
                };
                Source::Lines {
                    store,
                    used: (0..rule.lines.len())
                        .filter(|&li| rule.uses(&rule.lines[li], stage))
                        .map(|li| {
                            let line = &rule.lines[li];
                            (li, rule.weight(line, stage), line.replicate)
                        })
                        .collect(),
                    stride,
                    replicates,
                }
            }
        }
    }

    /// The estimate alone.
    fn fine(&self, nominal: &Reference, reqs: &Requirements, l: Layout) -> Tally {
        match self {
            Source::Tensor {
                main,
                fine_lines,
                stride,
                ..
            } => weighted(main, nominal, fine_lines, *stride, reqs, l),
            Source::Lines {
                store,
                used,
                stride,
                ..
            } => {
                let lines: Vec<(usize, f64)> = used.iter().map(|x| (x.0, x.1)).collect();
                weighted(store, nominal, &lines, *stride, reqs, l)
            }
        }
    }

    /// The estimate with what its error estimate needs.
    fn tallies(&self, nominal: &Reference, reqs: &Requirements, l: Layout) -> Tallies {
        match self {
            Source::Tensor {
                main,
                check,
                half,
                fine_lines,
                half_lines,
                stride,
                check_stride,
            } => {
                let w = |store, lines, stride| weighted(store, nominal, lines, stride, reqs, l);
                let fine = w(main, fine_lines, *stride);
                let main_at_check = w(main, fine_lines, *check_stride);
                let checked = w(check, fine_lines, *check_stride);
                let half = w(half, half_lines, *stride);
                Tallies {
                    rough: w(main, fine_lines, *stride << 1),
                    across: Across::Pairs(vec![(main_at_check, checked), (fine.clone(), half)]),
                    fine,
                }
            }
            Source::Lines {
                store,
                used,
                stride,
                replicates,
            } => {
                let contexts = contexts(store, nominal);
                let per_line: Vec<(Tally, Tally)> = used
                    .par_iter()
                    .map(|&(li, _, _)| {
                        (
                            line_tally(&contexts, li, *stride, reqs, l),
                            line_tally(&contexts, li, *stride << 1, reqs, l),
                        )
                    })
                    .collect();
                let mut fine = Tally::new(l);
                let mut rough = Tally::new(l);
                let mut reps = vec![Tally::new(l); *replicates];
                for (&(_, w, rep), (t, r)) in used.iter().zip(&per_line) {
                    fine.add_scaled(t, w);
                    rough.add_scaled(r, w);
                    reps[rep].add_scaled(t, w * *replicates as f64);
                }
                Tallies {
                    fine,
                    rough,
                    across: if *replicates > 1 {
                        Across::Replicates(reps)
                    } else {
                        Across::None
                    },
                }
            }
        }
    }
}

/// The yield at `stage` with its error estimates' parts (the margins met at the target are
/// left to [`at_target`]).
pub(super) fn evaluate_yield(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    reqs: &Requirements,
) -> (QuadYield, ErrorParts) {
    let l = Layout {
        reqs: reqs.list.len(),
        speeds: store.speeds,
    };
    let tallies = Source::new(store, rule, stage).tallies(nominal, reqs, l);
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

/// Fills every margin's [`AtTarget`] at `stage` (the last): the roots of `P(M_r ≥ q) = Y`,
/// then of `Y ± e` with `e` the probability's error estimate at the first root.
pub(super) fn at_target(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    reqs: &Requirements,
    y: &mut QuadYield,
) {
    let n = reqs.list.len();
    let with_margin: Vec<usize> = (0..n).filter(|&r| y.margins[r].is_some()).collect();
    if with_margin.is_empty() {
        return;
    }
    let source = Source::new(store, rule, stage);
    let target = reqs.target;
    let l = Layout {
        reqs: n,
        speeds: store.speeds,
    };
    // P(M ≥ q) for q → −∞: the designs with a margin.
    let reqs = &Requirements {
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
    let reached = |r: usize| reached.ratio(l, l.each(r));
    // Each sought root as (requirement, target probability, start, scale); several at once
    // share an integration: the requirements are repeated, each copy with its own offset.
    let solve = |goals: &[(usize, f64, f64, f64)]| -> Vec<Root> {
        let list: Vec<Requirement> = goals.iter().map(|g| reqs.list[g.0].clone()).collect();
        let lg = Layout {
            reqs: goals.len(),
            speeds: store.speeds,
        };
        let moved = |offset: &[f64]| Requirements {
            list: &list,
            offset: offset.to_vec(),
            shift: goals.iter().map(|g| reqs.shift[g.0]).collect(),
            ..reqs.clone()
        };
        let roots = goals
            .iter()
            .map(|&(r, p, start, scale)| Root::new(p, reached(r), start, scale, reqs.request))
            .collect::<Vec<_>>();
        find_roots(roots, |q| {
            let t = source.fine(nominal, &moved(q), lg);
            (0..goals.len()).map(|k| t.ratio(lg, lg.each(k))).collect()
        })
    };
    // From the normal quantile of the margin's moments, on the scale of its σ.
    let z = Normal::standard().inverse_cdf((1.0 - target).clamp(1e-300, 1.0 - 1e-16));
    let first: Vec<(usize, f64, f64, f64)> = with_margin
        .iter()
        .map(|&r| {
            let m = y.margins[r].expect("a margin");
            (r, target, m.mean + m.std * z, m.std)
        })
        .collect();
    let roots = solve(&first);
    let estimates: Vec<f64> = roots.iter().map(|r| r.found.expect("found")).collect();
    // The probability's error at each estimate.
    let mut offset = vec![0.0; n];
    for (&r, &q) in with_margin.iter().zip(&estimates) {
        offset[r] = if q.is_finite() { q } else { 0.0 };
    }
    let tallies = source.tallies(
        nominal,
        &Requirements {
            offset,
            ..reqs.clone()
        },
        l,
    );
    let errors: Vec<f64> = with_margin
        .iter()
        .zip(&estimates)
        .map(|(&r, q)| {
            if q.is_finite() {
                tallies.probability(l, l.each(r)).0.1
            } else {
                0.0
            }
        })
        .collect();
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
    let ends = solve(&ends);
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

/// One sought root of a decreasing `P(q)` (`P(M ≥ q)`): `P(q) = goal`, with the bracket
/// found so far (`q` where `P ≥ goal`, and where `P < goal`, each with its `P`).
struct Root {
    goal: f64,
    /// Where the search starts and its scale.
    start: f64,
    scale: f64,
    /// `|P − goal|` at which the root is taken as found.
    tolerance: f64,
    above: Option<(f64, f64)>,
    below: Option<(f64, f64)>,
    /// Where the root is (once known), `±∞` where the goal is beyond what `P` reaches.
    found: Option<f64>,
    /// Steps taken, and the bracket's widths after the last two (the bisection safeguard).
    steps: usize,
    widths: [f64; 2],
}

impl Root {
    /// The root of `P(q) = goal` given `P(−∞) = reached`, searched from `start` on `scale`
    /// (a scale of 0: every design with a margin has the same, `start`).
    fn new(goal: f64, reached: f64, start: f64, scale: f64, request: f64) -> Root {
        let found = if goal <= 0.0 {
            Some(f64::INFINITY)
        } else if goal >= reached || goal >= 1.0 {
            // More than 1 − goal of the designs fail without a margin.
            Some(f64::NEG_INFINITY)
        } else if scale.is_nan() || scale <= 0.0 {
            // The step from `reached` to 0 is there.
            Some(start)
        } else {
            None
        };
        Root {
            goal,
            start,
            scale,
            // Relative to the goal near 0 or 1, where the request is coarser than the goal.
            tolerance: ROOT_FRACTION * request.min(goal).min(1.0 - goal),
            above: None,
            below: None,
            found,
            steps: 0,
            widths: [f64::INFINITY; 2],
        }
    }

    /// `−dP/dq` across the last bracket, where there is one.
    fn slope(&self) -> Option<f64> {
        let (a, b) = (self.above?, self.below?);
        let s = (a.1 - b.1) / (b.0 - a.0);
        (s.is_finite() && s > 0.0).then_some(s)
    }

    /// The next `q` to integrate at, `None` once found.
    fn next(&mut self) -> Option<f64> {
        if self.found.is_some() {
            return None;
        }
        let grow = self.scale * 2f64.powi(self.steps as i32);
        Some(match (self.above, self.below) {
            (None, None) => self.start,
            (Some(a), None) => a.0 + grow,
            (None, Some(b)) => b.0 - grow,
            (Some(a), Some(b)) => {
                let w = b.0 - a.0;
                // Regula falsi on Φ⁻¹(P) − Φ⁻¹(goal), nearly linear in q for a nearly
                // normal margin; bisection where it does not shrink the bracket fast enough.
                let nd = Normal::standard();
                let g = |p: f64| nd.inverse_cdf(p.clamp(1e-300, 1.0 - 1e-16));
                let (ga, gb) = (g(a.1) - g(self.goal), g(b.1) - g(self.goal));
                let falsi = a.0 + w * ga / (ga - gb);
                let slow = w > 0.5 * self.widths[0];
                if slow || !(falsi > a.0 + 1e-3 * w && falsi < b.0 - 1e-3 * w) {
                    0.5 * (a.0 + b.0)
                } else {
                    falsi
                }
            }
        })
    }

    /// Takes `p = P(q)`.
    fn take(&mut self, q: f64, p: f64) {
        self.steps += 1;
        if (p - self.goal).abs() <= self.tolerance {
            self.found = Some(q);
            return;
        }
        if p >= self.goal {
            self.above = Some((q, p));
        } else {
            self.below = Some((q, p));
        }
        if let (Some(a), Some(b)) = (self.above, self.below) {
            let w = b.0 - a.0;
            self.widths = [self.widths[1], w];
            if w <= 4.0 * f64::EPSILON * (a.0.abs() + b.0.abs() + self.scale) {
                // The bracket is at rounding: a step of P there (an atom of the margin).
                self.found = Some(if (a.1 - self.goal) < (self.goal - b.1) {
                    a.0
                } else {
                    b.0
                });
            }
        }
        if self.steps >= ROOT_ITERATIONS && self.found.is_none() {
            self.found = Some(match (self.above, self.below) {
                (Some(a), Some(b)) => 0.5 * (a.0 + b.0),
                (Some(_), None) => f64::INFINITY,
                _ => f64::NEG_INFINITY,
            });
        }
    }
}

/// Every root of `roots`, each integration `eval(q)` giving `P` at every root's `q` (roots
/// already found keep theirs).
fn find_roots(mut roots: Vec<Root>, eval: impl Fn(&[f64]) -> Vec<f64>) -> Vec<Root> {
    loop {
        let qs: Vec<Option<f64>> = roots.iter_mut().map(Root::next).collect();
        if qs.iter().all(Option::is_none) {
            break;
        }
        let at: Vec<f64> = roots
            .iter()
            .zip(&qs)
            .map(|(r, q)| q.unwrap_or_else(|| r.found.filter(|f| f.is_finite()).unwrap_or(0.0)))
            .collect();
        let p = eval(&at);
        for ((root, q), p) in roots.iter_mut().zip(&qs).zip(p) {
            if let Some(q) = q {
                root.take(*q, p);
            }
        }
    }
    roots
}

/// The pieces of one line at every speed, and the requirements' margins at a point of it.
struct LineView<'a> {
    pieces: Vec<Vec<(f64, f64, Option<Stencil<'a>>)>>,
    contexts: &'a [Context<'a>],
    reqs: &'a Requirements<'a>,
    /// Per speed: the requirements it is at or above the range's start of ([`reaches`]).
    active: Vec<Vec<usize>>,
    /// `[speed · requirements + requirement]`: is the speed in the requirement's range?
    covered: Vec<bool>,
}

impl LineView<'_> {
    /// What the requirements read at speed `i` at `t` on piece `at` of that speed (the
    /// carriers interpolated into `c`), `None` where the design has no point there.
    fn state<'c>(&self, t: f64, at: usize, i: usize, c: &'c mut Vec<f64>) -> Option<State<'c>> {
        let ctx = &self.contexts[i];
        let st = self.pieces[i][at].2.as_ref()?;
        c.resize(ctx.store.width, 0.0);
        st.eval(t, c);
        Some(State {
            speed: self.reqs.speeds[i],
            carriers: c,
            modes: ctx.modes,
            same_branch: st.branch == ctx.branch,
        })
    }

    /// Requirement `r`'s margin less its offset (`−∞` stays: no margin at any offset).
    fn moved(&self, r: usize, s: &State) -> f64 {
        let m = margin(&self.reqs.list[r], s);
        if m == f64::NEG_INFINITY {
            m
        } else {
            m - self.reqs.offset[r]
        }
    }

    /// The margin of requirement `r` at speed `i` at `t` on piece `at` of that speed.
    fn margin(&self, t: f64, at: usize, i: usize, r: usize, c: &mut Vec<f64>) -> f64 {
        self.state(t, at, i, c)
            .map_or(f64::NEG_INFINITY, |s| self.moved(r, &s))
    }

    /// The margin of every (speed, requirement) at `t`, `[speed][requirement]` flattened
    /// (+∞ where the speed is below the requirement's range; −∞ where the design has no
    /// point there), the pieces `at[i]` in use at each speed.
    fn margins(&self, t: f64, at: &[usize], out: &mut [f64], c: &mut Vec<f64>) {
        let r = self.reqs.list.len();
        out.iter_mut().for_each(|x| *x = f64::INFINITY);
        for (i, active) in self.active.iter().enumerate() {
            if active.is_empty() {
                continue;
            }
            let state = self.state(t, at[i], i, c);
            for &k in active {
                out[i * r + k] = state
                    .as_ref()
                    .map_or(f64::NEG_INFINITY, |s| self.moved(k, s));
            }
        }
    }
}

/// The tally of line `li` with the nodes at `stride`.
fn line_tally(
    contexts: &[Context],
    li: usize,
    stride: usize,
    reqs: &Requirements,
    l: Layout,
) -> Tally {
    let nr = reqs.list.len();
    let view = LineView {
        pieces: contexts.iter().map(|c| c.pieces(li, stride)).collect(),
        contexts,
        reqs,
        active: (0..l.speeds)
            .map(|i| {
                (0..nr)
                    .filter(|&k| reaches(&reqs.list[k], reqs.speeds[i]))
                    .collect()
            })
            .collect(),
        covered: reqs
            .speeds
            .iter()
            .flat_map(|&w| reqs.list.iter().map(move |r| covers(r, w)))
            .collect(),
    };
    // Every boundary of every speed's pieces, in order.
    let mut cuts: Vec<f64> = view
        .pieces
        .iter()
        .flat_map(|p| p.iter().flat_map(|x| [x.0, x.1]))
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut tally = Tally::new(l);
    let n = l.speeds * nr;
    let (mut m0, mut m1, mut mm) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut c = Vec::new();
    let mut at = vec![0usize; l.speeds];
    for seg in cuts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        if b <= a {
            continue;
        }
        // The piece of each speed holding this segment.
        let mid = 0.5 * (a + b);
        for (i, p) in view.pieces.iter().enumerate() {
            at[i] = p.iter().position(|x| x.0 <= mid && mid <= x.1).unwrap_or(0);
        }
        let subs = ((b - a) / STEP).ceil().max(1.0) as usize;
        let h = (b - a) / subs as f64;
        view.margins(a, &at, &mut m0, &mut c);
        for j in 0..subs {
            let (x0, x1) = (
                a + h * j as f64,
                if j + 1 == subs {
                    b
                } else {
                    a + h * (j + 1) as f64
                },
            );
            view.margins(x1, &at, &mut m1, &mut c);
            // The zeros of the margins that change sign across [x0, x1].
            let mut zeros = vec![x0, x1];
            for k in 0..n {
                if (m0[k] >= 0.0) != (m1[k] >= 0.0) {
                    let (i, r) = (k / nr, k % nr);
                    let met = |t: f64, c: &mut Vec<f64>| view.margin(t, at[i], i, r, c) >= 0.0;
                    zeros.push(boundary(met, x0, x1, m0[k] >= 0.0, &mut c));
                }
            }
            zeros.sort_by(f64::total_cmp);
            for w in zeros.windows(2) {
                let (y0, y1) = (w[0], w[1]);
                if y1 <= y0 {
                    continue;
                }
                add_piece(&view, &at, y0, y1, &mut tally, l, &mut mm, &mut c);
            }
            std::mem::swap(&mut m0, &mut m1);
        }
    }
    tally
}

/// Where `met` changes from `met0` (at `a`) in `[a, b]`, by bisection to rounding.
fn boundary(
    met: impl Fn(f64, &mut Vec<f64>) -> bool,
    mut a: f64,
    mut b: f64,
    met0: bool,
    c: &mut Vec<f64>,
) -> f64 {
    for _ in 0..64 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if met(m, c) == met0 {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// Adds `[y0, y1]` (where which requirements are met does not change) to `tally`: its mass to
/// what is met at its middle, and the worst margins' moments by 5-point Gauss–Legendre.
#[allow(clippy::too_many_arguments)]
fn add_piece(
    view: &LineView,
    at: &[usize],
    y0: f64,
    y1: f64,
    tally: &mut Tally,
    l: Layout,
    mm: &mut [f64],
    c: &mut Vec<f64>,
) {
    let nr = l.reqs;
    let mass = normal_mass(y0, y1);
    view.margins(0.5 * (y0 + y1), at, mm, c);
    tally.v[l.mass()] += mass;
    let mut all = true;
    for r in 0..nr {
        let (mut met, mut holds) = (true, true);
        for i in 0..l.speeds {
            let ok = mm[i * nr + r] >= 0.0;
            holds &= ok;
            if holds {
                tally.v[l.prefix(i, r)] += mass;
            }
            if !view.covered[i * nr + r] {
                continue;
            }
            if ok {
                tally.v[l.curve(i, r)] += mass;
            } else {
                met = false;
            }
        }
        all &= met;
        if met {
            tally.v[l.each(r)] += mass;
        }
    }
    if all {
        tally.v[l.all()] += mass;
    }
    if !view.reqs.moments {
        return;
    }
    // The worst margin over each requirement's range.
    for (&x, &wx) in GL_X.iter().zip(&GL_W) {
        let t = y0 + (y1 - y0) * 0.5 * (1.0 + x);
        let wt = 0.5 * wx * (y1 - y0) * density(t);
        view.margins(t, at, mm, c);
        for r in 0..nr {
            if !has_margin(&view.reqs.list[r]) {
                continue;
            }
            let worst = (0..l.speeds)
                .filter(|&i| view.covered[i * nr + r])
                .map(|i| mm[i * nr + r])
                .fold(f64::INFINITY, f64::min);
            if worst.is_finite() {
                let d = worst - view.reqs.shift[r];
                tally.v[l.margin(r, 0)] += wt;
                tally.v[l.margin(r, 1)] += wt * d;
                tally.v[l.margin(r, 2)] += wt * d * d;
            }
        }
    }
}
