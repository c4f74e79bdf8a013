//! The tallies of a stage and the lines it integrates on: the node grid in use and every other
//! node of it, and what gives the transverse error.

use super::line::line_tally;
use super::tally::{Layout, Tally};
use super::{PROBABILITY_FLOOR, Requirements};
use crate::quadrature::line::Context;
use crate::quadrature::rules::{Rule, Stage, Transverse};
use crate::quadrature::sums::{ErrorParts, across};
use crate::quadrature::surrogate::{VirtualRule, interpolate};
use crate::quadrature::{NodeData, Reference};
use rayon::prelude::*;

/// The tallies of one stage: on the node grid in use (`fine`) and on every other node of it
/// (`rough`, the along-line error), and what gives the transverse error.
pub(super) struct Tallies {
    pub(super) fine: Tally,
    pub(super) rough: Tally,
    pub(super) across: Across,
}

/// What the transverse error of a statistic comes from.
pub(super) enum Across {
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
    pub(super) fn error(&self, f: &dyn Fn(&Tally) -> Option<f64>) -> f64 {
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
    pub(super) fn probability(&self, l: Layout, k: usize) -> ((f64, f64), ErrorParts) {
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
pub(super) fn contexts<'a>(store: &'a NodeData, nominal: &'a Reference) -> Vec<Context<'a>> {
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

/// `Σ w · tally` over `lines` (line index and weight) of the store whose per-speed `contexts`
/// these are ([`contexts`]) with the nodes at `stride`, the lines in parallel.
pub(super) fn weighted(
    contexts: &[Context],
    lines: &[(usize, f64)],
    stride: usize,
    reqs: &Requirements,
    l: Layout,
) -> Tally {
    let parts: Vec<(f64, Tally)> = lines
        .par_iter()
        .map(|&(li, w)| (w, line_tally(contexts, li, stride, reqs, l)))
        .collect();
    let mut sum = Tally::new(l);
    for (w, t) in &parts {
        sum.add_scaled(t, *w);
    }
    sum
}

/// The lines a stage's tallies are integrated on, prepared once for every integration of
/// the stage (the margin at the target integrates many times).
pub(super) enum Source<'a> {
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
    pub(super) fn new(store: &'a NodeData, rule: &Rule, stage: Stage) -> Source<'a> {
        let stride = 1 << (rule.levels.last - stage.level);
        match rule.transverse {
            Transverse::Tensor => {
                let check_stride = 1 << (rule.levels.last - rule.levels.first);
                let dims = rule.lines.first().map_or(0, |line| line.y.len());
                let (fine_rule, half_rule) = VirtualRule::for_dims(dims);
                let (main, check) = (stage.per, stage.per - 1);
                let lines_of = |r: &VirtualRule| -> Vec<(usize, f64)> {
                    r.points
                        .iter()
                        .enumerate()
                        .map(|(v, (_, w))| (v, *w))
                        .collect()
                };
                Source::Tensor {
                    main: interpolate(store, rule, main, stride, &fine_rule),
                    check: interpolate(store, rule, check, check_stride, &fine_rule),
                    half: interpolate(store, rule, main, stride, &half_rule),
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

    /// The number of speeds of the lines' nodes.
    pub(super) fn speeds(&self) -> usize {
        match self {
            Source::Tensor { main, .. } => main.speeds,
            Source::Lines { store, .. } => store.speeds,
        }
    }

    /// The estimate alone.
    pub(super) fn fine(&self, nominal: &Reference, reqs: &Requirements, l: Layout) -> Tally {
        match self {
            Source::Tensor {
                main,
                fine_lines,
                stride,
                ..
            } => weighted(&contexts(main, nominal), fine_lines, *stride, reqs, l),
            Source::Lines {
                store,
                used,
                stride,
                ..
            } => {
                let lines: Vec<(usize, f64)> = used.iter().map(|x| (x.0, x.1)).collect();
                weighted(&contexts(store, nominal), &lines, *stride, reqs, l)
            }
        }
    }

    /// The estimate with what its error estimate needs.
    pub(super) fn tallies(&self, nominal: &Reference, reqs: &Requirements, l: Layout) -> Tallies {
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
                let w = |store, lines, stride| {
                    weighted(&contexts(store, nominal), lines, stride, reqs, l)
                };
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
