//! The shard file: what `analyze --shard K/N` writes, and how it is read back.

use super::fingerprint::{Fingerprint, RunSettings};
use crate::analyze::Analysis;
use crate::model::{Case, Model, Sampling};
use crate::montecarlo::{self, Block, Kept};
use crate::quadrature::QuadOptions;
use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde::{Deserialize, Serialize};

/// Largest shard file read (a shard holds a few blocks of moments per case).
pub const MAX_BYTES: u64 = 1 << 30;

/// The outputs per speed of the model's Monte Carlo ([`crate::output::of_model`], as `analyze`
/// makes them).
pub fn output_count(m: &Model) -> usize {
    crate::output::of_model(m).len()
}

/// Format tag of shard files (2: aligned blocks, digest; 3: the fingerprint by section, the
/// quadrature's options; 4: the requirements' prefix counts; 5: the values kept for the
/// quantiles).
pub const FORMAT: &str = "modaltol-shard-5";

/// What `analyze --shard K/N` writes.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardFile {
    pub format: String,
    /// What the shard was computed from ([`Fingerprint`]).
    pub fingerprint: Fingerprint,
    /// The speed range, as `from:to:step` (rad/s).
    pub speed: String,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    /// The quadrature's requested relative error of the run the shard belongs to (`merge`
    /// runs the quadrature with it); `None`: the run has no quadrature (`--no-quadrature`).
    pub quadrature: Option<f64>,
    /// The most nodes that quadrature may sweep per case, where asked (`--quadrature-nodes`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadrature_nodes: Option<usize>,
    /// 1-based shard number `K` of `of`.
    pub shard: usize,
    pub of: usize,
    /// Outputs per speed (ω_d and ζ per mode, then |H|).
    pub outputs: usize,
    /// Per tolerance case, the blocks of this shard's chunks, in chunk order.
    pub cases: Vec<Vec<Block>>,
    /// The names of the tolerance cases run, in order (as `analyze --case` chose them), so that
    /// `merge` needs no `--case`; absent from shards written before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub case_names: Vec<String>,
    /// Per tolerance case, its samples' values for the quantiles ([`Kept`]), where the run
    /// keeps them ([`crate::montecarlo::MonteCarlo::keeps`]; empty otherwise): so the merge's quantiles are
    /// one run's.
    #[serde(default)]
    pub kept: Vec<KeptFile>,
    /// The wall time this shard's Monte Carlo took (s): `merge` reports the shards' total, not
    /// its own fold (absent from shards written before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo_seconds: Option<f64>,
    /// SHA-256 (hex) of the file's JSON with this field empty.
    #[serde(default)]
    pub digest: String,
}

/// A case's kept values in a shard file: per `[speed · outputs + output]` its samples' finite
/// values (`f32`, infinite beyond its range as in the run) and per requirement their worst margins (`f64`), in sample order, each list
/// the base64 of its little-endian bytes: exact, and a third of decimal text's size.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct KeptFile {
    pub values: Vec<String>,
    pub worst: Vec<String>,
}

impl KeptFile {
    pub(super) fn of(k: &Kept) -> KeptFile {
        KeptFile {
            values: (k.values.iter())
                .map(|v| BASE64.encode(v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>()))
                .collect(),
            worst: (k.worst.iter())
                .map(|v| BASE64.encode(v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>()))
                .collect(),
        }
    }

    /// The values, or why they cannot be read.
    pub(super) fn decode(&self) -> Result<Kept, String> {
        let bytes = |s: &String, width: usize| -> Result<Vec<u8>, String> {
            let b = BASE64
                .decode(s)
                .map_err(|e| format!("kept values are not base64 ({e})"))?;
            if b.len() % width != 0 {
                return Err("kept values cut short".into());
            }
            Ok(b)
        };
        let values = (self.values.iter())
            .map(|s| {
                Ok(bytes(s, 4)?
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect())
            })
            .collect::<Result<Vec<Vec<f32>>, String>>()?;
        let worst = (self.worst.iter())
            .map(|s| {
                Ok(bytes(s, 8)?
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().expect("eight bytes")))
                    .collect())
            })
            .collect::<Result<Vec<Vec<f64>>, String>>()?;
        Ok(Kept { values, worst })
    }
}

/// Why a shard file is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {message}")]
pub struct ShardError {
    pub file: String,
    pub message: String,
}

impl ShardFile {
    /// The file name of shard `k` (0-based) of `n`: `shard-K-of-N.json`, `K` from 1.
    pub fn name(k: usize, n: usize) -> String {
        format!("shard-{}-of-{n}.json", k + 1)
    }

    /// Shard `k` (0-based) of `run.of` of the analysis `a` of `model` with `cases`, run with
    /// the settings `run`; `None` when the run was interrupted before all of the shard's
    /// chunks were done (a shard is complete or absent).
    pub fn of_analysis(
        model: &Model,
        cases: &[Case],
        a: &Analysis,
        run: &RunSettings,
        k: usize,
    ) -> Option<ShardFile> {
        let expect = montecarlo::shard_chunks(run.samples, k, run.of);
        let complete = a
            .shard_states
            .iter()
            .all(|c| c.blocks.last().map_or(expect.start, |b| b.chunks().end) == expect.end);
        complete.then(|| ShardFile {
            format: FORMAT.into(),
            fingerprint: Fingerprint::of(model, cases, run),
            speed: run.speed.clone(),
            samples: run.samples,
            seed: run.seed,
            sampling: run.sampling,
            quadrature: run.quadrature.map(|q| q.tolerance),
            quadrature_nodes: run.quadrature.and_then(|q| q.nodes),
            shard: k + 1,
            of: run.of,
            outputs: output_count(model),
            cases: a.shard_states.iter().map(|c| c.blocks.clone()).collect(),
            case_names: cases.iter().map(|c| c.name.clone()).collect(),
            kept: (a.shard_states.iter())
                .filter_map(|c| c.kept.as_ref().map(KeptFile::of))
                .collect(),
            monte_carlo_seconds: a.monte_carlo_seconds,
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

    /// The settings of the run this shard belongs to.
    pub fn run(&self) -> RunSettings {
        RunSettings {
            speed: self.speed.clone(),
            samples: self.samples,
            seed: self.seed,
            sampling: self.sampling,
            quadrature: self.quadrature.map(|tolerance| QuadOptions {
                tolerance,
                nodes: self.quadrature_nodes,
            }),
            of: self.of,
        }
    }
}
