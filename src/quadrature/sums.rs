//! Moments, event masses and quantiles from the line integrals, with the along-line and
//! transverse error estimates: the statistics of one refinement level.

use super::control::Control;
use super::line::{Context, Sums};
use super::rules::{Rule, Stage, Transverse};
use super::{NodeData, Probability, QuadStat, Reference};
use crate::output::Output;
use crate::table::Event;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, StudentsT};

// A floor of the error estimates, times the size of the output.
use crate::output::EVAL_PRECISION;

/// What one refinement stage gives: per speed and output the statistics and their error
/// estimates' two parts (along the lines, across them: [`ErrorParts`]), and per speed the
/// probabilities.
pub(super) struct Evaluation {
    pub stats: Vec<Vec<Option<QuadStat>>>,
    pub parts: Vec<Vec<Option<ErrorParts>>>,
    pub probabilities: Vec<Vec<Probability>>,
    pub probability_parts: Vec<Vec<ErrorParts>>,
}

/// The larger of a statistic's mean and σ error estimates, split into the part along the lines
/// (the grid's) and the part across them (the transverse rule's): which refinement pays.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ErrorParts {
    pub along: f64,
    pub across: f64,
}

/// Statistics at every speed from the nodes of refinement `stage` (the answer) and of the
/// level below (its along-line error estimate), against the `nominal` reference, with the
/// `control` variates where the rule has them.
pub(super) fn evaluate(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    control: Option<&Control>,
) -> Evaluation {
    let per_speed: Vec<_> = (0..store.speeds)
        .into_par_iter()
        .map(|i| {
            let shift: Vec<f64> = nominal.values[i]
                .iter()
                .map(|v| if v.is_finite() { *v } else { 0.0 })
                .collect();
            let ctx = Context {
                store,
                speed: i,
                outs: nominal.outs,
                modes: nominal.modes,
                shift: &shift,
                branch: nominal.branches[i] as u32,
            };
            let mut sums = SpeedSums::new(&ctx, rule, stage, control);
            let (stats, parts) = sums.statistics(&shift, control.is_some());
            let (probabilities, probability_parts) = sums.probabilities(nominal.modes);
            (stats, parts, probabilities, probability_parts)
        })
        .collect();
    let mut out = Evaluation {
        stats: Vec::new(),
        parts: Vec::new(),
        probabilities: Vec::new(),
        probability_parts: Vec::new(),
    };
    for (stats, parts, probabilities, probability_parts) in per_speed {
        out.stats.push(stats);
        out.parts.push(parts);
        out.probabilities.push(probabilities);
        out.probability_parts.push(probability_parts);
    }
    out
}

/// The sums of one speed over the lines a stage uses: on the stage's nodes (`fine`, with the
/// outputs' atoms for the quantiles), on every other one (`rough`), per replicate of a
/// scrambled rule (`reps`), and for the tensor rule's transverse check the lines of the order
/// below (`check`) and the rule in use (`main_at_check`) on the coarsest grid.
struct SpeedSums {
    transverse: Transverse,
    fine: Sums,
    rough: Sums,
    check: Sums,
    main_at_check: Sums,
    reps: Vec<Sums>,
    atoms: Vec<Vec<(f64, f64)>>,
}

impl SpeedSums {
    fn new(ctx: &Context, rule: &Rule, stage: Stage, control: Option<&Control>) -> SpeedSums {
        let (first_level, last_level) = (rule.levels.first, rule.levels.last);
        let stride = 1 << (last_level - stage.level);
        let coarse = stride << 1;
        let check_stride = 1 << (last_level - first_level);
        let (outs, modes) = (ctx.outs.len(), ctx.modes);
        let transverse = rule.transverse;
        let replicates = match transverse {
            Transverse::Scrambled { replicates } => replicates,
            _ => 1,
        };
        let mut sums = SpeedSums {
            transverse,
            fine: Sums::new(outs, modes),
            rough: Sums::new(outs, modes),
            check: Sums::new(outs, modes),
            main_at_check: Sums::new(outs, modes),
            reps: vec![Sums::new(outs, modes); replicates],
            atoms: vec![Vec::new(); outs],
        };
        let none = vec![None; outs];
        for (li, line) in rule.lines.iter().enumerate() {
            if !rule.uses(line, stage) {
                continue;
            }
            let on_line = control.map(|c| c.on_line(ctx.speed, li, outs));
            let cv = on_line.as_deref().unwrap_or(&none);
            let weight = rule.weight(line, stage);
            if rule.checks(line, stage) {
                let s = ctx.line(li, check_stride, cv, None);
                sums.check.add_scaled(&s, weight);
                continue;
            }
            let s = ctx.line(li, stride, cv, Some((&mut sums.atoms, weight)));
            sums.fine.add_scaled(&s, weight);
            sums.reps[line.replicate].add_scaled(&s, weight * replicates as f64);
            sums.rough
                .add_scaled(&ctx.line(li, coarse, cv, None), weight);
            if transverse == Transverse::Tensor {
                let s = ctx.line(li, check_stride, cv, None);
                sums.main_at_check.add_scaled(&s, weight);
            }
        }
        sums
    }

    /// Transverse error of a statistic computed from sums.
    fn transverse_error(&self, f: &dyn Fn(&Sums) -> Option<f64>) -> f64 {
        across(
            self.transverse,
            (&self.main_at_check, &self.check),
            &self.reps,
            f,
        )
    }

    /// Each output's moments and quantiles with their error estimates (`shift` the nominal
    /// values the sums are taken about; the quantiles rescaled to the moments where the sums
    /// are of `controlled` outputs).
    fn statistics(
        &mut self,
        shift: &[f64],
        controlled: bool,
    ) -> (Vec<Option<QuadStat>>, Vec<Option<ErrorParts>>) {
        let finite = |e: f64| if e.is_finite() { e } else { f64::INFINITY };
        (0..shift.len())
            .map(|o| {
                let Some((mean, std)) = self.fine.moments(o, shift[o]) else {
                    return (None, None);
                };
                let (rm, rs) = (self.rough)
                    .moments(o, shift[o])
                    .unwrap_or((f64::NAN, f64::NAN));
                let floor = EVAL_PRECISION * (mean.abs() + std);
                let along = (
                    finite(2.0 * (mean - rm).abs() + floor),
                    finite(2.0 * (std - rs).abs() + floor),
                );
                let across = (
                    finite(self.transverse_error(&|s: &Sums| s.moments(o, shift[o]).map(|m| m.0))),
                    finite(self.transverse_error(&|s: &Sums| s.moments(o, shift[o]).map(|m| m.1))),
                );
                let mut q = quantiles(&mut self.atoms[o]);
                if controlled {
                    q = rescaled(q, &self.atoms[o], mean, std);
                }
                let stat = QuadStat {
                    mean,
                    std,
                    quantiles: q,
                    mean_error: along.0 + across.0,
                    std_error: along.1 + across.1,
                    // Decided once the refinement stops ([`within`]).
                    within_request: false,
                };
                let parts = ErrorParts {
                    along: along.0.max(along.1),
                    across: across.0.max(across.1),
                };
                (Some(stat), Some(parts))
            })
            .unzip()
    }

    /// The probability of each event (each of the `modes` overdamped, unstable, on another
    /// branch) with its error estimate; none where no design has a point here.
    fn probabilities(&self, modes: usize) -> (Vec<Probability>, Vec<ErrorParts>) {
        let has_mass = self.fine.mass > 0.0;
        if !has_mass {
            return (Vec::new(), Vec::new());
        }
        let finite = |e: f64| if e.is_finite() { e } else { f64::INFINITY };
        (0..modes + 2)
            .map(|e| {
                let p = self.fine.probability(e);
                let part = ErrorParts {
                    along: 2.0 * (p - self.rough.probability(e)).abs(),
                    across: self.transverse_error(&|s: &Sums| Some(s.probability(e))),
                };
                let err = part.along + part.across;
                let probability = Probability {
                    event: match e {
                        e if e < modes => Event::Overdamped,
                        e if e == modes => Event::Unstable,
                        _ => Event::OtherBranch,
                    },
                    mode: (e < modes).then_some(e),
                    probability: p,
                    error: if err.is_finite() { err } else { 1.0 },
                };
                let part = ErrorParts {
                    along: finite(part.along),
                    across: finite(part.across),
                };
                (probability, part)
            })
            .unzip()
    }
}

/// The transverse part of the error estimate of a statistic `f` of a rule's sums: none for one
/// line; for the tensor rule, the difference between the rule in use on the check's nodes and
/// the rule of the order below (`tensor`); for the scrambled rule, the Student-t 95 %
/// half-width of the replicates `reps`. NaN where `f` has no value on one of them.
pub(super) fn across<T>(
    transverse: Transverse,
    tensor: (&T, &T),
    reps: &[T],
    f: &dyn Fn(&T) -> Option<f64>,
) -> f64 {
    match transverse {
        Transverse::Single => 0.0,
        Transverse::Tensor => match (f(tensor.0), f(tensor.1)) {
            (Some(a), Some(b)) => (a - b).abs(),
            _ => f64::NAN,
        },
        Transverse::Scrambled { .. } => {
            let t975 = if reps.len() > 1 {
                StudentsT::new(0.0, 1.0, (reps.len() - 1) as f64)
                    .map_or(2.0, |t| t.inverse_cdf(0.975))
            } else {
                0.0
            };
            let v: Option<Vec<f64>> = reps.iter().map(f).collect();
            v.map_or(f64::NAN, |v| {
                let r = v.len() as f64;
                let m = v.iter().sum::<f64>() / r;
                let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (r - 1.0);
                t975 * (var / r).sqrt()
            })
        }
    }
}

/// Quantiles `q` of the weighted `atoms` moved to the control-variate estimator's `mean` and
/// `std`: the atoms' shape, standardised by their own mean and σ. The atoms of few lines place
/// the distribution's location and width with the plain estimator's transverse error; the
/// shape they give is much less sensitive to it.
fn rescaled(q: [f64; 3], atoms: &[(f64, f64)], mean: f64, std: f64) -> [f64; 3] {
    let total: f64 = atoms.iter().map(|a| a.1).sum();
    let m = atoms.iter().map(|a| a.0 * a.1).sum::<f64>() / total;
    let s = (atoms.iter().map(|a| (a.0 - m).powi(2) * a.1).sum::<f64>() / total).sqrt();
    if s.is_nan() || s <= 0.0 || !std.is_finite() {
        return q;
    }
    q.map(|v| mean + (v - m) * std / s)
}

/// The 5, 50 and 95 % quantiles of weighted atoms (value, weight).
pub(super) fn quantiles(atoms: &mut [(f64, f64)]) -> [f64; 3] {
    atoms.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = atoms.iter().map(|a| a.1).sum();
    [0.05, 0.5, 0.95].map(|q| sorted_quantile(atoms, total, q))
}

/// The `q` quantile of weighted atoms sorted by value, of weight `total`: each atom's weight
/// centred on it, linear between neighbouring centres (the lower atom where one of the two is
/// infinite).
pub(super) fn sorted_quantile(atoms: &[(f64, f64)], total: f64, q: f64) -> f64 {
    let target = q * total;
    let mut acc = 0.0;
    for (k, &(v, w)) in atoms.iter().enumerate() {
        let centre = acc + 0.5 * w;
        if centre >= target {
            if k == 0 {
                return v;
            }
            let (pv, pw) = atoms[k - 1];
            let pc = acc - 0.5 * pw;
            let f = ((target - pc) / (centre - pc)).clamp(0.0, 1.0);
            if !(pv.is_finite() && v.is_finite()) {
                return if f >= 1.0 { v } else { pv };
            }
            return pv + f * (v - pv);
        }
        acc += w;
    }
    atoms.last().map_or(f64::NAN, |a| a.0)
}

/// The next stage of the refinement, `None` where every error estimate meets the requested
/// accuracy `tol` (probabilities: `5 tol`) or no refinement can help within the rule's budget.
/// A part of the error (along the lines: the grid; across them: the transverse rule) is
/// refined only where it alone takes more than half the target of a row that misses it; of
/// two such parts, first the one predicted to leave fewer rows missing. The yield's error
/// (`yields`: its parts and its largest error, [`super::yields`]) counts as a row whose target
/// is `tol` (absolute).
pub(super) fn next_stage(
    eval: &Evaluation,
    outs: &[Output],
    yields: Option<(ErrorParts, f64)>,
    rule: &Rule,
    stage: Stage,
    tol: f64,
) -> Option<Stage> {
    let targets = targets(&eval.stats, outs, tol);
    // The worst share of each part, and how many of the rows that miss would still miss
    // after each refinement as predicted: the grid's error falls 16-fold per halving (the
    // cubic interpolants), the transverse rule's √2-fold per doubling (the Monte Carlo rate,
    // the slowest the randomised rule has).
    let (mut along, mut across) = (0.0f64, 0.0f64);
    let (mut after_finer, mut after_wider) = (0usize, 0usize);
    let mut note = |part: &ErrorParts, target: f64| {
        along = along.max(part.along / target);
        across = across.max(part.across / target);
        after_finer += usize::from(part.along / 16.0 + part.across > target);
        after_wider += usize::from(part.along + part.across / 2f64.sqrt() > target);
    };
    for ((stats, parts), targets) in eval.stats.iter().zip(&eval.parts).zip(&targets) {
        for ((stat, part), target) in stats.iter().zip(parts).zip(targets) {
            if let (Some(stat), Some(part), Some(target)) = (stat, part, target)
                && (stat.mean_error > *target || stat.std_error > *target)
            {
                note(part, *target);
            }
        }
    }
    for (probabilities, parts) in eval.probabilities.iter().zip(&eval.probability_parts) {
        for (p, part) in probabilities.iter().zip(parts) {
            if p.error > 5.0 * tol {
                note(part, 5.0 * tol);
            }
        }
    }
    if let Some((part, error)) = yields
        && error > tol
    {
        note(&part, tol);
    }
    let affordable = |next: Stage| rule.nodes(next) <= rule.budget();
    let finer = Some(Stage {
        level: stage.level + 1,
        ..stage
    })
    .filter(|s| along > 0.5 && s.level <= rule.levels.last && affordable(*s));
    // The tensor rule's next order (3, 5, 7 points), the scrambled rule's doubled lines.
    let wider = Some(Stage {
        per: match rule.transverse {
            Transverse::Tensor => stage.per + 1,
            _ => 2 * stage.per,
        },
        ..stage
    })
    .filter(|s| across > 0.5 && s.per <= rule.per.1 && affordable(*s));
    if after_finer <= after_wider {
        finer.or(wider)
    } else {
        wider.or(finer)
    }
}

/// What the evaluation resolves of a row of `output`
/// ([`Quantity::resolution`](crate::output::Quantity::resolution)).
fn resolution(output: &Output, stat: &QuadStat) -> f64 {
    output.quantity.resolution(stat.mean, stat.std)
}

/// Per speed and output (`stats[speed][output]`, the outputs `outs`), the error the request
/// `tol` allows: `tol` times the larger of the row's σ and 2 % of the output's largest σ over
/// the speeds; where that spread is itself below the row's [`resolution`] (an output the
/// variables do not move, as the ζ of an undamped mode, rounding about zero at every node), the
/// resolution, so that such a row is not refined to the budget and flagged for its rounding;
/// `None` where there is no statistic.
fn targets(stats: &[Vec<Option<QuadStat>>], outs: &[Output], tol: f64) -> Vec<Vec<Option<f64>>> {
    let n = stats.first().map_or(0, |r| r.len());
    let largest: Vec<f64> = (0..n)
        .map(|o| {
            stats
                .iter()
                .filter_map(|r| r[o].map(|s| s.std))
                .fold(0.0f64, f64::max)
        })
        .collect();
    stats
        .iter()
        .map(|row| {
            row.iter()
                .zip(&largest)
                .zip(outs)
                .map(|((s, &largest), o)| {
                    s.map(|s| {
                        let (spread, floor) = (s.std.max(0.02 * largest), resolution(o, &s));
                        if spread > floor { tol * spread } else { floor }
                    })
                })
                .collect()
        })
        .collect()
}

/// Per speed and output (`stats[speed][output]`, the outputs `outs`), whether both error
/// estimates meet the requested accuracy `tol` ([`targets`]); `None` where there is no
/// statistic.
pub(super) fn within(
    stats: &[Vec<Option<QuadStat>>],
    outs: &[Output],
    tol: f64,
) -> Vec<Vec<Option<bool>>> {
    stats
        .iter()
        .zip(targets(stats, outs, tol))
        .map(|(row, targets)| {
            row.iter()
                .zip(targets)
                .map(|(s, t)| Some(s.as_ref()?.mean_error <= t? && s.as_ref()?.std_error <= t?))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::line::density;

    #[test]
    fn weighted_quantiles_of_a_fine_normal_grid() {
        // Atoms of N(0,1) on a fine grid: the quantiles are ±1.6449 and 0.
        let mut atoms: Vec<(f64, f64)> = (0..=20000)
            .map(|k| {
                let t = -8.0 + 16.0 * k as f64 / 20000.0;
                (t, density(t) * 16.0 / 20000.0)
            })
            .collect();
        let q = quantiles(&mut atoms);
        assert!((q[0] + 1.644_853_6).abs() < 1e-3, "{q:?}");
        assert!(
            q[1].abs() < 1e-3 && (q[2] - 1.644_853_6).abs() < 1e-3,
            "{q:?}"
        );
    }
}
