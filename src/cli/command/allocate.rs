//! `modaltol allocate`.

use crate::cli::*;
use anyhow::Result;
use modaltol::allocate::{Allocation, allocate};
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::cancel::Cancel;
use modaltol::files::{Inputs, ResultDir};
use modaltol::model::{Cost, Model, SpeedRange};
use modaltol::report;
use modaltol::request::{AllocateRequest, Speeds};
use modaltol::results::WriteOptions;
use std::io::Write;

/// `modaltol allocate` (see its `--help`).
pub(crate) fn allocate_command(
    args: AllocateArgs,
    set: &[(String, f64)],
    cancel: &Cancel,
) -> Result<()> {
    let AllocateArgs {
        model,
        output,
        target_yield,
        case,
        costs,
        speed,
        quadrature_tolerance,
        quadrature_nodes,
        threads,
    } = args;
    let request = AllocateRequest {
        speeds: match &speed {
            Some(s) => Speeds::Range(
                SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
            ),
            None => Speeds::Model,
        },
        case,
        costs: Vec::new(),
        target_yield,
        quadrature_tolerance,
        quadrature_nodes,
        threads,
    };
    // The settings that need no model first: a bad flag is reported before a slow load.
    request.check().map_err(|e| refused(e, &None, true))?;
    let m = load(&model, set)?;
    // The allocation's target is what its analysis is judged against too.
    let m = match target_yield {
        Some(y) => m.with_target_yield(y),
        None => m,
    };
    let md = m.model();
    let request = AllocateRequest {
        costs: (costs.iter())
            .map(|c| cost(md, c))
            .collect::<Result<Vec<_>>>()?,
        ..request
    };
    let opt = request
        .resolve(md, cancel.clone())
        .map_err(|e| refused(e, &None, true))?;
    let inputs = Inputs::new(&[&model]);
    refuse_input(&inputs, &output)?;
    let mut dir = protect(ResultDir::create(&output)?, inputs)?;
    let a = allocate(&m, &opt, &|r| {
        note!(
            "modaltol: β = {:.4}: predicted {:.6}, verified yield {:.6} ± {:.1e} ({} nodes)",
            r.beta,
            r.predicted,
            r.verified.0,
            r.verified.1,
            r.nodes
        )
    })
    .map_err(|e| Failed(e.to_string()))?;
    if cancel.is_cancelled() {
        return Err(Interrupted("nothing written (a result is complete or absent)".into()).into());
    }
    print!("{}", report::allocation_table(md, &a));
    write_allocation(&mut dir, md, &a)?;
    // The allocated design's whole analysis (its yield by the quadrature, the report).
    let analysis = analyze(
        &m,
        &AnalyzeOptions {
            speeds: opt.speeds.clone(),
            cases: vec![a.case.clone()],
            quadrature: Some(opt.quadrature),
            monte_carlo: None,
            threads,
            cancel: cancel.clone(),
            ..Default::default()
        },
        &progress_printer(),
    );
    let o = WriteOptions {
        threads: threads.unwrap_or_else(rayon::current_num_threads),
        allocation: Some(&a),
        ..Default::default()
    };
    write_outputs(&m, &analysis, o, dir, &output)?;
    if !a.met {
        return Err(Failed(format!(
            "the verified yield does not reach the target {} after {} rounds (see allocation.json)",
            a.target,
            a.rounds.len()
        ))
        .into());
    }
    Ok(())
}

/// `NAME=B` or `NAME=B,K`.
fn cost(md: &Model, spec: &str) -> Result<(usize, Cost)> {
    let bad = || {
        InputError(format!(
            "--cost {spec}: expected NAME=B or NAME=B,K with B, K > 0"
        ))
    };
    let (name, rest) = spec.split_once('=').ok_or_else(bad)?;
    let p = md
        .parameter(name.trim())
        .ok_or_else(|| {
            let n = name.trim();
            InputError(match md.derived.iter().find(|d| d.name == n) {
                Some(d) => format!(
                    "--cost {spec}: parameter '{n}' is derived (= \"{}\"); give the cost to the parameters it is made of",
                    d.text
                ),
                None => format!("--cost {spec}: no parameter '{n}'"),
            })
        })?;
    let mut parts = rest.split(',').map(|x| x.trim().parse::<f64>());
    let b = parts.next().and_then(|x| x.ok()).ok_or_else(bad)?;
    let k = match parts.next() {
        Some(x) => x.map_err(|_| bad())?,
        None => 1.0,
    };
    if parts.next().is_some() || !(b.is_finite() && b > 0.0 && k.is_finite() && k > 0.0) {
        return Err(bad().into());
    }
    let base = md
        .allocation
        .costs
        .iter()
        .find(|c| c.0 == p)
        .map_or(Cost::default(), |c| c.1);
    Ok((p, Cost { b, k, ..base }))
}

/// `allocation.csv` and `allocation.json`.
fn write_allocation(dir: &mut ResultDir, md: &Model, a: &Allocation) -> Result<()> {
    dir.write(
        "allocation.csv",
        &modaltol::results::csv_bytes(&report::ALLOCATION_HEADER, &report::allocation_rows(md, a)),
    )?;
    dir.write(
        "allocation.json",
        serde_json::to_string_pretty(&report::allocation_json(md, a))?.as_bytes(),
    )?;
    Ok(())
}
