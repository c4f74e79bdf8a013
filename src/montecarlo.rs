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

use crate::modal::ModeClass;
use crate::model::Sampling;
use crate::program::{Tier, Workspace};
use crate::propagate::{Estimate, Propagation, Run, Study, Termination};
use crate::sampling::{DesignMap, sample_sweep};
use crate::tolerance::{Spread, value};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Monte Carlo settings.
#[derive(Debug, Clone, Copy)]
pub struct McOptions {
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
}

/// Statistics of one output at one speed.
#[derive(Debug, Clone, Copy, Default)]
pub struct McStat {
    /// Samples that gave a value.
    pub n: usize,
    pub mean: f64,
    pub std: f64,
    pub mean_ci: (f64, f64),
    pub std_ci: (f64, f64),
    /// Samples where the point failed.
    pub failed: usize,
    /// Samples whose mode had another class than the nominal one.
    pub class_changed: usize,
    /// Samples whose output's mode was overdamped (ω_d and ζ rows; 0 for the transfer).
    pub overdamped: usize,
    /// Samples whose equilibrium was unstable.
    pub unstable: usize,
    /// Samples on another equilibrium branch than the nominal design (another number of
    /// branch switches since the lowest speed).
    pub other_branch: usize,
    /// The 5, 50 and 95 % sample quantiles (linear interpolation between order statistics),
    /// where the run kept the values (see [`MonteCarlo::quantiles`]).
    pub quantiles: Option<[f64; 3]>,
}

/// One-pass central moments (Welford, extended to the fourth moment by Terriberry), with the
/// counts of failed and class-changed samples; combinable (Pébay's pairwise formulas).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Moments {
    n: usize,
    mean: f64,
    m2: f64,
    m3: f64,
    m4: f64,
    failed: usize,
    class_changed: usize,
    #[serde(default)]
    overdamped: usize,
    #[serde(default)]
    unstable: usize,
    #[serde(default)]
    other_branch: usize,
}

/// Moments of one chunk (or block of chunks) of samples: `[speed][output]`.
pub type ChunkState = Vec<Vec<Moments>>;

/// The moments of the aligned block of chunks `[index·2^level, (index+1)·2^level)`: a node of
/// the one binary tree over global chunk indices along which every run combines its chunks.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Block {
    pub level: u32,
    pub index: usize,
    pub moments: ChunkState,
}

impl Block {
    /// The chunks this block covers.
    pub fn chunks(&self) -> std::ops::Range<usize> {
        let w = 1usize.checked_shl(self.level).unwrap_or(usize::MAX);
        self.index.saturating_mul(w)..(self.index.saturating_add(1)).saturating_mul(w)
    }
}

/// The maximal aligned blocks `(level, index)` of the chunks `range`, in order: what a
/// [`TreeFold`] fed those chunks keeps (the largest aligned block that fits, greedily).
pub fn block_layout(range: std::ops::Range<usize>) -> Vec<(u32, usize)> {
    let mut out = Vec::new();
    let mut x = range.start;
    while x < range.end {
        let mut level = 0u32;
        while level < 62 && x.is_multiple_of(2usize << level) && x + (2usize << level) <= range.end
        {
            level += 1;
        }
        out.push((level, x >> level));
        x += 1usize << level;
    }
    out
}

/// Combines chunk moments along a fixed binary tree over the chunk indices, in memory
/// logarithmic in their number.
///
/// Pébay's pairwise combination is exact in arithmetic but not associative in floating point,
/// so the order of combination must not depend on how the work was split. Here it does not: a
/// block is only ever combined with its sibling, so a whole run pushing chunk after chunk, and a
/// merge pushing the blocks its shards kept (each shard keeps the maximal aligned blocks of its
/// range, at most two per level), build the same tree and give bit-identical statistics. The
/// stack holds at most one block per level: memory does not grow with the sample count.
#[derive(Debug, Clone, Default)]
pub struct TreeFold {
    stack: Vec<Block>,
}

impl TreeFold {
    /// Adds the next block; blocks must come in chunk order without gaps (shards read from
    /// files are checked against [`block_layout`] first, see [`crate::shard`]).
    pub fn push(&mut self, mut b: Block) {
        while let Some(top) = self.stack.last() {
            if top.level == b.level && top.index % 2 == 0 && top.index + 1 == b.index {
                let mut left = self.stack.pop().expect("a top");
                for (ra, rb) in left.moments.iter_mut().zip(&b.moments) {
                    for (x, y) in ra.iter_mut().zip(rb) {
                        x.combine(y);
                    }
                }
                left.level += 1;
                left.index /= 2;
                b = left;
            } else {
                break;
            }
        }
        self.stack.push(b);
    }

    /// The maximal aligned blocks of the chunks pushed, in chunk order.
    pub fn into_blocks(self) -> Vec<Block> {
        self.stack
    }

    /// All blocks combined from left to right (the same order for a run and a merge).
    pub fn total(&self) -> Option<ChunkState> {
        let mut it = self.stack.iter();
        let mut acc = it.next()?.moments.clone();
        for b in it {
            for (ra, rb) in acc.iter_mut().zip(&b.moments) {
                for (x, y) in ra.iter_mut().zip(rb) {
                    x.combine(y);
                }
            }
        }
        Some(acc)
    }
}

impl Moments {
    /// Merges `b` (later samples) into `self` (Pébay 2008, eqs. 2.1–2.4).
    pub fn combine(&mut self, b: &Moments) {
        let (fa, fb) = (self.failed + b.failed, self.class_changed + b.class_changed);
        let events = (
            self.overdamped + b.overdamped,
            self.unstable + b.unstable,
            self.other_branch + b.other_branch,
        );
        if b.n == 0 {
        } else if self.n == 0 {
            *self = *b;
        } else {
            let (na, nb) = (self.n as f64, b.n as f64);
            let n = na + nb;
            let d = b.mean - self.mean;
            let (d2, d3, d4) = (d * d, d * d * d, d * d * d * d);
            let m4 = self.m4
                + b.m4
                + d4 * na * nb * (na * na - na * nb + nb * nb) / (n * n * n)
                + 6.0 * d2 * (na * na * b.m2 + nb * nb * self.m2) / (n * n)
                + 4.0 * d * (na * b.m3 - nb * self.m3) / n;
            let m3 = self.m3
                + b.m3
                + d3 * na * nb * (na - nb) / (n * n)
                + 3.0 * d * (na * b.m2 - nb * self.m2) / n;
            let m2 = self.m2 + b.m2 + d2 * na * nb / n;
            self.mean += d * nb / n;
            self.m2 = m2;
            self.m3 = m3;
            self.m4 = m4;
            self.n += b.n;
        }
        self.failed = fa;
        self.class_changed = fb;
        (self.overdamped, self.unstable, self.other_branch) = events;
    }

    fn add(&mut self, x: f64) {
        let n1 = self.n as f64;
        self.n += 1;
        let n = self.n as f64;
        let d = x - self.mean;
        let dn = d / n;
        let dn2 = dn * dn;
        let t1 = d * dn * n1;
        self.mean += dn;
        self.m4 += t1 * dn2 * (n * n - 3.0 * n + 3.0) + 6.0 * dn2 * self.m2 - 4.0 * dn * self.m3;
        self.m3 += t1 * dn * (n - 2.0) - 3.0 * dn * self.m2;
        self.m2 += t1;
    }

    fn stat(&self) -> McStat {
        let n = self.n;
        let var = if n > 1 {
            self.m2 / (n - 1) as f64
        } else {
            f64::NAN
        };
        let std = var.sqrt();
        let (mean_ci, std_ci) = if n > 3 {
            let dof = (n - 1) as f64;
            let t = StudentsT::new(0.0, 1.0, dof).map_or(1.96, |d| d.inverse_cdf(0.975));
            let half = t * std / (n as f64).sqrt();
            // Asymptotic interval of σ from the sample kurtosis (normal outputs: κ = 3).
            let kurt = if self.m2 > 0.0 {
                n as f64 * self.m4 / (self.m2 * self.m2)
            } else {
                3.0
            };
            let se = ((kurt - (n as f64 - 3.0) / (n as f64 - 1.0)).max(0.0) / n as f64).sqrt();
            let z = Normal::standard().inverse_cdf(0.975);
            let lo = std * (1.0 - z * se).max(0.0).sqrt();
            let hi = std * (1.0 + z * se).sqrt();
            ((self.mean - half, self.mean + half), (lo, hi))
        } else {
            ((f64::NAN, f64::NAN), (f64::NAN, f64::NAN))
        };
        McStat {
            n,
            mean: if n > 0 { self.mean } else { f64::NAN },
            std,
            mean_ci,
            std_ci,
            failed: self.failed,
            class_changed: self.class_changed,
            overdamped: self.overdamped,
            unstable: self.unstable,
            other_branch: self.other_branch,
            quantiles: None,
        }
    }

    /// Values folded in.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Samples without a value.
    pub fn failed(&self) -> usize {
        self.failed
    }

    /// The event counts: class changed, overdamped, unstable, other branch.
    pub fn events(&self) -> [usize; 4] {
        [
            self.class_changed,
            self.overdamped,
            self.unstable,
            self.other_branch,
        ]
    }

    /// Mean and the sums of the 2nd, 3rd and 4th powers of deviations.
    pub fn central(&self) -> [f64; 4] {
        [self.mean, self.m2, self.m3, self.m4]
    }

    /// Counts one sample's events.
    fn count(&mut self, e: Events) {
        self.class_changed += usize::from(e.class_changed);
        self.overdamped += usize::from(e.overdamped);
        self.unstable += usize::from(e.unstable);
        self.other_branch += usize::from(e.other_branch);
    }
}

/// What happened to one sample at one speed, for one output.
#[derive(Debug, Clone, Copy, Default)]
pub struct Events {
    /// The output's mode has another class than the nominal one.
    pub class_changed: bool,
    /// The output's mode is overdamped.
    pub overdamped: bool,
    /// The sample's equilibrium is unstable.
    pub unstable: bool,
    /// The sample is on another branch than the nominal design.
    pub other_branch: bool,
}

/// Sample quantile of sorted values (linear interpolation between order statistics,
/// Hyndman & Fan's type 7).
pub fn sorted_quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        n => {
            let h = (n - 1) as f64 * q;
            let (lo, frac) = (h.floor() as usize, h - h.floor());
            let hi = (lo + 1).min(n - 1);
            sorted[lo] + frac * (sorted[hi] - sorted[lo])
        }
    }
}

/// Element `i` of a pseudo-random permutation of `0..len` chosen by `key` (Kensler 2013,
/// *Correlated Multi-Jittered Sampling*, Pixar technical memo 13-01, `permute`): a hash that is
/// a bijection on the next power of two, walked until it lands in range. The Latin hypercube's
/// strata come from it in constant memory, whatever the number of samples (`len ≤ 2³²`).
pub fn permute(mut i: u32, len: u32, key: u32) -> u32 {
    debug_assert!(len > 0 && i < len);
    let p = key;
    let mut w = len.wrapping_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            return ((i as u64 + p as u64) % len as u64) as u32;
        }
    }
}

/// Design-variable values of sample `index` (the study's variables, in the order of the
/// spread).
pub struct Sampler {
    map: DesignMap,
    /// Number of design variables.
    dims: usize,
    opt: McOptions,
    /// Latin hypercube: the key of variable v's permutation of the strata ([`permute`]).
    strata: Vec<u32>,
}

impl Sampler {
    /// The samples of the study's variables under `spread`.
    pub fn new(study: &Study, spread: &Spread, opt: McOptions) -> Sampler {
        let n = study.vars.len();
        // One permutation key per variable, drawn from a stream reserved for it.
        let strata = (0..n)
            .map(|v| {
                let mut rng = ChaCha8Rng::seed_from_u64(opt.seed);
                rng.set_stream(u64::MAX - v as u64);
                rng.random::<u32>()
            })
            .collect();
        Sampler {
            map: DesignMap::new(
                study.model.model().nominal(),
                study.vars.clone(),
                spread.clone(),
            ),
            dims: n,
            opt,
            strata,
        }
    }

    /// Uniform numbers in (0, 1), one per variable, for sample `index`.
    fn uniforms(&self, index: usize) -> Vec<f64> {
        let n = self.dims;
        let clamp = |u: f64| u.clamp(1e-12, 1.0 - 1e-12);
        match self.opt.sampling {
            Sampling::Sobol => (0..n)
                .map(|d| {
                    clamp(
                        sobol_burley::sample(index as u32, d as u32, self.opt.seed as u32) as f64
                            + 0.5 / (1u64 << 24) as f64,
                    )
                })
                .collect(),
            Sampling::Random | Sampling::Lhs => {
                let mut rng = ChaCha8Rng::seed_from_u64(self.opt.seed);
                rng.set_stream(index as u64);
                (0..n)
                    .map(|v| {
                        let u: f64 = rng.random();
                        if self.opt.sampling == Sampling::Lhs {
                            let stratum =
                                permute(index as u32, self.opt.samples as u32, self.strata[v]);
                            clamp((stratum as f64 + u) / self.opt.samples as f64)
                        } else {
                            clamp(u)
                        }
                    })
                    .collect()
            }
        }
    }

    /// All parameter values of sample `index`.
    pub fn parameters(&self, index: usize) -> Vec<f64> {
        let u = self.uniforms(index);
        let normal = Normal::standard();
        let z: Vec<f64> = u.iter().map(|&x| normal.inverse_cdf(x)).collect();
        self.map.parameters(&z, &u)
    }
}

/// One sample's outputs, `[speed][output]` flattened (one allocation per sample, freed by
/// the thread that folds it): the value (NaN where the output or the whole point failed) and
/// what happened to the sample there.
type SampleResult = Vec<(f64, Events)>;

/// Sweeps the design `p` across the study's speeds and reads every output there, with what
/// happened to the sample.
fn run_sample(study: &Study, p: Vec<f64>, run: (Tier, &Workspace)) -> SampleResult {
    let outs = &study.outputs;
    let mut out = Vec::with_capacity(study.speeds.len() * outs.len());
    sample_sweep(
        study.model,
        p,
        &study.speeds,
        &study.nominal,
        run,
        |i, pts| {
            let Some((nom, pt, switches)) = pts else {
                out.extend(std::iter::repeat_n(
                    (f64::NAN, Events::default()),
                    outs.len(),
                ));
                return;
            };
            let tf = study.transfer_at(i);
            let unstable = !pt.stable();
            let other_branch = switches != study.branches[i];
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
                (value(pt, o, tf).unwrap_or(f64::NAN), events)
            }));
        },
    );
    out
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

/// The Monte Carlo as a propagation method: the samples of `chunks` (samples
/// `CHUNK·i .. CHUNK·(i+1)` of chunk `i`), each a whole sweep, their moments folded along the
/// fixed tree (see the module documentation).
#[derive(Debug, Clone)]
pub struct MonteCarlo {
    pub options: McOptions,
    /// The chunks evaluated here: all of them, or one shard's.
    pub chunks: std::ops::Range<usize>,
    /// Keep every value for the 5/50/95 % quantiles (a whole run, unless more than
    /// [`MAX_KEPT_VALUES`] values would be kept).
    pub quantiles: bool,
}

/// What a [`MonteCarlo`] run gives.
#[derive(Debug, Clone)]
pub struct McResult {
    /// Each chunk's moments, in chunk order (folded).
    pub fold: TreeFold,
    /// Statistics `[speed][output]` of the chunks done, with the quantiles where they were
    /// kept.
    pub stats: Vec<Vec<McStat>>,
    /// Samples evaluated (fewer than asked where the run was cancelled).
    pub samples: usize,
}

impl MonteCarlo {
    /// All samples of `options`.
    pub fn whole(options: McOptions) -> MonteCarlo {
        MonteCarlo {
            options,
            chunks: 0..chunks(options.samples),
            quantiles: true,
        }
    }

    /// The chunks of shard `k` (0-based) of `n` ([`shard_chunks`]), no quantiles.
    pub fn shard(options: McOptions, k: usize, n: usize) -> MonteCarlo {
        MonteCarlo {
            options,
            chunks: shard_chunks(options.samples, k, n),
            quantiles: false,
        }
    }

    /// Evaluates the chunks and folds each chunk's moments `[speed][output]` in chunk order
    /// ([`TreeFold`]); stops early (fewer chunks, [`Termination::Cancelled`]) when the run is
    /// cancelled. Progress counts the samples done in this call. With `values`, also keeps
    /// every finite value per `[speed · outputs + output]`, in sample order (for quantiles).
    fn run_chunks(
        &self,
        study: &Study,
        spread: &Spread,
        run: &Run,
        mut values: Option<&mut Vec<Vec<f32>>>,
    ) -> (TreeFold, Termination) {
        let opt = self.options;
        let (speeds, outs) = (study.speeds.len(), study.outputs.len());
        let sampler = Sampler::new(study, spread, opt);
        let here = (self.chunks.len() * CHUNK).min(opt.samples);
        let tier = Tier::for_points(here * speeds);
        let mut out = TreeFold::default();
        let mut done = 0;
        if let Some(v) = values.as_deref_mut() {
            v.resize(speeds * outs, Vec::new());
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
            for r in results {
                for (k, (m, &(v, events))) in acc.iter_mut().flatten().zip(&r).enumerate() {
                    if v.is_finite() {
                        m.add(v);
                        if let Some(vals) = values.as_deref_mut() {
                            vals[k].push(v as f32);
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
            });
            done += end - start;
            (run.progress)(done, opt.samples);
        }
        (out, Termination::Completed)
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

impl Propagation for MonteCarlo {
    type Value = McResult;

    fn propagate(&self, study: &Study, spread: &Spread, run: &Run) -> Estimate<McResult> {
        let (speeds, outs) = (study.speeds.len(), study.outputs.len());
        let samples = self.options.samples;
        let keep = self.quantiles && samples.saturating_mul(speeds * outs) <= MAX_KEPT_VALUES;
        let mut values = Vec::new();
        let (fold, termination) = self.run_chunks(study, spread, run, keep.then_some(&mut values));
        let (mut stats, done) = statistics(&fold, speeds, outs, samples);
        if keep {
            for (st, vals) in stats.iter_mut().flatten().zip(values) {
                let mut v: Vec<f64> = vals.into_iter().map(f64::from).collect();
                v.sort_by(f64::total_cmp);
                if !v.is_empty() {
                    st.quantiles = Some([0.05, 0.5, 0.95].map(|q| sorted_quantile(&v, q)));
                }
            }
        }
        Estimate {
            value: McResult {
                fold,
                stats,
                samples: done,
            },
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streaming_moments_match_two_pass() {
        let xs: Vec<f64> = (0..1000)
            .map(|i| ((i * 7919) % 1000) as f64 / 100.0 + (i as f64 * 0.37).sin().powi(3))
            .collect();
        let mut w = Moments::default();
        xs.iter().for_each(|&x| w.add(x));
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let m2: f64 = xs.iter().map(|x| (x - mean).powi(2)).sum();
        let m3: f64 = xs.iter().map(|x| (x - mean).powi(3)).sum();
        let m4: f64 = xs.iter().map(|x| (x - mean).powi(4)).sum();
        assert!((w.mean - mean).abs() < 1e-12 * mean.abs());
        assert!((w.m2 - m2).abs() < 1e-10 * m2);
        assert!((w.m3 - m3).abs() < 1e-8 * m3.abs().max(m2));
        assert!((w.m4 - m4).abs() < 1e-10 * m4);
        // Combining two halves gives the moments of the whole.
        let (mut a, mut b) = (Moments::default(), Moments::default());
        xs[..377].iter().for_each(|&x| a.add(x));
        xs[377..].iter().for_each(|&x| b.add(x));
        a.combine(&b);
        assert_eq!(a.n, w.n);
        assert!((a.mean - w.mean).abs() < 1e-12 * w.mean.abs());
        assert!((a.m2 - w.m2).abs() < 1e-10 * w.m2);
        assert!((a.m3 - w.m3).abs() < 1e-8 * w.m3.abs().max(w.m2));
        assert!((a.m4 - w.m4).abs() < 1e-10 * w.m4);
        // Normal-like data: the σ interval is close to the χ² one, about ±1.96/√(2n).
        let s = w.stat();
        assert!(s.std_ci.0 < s.std && s.std < s.std_ci.1);
    }
}
