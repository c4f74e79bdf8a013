//! Shard files: one share of a Monte Carlo run split across batch jobs (`analyze --shard K/N`),
//! and their verification before `merge` combines them into exactly the result of one run.
//!
//! A shard keeps, per tolerance case, the maximal aligned blocks of chunk moments of its range
//! of chunks (see [`crate::montecarlo::TreeFold`]): a few per level, so a file's size does not
//! grow with the number of samples. Shard files travel between machines and are read back, so
//! `merge` trusts nothing in them:
//!
//! * a SHA-256 digest of the whole content (with the digest field empty) catches any edit or
//!   truncation;
//! * a [`Fingerprint`] of everything the numbers depend on (the whole validated model, the
//!   tolerance cases, the speeds, samples, seed, sampling and the quadrature's options), one
//!   SHA-256 per section, so a shard of another model or run is refused naming what differs
//!   (SHA-256 is stable; std's `DefaultHasher` may change between Rust releases);
//! * the blocks of shard `K` must be exactly the layout of shard `K`'s chunks, so a shard
//!   relabelled as another (even with a recomputed digest) is refused;
//! * every count and moment must be possible: `n + failed` equals the block's samples, every
//!   event count lies within them, `m2, m4 ≥ 0`, all numbers finite, the dimensions those of
//!   the model's outputs at the run's speeds.

use crate::analyze::{Analysis, AnalyzeOptions, Split};
use crate::model::{Case, Model, Sampling, SpeedRange};
use crate::montecarlo::{self, Block, CaseShard, Kept, McOptions, Moments, MonteCarlo};
use crate::quadrature::QuadOptions;
use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

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
    /// 1-based shard number `K` of `of`.
    pub shard: usize,
    pub of: usize,
    /// Outputs per speed (ω_d and ζ per mode, then |H|).
    pub outputs: usize,
    /// Per tolerance case, the blocks of this shard's chunks, in chunk order.
    pub cases: Vec<Vec<Block>>,
    /// Per tolerance case, its samples' values for the quantiles ([`Kept`]), where the run
    /// keeps them ([`MonteCarlo::keeps`]; empty otherwise): so the merge's quantiles are
    /// one run's.
    #[serde(default)]
    pub kept: Vec<KeptFile>,
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
    fn of(k: &Kept) -> KeptFile {
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
    fn decode(&self) -> Result<Kept, String> {
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

/// What a shard was computed from, section by section: for each top-level part of the
/// validated model (its serialisation, see [`Model`]: `name`, `parameters`, `gravity`,
/// `bodies`, `joints`, `forces`, `constraints`, `ports`, `independent`, `analysis`, …), the
/// tolerance cases run (`cases`) and each run setting (`speed`, `samples`, `seed`,
/// `sampling`, `quadrature`), the first 32 hex digits of the SHA-256 of its canonical JSON.
/// Where the model was written (file, lines, columns, comments) is no part of it; every
/// number the model holds is, bit for bit. Two shards with equal fingerprints computed the
/// same numbers; where they differ, [`Fingerprint::differences`] names what.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint(pub BTreeMap<String, String>);

impl Fingerprint {
    /// The fingerprint of a run of `model` with `cases` and the settings `run` (its shard
    /// count left out: [`gather`] checks that).
    pub fn of(model: &Model, cases: &[Case], run: &RunSettings) -> Fingerprint {
        let mut sections = BTreeMap::new();
        let mut add = |name: &str, value: serde_json::Value| {
            let text = serde_json::to_string(&value).expect("a JSON value serialises");
            sections.insert(
                name.to_string(),
                crate::files::sha256_hex(text.as_bytes())[..32].to_string(),
            );
        };
        let model = serde_json::to_value(model).expect("a model serialises");
        let serde_json::Value::Object(parts) = model else {
            unreachable!("a model serialises to an object")
        };
        for (name, value) in parts {
            add(&name, value);
        }
        add("cases", json(&cases));
        add("speed", json(&run.speed));
        add("samples", json(&run.samples));
        add("seed", json(&run.seed));
        add("sampling", json(&run.sampling));
        add("quadrature", json(&run.quadrature));
        Fingerprint(sections)
    }

    /// The sections in which `other` differs from `self` (present in one only, or with
    /// another digest), as readers know them.
    pub fn differences(&self, other: &Fingerprint) -> Vec<&'static str> {
        let names: std::collections::BTreeSet<&String> =
            self.0.keys().chain(other.0.keys()).collect();
        let mut out: Vec<&'static str> = Vec::new();
        for k in names {
            let title = section_title(k);
            if self.0.get(k) != other.0.get(k) && !out.contains(&title) {
                out.push(title);
            }
        }
        out
    }
}

fn json(v: &impl Serialize) -> serde_json::Value {
    serde_json::to_value(v).expect("a plain value serialises")
}

/// What a fingerprint's section is called in messages.
fn section_title(section: &str) -> &'static str {
    match section {
        "name" => "model name",
        "parameters" => "parameters (values, tolerances, distributions; --set)",
        "gravity" => "gravity",
        "bodies" => "bodies",
        "joints" | "order" | "coordinates" => "joints",
        "forces" => "force elements",
        "constraints" => "constraints (cut joints)",
        "ports" => "ports",
        "loads" => "loads",
        "couplers" => "couplers",
        "requirements" => "requirements",
        "allocation" => "[allocation] table",
        "independent" => "independent coordinates",
        "analysis" => "[analysis] table",
        "cases" => "tolerance cases (--case)",
        "speed" => "speeds (--speed)",
        "samples" => "samples (--samples)",
        "seed" => "seed (--seed)",
        "sampling" => "sampling (--sampling)",
        "quadrature" => "quadrature options (--quadrature-tolerance, --no-quadrature)",
        _ => "a part this version of modaltol does not know",
    }
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
            quadrature: run.quadrature,
            shard: k + 1,
            of: run.of,
            outputs: output_count(model),
            cases: a.shard_states.iter().map(|c| c.blocks.clone()).collect(),
            kept: (a.shard_states.iter())
                .filter_map(|c| c.kept.as_ref().map(KeptFile::of))
                .collect(),
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
            quadrature: self.quadrature,
            of: self.of,
        }
    }

    /// Checks that the shard was computed from what `fingerprint` describes (naming what
    /// differs otherwise), and that every block and count is what shard `shard` of `of` must
    /// hold: `speeds` speeds, `outputs` outputs per speed, `cases` tolerance cases.
    pub fn check(
        &self,
        file: &str,
        fingerprint: &Fingerprint,
        speeds: usize,
        outputs: usize,
        cases: usize,
        requirements: usize,
    ) -> Result<(), ShardError> {
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
        self.check_kept(speeds, outputs, cases, requirements)
            .map_err(err)
    }

    /// The kept values: one set per case where the run keeps them (none otherwise), each
    /// value finite, as many per output as its blocks count values, and per requirement one
    /// worst margin per sample.
    fn check_kept(
        &self,
        speeds: usize,
        outputs: usize,
        cases: usize,
        requirements: usize,
    ) -> Result<(), String> {
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

/// The settings every shard of one run shares.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// The speed range, as `from:to:step` (rad/s).
    pub speed: String,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    /// The quadrature's requested relative error; `None`: no quadrature.
    pub quadrature: Option<f64>,
    /// The number of shards.
    pub of: usize,
}

impl RunSettings {
    /// The settings of a sharded run over `speed` with the Monte Carlo options `mc`, the
    /// quadrature's tolerance `quadrature` (`None`: none) split into `of` shards.
    pub fn new(speed: &SpeedRange, mc: &McOptions, quadrature: Option<f64>, of: usize) -> Self {
        RunSettings {
            speed: format!("{}:{}:{}", speed.from, speed.to, speed.step),
            samples: mc.samples,
            seed: mc.seed,
            sampling: mc.sampling,
            quadrature,
            of,
        }
    }
}

/// The analysis that merges shards of the run `run` (their gathered `states`): `base`'s cases,
/// threads and cancel token with the run's speeds, Monte Carlo and quadrature, folded as one
/// run would. What `merge` runs, from the command line or Python; refused where the run's
/// speeds are not a range of at most [`crate::settings::analysis_speeds`].
pub fn merged_options(
    run: &RunSettings,
    states: Vec<CaseShard>,
    base: AnalyzeOptions,
) -> Result<(AnalyzeOptions, McOptions), String> {
    let range = SpeedRange::parse(&run.speed)?;
    crate::settings::analysis_speeds(range.len())?;
    let mc = McOptions {
        samples: run.samples,
        seed: run.seed,
        sampling: run.sampling,
    };
    let opt = AnalyzeOptions {
        speeds: range.speeds().collect(),
        // The quadrature of the run the shards belong to.
        quadrature: run.quadrature.map(|tolerance| QuadOptions { tolerance }),
        monte_carlo: Some(mc),
        split: Split::Merged(states),
        sobol: None,
        ..base
    };
    Ok((opt, mc))
}

/// Checks that `files` (path, parsed shard) are shards `1..=N` of one run, each once, made from
/// `fingerprint`, and returns the run's settings and, per case, all blocks in chunk order.
pub fn gather(
    files: Vec<(String, ShardFile)>,
    fingerprint: &Fingerprint,
) -> Result<(RunSettings, Vec<CaseShard>), ShardError> {
    let mut files = files;
    files.sort_by_key(|(_, f)| f.shard);
    let Some((first_path, first)) = files.first() else {
        return Err(ShardError {
            file: "merge".into(),
            message: "needs at least one shard file".into(),
        });
    };
    let run = first.run();
    for (path, f) in &files {
        if &f.fingerprint != fingerprint {
            return Err(ShardError {
                file: path.clone(),
                message: format!(
                    "made from another model, other tolerance cases or other settings: its {} \
                     differ from the merge's",
                    fingerprint.differences(&f.fingerprint).join(", ")
                ),
            });
        }
        if f.run() != run {
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
    let keeps = !first.kept.is_empty();
    let mut out: Vec<CaseShard> = (0..cases)
        .map(|_| CaseShard {
            blocks: Vec::new(),
            kept: keeps.then(Kept::default),
        })
        .collect();
    for (path, f) in files {
        if f.kept.is_empty() == keeps {
            return Err(ShardError {
                file: path,
                message: "kept values where the first shard has none, or none where it has".into(),
            });
        }
        for (ci, k) in f.kept.iter().enumerate() {
            let k = k.decode().map_err(|message| ShardError {
                file: path.clone(),
                message,
            })?;
            if let Some(all) = out[ci].kept.as_mut() {
                all.extend(k);
            }
        }
        for (ci, b) in f.cases.into_iter().enumerate() {
            out[ci].blocks.extend(b);
        }
    }
    Ok((run, out))
}

/// Reads and verifies the shard files `paths` of one run of `model` with `cases` and gathers
/// them ([`verify`]).
pub fn read_all(
    model: &Model,
    cases: &[Case],
    paths: &[PathBuf],
) -> Result<(RunSettings, Vec<CaseShard>), ShardError> {
    let mut texts = Vec::with_capacity(paths.len());
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
        texts.push((name, text));
    }
    verify(model, cases, texts)
}

/// Parses and verifies shards given as `(name, text)` (the name says which in messages) of one
/// run of `model` with `cases`, and gathers them ([`gather`]): what `merge` does with files,
/// for shards that travelled as text (the Python package's executors). The run's settings are
/// those of the lowest-numbered shard; every shard must have been computed from `model`,
/// `cases` and those settings ([`Fingerprint`]).
pub fn verify(
    model: &Model,
    cases: &[Case],
    texts: Vec<(String, String)>,
) -> Result<(RunSettings, Vec<CaseShard>), ShardError> {
    let mut files = Vec::with_capacity(texts.len());
    for (name, text) in texts {
        let f = ShardFile::parse(&text, &name)?;
        files.push((name, f));
    }
    let Some((_, first)) = files.iter().min_by_key(|(_, f)| f.shard) else {
        return Err(ShardError {
            file: "merge".into(),
            message: "needs at least one shard file".into(),
        });
    };
    let fingerprint = Fingerprint::of(model, cases, &first.run());
    for (name, f) in &files {
        // The speeds analysed: the range's, with the requirements' range ends
        // (`Model::judged_speeds`), as the run that wrote the shard had them.
        let range = SpeedRange::parse(&f.speed)
            .map_err(|e| e.to_string())
            .and_then(|r| crate::settings::analysis_speeds(r.len()).map(|_| r))
            .map_err(|e| ShardError {
                file: name.clone(),
                message: format!("speed '{}': {e}", f.speed),
            })?;
        let speeds = model
            .judged_speeds(&range.speeds().collect::<Vec<_>>())
            .len();
        f.check(
            name,
            &fingerprint,
            speeds,
            output_count(model),
            cases.len(),
            model.requirements.len(),
        )?;
    }
    gather(files, &fingerprint)
}
