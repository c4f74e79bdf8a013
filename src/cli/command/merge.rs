//! `modaltol merge`.

use crate::cli::*;
use anyhow::Result;
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::cancel::Cancel;
use modaltol::files::{Inputs, ResultDir};
use modaltol::results::WriteOptions;
use std::path::PathBuf;

/// `modaltol merge` (see its `--help`).
pub(crate) fn merge_command(args: MergeArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let MergeArgs {
        model,
        output,
        shards,
        cases: only,
        target_yield,
        display,
    } = args;
    let target_yield = target_yield
        .map(|y| {
            modaltol::settings::target_yield(y)
                .map_err(|e| InputError(format!("--target-yield {e}")))
        })
        .transpose()?;
    let m = model_or_governor(&model, set)?;
    let m = match target_yield {
        Some(y) => m.with_target_yield(y),
        None => m,
    };
    // The shards know their cases (a shard written before they were kept: the default).
    let cases = match (only.is_empty(), shards.first()) {
        (true, Some(first)) => {
            let named = modaltol::shard::cases_run(first).map_err(|e| InputError(e.to_string()))?;
            // The default (the model's cases, or its parameters' own tolerances as one case)
            // where the shards ran it.
            let default = tolerance_cases(m.model(), &[])?;
            let names: Vec<&str> = default.iter().map(|c| c.name.as_str()).collect();
            if named.is_empty() || named == names {
                default
            } else {
                m.model().tolerance_cases(&named).map_err(|e| {
                    InputError(format!(
                        "{}: made from another model than the merge's ({e}); give the shards' \
                         model with --model, and the --set options they were run with",
                        first.display()
                    ))
                })?
            }
        }
        _ => tolerance_cases(m.model(), &only)?,
    };
    let display = display.of(&cases)?;
    let gathered = modaltol::shard::read_all(m.model(), &cases, &shards)
        .map_err(|e| InputError(e.to_string()))?;
    let base = AnalyzeOptions {
        cases,
        threads: None,
        cancel: cancel.clone(),
        ..Default::default()
    };
    let (opt, mc) = modaltol::shard::merged_options(&gathered.run, gathered.states, base)
        .map_err(InputError)?;
    note_unresolved_target(&m, Some(&mc));
    let mut inputs: Vec<&PathBuf> = model.iter().collect();
    inputs.extend(&shards);
    let inputs = Inputs::new(&inputs);
    refuse_input(&inputs, &output)?;
    let dir = protect(ResultDir::create(&output)?, inputs)?;
    let mut a = analyze(&m, &opt, &progress_printer());
    // The Monte Carlo's time is the shards', not the fold's.
    if gathered.monte_carlo_seconds.is_some() {
        a.monte_carlo_seconds = gathered.monte_carlo_seconds;
    }
    let o = WriteOptions {
        mc: Some(&mc),
        threads: rayon::current_num_threads(),
        display,
        allocation: None,
    };
    write_outputs(&m, &a, o, dir, &output)?;

    Ok(())
}
