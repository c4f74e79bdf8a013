//! The main job: how the tolerance cases spread every mode's ω_d and ζ and the transfer
//! magnitude across the speed range, by every analytic method and by Monte Carlo.
//!
//! The [`Study`]: one nominal sweep and, at each speed (in parallel), one [`LocalModel`] for
//! the union of the cases' variables (derivatives do not depend on the tolerances, so cases
//! share them). Then the propagation methods ([`crate::propagate`]) per case: the
//! [`Quadrature`] (the whole pipeline integrated over the distribution, the answer the
//! `analytic` row takes), the [`Taylor`] methods (first order, second order, invariant) and
//! optionally the [`MonteCarlo`]. Wall times of the Taylor methods, the quadrature and the
//! Monte Carlo are measured for the summary.

use crate::cancel::Cancel;
use crate::compiled::Compiled;
use crate::modal::ModeClass;
use crate::model::Case;
use crate::montecarlo::{self, CaseShard, McOptions, McStat, MonteCarlo, TreeFold};
use crate::output::Missing;
use crate::output::{Output, Quantity};
use crate::propagate::{Method, Propagation, Run, Study, Termination};
use crate::quadrature::{Event, QuadOptions, QuadResult, QuadStat, Quadrature};
use crate::sobol::{SobolIndex, SobolOptions, Target, sobol};
use crate::sweep::Point;
use crate::taylor::{Taylor, TaylorStats};
use crate::tolerance::{KINK_SIGMAS, LocalModel, Spread, Stat};
use crate::yields::{self, YieldRow};

use std::time::Instant;

/// One line of the result: a statistic of one output at one speed by one method.
#[derive(Debug, Clone)]
pub struct Row {
    pub speed: f64,
    pub quantity: Quantity,
    /// 0-based mode, `None` for the transfer magnitude.
    pub mode: Option<usize>,
    pub case: usize,
    pub method: Method,
    /// NaN where the method gives no answer (an output not differentiable there).
    pub mean: f64,
    pub std: f64,
    pub mc: Option<McStat>,
    /// First order: each variable's share of the variance.
    pub shares: Option<Vec<f64>>,
    /// For [`Method::Analytic`]: the method its mean and σ come from.
    pub basis: Option<Method>,
    /// The 5, 50 and 95 % quantiles (quadrature, Monte Carlo).
    pub quantiles: Option<[f64; 3]>,
    /// Error estimates of the mean and σ (quadrature).
    pub errors: Option<(f64, f64)>,
    /// Whether those error estimates meet the requested accuracy (quadrature: see
    /// [`QuadStat::within_request`]).
    pub within_request: Option<bool>,
    /// Why the method gives no mean and σ here (`mean`, `std` are then NaN).
    pub missing: Option<Missing>,
}

/// Probability of a change of character at one speed, by one method.
#[derive(Debug, Clone)]
pub struct ProbabilityRow {
    pub speed: f64,
    pub case: usize,
    /// [`Method::Quadrature`] or [`Method::MonteCarlo`].
    pub method: Method,
    pub event: Event,
    /// 0-based mode (overdamped only).
    pub mode: Option<usize>,
    pub probability: f64,
    /// Quadrature: probability ± its error estimate (clamped to [0, 1]); Monte Carlo: the
    /// 95 % Wilson score interval.
    pub ci: (f64, f64),
}

/// How the Monte Carlo samples are split across runs.
#[derive(Debug, Clone, Default)]
pub enum Split {
    /// All samples here.
    #[default]
    Whole,
    /// Only the chunks of shard `k` (0-based) of `n`; no Monte Carlo rows, the blocks of chunk
    /// moments and the values kept are returned in [`Analysis::shard_states`] for
    /// [`Split::Merged`].
    Shard(usize, usize),
    /// The blocks of all shards, per case, in chunk order, and their values in sample order:
    /// folded (and the quantiles taken) as a whole run would.
    Merged(Vec<CaseShard>),
}

/// What to analyse.
#[derive(Debug, Clone)]
pub struct AnalyzeOptions {
    pub speeds: Vec<f64>,
    pub cases: Vec<Case>,
    /// The quadrature (on by default).
    pub quadrature: Option<QuadOptions>,
    pub monte_carlo: Option<McOptions>,
    pub split: Split,
    /// Worker threads of every stage (`None`: rayon's default); results do not depend on
    /// their number.
    pub threads: Option<usize>,
    /// Sobol indices (none by default).
    pub sobol: Option<SobolOptions>,
    /// Cancelling it stops the run at its next check: the sweep before its next speed (the
    /// speeds left are failures, "interrupted"), the quadrature before its next case, the Monte
    /// Carlo after its current chunk. The result then covers what was done
    /// ([`Analysis::interrupted`]).
    pub cancel: Cancel,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            speeds: Vec::new(),
            cases: Vec::new(),
            quadrature: Some(QuadOptions::default()),
            monte_carlo: None,
            split: Split::default(),
            threads: None,
            cancel: Cancel::new(),
            sobol: None,
        }
    }
}

/// Result of [`analyze`].
#[derive(Debug, Clone)]
pub struct Analysis {
    /// Design variables (union over the cases), the order of `shares`.
    pub vars: Vec<usize>,
    pub cases: Vec<Case>,
    pub rows: Vec<Row>,
    /// Probabilities of character per speed, case and method.
    pub probabilities: Vec<ProbabilityRow>,
    /// The yield of the model's requirements per case and method (empty without
    /// requirements).
    pub yields: Vec<YieldRow>,
    /// Sobol indices per case (with [`AnalyzeOptions::sobol`]), and per case the reason where
    /// none could be computed.
    pub sobol: Vec<(usize, SobolIndex)>,
    pub sobol_refused: Vec<(usize, String)>,
    /// The speeds analysed and the outputs at each (what the Sobol indices' targets index).
    pub speeds: Vec<f64>,
    pub outputs: Vec<Output>,
    /// The Taylor methods (nominal sweep, derivatives, first/second order, invariant).
    pub analytic_seconds: f64,
    /// Of which the first-order stage (the nominal sweep and the exact gradients at every
    /// speed) and the second-order stage (the exact Hessians).
    pub first_order_seconds: f64,
    pub second_order_seconds: f64,
    pub quadrature_seconds: Option<f64>,
    /// Per case: the quadrature's rule in words and its number of swept nodes.
    pub quadrature_rules: Vec<(String, usize)>,
    pub monte_carlo_seconds: Option<f64>,
    /// Speeds whose nominal point or local model failed, with the reason.
    pub failures: Vec<(f64, String)>,
    /// The nominal points (for plots), `None` where they failed.
    pub nominal: Vec<Option<Point>>,
    /// Monte Carlo samples evaluated per case (fewer than asked if the run was interrupted).
    pub samples_done: Vec<usize>,
    /// Per case (with a whole or merged Monte Carlo), the samples whose design is not physically
    /// admissible, by reason: `(reason, count, first value)`; they count as failed at every speed.
    pub inadmissible: Vec<Vec<(String, usize, f64)>>,
    /// With [`Split::Shard`]: this shard's chunk moments per case, in chunk order.
    pub shard_states: Vec<CaseShard>,
    /// How the run ended: [`Termination::Cancelled`] where a stage stopped early because the
    /// run's [`Cancel`] token was cancelled (see [`AnalyzeOptions::cancel`]), as the stages'
    /// estimates report it.
    pub termination: Termination,
}

impl Analysis {
    /// The nominal point nearest the middle of the speeds analysed (`None` where every one
    /// failed): the operating point the report draws and names the modes at.
    pub fn middle_point(&self) -> Option<&Point> {
        let mid = self.nominal.len() / 2;
        (0..self.nominal.len())
            .filter(|&i| self.nominal[i].is_some())
            .min_by_key(|&i| i.abs_diff(mid))
            .and_then(|i| self.nominal[i].as_ref())
    }

    /// The Sobol indices worth showing: every requirement's worst margin, and each output at
    /// the speed where its analytic σ is largest; per case, margins first then outputs in
    /// order, each target's variables by decreasing total index.
    pub fn sobol_shown(&self) -> Vec<&(usize, SobolIndex)> {
        // Per case and output: the speed index with the largest analytic σ.
        let worst = |case: usize, o: usize| -> Option<usize> {
            let out = self.outputs[o];
            let mut best: Option<(usize, f64)> = None;
            for r in &self.rows {
                if r.case == case
                    && r.method == Method::Analytic
                    && r.quantity == out.quantity
                    && r.mode == out.mode
                    && r.std.is_finite()
                    && best.is_none_or(|b| r.std > b.1)
                {
                    let i = self
                        .speeds
                        .iter()
                        .position(|w| w.to_bits() == r.speed.to_bits())?;
                    best = Some((i, r.std));
                }
            }
            best.map(|b| b.0)
        };
        // Margins first, then outputs in order.
        let key = |t: &Target| match *t {
            Target::Margin(r) => (0, r),
            Target::Output(_, o) => (1, o),
        };
        let mut shown: Vec<&(usize, SobolIndex)> = self
            .sobol
            .iter()
            .filter(|(case, s)| match s.target {
                Target::Margin(_) => true,
                Target::Output(i, o) => worst(*case, o) == Some(i),
            })
            .collect();
        shown.sort_by(|x, y| {
            (x.0, key(&x.1.target))
                .cmp(&(y.0, key(&y.1.target)))
                .then(y.1.total.total_cmp(&x.1.total))
        });
        shown
    }

    /// Did a stage stop early (a speed of the sweep, a case of the quadrature, Monte Carlo
    /// samples left out)?
    pub fn cancelled(&self) -> bool {
        self.termination == Termination::Cancelled
    }

    /// Is the result partial: cancelled, or fewer Monte Carlo samples than the `asked` (a
    /// merge of the shards of a cancelled run)?
    pub fn interrupted(&self, asked: usize) -> bool {
        self.cancelled() || self.samples_done.iter().any(|&n| n < asked)
    }
}

/// Progress callback: (stage, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Runs the analysis. Failed speeds are reported in `failures` and skipped; the run goes on.
///
/// The stages, in order: the [`Study`] (nominal sweep and local models, shared by the cases);
/// per case the [`Quadrature`]; per case the [`Taylor`] methods and the `analytic` rows; per
/// case the [`MonteCarlo`] (whole, one shard, or the shards' blocks merged).
pub fn analyze(model: &Compiled, opt: &AnalyzeOptions, progress: Progress) -> Analysis {
    let mut vars: Vec<usize> = opt
        .cases
        .iter()
        .flat_map(|c| c.tolerances.iter().map(|t| t.0))
        .collect();
    vars.sort_unstable();
    vars.dedup();
    let pool = crate::threads::pool(opt.threads);
    let stage = |name: &str| {
        let name = name.to_string();
        move |d: usize, n: usize| progress(&name, d, n)
    };
    let derivatives = stage("derivatives");
    let run = Run {
        cancel: &opt.cancel,
        pool: &pool,
        progress: &derivatives,
    };
    let t0 = Instant::now();
    let study = Study::build(model, vars, opt.speeds.clone(), &run);
    let spreads: Vec<Spread> = opt
        .cases
        .iter()
        .map(|c| Spread::new(model, c, &study.vars))
        .collect();
    let taylor_seconds = t0.elapsed().as_secs_f64();
    let tq = Instant::now();
    let mut termination = study.termination;
    let mut ended = |how: Termination| termination = termination.and(how);
    let quad: Vec<Option<QuadResult>> = match opt.quadrature {
        Some(options) => spreads
            .iter()
            .zip(&opt.cases)
            .map(|(s, case)| {
                let progress = stage(&format!("quadrature {}", case.name));
                let estimate =
                    Quadrature { options }.propagate(&study, s, &run.with_progress(&progress));
                ended(estimate.termination);
                estimate.value
            })
            .collect(),
        None => vec![None; spreads.len()],
    };
    let quadrature_seconds = opt.quadrature.map(|_| tq.elapsed().as_secs_f64());
    let quadrature_rules = quad
        .iter()
        .flatten()
        .map(|r| (r.rule.clone(), r.nodes))
        .collect();
    let t2 = Instant::now();
    let mut rows = Vec::new();
    let mut probabilities = Vec::new();
    let mut yield_rows = Vec::new();
    let has_requirements = !model.model().requirements.is_empty();
    for (ci, s) in spreads.iter().enumerate() {
        if has_requirements {
            yield_rows.extend(yields::first_order_rows(&study, ci, s));
            if let Some(q) = &quad[ci]
                && let Some(y) = &q.yields
            {
                let m = model.model();
                yield_rows.extend(yields::quadrature_rows(
                    ci,
                    y,
                    &m.requirements,
                    &study.speeds,
                    q.nodes,
                    m.allocation.target_yield,
                ));
            }
        }
        let taylor = Taylor.propagate(&study, s, &run);
        ended(taylor.termination);
        let taylor = taylor.value;
        for (si, (lm, stats)) in study.locals.iter().zip(taylor).enumerate() {
            let (Some(lm), Some(stats)) = (lm, stats) else {
                continue;
            };
            let q = quad[ci].as_ref().map(|q| q.stats[si].as_slice());
            rows.extend(analytic_rows(study.speeds[si], ci, lm, &stats, q));
        }
        if let Some(q) = &quad[ci] {
            probabilities.extend(quadrature_probabilities(&study, ci, q));
        }
    }
    let analytic_seconds = taylor_seconds + t2.elapsed().as_secs_f64();
    let (mut sobol_rows, mut sobol_refused) = (Vec::new(), Vec::new());
    if let Some(so) = opt.sobol {
        for (ci, s) in spreads.iter().enumerate() {
            if opt.cancel.is_cancelled() {
                ended(Termination::Cancelled);
                break;
            }
            let progress = stage(&format!("sobol {}", opt.cases[ci].name));
            match sobol(&study, s, so, &run.with_progress(&progress)) {
                Ok(rows) => sobol_rows.extend(rows.into_iter().map(|r| (ci, r))),
                Err(e) => sobol_refused.push((ci, e.to_string())),
            }
        }
    }
    let t1 = Instant::now();
    let mc = opt
        .monte_carlo
        .map(|mc| monte_carlo(&study, &spreads, opt, mc, &run, &stage));
    let monte_carlo_seconds = mc.as_ref().map(|_| t1.elapsed().as_secs_f64());
    let mc = mc.unwrap_or_default();
    ended(mc.termination);
    rows.extend(mc.rows);
    probabilities.extend(mc.probabilities);
    yield_rows.extend(mc.yields);
    let Study {
        vars,
        speeds,
        outputs,
        failures,
        nominal,
        seconds: (first_order_seconds, second_order_seconds),
        ..
    } = study;
    Analysis {
        vars,
        cases: opt.cases.clone(),
        rows,
        probabilities,
        yields: yield_rows,
        sobol: sobol_rows,
        sobol_refused,
        speeds,
        outputs,
        analytic_seconds,
        first_order_seconds,
        second_order_seconds,
        quadrature_seconds,
        quadrature_rules,
        monte_carlo_seconds,
        failures,
        nominal,
        samples_done: mc.samples_done,
        inadmissible: mc.inadmissible,
        shard_states: mc.shard_states,
        termination,
    }
}

/// The quadrature's probabilities of character of case `case`, at the speeds whose nominal
/// point exists.
fn quadrature_probabilities(study: &Study, case: usize, q: &QuadResult) -> Vec<ProbabilityRow> {
    let mut out = Vec::new();
    for (si, ps) in q.probabilities.iter().enumerate() {
        if study.nominal[si].is_none() {
            continue;
        }
        out.extend(ps.iter().map(|p| ProbabilityRow {
            speed: study.speeds[si],
            case,
            method: Method::Quadrature,
            event: p.event,
            mode: p.mode,
            probability: p.probability,
            ci: (
                (p.probability - p.error).max(0.0),
                (p.probability + p.error).min(1.0),
            ),
        }));
    }
    out
}

/// What the Monte Carlo stage adds to an [`Analysis`].
#[derive(Debug, Default)]
struct MonteCarloPart {
    termination: Termination,
    rows: Vec<Row>,
    probabilities: Vec<ProbabilityRow>,
    yields: Vec<YieldRow>,
    samples_done: Vec<usize>,
    inadmissible: Vec<Vec<(String, usize, f64)>>,
    shard_states: Vec<CaseShard>,
}

/// The Monte Carlo of every case as `opt.split` asks: all samples here, one shard's chunks
/// (their blocks kept for the merge), or the shards' blocks folded as a whole run would.
fn monte_carlo<S, F>(
    study: &Study,
    spreads: &[Spread],
    opt: &AnalyzeOptions,
    mc: McOptions,
    run: &Run,
    stage: &S,
) -> MonteCarloPart
where
    S: Fn(&str) -> F,
    F: Fn(usize, usize) + Sync,
{
    let mut part = MonteCarloPart::default();
    let (speeds, outs) = (study.speeds.len(), study.outputs.len());
    for (ci, s) in spreads.iter().enumerate() {
        let progress = stage(&format!("monte carlo {}", opt.cases[ci].name));
        let run = run.with_progress(&progress);
        let (stats, done, counts, worst) = match &opt.split {
            Split::Merged(cases) => {
                let mut fold = TreeFold::default();
                for b in &cases[ci].blocks {
                    fold.push(b.clone());
                }
                let (mut stats, done) = montecarlo::statistics(&fold, speeds, outs, mc.samples);
                let worst = cases[ci].kept.clone().map(|k| k.apply(&mut stats));
                (stats, done, fold.total_yields(), worst)
            }
            Split::Shard(k, n) => {
                let method = MonteCarlo::shard(mc, *k, *n);
                let states = method.propagate(study, s, &run);
                part.termination = part.termination.and(states.termination);
                part.shard_states.push(CaseShard {
                    blocks: states.value.fold.into_blocks(),
                    kept: states.value.kept,
                });
                continue;
            }
            Split::Whole => {
                if opt.cancel.is_cancelled() {
                    part.termination = Termination::Cancelled;
                    part.samples_done.push(0);
                    continue;
                }
                let r = MonteCarlo::whole(mc).propagate(study, s, &run);
                part.termination = part.termination.and(r.termination);
                let counts = r.value.fold.total_yields();
                (
                    r.value.stats,
                    r.value.samples,
                    counts,
                    r.value.worst_margins,
                )
            }
        };
        part.samples_done.push(done);
        if let Some(y) = &counts {
            let m = study.model.model();
            part.yields.extend(yields::monte_carlo_rows(
                ci,
                y,
                worst.as_deref(),
                &m.requirements,
                &study.speeds,
                done,
                m.allocation.target_yield,
            ));
        }
        part.inadmissible
            .push(MonteCarlo::whole(mc).inadmissible(study, s, done, &run));
        for (si, row) in stats.iter().enumerate() {
            if study.nominal[si].is_none() || done < 2 {
                continue;
            }
            part.probabilities.extend(monte_carlo_probabilities(
                study.speeds[si],
                ci,
                &study.outputs,
                row,
            ));
            part.rows.extend(monte_carlo_rows(study, si, ci, row));
        }
    }
    part
}

/// The Monte Carlo rows of case `case` at speed `si`; a row without a value says why.
fn monte_carlo_rows(study: &Study, si: usize, case: usize, stats: &[McStat]) -> Vec<Row> {
    let nominal = study.nominal[si].as_ref();
    study
        .outputs
        .iter()
        .zip(stats)
        .map(|(o, st)| Row {
            speed: study.speeds[si],
            quantity: o.quantity,
            mode: o.mode,
            case,
            method: Method::MonteCarlo,
            mean: st.mean,
            std: st.std,
            mc: Some(*st),
            shares: None,
            basis: None,
            quantiles: st.quantiles,
            errors: None,
            within_request: None,
            missing: if !st.mean.is_finite() {
                Some(nominal.map_or(Missing::NoValue, |pt| no_value(pt, o)))
            } else {
                (!st.std.is_finite()).then_some(Missing::OneSample)
            },
        })
        .collect()
}

/// First-order, second-order, (for ω_d) invariant, quadrature and the `analytic` rows of one
/// speed and case from the [`Taylor`] statistics `taylor` of the local model `lm`; a method
/// that gives no value says why in its row.
fn analytic_rows(
    speed: f64,
    case: usize,
    lm: &LocalModel,
    taylor: &[TaylorStats],
    quad: Option<&[Option<QuadStat>]>,
) -> Vec<Row> {
    let mut rows = Vec::new();
    let row = |o: &Output, method, stat: Result<Stat, Missing>, shares, basis| {
        let (mean, std, missing) = match stat {
            Ok(st) if st.mean.is_finite() && st.std.is_finite() => (st.mean, st.std, None),
            // An overflow on the way (a Hessian of 10³⁰⁰'s): no value, and why.
            Ok(_) => (f64::NAN, f64::NAN, Some(Missing::NotFinite)),
            Err(e) => (f64::NAN, f64::NAN, Some(e)),
        };
        Row {
            speed,
            quantity: o.quantity,
            mode: o.mode,
            case,
            method,
            mean,
            std,
            mc: None,
            shares,
            basis,
            quantiles: None,
            errors: None,
            within_request: None,
            missing,
        }
    };
    for (k, (o, t)) in lm.outputs.iter().zip(taylor).enumerate() {
        let shares = t
            .first_order
            .as_ref()
            .ok()
            .map(|(_, shares)| shares.clone());
        let fo = t.first_order.clone().map(|(st, _)| st);
        rows.push(row(o, Method::FirstOrder, fo.clone(), shares, None));
        let so = t.second_order.clone();
        rows.push(row(o, Method::SecondOrder, so.clone(), None, None));
        let mut choice = so
            .map(|st| (Method::SecondOrder, st))
            .or(fo.map(|st| (Method::FirstOrder, st)));
        if let Some(inv) = &t.invariant {
            rows.push(row(
                o,
                Method::Invariant,
                inv.clone().map(|(st, _)| st),
                None,
                None,
            ));
            if let Ok((st, dst)) = inv
                && (choice.is_err() || dst.mean.abs() < KINK_SIGMAS * dst.std)
            {
                choice = Ok((Method::Invariant, *st));
            }
        }
        let q = quad.map(|q| {
            q.get(k)
                .copied()
                .flatten()
                .ok_or_else(|| quadrature_missing(lm, k))
        });
        if let Some(q) = &q {
            let stat = q.clone().map(|q| Stat {
                mean: q.mean,
                std: q.std,
            });
            rows.push(Row {
                quantiles: q.as_ref().ok().map(|q| q.quantiles),
                errors: q.as_ref().ok().map(|q| (q.mean_error, q.std_error)),
                within_request: q.as_ref().ok().map(|q| q.within_request),
                ..row(o, Method::Quadrature, stat, None, None)
            });
        }
        let answer = match q {
            Some(Ok(q)) => Row {
                quantiles: Some(q.quantiles),
                errors: Some((q.mean_error, q.std_error)),
                within_request: Some(q.within_request),
                ..row(
                    o,
                    Method::Analytic,
                    Ok(Stat {
                        mean: q.mean,
                        std: q.std,
                    }),
                    None,
                    Some(Method::Quadrature),
                )
            },
            _ => match choice {
                Ok((m, st)) => row(o, Method::Analytic, Ok(st), None, Some(m)),
                Err(e) => row(o, Method::Analytic, Err(e), None, None),
            },
        };
        rows.push(answer);
    }
    rows
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

/// Why the quadrature has no value for output `k`: the output has none at the nominal point
/// either (the damping ratio of a rigid-body mode), or no node gave one.
fn quadrature_missing(lm: &LocalModel, k: usize) -> Missing {
    match (lm.outputs[k].quantity, lm.outputs[k].mode, &lm.grad[k]) {
        (Quantity::DampingRatio, Some(_), Err(e @ Missing::RigidDamping { .. })) => e.clone(),
        (Quantity::TransferMagnitude, _, Err(e @ Missing::TransferUnbounded)) => e.clone(),
        _ => Missing::NoValue,
    }
}

/// Monte Carlo probabilities of character at one speed from the event counts of its
/// statistics, with 95 % Wilson score intervals.
fn monte_carlo_probabilities(
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

/// The 95 % Wilson score interval of `k` successes in `n` trials.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    let z = 1.959_963_984_540_054;
    let (n, p) = (n as f64, k as f64 / n as f64);
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}
