//! `Model.analyze`: the tolerance analysis, its tables and result directory.

use crate::NativeModel;
use crate::convert::{interruptible, table, unit};
use crate::errors::{bad, refused};
use modaltol::analyze::AnalyzeOptions;
use modaltol::cancel::Cancel;
use modaltol::compiled::Compiled;
use modaltol::files::ResultDir;
use modaltol::model::{Sampling, SpeedRange};
use modaltol::montecarlo::McOptions;
use modaltol::plots::Display;
use modaltol::quadrature::QuadOptions;
use modaltol::report;
use modaltol::request::{Request, Resolved, Speeds};
use modaltol::settings;
use modaltol::shard::{RunSettings, ShardFile};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The keywords of `Model.analyze` (the Python wrapper passes them all, as a dict): the
/// package's spelling of a [`Request`], with the result directory and its display units.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct AnalyzeKeywords {
    cases: Option<Vec<String>>,
    samples: Option<i64>,
    seed: Option<u64>,
    sampling: Option<String>,
    monte_carlo: bool,
    quadrature: bool,
    quadrature_tolerance: f64,
    quadrature_nodes: Option<i64>,
    threads: Option<i64>,
    output: Option<PathBuf>,
    speed_unit: String,
    frequency_unit: String,
    campbell_case: Option<String>,
    sobol: Option<i64>,
    /// `(K, N)`: run shard K (1-based) of N of the Monte Carlo and return the shard's text.
    shard: Option<(i64, i64)>,
    target_yield: Option<f64>,
}

/// Runs the analysis `opt` of `model` without the GIL, stopping on Ctrl-C.
pub(crate) fn run_analysis(
    py: Python<'_>,
    model: &Compiled,
    opt: &AnalyzeOptions,
) -> PyResult<modaltol::analyze::Analysis> {
    let a = interruptible(py, &opt.cancel, || {
        modaltol::analyze::analyze(model, opt, &|_: &str, _: usize, _: usize| {})
    })?;
    if a.cancelled() {
        // Ctrl-C arrived between the worker's last check and its end.
        return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(()));
    }
    Ok(a)
}

/// The tables and summary of an analysis (and its result directory where `dir` is given).
pub(crate) fn analysis_dict<'py>(
    py: Python<'py>,
    model: &Compiled,
    a: &modaltol::analyze::Analysis,
    mc: Option<&McOptions>,
    used: usize,
    dir: Option<ResultDir>,
    display: Display,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.model();
    if let Some(dir) = dir {
        py.detach(|| {
            let o = modaltol::results::WriteOptions {
                mc,
                threads: used,
                display,
                allocation: None,
            };
            modaltol::results::write(model, a, o, dir)
        })
        .map_err(|e| PyRuntimeError::new_err(format!("{e}: {}", e.source)))?;
    }
    let d = PyDict::new(py);
    d.set_item(
        "tolerance",
        table(
            py,
            &report::tolerance_header(m, a),
            &report::tolerance_rows(a, false),
        )?,
    )?;
    d.set_item(
        "probabilities",
        table(
            py,
            &report::PROBABILITY_HEADER,
            &report::probability_rows(a),
        )?,
    )?;
    d.set_item(
        "yield",
        table(py, &report::YIELD_HEADER, &report::yield_rows(m, a))?,
    )?;
    d.set_item(
        "limits",
        table(py, &report::LIMITS_HEADER, &report::limit_rows(m, a))?,
    )?;
    d.set_item(
        "sobol",
        table(py, &report::SOBOL_HEADER, &report::sobol_rows(m, a))?,
    )?;
    d.set_item(
        "peaks",
        table(py, &report::PEAK_HEADER, &report::peak_rows(m, a))?,
    )?;
    d.set_item(
        "summary",
        serde_json::to_string(&report::summary_json(m, a, mc, used)).expect("a JSON value"),
    )?;
    Ok(d)
}

/// The tolerance analysis (the CLI's `analyze`): tolerance and probability tables and the
/// summary (JSON text); with `output`, also the CLI's result directory.
pub(crate) fn analyze<'py>(
    model: &NativeModel,
    py: Python<'py>,
    speeds: Option<&Bound<'py, PyAny>>,
    options: AnalyzeKeywords,
) -> PyResult<Bound<'py, PyDict>> {
    let AnalyzeKeywords {
        cases,
        samples,
        seed,
        sampling,
        monte_carlo,
        quadrature,
        quadrature_tolerance,
        quadrature_nodes,
        threads,
        output,
        speed_unit,
        frequency_unit,
        campbell_case,
        sobol,
        shard,
        target_yield,
    } = options;
    let shard = shard
        .map(|(k, n)| settings::shard(&format!("{k}/{n}")).map_err(|e| bad(format!("shard {e}"))))
        .transpose()?;
    let (sampling, speed_unit, frequency_unit) =
        (sampling.as_deref(), &*speed_unit, &*frequency_unit);
    let m = model.m();
    let mut display = Display {
        speed: unit(speed_unit, "speed_unit")?,
        frequency: unit(frequency_unit, "frequency_unit")?,
        campbell_case: None,
    };
    let sampling = match sampling {
        None => None,
        Some(s) => Some(Sampling::named(s).ok_or_else(|| {
            bad(format!(
                "sampling must be {}, got {s:?}",
                Sampling::names(true)
            ))
        })?),
    };
    let request = Request {
        speeds: match speeds {
            None => Speeds::Model,
            Some(s) => match s.extract::<String>() {
                Ok(text) => Speeds::Range(
                    SpeedRange::parse(&text).map_err(|e| bad(format!("speeds: {e}")))?,
                ),
                Err(_) => Speeds::Values(
                    s.extract()
                        .map_err(|_| bad("speeds: expected \"FROM:TO:STEP\" or numbers"))?,
                ),
            },
        },
        cases: cases.unwrap_or_default(),
        // A negative count is refused as the rule refuses any count out of range.
        samples: samples
            .map(|n| settings::samples(n).map_err(|e| bad(format!("samples {e}"))))
            .transpose()?,
        seed,
        sampling,
        monte_carlo,
        quadrature,
        quadrature_tolerance,
        // A negative count is refused as any count out of range.
        quadrature_nodes: quadrature_nodes
            .map(|n| {
                settings::quadrature_nodes(n).map_err(|e| bad(format!("quadrature_nodes {e}")))
            })
            .transpose()?,
        // A negative count is refused as zero is (the command line's parser refuses it too).
        threads: threads.map(|n| usize::try_from(n).unwrap_or(0)),
        shard,
        // A negative count is refused as zero is.
        sobol: sobol.map(|n| usize::try_from(n).unwrap_or(0)),
        target_yield,
    };
    if shard.is_some() && output.is_some() {
        return Err(bad(
            "a shard is returned, not written as a result directory: merge the shards \
             (modaltol.merge) with output=",
        ));
    }
    // The quadrature of the run a shard belongs to (`merge` runs it).
    let run_quadrature = quadrature.then_some(QuadOptions {
        tolerance: quadrature_tolerance,
        nodes: request.quadrature_nodes,
    });
    let Resolved {
        options: opt,
        range,
        target_yield,
    } = request
        .check()
        .and_then(|r| r.resolve(m, Cancel::new()))
        .map_err(refused)?;
    display.campbell_case = campbell(campbell_case.as_deref(), &opt.cases)?;
    let (mc, threads) = (opt.monte_carlo, opt.threads);
    // Fail early where the results cannot be written.
    let dir = model.result_dir(&output)?;
    let targeted = model.targeted(target_yield);
    let model = &*targeted;
    let a = run_analysis(py, model, &opt)?;
    if let (Some((k, n)), Some(mc)) = (shard, mc) {
        let range =
            range.ok_or_else(|| bad("shards need speeds as \"FROM:TO:STEP\" (or the model's)"))?;
        let run = RunSettings::new(&range, &mc, run_quadrature, n);
        let file = ShardFile::of_analysis(m, &opt.cases, &a, &run, k).ok_or_else(|| {
            PyRuntimeError::new_err("the shard was not completed (a shard is complete or absent)")
        })?;
        let d = PyDict::new(py);
        d.set_item("shard", file.to_json())?;
        d.set_item("name", ShardFile::name(k, n))?;
        return Ok(d);
    }
    let used =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    analysis_dict(py, model, &a, mc.as_ref(), used, dir, display)
}

/// The index of the case `name` (the keyword `campbell_case`) among the cases analysed.
pub(crate) fn campbell(
    name: Option<&str>,
    cases: &[modaltol::model::Case],
) -> PyResult<Option<usize>> {
    let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
    name.map(|n| Display::case_named(n, &names).map_err(|e| bad(format!("campbell_case: {e}"))))
        .transpose()
}
