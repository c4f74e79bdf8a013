//! A model from Python: read from a file or text, and what the commands ask of it (its
//! transfer function, design variables, speeds, the nominal point, the result directory).

use crate::NativeModel;
use crate::convert::{self, Fits, range};
use crate::errors::{SolveError, bad, model_error};
use modaltol::compiled::Compiled;
use modaltol::files::{Inputs, ResultDir};
use modaltol::model::{Model, Transfer};
use modaltol::request::{PointRequest, PointRequestError};
use modaltol::sweep::Options;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::Arc;

impl NativeModel {
    /// The model with the target yield asked for (checked), else itself.
    pub(crate) fn targeted(&self, target_yield: Option<f64>) -> Arc<Compiled> {
        match target_yield {
            Some(y) => Arc::new((*self.model).clone().with_target_yield(y)),
            None => self.model.clone(),
        }
    }

    pub(crate) fn m(&self) -> &Model {
        self.model.model()
    }

    /// The transfer function `spec` spells, none for `"none"`, the model's `[analysis]
    /// transfer` (if any) where it is not given: as the command line's `sweep` and
    /// `sensitivity`.
    pub(crate) fn transfer(&self, spec: Option<&str>) -> PyResult<Option<Transfer>> {
        match spec {
            Some("none") => Ok(None),
            Some(s) => (self.m().parse_transfer(s))
                .map(Some)
                .map_err(|e| bad(format!("transfer {s:?}: {e}"))),
            None => Ok(self.m().analysis.transfer),
        }
    }

    pub(crate) fn wrt(&self, names: Option<Vec<String>>) -> PyResult<Vec<usize>> {
        self.m()
            .design_variables(names.as_deref())
            .map_err(|e| bad(format!("wrt: {e}")))
    }

    /// With the branch to report: `"stable"` (switch to a stable equilibrium where the one
    /// reached is unstable) or `"as-given"`.
    pub(crate) fn options_on(
        &self,
        independent: Option<Vec<String>>,
        branch: &str,
    ) -> PyResult<Options> {
        let no_branch_switch = match branch {
            "stable" => false,
            "as-given" => true,
            other => {
                return Err(bad(format!(
                    "branch must be \"stable\" or \"as-given\", got {other:?}"
                )));
            }
        };
        Ok(Options {
            no_branch_switch,
            independent: independent
                .map(|n| {
                    self.m()
                        .independent_coordinates(&n)
                        .map_err(|e| bad(format!("independent: {e}")))
                })
                .transpose()?,
            ..Default::default()
        })
    }

    /// The speeds asked for, or the model's `[analysis] speed`, as many as `fits` allows.
    pub(crate) fn speeds_or_model(
        &self,
        speeds: Option<&Bound<'_, PyAny>>,
        fits: Fits<'_>,
    ) -> PyResult<Vec<f64>> {
        match speeds {
            Some(s) => convert::speeds(s, "speeds", fits),
            None => {
                let r =
                    self.m().analysis.speed.ok_or_else(|| {
                        bad("no speeds given and the model has no [analysis] speed")
                    })?;
                range(&r, "the model's [analysis] speed", fits)
            }
        }
    }

    /// The nominal point at `speed`.
    pub(crate) fn point(&self, speed: f64, opt: &Options) -> PyResult<modaltol::sweep::Point> {
        let at = PointRequest::new(&self.model, speed).map_err(|e| match e {
            PointRequestError::Speed(why) => bad(format!("speed {why}")),
            PointRequestError::Start(why) => bad(why),
        })?;
        at.solve(&self.model, opt)
            .map_err(|e| SolveError::new_err(format!("speed {speed:?} rad/s failed: {e}")))
    }
}

impl NativeModel {
    /// The result directory `output` (none without one), refused where it is the model file
    /// or holds files other than a result's.
    pub(crate) fn result_dir(&self, output: &Option<PathBuf>) -> PyResult<Option<ResultDir>> {
        output
            .as_ref()
            .map(|o| {
                let inputs = Inputs::new(&self.source.iter().collect::<Vec<_>>());
                ResultDir::create(o)
                    .and_then(|d| d.protect(inputs, modaltol::results::is_result_file))
                    .map_err(|e| bad(format!("{e}: {}", e.source)))
            })
            .transpose()
    }
}

/// Parameter overrides from a dict (name → number).
pub(crate) fn overrides(parameters: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, f64)>> {
    let Some(d) = parameters else {
        return Ok(Vec::new());
    };
    d.iter()
        .map(|(k, v)| {
            let k: String = k
                .extract()
                .map_err(|_| bad("parameters: the keys must be parameter names (str)"))?;
            let v: f64 = v
                .extract()
                .map_err(|_| bad(format!("parameters[{k:?}]: expected a number")))?;
            Ok((k, v))
        })
        .collect()
}

/// Reads and validates a model file; `parameters` replaces nominal values.
#[pyfunction]
#[pyo3(signature = (path, parameters=None))]
pub(crate) fn load(
    py: Python<'_>,
    path: PathBuf,
    parameters: Option<&Bound<'_, PyDict>>,
) -> PyResult<NativeModel> {
    let set = overrides(parameters)?;
    Compiled::from_file_with(&path, &set)
        .map(|m| NativeModel {
            model: Arc::new(m),
            source: Some(path),
        })
        .map_err(|e| model_error(py, e))
}

/// Validates a model given as TOML text; `name` names it in messages.
#[pyfunction]
#[pyo3(signature = (text, parameters=None, name="<string>"))]
pub(crate) fn loads(
    py: Python<'_>,
    text: &str,
    parameters: Option<&Bound<'_, PyDict>>,
    name: &str,
) -> PyResult<NativeModel> {
    let set = overrides(parameters)?;
    Compiled::from_bytes_with(text.as_bytes(), name, &set)
        .map(|m| NativeModel {
            model: Arc::new(m),
            source: None,
        })
        .map_err(|e| model_error(py, e))
}
