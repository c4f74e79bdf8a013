//! Shard files: one share of a Monte Carlo run split across batch jobs (`analyze --shard K/N`),
//! and their verification before `merge` combines them into exactly the result of one run.
//!
//! A shard keeps, per tolerance case, the maximal aligned blocks of chunk moments of its range
//! of chunks (see [`crate::montecarlo::TreeFold`]): a few per level, so a file's size does not
//! grow with the number of samples. Shard files travel between machines and are read back, so
//! `merge` trusts nothing in them:
//!
//! * a SHA-256 digest of the whole content (with the digest field empty) catches any edit or
//!   truncation; the model fingerprint is a SHA-256 too (a stable hash: std's `DefaultHasher`
//!   may change between Rust releases);
//! * the blocks of shard `K` must be exactly the layout of shard `K`'s chunks, so a shard
//!   relabelled as another (even with a recomputed digest) is refused;
//! * every count and moment must be possible: `n + failed` equals the block's samples, every
//!   event count lies within them, `m2, m4 ≥ 0`, all numbers finite, the dimensions those of
//!   the model's outputs at the run's speeds.

use crate::analyze::Analysis;
use crate::model::{Case, Model, Sampling, SpeedRange};
use crate::montecarlo::{self, Block, McOptions, Moments};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Largest shard file read (a shard holds a few blocks of moments per case).
pub const MAX_BYTES: u64 = 1 << 30;

/// The outputs per speed of the model's Monte Carlo (as `analyze` makes them).
pub fn output_count(m: &Model) -> usize {
    crate::output::outputs(m.dof(), m.analysis.transfer.is_some()).len()
}

/// Format tag of shard files (2: aligned blocks, digest).
pub const FORMAT: &str = "modaltol-shard-2";

/// What `analyze --shard K/N` writes.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardFile {
    pub format: String,
    /// Identifies the model and its tolerance cases ([`fingerprint`]).
    pub fingerprint: String,
    /// The speed range, as `from:to:step` (rad/s).
    pub speed: String,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    /// 1-based shard number `K` of `of`.
    pub shard: usize,
    pub of: usize,
    /// Outputs per speed (ω_d and ζ per mode, then |H|).
    pub outputs: usize,
    /// Per tolerance case, the blocks of this shard's chunks, in chunk order.
    pub cases: Vec<Vec<Block>>,
    /// SHA-256 (hex) of the file's JSON with this field empty.
    #[serde(default)]
    pub digest: String,
}

/// Why a shard file is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {message}")]
pub struct ShardError {
    pub file: String,
    pub message: String,
}

/// A SHA-256 fingerprint of the model's parameters and the tolerance cases: shards made from
/// another model or other cases are refused by `merge`.
pub fn fingerprint(model: &Model, cases: &[crate::model::Case]) -> String {
    let mut bytes = Vec::new();
    bytes.extend(model.name.as_bytes());
    bytes.push(0);
    for p in &model.parameters {
        bytes.extend(p.name.as_bytes());
        bytes.push(0);
        bytes.extend(p.value.to_bits().to_le_bytes());
    }
    bytes.extend(format!("{cases:?}").as_bytes());
    crate::files::sha256_hex(&bytes)[..32].to_string()
}

impl ShardFile {
    /// Shard `k` (0-based) of `n` of the analysis `a` of `model` with `cases` over `speed`, run
    /// with `mc`; `None` when the run was interrupted before all of the shard's chunks were
    /// done (a shard is complete or absent).
    pub fn of_analysis(
        model: &Model,
        cases: &[Case],
        a: &Analysis,
        mc: McOptions,
        speed: &SpeedRange,
        (k, n): (usize, usize),
    ) -> Option<ShardFile> {
        let expect = montecarlo::shard_chunks(mc.samples, k, n);
        let complete = a
            .shard_states
            .iter()
            .all(|c| c.last().map_or(expect.start, |b| b.chunks().end) == expect.end);
        complete.then(|| ShardFile {
            format: FORMAT.into(),
            fingerprint: fingerprint(model, cases),
            speed: format!("{}:{}:{}", speed.from, speed.to, speed.step),
            samples: mc.samples,
            seed: mc.seed,
            sampling: mc.sampling,
            shard: k + 1,
            of: n,
            outputs: output_count(model),
            cases: a.shard_states.clone(),
            digest: String::new(),
        })
    }

    fn content_digest(&self) -> String {
        let mut unsealed = self.clone();
        unsealed.digest = String::new();
        let text = serde_json::to_vec(&unsealed).expect("a shard serialises");
        crate::files::sha256_hex(&text)
    }

    /// The file's JSON text, with its digest.
    pub fn to_json(&self) -> String {
        let mut sealed = self.clone();
        sealed.digest = self.content_digest();
        serde_json::to_string(&sealed).expect("a shard serialises")
    }

    /// Parses a shard file and checks its format and digest.
    pub fn parse(text: &str, file: &str) -> Result<ShardFile, ShardError> {
        let err = |message: String| ShardError {
            file: file.to_string(),
            message,
        };
        let f: ShardFile = serde_json::from_str(text)
            .map_err(|e| err(format!("not a modaltol shard file ({e})")))?;
        if f.format != FORMAT {
            return Err(err(format!(
                "shard format '{}', expected '{FORMAT}' (re-run the shard with this version)",
                f.format
            )));
        }
        if f.digest != f.content_digest() {
            return Err(err(
                "the content does not match its SHA-256 digest: the file was edited, truncated or corrupted".into(),
            ));
        }
        Ok(f)
    }

    /// Checks that the shard was made from the model and cases of `fingerprint`, and that every
    /// block and count is what shard `shard` of `of` must hold: `speeds` speeds, `outputs`
    /// outputs per speed, `cases` tolerance cases.
    pub fn check(
        &self,
        file: &str,
        fingerprint: &str,
        speeds: usize,
        outputs: usize,
        cases: usize,
    ) -> Result<(), ShardError> {
        let err = |message: String| ShardError {
            file: file.to_string(),
            message,
        };
        if self.fingerprint != fingerprint {
            return Err(err(
                "made from another model or other tolerance cases".into()
            ));
        }
        if self.of == 0 || self.shard == 0 || self.shard > self.of {
            return Err(err(format!(
                "shard {}/{} is not a shard",
                self.shard, self.of
            )));
        }
        if self.samples < 2 || self.samples > montecarlo::MAX_SAMPLES {
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
    let [mean, m2, m3, m4] = m.central();
    if ![mean, m2, m3, m4].iter().all(|v| v.is_finite()) {
        return Err("a moment is not finite".into());
    }
    if m2 < 0.0 || m4 < 0.0 {
        return Err(format!("negative sum of squares (m2 = {m2}, m4 = {m4})"));
    }
    if n == 0 && [mean, m2, m3, m4].iter().any(|&v| v != 0.0) {
        return Err("moments of no values".into());
    }
    Ok(())
}

/// The settings every shard of one run shares.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    pub speed: String,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    pub of: usize,
}

/// Checks that `files` (path, parsed shard) are shards `1..=N` of one run, each once, made from
/// `fingerprint`, and returns the run's settings and, per case, all blocks in chunk order.
pub fn gather(
    files: Vec<(String, ShardFile)>,
    fingerprint: &str,
) -> Result<(RunSettings, Vec<Vec<Block>>), ShardError> {
    let mut files = files;
    files.sort_by_key(|(_, f)| f.shard);
    let Some((first_path, first)) = files.first() else {
        return Err(ShardError {
            file: "merge".into(),
            message: "needs at least one shard file".into(),
        });
    };
    let settings = |f: &ShardFile| RunSettings {
        speed: f.speed.clone(),
        samples: f.samples,
        seed: f.seed,
        sampling: f.sampling,
        of: f.of,
    };
    let run = settings(first);
    for (path, f) in &files {
        if f.fingerprint != fingerprint {
            return Err(ShardError {
                file: path.clone(),
                message: "made from another model or other tolerance cases".into(),
            });
        }
        if settings(f) != run {
            return Err(ShardError {
                file: path.clone(),
                message: format!(
                    "shard {}/{} was run with other settings than {first_path} (shard {}/{})",
                    f.shard, f.of, first.shard, first.of
                ),
            });
        }
    }
    let got: Vec<usize> = files.iter().map(|(_, f)| f.shard).collect();
    if got != (1..=run.of).collect::<Vec<_>>() {
        return Err(ShardError {
            file: "merge".into(),
            message: format!("needs shards 1..={} once each, got {got:?}", run.of),
        });
    }
    let cases = first.cases.len();
    let mut blocks: Vec<Vec<Block>> = vec![Vec::new(); cases];
    for (_, f) in files {
        for (ci, b) in f.cases.into_iter().enumerate() {
            blocks[ci].extend(b);
        }
    }
    Ok((run, blocks))
}

/// Reads and verifies the shard files `paths` of one run of `model` with `cases` and gathers
/// them ([`gather`]).
pub fn read_all(
    model: &Model,
    cases: &[Case],
    paths: &[PathBuf],
) -> Result<(RunSettings, Vec<Vec<Block>>), ShardError> {
    let fingerprint = fingerprint(model, cases);
    let mut files = Vec::with_capacity(paths.len());
    for path in paths {
        let name = path.display().to_string();
        let refuse = |message: String| ShardError {
            file: name.clone(),
            message,
        };
        let bytes = crate::files::read_bounded(path, MAX_BYTES)
            .map_err(|e| refuse(format!("cannot read: {}", e.source)))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| refuse("not a modaltol shard file (not UTF-8)".into()))?;
        let f = ShardFile::parse(&text, &name)?;
        let speeds = SpeedRange::parse(&f.speed)
            .map_err(|e| refuse(format!("speed '{}': {e}", f.speed)))?
            .len();
        f.check(
            &name,
            &fingerprint,
            speeds,
            output_count(model),
            cases.len(),
        )?;
        files.push((name, f));
    }
    gather(files, &fingerprint)
}
