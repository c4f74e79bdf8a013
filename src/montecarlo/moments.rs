//! One-pass moments of the samples' outputs, combined chunk by chunk along a fixed tree
//! (Welford, Terriberry, Pébay), so that a run's result does not depend on its threads or shards.

use super::McStat;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Values from this binary magnitude on (or below its reciprocal) are folded in scaled: the
/// fourth power of a deviation of 2^256 is 2^1024, beyond `f64`.
const SCALE_FROM: i32 = 128;

/// One-pass central moments (Welford, extended to the fourth moment by Terriberry), with the
/// counts of failed and class-changed samples; combinable (Pébay's pairwise formulas).
///
/// The moments are of the values times `2^−scale`, `scale` the binary exponent of the first
/// value where that is at least 2^128 in size or below 2^−128 (0 otherwise, so values of
/// ordinary size are folded in as they are): an |H| or a frequency of 1e147 has a fourth central moment
/// beyond `f64`, which its scaled values keep. Scaling by a power of two is exact, so a run
/// whose values are scaled gives the statistics of the unscaled arithmetic where that does
/// not overflow. Blocks of different scales combine at the larger.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Moments {
    n: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    scale: i32,
    #[serde(with = "any_number")]
    mean: f64,
    #[serde(with = "any_number")]
    m2: f64,
    #[serde(with = "any_number")]
    m3: f64,
    #[serde(with = "any_number")]
    m4: f64,
    pub(super) failed: usize,
    class_changed: usize,
    #[serde(default)]
    overdamped: usize,
    #[serde(default)]
    unstable: usize,
    #[serde(default)]
    other_branch: usize,
}

/// Any `f64` in a shard file as it was computed: a finite number as a JSON number, an infinite
/// or NaN one as the text `"inf"`, `"-inf"` or `"NaN"` (JSON has no such numbers, and
/// `serde_json` writes them as `null`, which no `f64` reads back). The moments of outputs
/// whose deviations overflow (an |H| of 1e147 has a fourth central moment beyond `f64`) are
/// infinite; a merge must read them as the run that wrote them had them, and give the same
/// statistics as one run.
mod any_number {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_finite() {
            s.serialize_f64(*x)
        } else if x.is_nan() {
            s.serialize_str("NaN")
        } else if *x > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_str("-inf")
        }
    }

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Number(f64),
        Text(String),
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        match Written::deserialize(d)? {
            Written::Number(x) => Ok(x),
            Written::Text(t) => match t.as_str() {
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                "NaN" => Ok(f64::NAN),
                _ => Err(D::Error::custom(format!(
                    "expected a number, \"inf\", \"-inf\" or \"NaN\", found \"{t}\""
                ))),
            },
        }
    }
}

fn is_zero(k: &i32) -> bool {
    *k == 0
}

/// `x · 2^k`, exact where the result is a normal number (in two factors, each representable,
/// for `|k|` up to 2 · 1074).
fn times_two_to(x: f64, k: i32) -> f64 {
    let half = k / 2;
    x * 2f64.powi(half) * 2f64.powi(k - half)
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
    /// The requirements' tallies (models with requirements only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yields: Option<YieldCounts>,
}

/// How many samples of a block met the model's requirements: every one at every speed of its
/// range, each one, each one per speed (`[speed · requirements + requirement]`), each one at
/// every speed from its range's start up to each speed (`prefix`, same layout, beyond the
/// range's end too: the operating range it holds over), and the moments of each one's worst
/// margin over its range (designs with a finite margin).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct YieldCounts {
    pub all: usize,
    pub each: Vec<usize>,
    pub curves: Vec<usize>,
    pub prefix: Vec<usize>,
    pub margins: Vec<Moments>,
}

impl YieldCounts {
    /// Nothing counted, for `reqs` requirements at `speeds` speeds.
    pub fn new(reqs: usize, speeds: usize) -> YieldCounts {
        YieldCounts {
            all: 0,
            each: vec![0; reqs],
            curves: vec![0; reqs * speeds],
            prefix: vec![0; reqs * speeds],
            margins: vec![Moments::default(); reqs],
        }
    }

    /// Adds a later block's counts.
    pub fn combine(&mut self, b: &YieldCounts) {
        self.all += b.all;
        for (x, y) in self.each.iter_mut().zip(&b.each) {
            *x += y;
        }
        for (x, y) in self.curves.iter_mut().zip(&b.curves) {
            *x += y;
        }
        for (x, y) in self.prefix.iter_mut().zip(&b.prefix) {
            *x += y;
        }
        for (x, y) in self.margins.iter_mut().zip(&b.margins) {
            x.combine(y);
        }
    }

    /// Counts one sample from its margins `[speed · requirements + requirement]` (`+∞` before
    /// a requirement's range, `−∞` where the design has no point), which of them lie in the
    /// requirement's range (`covered`, same layout) and which requirements have a margin
    /// distribution; writes each requirement's worst margin over its range to `worst`.
    pub fn add(
        &mut self,
        margins: &[f64],
        covered: &[bool],
        has_margin: &[bool],
        worst: &mut [f64],
    ) {
        let reqs = self.each.len();
        let mut all = true;
        for (r, &with_margin) in has_margin.iter().enumerate().take(reqs) {
            let mut low = f64::INFINITY;
            let mut holds = true;
            for (i, m) in margins.iter().enumerate().skip(r).step_by(reqs) {
                holds &= *m >= 0.0;
                if holds {
                    self.prefix[i] += 1;
                }
                if !covered[i] {
                    continue;
                }
                low = low.min(*m);
                if *m >= 0.0 {
                    self.curves[i] += 1;
                }
            }
            worst[r] = low;
            let met = low >= 0.0;
            all &= met;
            self.each[r] += usize::from(met);
            if with_margin {
                if low.is_finite() {
                    self.margins[r].add(low);
                } else {
                    self.margins[r].failed += 1;
                }
            }
        }
        self.all += usize::from(all);
    }
}

fn combine_yields(a: &mut Option<YieldCounts>, b: &Option<YieldCounts>) {
    match (a.as_mut(), b) {
        (Some(x), Some(y)) => x.combine(y),
        (None, Some(y)) => *a = Some(y.clone()),
        _ => {}
    }
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
    pub(super) stack: Vec<Block>,
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
                combine_yields(&mut left.yields, &b.yields);
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

    /// The requirements' tallies of all blocks combined from left to right.
    pub fn total_yields(&self) -> Option<YieldCounts> {
        let mut acc = None;
        for b in &self.stack {
            combine_yields(&mut acc, &b.yields);
        }
        acc
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
            let scale = self.scale.max(b.scale);
            let b = &b.rescaled(scale);
            *self = self.rescaled(scale);
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

    /// The same moments at the scale `k ≥ self.scale`.
    fn rescaled(&self, k: i32) -> Moments {
        let f = k - self.scale;
        if f == 0 {
            return *self;
        }
        Moments {
            scale: k,
            mean: times_two_to(self.mean, -f),
            m2: times_two_to(self.m2, -2 * f),
            m3: times_two_to(self.m3, -3 * f),
            m4: times_two_to(self.m4, -4 * f),
            ..*self
        }
    }

    pub(super) fn add(&mut self, x: f64) {
        if self.n == 0 {
            let e = if x == 0.0 {
                0
            } else {
                x.abs().log2().floor() as i32
            };
            self.scale = if e.abs() >= SCALE_FROM { e } else { 0 };
        }
        let x = times_two_to(x, -self.scale);
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

    /// The statistics of the values folded in. Where the scaled moments themselves overflow
    /// (values spanning more than `f64`'s range in one output), σ is that of `m2` and the
    /// interval of σ, which needs `m4`, is NaN (none), never a number made of an overflow.
    pub(super) fn stat(&self) -> McStat {
        let unscaled = |x: f64| times_two_to(x, self.scale);
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
            let se = if kurt.is_finite() {
                ((kurt - (n as f64 - 3.0) / (n as f64 - 1.0)).max(0.0) / n as f64).sqrt()
            } else {
                f64::NAN
            };
            let z = Normal::standard().inverse_cdf(0.975);
            let std_ci = if se.is_finite() {
                (
                    unscaled(std * (1.0 - z * se).max(0.0).sqrt()),
                    unscaled(std * (1.0 + z * se).sqrt()),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            (
                (unscaled(self.mean - half), unscaled(self.mean + half)),
                std_ci,
            )
        } else {
            ((f64::NAN, f64::NAN), (f64::NAN, f64::NAN))
        };
        McStat {
            n,
            mean: if n > 0 { unscaled(self.mean) } else { f64::NAN },
            std: unscaled(std),
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

    /// The binary scale of the moments (see [`Moments`]).
    pub fn scale(&self) -> i32 {
        self.scale
    }

    /// Values folded in.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Mean and sample σ of the values folded in (NaN where there are too few).
    pub fn mean_std(&self) -> (f64, f64) {
        let s = self.stat();
        (s.mean, s.std)
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

    /// Mean and the sums of the 2nd, 3rd and 4th powers of deviations, of the values times
    /// `2^−scale` (see [`Moments`]).
    pub fn central(&self) -> [f64; 4] {
        [self.mean, self.m2, self.m3, self.m4]
    }

    /// Counts one sample's events.
    pub(super) fn count(&mut self, e: Events) {
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

#[cfg(test)]
mod tests;
