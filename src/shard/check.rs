//! A shard file's checks: its fingerprint, its blocks' layout and every count and moment.

use super::file::{ShardError, ShardFile};
use super::fingerprint::Fingerprint;
use crate::montecarlo::{self, Moments, MonteCarlo};

/// What every shard of a run holds: so many speeds, outputs per speed, tolerance cases and
/// requirements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub speeds: usize,
    pub outputs: usize,
    pub cases: usize,
    pub requirements: usize,
}

impl ShardFile {
    /// Checks that the shard was computed from what `fingerprint` describes (naming what
    /// differs otherwise), and that every block and count is what shard `shard` of `of` of a
    /// run of `layout` must hold.
    pub fn check(
        &self,
        file: &str,
        fingerprint: &Fingerprint,
        expected: Layout,
    ) -> Result<(), ShardError> {
        let Layout {
            speeds,
            outputs,
            cases,
            ..
        } = expected;
        let err = |message: String| ShardError {
            file: file.to_string(),
            message,
        };
        let differ = fingerprint.differences(&self.fingerprint);
        if !differ.is_empty() {
            return Err(err(format!(
                "made from another model, other tolerance cases or other settings than the \
                 merge's: it differs in its {} (merge reads the model of --model with --set \
                 and --case, and the settings of the first shard; re-run the shard, or merge \
                 only shards of one run)",
                differ.join(", ")
            )));
        }
        if self.of == 0 || self.shard == 0 || self.shard > self.of {
            return Err(err(format!(
                "shard {}/{} is not a shard",
                self.shard, self.of
            )));
        }
        if self.samples < 2 || self.samples > crate::settings::MAX_SAMPLES {
            return Err(err(format!("{} samples is out of range", self.samples)));
        }
        if self.outputs != outputs {
            return Err(err(format!(
                "{} outputs per speed; the model has {outputs}",
                self.outputs
            )));
        }
        if self.cases.len() != cases {
            return Err(err(format!(
                "{} tolerance cases; the merge asks for {cases}",
                self.cases.len()
            )));
        }
        let range = montecarlo::shard_chunks(self.samples, self.shard - 1, self.of);
        let layout = montecarlo::block_layout(range.clone());
        for (ci, blocks) in self.cases.iter().enumerate() {
            let got: Vec<(u32, usize)> = blocks.iter().map(|b| (b.level, b.index)).collect();
            if got != layout {
                return Err(err(format!(
                    "case {}: its blocks do not cover chunks {}..{} of shard {}/{} (a shard relabelled, cut short or from another split)",
                    ci + 1,
                    range.start,
                    range.end,
                    self.shard,
                    self.of
                )));
            }
            for b in blocks {
                let c = b.chunks();
                let n = (c.end.saturating_mul(montecarlo::CHUNK)).min(self.samples)
                    - (c.start * montecarlo::CHUNK).min(self.samples);
                if b.moments.len() != speeds || b.moments.iter().any(|r| r.len() != outputs) {
                    return Err(err(format!(
                        "case {}: a block is not {speeds} speeds × {outputs} outputs",
                        ci + 1
                    )));
                }
                for m in b.moments.iter().flatten() {
                    if let Err(why) = plausible(m, n) {
                        return Err(err(format!(
                            "case {}, chunks {}..{}: {why}",
                            ci + 1,
                            c.start,
                            c.end
                        )));
                    }
                }
            }
        }
        self.check_kept(expected).map_err(err)
    }

    /// The kept values: one set per case where the run keeps them (none otherwise), each
    /// value finite, as many per output as its blocks count values, and per requirement one
    /// worst margin per sample.
    fn check_kept(&self, layout: Layout) -> Result<(), String> {
        let Layout {
            speeds,
            outputs,
            cases,
            requirements,
        } = layout;
        let want = if MonteCarlo::keeps(self.samples, speeds, outputs) {
            cases
        } else {
            0
        };
        if self.kept.len() != want {
            return Err(format!(
                "{} sets of kept values for {want} (the run keeps its values for the quantiles: {})",
                self.kept.len(),
                want > 0
            ));
        }
        for (ci, (k, blocks)) in self.kept.iter().zip(&self.cases).enumerate() {
            let kept = k
                .decode()
                .map_err(|why| format!("case {}: {why}", ci + 1))?;
            if kept.values.len() != speeds * outputs || kept.worst.len() != requirements {
                return Err(format!(
                    "case {}: kept values not for {speeds} speeds × {outputs} outputs and {requirements} requirement(s)",
                    ci + 1
                ));
            }
            for (j, v) in kept.values.iter().enumerate() {
                let n: usize = blocks
                    .iter()
                    .map(|b| b.moments[j / outputs][j % outputs].n())
                    .sum();
                // Kept as f32: a finite value beyond f32's range is kept infinite, as one run
                // keeps it (its quantiles are then none); NaN is no value of a sample.
                if v.len() != n || v.iter().any(|x| x.is_nan()) {
                    return Err(format!(
                        "case {}: the kept values of output {} at speed {} are not its {n} values",
                        ci + 1,
                        j % outputs + 1,
                        j / outputs + 1
                    ));
                }
            }
            let samples: usize = blocks
                .iter()
                .map(|b| {
                    let c = b.chunks();
                    (c.end.saturating_mul(montecarlo::CHUNK)).min(self.samples)
                        - (c.start * montecarlo::CHUNK).min(self.samples)
                })
                .sum();
            if kept
                .worst
                .iter()
                .any(|w| w.len() != samples || w.iter().any(|x| x.is_nan()))
            {
                return Err(format!(
                    "case {}: the kept worst margins are not one per sample ({samples})",
                    ci + 1
                ));
            }
        }
        Ok(())
    }
}

/// Can `m` be the moments of `samples` samples?
fn plausible(m: &Moments, samples: usize) -> Result<(), String> {
    let (n, failed) = (m.n(), m.failed());
    if n.checked_add(failed) != Some(samples) {
        return Err(format!("{n} values + {failed} failed ≠ {samples} samples"));
    }
    if m.events().iter().any(|&e| e > samples) {
        return Err(format!("an event count exceeds the {samples} samples"));
    }
    // The scale is a binary exponent of an f64 value (see `Moments`).
    if m.scale().abs() > 1100 {
        return Err(format!("a scale of 2^{} is no f64's", m.scale()));
    }
    // The mean is of values scaled to ordinary size; the higher moments may overflow where
    // one output's values span more than f64's range (the run reports no σ interval then).
    let [mean, m2, m3, m4] = m.central();
    if !mean.is_finite() {
        return Err("the mean is not finite".into());
    }
    if m2 < 0.0 || m4 < 0.0 {
        return Err(format!("negative sum of squares (m2 = {m2}, m4 = {m4})"));
    }
    if n == 0 && [mean, m2, m3, m4].iter().any(|&v| v != 0.0) {
        return Err("moments of no values".into());
    }
    Ok(())
}
