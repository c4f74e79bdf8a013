//! The inputs a command reads, checked: the model (or the built-in governor), the names
//! and choices of its arguments; each refusal an [`InputError`] naming its flag.

use crate::cli::*;
use anyhow::Result;
use modaltol::compiled::Compiled;
use modaltol::model::{Model, Transfer};
use modaltol::request::{PointRequest, PointRequestError, RequestError, Setting};
use modaltol::sensitivity;
use modaltol::settings::ThreadsError;
use std::path::PathBuf;

/// The governor example, built into the binary so `analyze` runs with no model file.
pub(crate) const EMBEDDED_GOVERNOR: &str = include_str!("../../examples/governor.toml");

pub(crate) fn load(path: &std::path::Path, set: &[(String, f64)]) -> Result<Compiled> {
    Compiled::from_file_with(path, set).map_err(|e| InputError(e.to_string()).into())
}

/// The point at `--speed` on `model`, checked ([`PointRequest`]): a refusal is bad input.
pub(crate) fn point_request(model: &Compiled, speed: f64) -> Result<PointRequest> {
    PointRequest::new(model, speed).map_err(|e| {
        InputError(match e {
            PointRequestError::Speed(why) => format!("--speed {why}"),
            PointRequestError::Start(why) => why,
        })
        .into()
    })
}

pub(crate) fn independent(
    model: &Model,
    names: &Option<Vec<String>>,
) -> Result<Option<Vec<usize>>> {
    names
        .as_deref()
        .map(|n| {
            model
                .independent_coordinates(n)
                .map_err(|e| InputError(format!("--independent: {e}")).into())
        })
        .transpose()
}

/// Design variables by name, or those with a tolerance.
pub(crate) fn design_variables(model: &Model, names: &Option<Vec<String>>) -> Result<Vec<usize>> {
    model
        .design_variables(names.as_deref())
        .map_err(|e| InputError(format!("--wrt: {e}")).into())
}

/// Parses `input=NAME,output=NAME[,order=K]` (or `model` for the model's own transfer function).
pub(crate) fn parse_transfer(model: &Model, spec: &str) -> Result<Transfer> {
    model
        .parse_transfer(spec)
        .map_err(|e| InputError(format!("--transfer {spec}: {e}")).into())
}

/// The transfer function of a command's `--transfer`: the one it spells, none for `none`, and
/// the model's `[analysis] transfer` (if any) where it is not given.
pub(crate) fn transfer_or_model(model: &Model, spec: Option<&str>) -> Result<Option<Transfer>> {
    match spec {
        Some("none") => Ok(None),
        Some(s) => parse_transfer(model, s).map(Some),
        None => Ok(model.analysis.transfer),
    }
}

/// The library's choice for the command line's.
pub(crate) fn how(d: Derivatives) -> sensitivity::Derivatives {
    match d {
        Derivatives::Ad => sensitivity::Derivatives::Exact,
        Derivatives::Fd => sensitivity::Derivatives::FiniteDifference,
    }
}
pub(crate) fn model_or_governor(
    model: &Option<PathBuf>,
    set: &[(String, f64)],
) -> Result<Compiled> {
    match model {
        Some(path) => load(path, set),
        None => Compiled::from_bytes_with(
            EMBEDDED_GOVERNOR.as_bytes(),
            "governor.toml (built in)",
            set,
        )
        .map_err(|e| InputError(e.to_string()).into()),
    }
}

/// A refused analysis request, in the command line's spelling: bad input, or a failure where
/// the operating system refuses the threads.
pub(crate) fn refused(
    e: RequestError,
    shard: &Option<String>,
    cases_chosen: bool,
) -> anyhow::Error {
    let spec = shard.as_deref().unwrap_or_default();
    match e {
        RequestError::Threads(t @ ThreadsError::Refused { .. }) => {
            Failed(format!("--threads: {t}")).into()
        }
        RequestError::NoSpeeds => {
            InputError("no --speed given and the model has no [analysis] speed".into()).into()
        }
        RequestError::Speeds(s) | RequestError::ModelSpeeds(s) => {
            InputError(format!("--speed: {s}")).into()
        }
        RequestError::Cases(s) => {
            let flag = if cases_chosen { "--case: " } else { "" };
            InputError(format!("{flag}{s}")).into()
        }
        RequestError::ShardWithoutMonteCarlo => {
            InputError("--shard splits the Monte Carlo; it cannot go with --no-monte-carlo".into())
                .into()
        }
        RequestError::TooManyShards { .. } => InputError(format!("--shard {spec}: {e}")).into(),
        e => {
            let flag = match e.setting() {
                Setting::QuadratureTolerance => "--quadrature-tolerance",
                Setting::QuadratureNodes => "--quadrature-nodes",
                Setting::Threads => "--threads",
                Setting::Samples => "--samples",
                Setting::Sobol => "--sobol",
                Setting::TargetYield => "--target-yield",
                _ => unreachable!("named above"),
            };
            InputError(format!("{flag} {e}")).into()
        }
    }
}

/// The model's tolerance cases, or one made of the parameters' own tolerances.
pub(crate) fn tolerance_cases(m: &Model, only: &[String]) -> Result<Vec<modaltol::model::Case>> {
    m.tolerance_cases(only).map_err(|e| {
        let flag = if only.is_empty() { "" } else { "--case: " };
        InputError(format!("{flag}{e}")).into()
    })
}
