//! A tolerance allocation as asked for (`modaltol allocate`, Python's `Model.allocate`),
//! checked once into [`AllocateOptions`], as an analysis's [`super::Request`] is.

use super::{RequestError, Speeds, judged_speeds};
use crate::allocate::AllocateOptions;
use crate::cancel::Cancel;
use crate::model::{Case, Cost, Model};
use crate::quadrature::QuadOptions;
use crate::settings;

/// An allocation as asked for, before it is checked.
#[derive(Debug, Clone)]
pub struct AllocateRequest {
    pub speeds: Speeds,
    /// The tolerance case to start from (`None`: the model's `[allocation] case`, else the
    /// parameters' own tolerances).
    pub case: Option<String>,
    /// Cost models replacing the model's `[allocation]` ones (parameter index, cost).
    pub costs: Vec<(usize, Cost)>,
    /// The target yield (`None`: the model's `[allocation] target_yield`).
    pub target_yield: Option<f64>,
    /// The verifying quadrature's requested error, relative to each output's σ.
    pub quadrature_tolerance: f64,
    /// The most nodes the verifying quadrature may sweep (`None`: its rule's own budget).
    pub quadrature_nodes: Option<usize>,
    /// Worker threads (`None`: one per core).
    pub threads: Option<usize>,
}

impl Default for AllocateRequest {
    /// The model's speeds, case and target, the quadrature to 1e-3 of σ, one thread per core.
    fn default() -> Self {
        AllocateRequest {
            speeds: Speeds::Model,
            case: None,
            costs: Vec::new(),
            target_yield: None,
            quadrature_tolerance: QuadOptions::default().tolerance,
            quadrature_nodes: None,
            threads: None,
        }
    }
}

impl AllocateRequest {
    /// The rules that need no model: the quadrature's tolerance and nodes, the thread count,
    /// the target yield.
    pub fn check(&self) -> Result<(), RequestError> {
        settings::quadrature_tolerance(self.quadrature_tolerance)
            .map_err(RequestError::QuadratureTolerance)?;
        if let Some(n) = self.quadrature_nodes {
            settings::quadrature_nodes(n).map_err(RequestError::QuadratureNodes)?;
        }
        settings::threads(self.threads).map_err(RequestError::Threads)?;
        if let Some(y) = self.target_yield {
            settings::target_yield(y).map_err(RequestError::TargetYield)?;
        }
        Ok(())
    }

    /// The request checked ([`AllocateRequest::check`]) and resolved against `model` (whose
    /// target yield is the one asked for, where one was: see
    /// [`crate::compiled::Compiled::with_target_yield`]): its speeds (with the requirements'
    /// range ends), the case to start from, the target. `cancel` is the run's cancellation.
    pub fn resolve(self, model: &Model, cancel: Cancel) -> Result<AllocateOptions, RequestError> {
        self.check()?;
        let (speeds, _) = judged_speeds(self.speeds, model)?;
        let case = match self.case.as_deref().or(model.allocation.case.as_deref()) {
            Some(n) => (model.analysis.cases.iter())
                .find(|c| c.name == n)
                .cloned()
                .ok_or_else(|| {
                    RequestError::Cases(format!("no tolerance case '{n}' in the model"))
                })?,
            None => Case::from_parameters(model),
        };
        Ok(AllocateOptions {
            speeds,
            case,
            target: self.target_yield.unwrap_or(model.allocation.target_yield),
            costs: self.costs,
            quadrature: QuadOptions {
                tolerance: self.quadrature_tolerance,
                nodes: self.quadrature_nodes,
            },
            threads: self.threads,
            cancel,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::request::Setting;
    use std::path::Path;

    fn governor() -> Model {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/governor.toml");
        Model::from_file(&path).expect("the shipped governor")
    }

    /// A default request takes the model's speeds (with the requirements' range ends), its
    /// target and its case (or the parameters' tolerances); each refusal names its setting.
    #[test]
    fn an_allocation_request_takes_the_models_defaults_and_names_its_refusals() {
        let m = governor();
        let o = AllocateRequest::default()
            .resolve(&m, Cancel::new())
            .unwrap();
        let grid: Vec<f64> = m.analysis.speed.unwrap().speeds().collect();
        assert_eq!(o.speeds, m.judged_speeds(&grid));
        assert_eq!(o.target.to_bits(), m.allocation.target_yield.to_bits());
        let expected = match &m.allocation.case {
            Some(n) => n.clone(),
            None => Case::from_parameters(&m).name,
        };
        assert_eq!(o.case.name, expected);
        let refused = |r: AllocateRequest| r.resolve(&m, Cancel::new()).unwrap_err().setting();
        let given = |f: fn(&mut AllocateRequest)| {
            let mut r = AllocateRequest::default();
            f(&mut r);
            refused(r)
        };
        assert_eq!(
            given(|r| r.quadrature_tolerance = 0.0),
            Setting::QuadratureTolerance
        );
        assert_eq!(
            given(|r| r.quadrature_nodes = Some(0)),
            Setting::QuadratureNodes
        );
        assert_eq!(given(|r| r.threads = Some(0)), Setting::Threads);
        assert_eq!(given(|r| r.target_yield = Some(1.5)), Setting::TargetYield);
        assert_eq!(given(|r| r.case = Some("none".into())), Setting::Cases);
        assert_eq!(
            given(|r| r.speeds = Speeds::Values(vec![f64::NAN])),
            Setting::Speeds
        );
    }
}
