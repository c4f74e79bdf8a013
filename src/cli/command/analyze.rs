//! `modaltol analyze`.

use crate::cli::*;
use anyhow::{Context, Result};
use modaltol::analyze::analyze;
use modaltol::cancel::Cancel;
use modaltol::files::{AtomicFile, Inputs, ResultDir};
use modaltol::model::Sampling;
use modaltol::model::SpeedRange;
use modaltol::montecarlo::Split;
use modaltol::quadrature::QuadOptions;
use modaltol::request::{Request, Resolved, Speeds};
use modaltol::results::WriteOptions;
use modaltol::settings;
use modaltol::shard::{RunSettings, ShardFile};
use std::io::Write;
use std::path::Path;

/// `modaltol analyze` (see its `--help`).
pub(crate) fn analyze_command(
    args: AnalyzeArgs,
    set: &[(String, f64)],
    cancel: &Cancel,
) -> Result<()> {
    let request = args.request()?;
    let AnalyzeArgs {
        model,
        output,
        quadrature_tolerance,
        quadrature_nodes,
        no_quadrature,
        shard,
        display,
        ..
    } = args;
    // The settings that need no model first: a bad flag is reported before a slow load.
    let chosen = !request.cases.is_empty();
    let request = request.check().map_err(|e| refused(e, &shard, chosen))?;
    let m = model_or_governor(&model, set)?;
    let Resolved {
        options: opt,
        range,
        target_yield,
    } = request
        .resolve(m.model(), cancel.clone())
        .map_err(|e| refused(e, &shard, chosen))?;
    let m = match target_yield {
        Some(y) => m.with_target_yield(y),
        None => m,
    };
    let display = display.of(&opt.cases)?;
    note_unresolved_target(&m, opt.monte_carlo.as_ref());
    let (mc, split) = (opt.monte_carlo, opt.split.clone());
    // Fail early where the results cannot be written.
    let inputs = Inputs::new(&model.iter().collect::<Vec<_>>());
    let destination = match split {
        Split::Shard(k, n) => {
            std::fs::create_dir_all(&output)
                .with_context(|| format!("{}: cannot create the directory", output.display()))?;
            let path = output.join(ShardFile::name(k, n));
            refuse_input(&inputs, &path)?;
            Destination::Shard(AtomicFile::create(&path)?, path)
        }
        _ => {
            refuse_input(&inputs, &output)?;
            Destination::Directory(protect(ResultDir::create(&output)?, inputs)?)
        }
    };
    let a = analyze(&m, &opt, &progress_printer());
    if let (Split::Shard(k, n), Some(mc)) = (&opt.split, mc) {
        let Destination::Shard(f, path) = destination else {
            unreachable!("a shard's destination is its file")
        };
        let quadrature = (!no_quadrature).then_some(QuadOptions {
            tolerance: quadrature_tolerance,
            nodes: quadrature_nodes,
        });
        let range = range.expect("a command-line analysis runs over a range");
        let run = RunSettings::new(&range, &mc, quadrature, *n);
        let file = ShardFile::of_analysis(m.model(), &opt.cases, &a, &run, *k);
        return write_shard(f, &path, file);
    }
    let Destination::Directory(dir) = destination else {
        unreachable!("a whole run's destination is a directory")
    };
    let o = WriteOptions {
        mc: mc.as_ref(),
        threads: opt.threads.unwrap_or_else(rayon::current_num_threads),
        display,
        allocation: None,
    };
    write_outputs(&m, &a, o, dir, &output)?;

    Ok(())
}

impl AnalyzeArgs {
    /// The request these flags make, its settings parsed but not yet checked.
    fn request(&self) -> Result<Request> {
        Ok(Request {
            speeds: match &self.speed {
                Some(s) => Speeds::Range(
                    SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
                ),
                None => Speeds::Model,
            },
            cases: self.cases.clone(),
            samples: self.samples,
            seed: self.seed,
            sampling: self.sampling.map(|s| match s {
                SamplingArg::Random => Sampling::Random,
                SamplingArg::Lhs => Sampling::Lhs,
                SamplingArg::Sobol => Sampling::Sobol,
            }),
            monte_carlo: !self.no_monte_carlo,
            quadrature: !self.no_quadrature,
            quadrature_tolerance: self.quadrature_tolerance,
            quadrature_nodes: self.quadrature_nodes,
            threads: self.threads,
            shard: (self.shard.as_deref())
                .map(|spec| settings::shard(spec).map_err(|e| InputError(format!("--shard {e}"))))
                .transpose()?,
            sobol: self.sobol,
            target_yield: self.target_yield,
        })
    }
}

/// Writes a shard's `file` to `f` at `path` and commits it; `None` (a run cut short) writes
/// nothing: a shard is complete or absent.
fn write_shard(mut f: AtomicFile, path: &Path, file: Option<ShardFile>) -> Result<()> {
    let Some(file) = file else {
        return Err(Interrupted(format!(
            "{} not written (a shard is complete or absent)",
            path.display()
        ))
        .into());
    };
    f.write_all(file.to_json().as_bytes())
        .with_context(|| format!("{}: cannot write", path.display()))?;
    f.commit()?;
    note!(
        "modaltol: wrote {}; combine the shards with `modaltol merge`",
        path.display()
    );
    Ok(())
}
