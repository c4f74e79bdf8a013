//! Gathering the shards of one run, and the analysis that merges them.

use super::check::Layout;
use super::file::{MAX_BYTES, ShardError, ShardFile, output_count};
use super::fingerprint::{Fingerprint, RunSettings};
use crate::analyze::AnalyzeOptions;
use crate::model::{Case, Model, SpeedRange};
use crate::montecarlo::Split;
use crate::montecarlo::{CaseShard, Kept, McOptions};
use std::path::PathBuf;

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
        quadrature: run.quadrature,
        monte_carlo: Some(mc),
        split: Split::Merged(states),
        sobol: None,
        ..base
    };
    Ok((opt, mc))
}

/// The shards of one run, gathered: what a merge folds.
#[derive(Debug)]
pub struct Gathered {
    /// The run's settings.
    pub run: RunSettings,
    /// Per case, all blocks in chunk order.
    pub states: Vec<CaseShard>,
    /// The wall time of the shards' Monte Carlos, summed (s): what one process would have
    /// taken; `None` where a shard does not say (written before it was kept).
    pub monte_carlo_seconds: Option<f64>,
}

/// Checks that `files` (path, parsed shard) are shards `1..=N` of one run, each once, made from
/// `fingerprint`, and gathers them.
pub fn gather(
    files: Vec<(String, ShardFile)>,
    fingerprint: &Fingerprint,
) -> Result<Gathered, ShardError> {
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
        let listed: Vec<String> = got.iter().map(|k| k.to_string()).collect();
        let missing: Vec<String> = (1..=run.of)
            .filter(|k| !got.contains(k))
            .map(|k| ShardFile::name(k - 1, run.of))
            .collect();
        let missing = match missing.is_empty() {
            true => String::new(),
            false => format!("; missing {}", missing.join(", ")),
        };
        return Err(ShardError {
            file: "merge".into(),
            message: format!(
                "needs shards 1 to {} of {}, once each; got shard{} {}{missing}",
                run.of,
                run.of,
                if got.len() == 1 { "" } else { "s" },
                listed.join(", ")
            ),
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
    let seconds = (files.iter())
        .map(|(_, f)| f.monte_carlo_seconds)
        .sum::<Option<f64>>();
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
    Ok(Gathered {
        run,
        states: out,
        monte_carlo_seconds: seconds,
    })
}

/// Reads and verifies the shard files `paths` of one run of `model` with `cases` and gathers
/// them ([`verify`]).
pub fn read_all(model: &Model, cases: &[Case], paths: &[PathBuf]) -> Result<Gathered, ShardError> {
    let texts = paths
        .iter()
        .map(|p| read_text(p))
        .collect::<Result<_, _>>()?;
    verify(model, cases, texts)
}

/// The names of the tolerance cases the shard at `path` was run with (empty for a shard
/// written before they were kept): what `merge` runs without `--case`.
pub fn cases_run(path: &std::path::Path) -> Result<Vec<String>, ShardError> {
    let (name, text) = read_text(path)?;
    Ok(ShardFile::parse(&text, &name)?.case_names)
}

/// A shard file's name (as messages give it) and text, within [`MAX_BYTES`].
fn read_text(path: &std::path::Path) -> Result<(String, String), ShardError> {
    let name = path.display().to_string();
    let refuse = |message: String| ShardError {
        file: name.clone(),
        message,
    };
    let bytes = crate::files::read_bounded(path, MAX_BYTES)
        .map_err(|e| refuse(format!("cannot read: {}", e.source)))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| refuse("not a modaltol shard file (not UTF-8)".into()))?;
    Ok((name, text))
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
) -> Result<Gathered, ShardError> {
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
        let layout = Layout {
            speeds,
            outputs: output_count(model),
            cases: cases.len(),
            requirements: model.requirements.len(),
        };
        f.check(name, &fingerprint, layout)?;
    }
    gather(files, &fingerprint)
}
