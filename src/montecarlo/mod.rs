//! Monte Carlo check of the analytic propagation: sample the design variables, re-run the whole
//! pipeline (equilibrium sweep, linearisation, modes, transfer function) per sample.
//!
//! Reproducibility: sample `i` draws from its own ChaCha8 stream `(seed, i)`; Latin hypercube
//! strata come from one hash permutation per variable ([`permute`]) keyed from a stream reserved
//! for it; scrambled Sobol points are a function of `(i, dimension, seed)`. Samples are evaluated
//! in parallel (rayon) in chunks, and the chunks' moments are combined along one fixed binary
//! tree over the chunk indices ([`TreeFold`]), so the output is bit-identical for any number of
//! threads or shards, and memory does not grow with the number of samples (at most
//! [`MAX_SAMPLES`](crate::settings::MAX_SAMPLES); the values kept for quantiles are capped by [`MAX_KEPT_VALUES`]).
//!
//! Per speed and output: mean and σ (one-pass central moments up to the fourth), their 95 %
//! confidence intervals, the samples that failed (no equilibrium or no modes) and those whose
//! mode changed class against the nominal design. Modes are matched to the nominal ones by shape.
//!
//! The interval of the mean is Student's t. The interval of σ is the asymptotic one from the
//! sample kurtosis κ: `Var(s²) ≈ s⁴ (κ − (n−3)/(n−1)) / n`, so it stays honest for skewed,
//! heavy-tailed outputs (|H| at a stationary point is χ²-like, κ ≈ 15), where the χ² interval,
//! valid for normal outputs only, would be several times too narrow.

mod moments;
mod sampler;
mod table;

pub use moments::{Block, ChunkState, Events, Moments, TreeFold, YieldCounts, block_layout};
pub use sampler::{Sampler, permute};

use crate::margins;
use crate::modal::ModeClass;
use crate::model::Sampling;
use crate::program::{Tier, Workspace};
use crate::propagate::{Estimate, Propagation, Run, Study, Termination};
use crate::table::McStat;
use crate::tolerance::Spread;
use rayon::prelude::*;

/// Monte Carlo settings.
#[derive(Debug, Clone, Copy)]
pub struct McOptions {
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
}

/// Sample quantile of sorted values (linear interpolation between order statistics,
/// Hyndman & Fan's type 7; the lower of two neighbours where one is infinite).
pub fn sorted_quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        n => {
            let h = (n - 1) as f64 * q;
            let (lo, frac) = (h.floor() as usize, h - h.floor());
            let hi = (lo + 1).min(n - 1);
            if !(sorted[lo].is_finite() && sorted[hi].is_finite()) {
                // An infinite neighbour (a design without a value): no interpolation.
                return sorted[lo];
            }
            sorted[lo] + frac * (sorted[hi] - sorted[lo])
        }
    }
}

/// One sample's outputs, `[speed][output]` flattened (one allocation per sample, freed by
/// the thread that folds it): the value (NaN where the output or the whole point failed) and
/// what happened to the sample there; and the requirements' margins `[speed][requirement]`
/// (see [`YieldCounts::add`]).
type SampleResult = (Vec<(f64, Events)>, Vec<f64>);

/// Sweeps the design `p` across the study's speeds and reads every output there, with what
/// happened to the sample, and every requirement's margin.
fn run_sample(study: &Study, p: Vec<f64>, run: (Tier, &Workspace)) -> SampleResult {
    let outs = &study.outputs;
    let reqs = &study.model.model().requirements;
    let mut margins = vec![f64::INFINITY; study.speeds.len() * reqs.len()];
    let mut out = Vec::with_capacity(study.speeds.len() * outs.len());
    study.sweep_design(p, run, |i, at| {
        study.margins(i, at, margins::reaches, |r, m| {
            margins[i * reqs.len() + r] = m;
        });
        let Some(at) = at else {
            out.extend(std::iter::repeat_n(
                (f64::NAN, Events::default()),
                outs.len(),
            ));
            return;
        };
        let (nom, pt) = (at.nominal, at.point);
        let unstable = !pt.stable();
        let other_branch = !at.same_branch;
        out.extend(outs.iter().map(|o| {
            let class = o.mode.and_then(|m| pt.modes.get(m)).map(|x| x.class);
            let events = Events {
                class_changed: o
                    .mode
                    .is_some_and(|m| class != nom.modes.get(m).map(|x| x.class)),
                overdamped: class == Some(ModeClass::Overdamped),
                unstable,
                other_branch,
            };
            (at.value(o), events)
        }));
    });
    (out, margins)
}

/// Samples per chunk: the unit of parallel work, of interruption and of sharding.
pub const CHUNK: usize = 64;

/// Number of chunks for `samples` samples.
pub fn chunks(samples: usize) -> usize {
    samples.div_ceil(CHUNK)
}

/// The chunks `[from, to)` of shard `k` (0-based) of `n`: contiguous, as even as possible.
pub fn shard_chunks(samples: usize, k: usize, n: usize) -> std::ops::Range<usize> {
    let c = chunks(samples);
    (c * k / n)..(c * (k + 1) / n)
}

/// How the Monte Carlo samples are split across runs.
#[derive(Debug, Clone, Default)]
pub enum Split {
    /// All samples here.
    #[default]
    Whole,
    /// Only the chunks of shard `k` (0-based) of `n`: no rows, the blocks of chunk moments and
    /// the values kept are the run's result ([`CaseShard`], for [`Split::Merged`]).
    Shard(usize, usize),
    /// The blocks of all shards, per case, in chunk order, and their values in sample order:
    /// folded (and the quantiles taken) as a whole run would.
    Merged(Vec<CaseShard>),
}

/// The Monte Carlo as a propagation method: the samples of `chunks` (samples
/// `CHUNK·i .. CHUNK·(i+1)` of chunk `i`), each a whole sweep, their moments folded along the
/// fixed tree (see the module documentation); or the shards' blocks of such runs, merged.
#[derive(Debug, Clone)]
pub struct MonteCarlo<'a> {
    pub options: McOptions,
    /// The chunks evaluated here: all of them, or one shard's (none for a merge).
    pub chunks: std::ops::Range<usize>,
    /// Keep every value for the 5/50/95 % quantiles (unless more than [`MAX_KEPT_VALUES`]
    /// values would be kept).
    pub quantiles: bool,
    /// A whole run, a shard (whose state goes to the merge: [`McRun::Shard`]) or the merge of
    /// the shards' states.
    pub part: Part<'a>,
}

/// Which part of a sharded run a [`MonteCarlo`] is.
#[derive(Debug, Clone)]
pub enum Part<'a> {
    Whole,
    Shard,
    /// The shards' state of the case, borrowed from the run's [`Split::Merged`].
    Merged(&'a CaseShard),
}

/// What a [`MonteCarlo`] run gives.
#[derive(Debug, Clone)]
pub enum McRun {
    /// A whole run cancelled before its first sample.
    NotStarted,
    /// A shard's blocks and kept values, for the merge.
    Shard(CaseShard),
    /// The statistics of a whole run or of the shards merged.
    Done(McResult),
}

impl McRun {
    /// A shard's state, or the run back where it is not a shard's.
    pub fn into_shard(self) -> Result<CaseShard, McRun> {
        match self {
            McRun::Shard(s) => Ok(s),
            other => Err(other),
        }
    }
}

/// The statistics of a whole Monte Carlo run (or of the shards merged).
#[derive(Debug, Clone)]
pub struct McResult {
    /// Each chunk's moments, in chunk order (folded).
    pub fold: TreeFold,
    /// Statistics `[speed][output]` of the chunks done, with the quantiles where they were
    /// kept.
    pub stats: Vec<Vec<McStat>>,
    /// Samples evaluated (fewer than asked where the run was cancelled).
    pub samples: usize,
    /// Per requirement: every sample's worst margin over its range (`−∞` where it failed),
    /// sorted; where the run kept the values (see [`MonteCarlo::quantiles`]).
    pub worst_margins: Option<Vec<Vec<f64>>>,
    /// The samples whose design is not admissible, by reason ([`MonteCarlo::inadmissible`]).
    pub inadmissible: Vec<(String, usize, f64)>,
}

/// One tolerance case's share of a sharded run: its blocks of chunk moments in chunk order,
/// and the values it kept ([`Kept`], where the run keeps them); for a merge, every shard's
/// blocks and values joined in order.
#[derive(Debug, Clone, Default)]
pub struct CaseShard {
    pub blocks: Vec<Block>,
    pub kept: Option<Kept>,
}

/// What a run keeps besides the moments, for the quantiles: every finite output value per
/// `[speed · outputs + output]` (as `f32`) and every requirement's worst margin, in sample
/// order. A shard keeps its samples' and the merge joins them in shard order, so the merged
/// quantiles are a whole run's, bit for bit.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Kept {
    pub values: Vec<Vec<f32>>,
    pub worst: Vec<Vec<f64>>,
}

impl Kept {
    /// Appends `other`'s samples (the next shard's) after these.
    pub fn extend(&mut self, other: Kept) {
        if self.values.is_empty() && self.worst.is_empty() {
            *self = other;
            return;
        }
        for (a, b) in self.values.iter_mut().zip(other.values) {
            a.extend(b);
        }
        for (a, b) in self.worst.iter_mut().zip(other.worst) {
            a.extend(b);
        }
    }

    /// The 5, 50 and 95 % quantiles of each output into `stats` (`[speed][output]`), and each
    /// requirement's worst margins sorted.
    pub fn apply(self, stats: &mut [Vec<McStat>]) -> Vec<Vec<f64>> {
        for (st, vals) in stats.iter_mut().flatten().zip(self.values) {
            let mut v: Vec<f64> = vals.into_iter().map(f64::from).collect();
            v.sort_by(f64::total_cmp);
            if !v.is_empty() {
                st.quantiles = Some([0.05, 0.5, 0.95].map(|q| sorted_quantile(&v, q)));
            }
        }
        self.worst
            .into_iter()
            .map(|mut v| {
                v.sort_by(f64::total_cmp);
                v
            })
            .collect()
    }
}

impl<'a> MonteCarlo<'a> {
    /// All samples of `options`.
    pub fn whole(options: McOptions) -> MonteCarlo<'a> {
        MonteCarlo {
            options,
            chunks: 0..chunks(options.samples),
            quantiles: true,
            part: Part::Whole,
        }
    }

    /// The chunks of shard `k` (0-based) of `n` ([`shard_chunks`]), their values kept for the
    /// merge's quantiles as a whole run keeps them ([`CaseShard::kept`]).
    pub fn shard(options: McOptions, k: usize, n: usize) -> MonteCarlo<'a> {
        MonteCarlo {
            options,
            chunks: shard_chunks(options.samples, k, n),
            quantiles: true,
            part: Part::Shard,
        }
    }

    /// The shards' blocks and kept values of one case, folded as a whole run would.
    pub fn merged(options: McOptions, shards: &'a CaseShard) -> MonteCarlo<'a> {
        MonteCarlo {
            options,
            chunks: 0..0,
            quantiles: true,
            part: Part::Merged(shards),
        }
    }

    /// The run of case `case` (0-based) that `split` asks for.
    pub fn of_case(options: McOptions, split: &'a Split, case: usize) -> MonteCarlo<'a> {
        match split {
            Split::Whole => MonteCarlo::whole(options),
            Split::Shard(k, n) => MonteCarlo::shard(options, *k, *n),
            Split::Merged(cases) => MonteCarlo::merged(options, &cases[case]),
        }
    }

    /// Whether a run of `samples` samples over `speeds × outputs` keeps its values (at most
    /// [`MAX_KEPT_VALUES`]); the same for a whole run and each of its shards.
    pub fn keeps(samples: usize, speeds: usize, outputs: usize) -> bool {
        samples.saturating_mul(speeds * outputs) <= MAX_KEPT_VALUES
    }

    /// Evaluates the chunks and folds each chunk's moments `[speed][output]` in chunk order
    /// ([`TreeFold`]); stops early (fewer chunks, [`Termination::Cancelled`]) when the run is
    /// cancelled. Progress counts the samples done in this call. With `kept`, also keeps the
    /// values for quantiles ([`Kept`]).
    fn run_chunks(
        &self,
        study: &Study,
        spread: &Spread,
        run: &Run,
        mut kept: Option<&mut Kept>,
    ) -> (TreeFold, Termination) {
        let opt = self.options;
        let (speeds, outs) = (study.speeds.len(), study.outputs.len());
        let sampler = Sampler::new(study, spread, opt);
        let here = (self.chunks.len() * CHUNK).min(opt.samples);
        let tier = Tier::for_points(here * speeds);
        let mut out = TreeFold::default();
        let mut done = 0;
        let reqs = &study.model.model().requirements;
        let has_margin: Vec<bool> = reqs.iter().map(margins::has_margin).collect();
        let covered: Vec<bool> = study
            .speeds
            .iter()
            .flat_map(|&w| reqs.iter().map(move |r| margins::covers(r, w)))
            .collect();
        let mut worst = vec![f64::INFINITY; reqs.len()];
        if let Some(k) = kept.as_deref_mut() {
            k.values.resize(speeds * outs, Vec::new());
            k.worst.resize(reqs.len(), Vec::new());
        }
        for chunk in self.chunks.clone() {
            if run.cancel.is_cancelled() {
                return (out, Termination::Cancelled);
            }
            let (start, end) = (chunk * CHUNK, ((chunk + 1) * CHUNK).min(opt.samples));
            let results: Vec<SampleResult> = run.pool.install(|| {
                (start..end)
                    .into_par_iter()
                    .map_init(Workspace::default, |workspace, i| {
                        run_sample(study, sampler.parameters(i), (tier, workspace))
                    })
                    .collect()
            });
            let mut acc = vec![vec![Moments::default(); outs]; speeds];
            let mut yields = (!reqs.is_empty()).then(|| YieldCounts::new(reqs.len(), speeds));
            for (r, margins) in results {
                if let Some(y) = yields.as_mut() {
                    y.add(&margins, &covered, &has_margin, &mut worst);
                    if let Some(kept) = kept.as_deref_mut() {
                        for (w, &x) in kept.worst.iter_mut().zip(&worst) {
                            w.push(x);
                        }
                    }
                }
                for (k, (m, &(v, events))) in acc.iter_mut().flatten().zip(&r).enumerate() {
                    if v.is_finite() {
                        m.add(v);
                        if let Some(kept) = kept.as_deref_mut() {
                            kept.values[k].push(v as f32);
                        }
                    } else {
                        m.failed += 1;
                    }
                    m.count(events);
                }
            }
            out.push(Block {
                level: 0,
                index: chunk,
                moments: acc,
                yields,
            });
            done += end - start;
            (run.progress)(done, opt.samples);
        }
        (out, Termination::Completed)
    }

    /// The statistics of the chunks `fold` (of a whole run, or the shards' merged), with the
    /// quantiles of the values `kept` where the run kept them, and the inadmissible designs.
    fn result(
        &self,
        study: &Study,
        spread: &Spread,
        run: &Run,
        fold: TreeFold,
        kept: Option<Kept>,
    ) -> McResult {
        let (speeds, outs) = (study.speeds.len(), study.outputs.len());
        let (mut stats, done) = statistics(&fold, speeds, outs, self.options.samples);
        let worst_margins = kept.map(|k| k.apply(&mut stats));
        McResult {
            inadmissible: self.inadmissible(study, spread, done, run),
            fold,
            stats,
            samples: done,
            worst_margins,
        }
    }

    /// The samples `0..samples` of `spread` whose design is not physically admissible
    /// ([`crate::model::Model::admissible`]), tallied by reason: `(reason, count, first
    /// offending value)`, most frequent first. They fail at every speed; this says why.
    /// `samples` may be fewer than the run's (a cancelled run): they are still the run's
    /// designs (the Latin hypercube's strata are those of every sample asked).
    pub fn inadmissible(
        &self,
        study: &Study,
        spread: &Spread,
        samples: usize,
        run: &Run,
    ) -> Vec<(String, usize, f64)> {
        let model = study.model;
        let sampler = Sampler::new(study, spread, self.options);
        let mut tally: Vec<(String, usize, f64)> = run.pool.install(|| {
            (0..samples)
                .into_par_iter()
                .filter_map(|i| model.model().admissible(&sampler.parameters(i)).err())
                .fold(Vec::new, |mut t: Vec<(String, usize, f64)>, d| {
                    match t.iter_mut().find(|x| x.0 == d.reason) {
                        Some(x) => x.1 += 1,
                        None => t.push((d.reason, 1, d.value)),
                    }
                    t
                })
                .reduce(Vec::new, |mut a, b| {
                    for (r, n, v) in b {
                        match a.iter_mut().find(|x| x.0 == r) {
                            Some(x) => x.1 += n,
                            None => a.push((r, n, v)),
                        }
                    }
                    a
                })
        });
        tally.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        tally
    }
}

impl Propagation for MonteCarlo<'_> {
    type Value = McRun;

    fn propagate(&self, study: &Study, spread: &Spread, run: &Run) -> Estimate<McRun> {
        let (speeds, outs) = (study.speeds.len(), study.outputs.len());
        let samples = self.options.samples;
        if let Part::Merged(shards) = self.part {
            let mut fold = TreeFold::default();
            for b in &shards.blocks {
                fold.push(b.clone());
            }
            let result = self.result(study, spread, run, fold, shards.kept.clone());
            return Estimate {
                value: McRun::Done(result),
                termination: Termination::Completed,
            };
        }
        let shard = matches!(self.part, Part::Shard);
        if !shard && run.cancel.is_cancelled() {
            return Estimate {
                value: McRun::NotStarted,
                termination: Termination::Cancelled,
            };
        }
        let keep = self.quantiles && MonteCarlo::keeps(samples, speeds, outs);
        let mut kept = Kept::default();
        let (fold, termination) = self.run_chunks(study, spread, run, keep.then_some(&mut kept));
        if shard {
            let kept = keep.then_some(kept);
            let blocks = fold.into_blocks();
            return Estimate {
                value: McRun::Shard(CaseShard { blocks, kept }),
                termination,
            };
        }
        let result = self.result(study, spread, run, fold, keep.then_some(kept));
        Estimate {
            value: McRun::Done(result),
            termination,
        }
    }
}

/// At most this many values (`samples × speeds × outputs`) are kept for the quantiles of a
/// whole run (4 bytes each); a larger run reports no quantiles.
pub const MAX_KEPT_VALUES: usize = 100_000_000;

/// Statistics `[speed][output]` of the chunks folded, and the number of samples (of `asked`)
/// they cover.
pub fn statistics(
    fold: &TreeFold,
    speeds: usize,
    outs: usize,
    asked: usize,
) -> (Vec<Vec<McStat>>, usize) {
    let total = fold
        .total()
        .unwrap_or_else(|| vec![vec![Moments::default(); outs]; speeds]);
    // From the chunks covered, not from the moments: a run with no outputs (every nominal
    // speed failed) still evaluated its samples.
    let samples = match (fold.stack.first(), fold.stack.last()) {
        (Some(a), Some(b)) => {
            (b.chunks().end.saturating_mul(CHUNK)).min(asked)
                - (a.chunks().start * CHUNK).min(asked)
        }
        _ => 0,
    };
    (
        total
            .iter()
            .map(|row| row.iter().map(Moments::stat).collect())
            .collect(),
        samples,
    )
}
