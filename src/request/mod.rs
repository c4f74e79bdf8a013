//! An analysis as it is asked for (the command line's flags, the Python keywords), checked once
//! into [`AnalyzeOptions`]: the one place where a request's limits and the model's defaults are
//! applied, so that both front ends accept and refuse the same requests for the same reasons.
//!
//! A front end parses its own spellings (a `FROM:TO:STEP` string, an array, `--shard K/N`) into
//! a [`Request`]; [`Request::check`] applies the rules that need no model (before a model file is
//! read, so that a bad flag is reported before a slow load), [`Checked::resolve`] the rest
//! against the model. A refusal is a [`RequestError`] naming the setting ([`Setting`]); each
//! front end writes that name its own way (`--samples`, `samples`). One operating point's
//! request is a [`PointRequest`], an allocation's an [`AllocateRequest`].

mod allocate;
mod point;

pub use allocate::AllocateRequest;
pub use point::{PointRequest, PointRequestError};

use crate::analyze::AnalyzeOptions;
use crate::cancel::Cancel;
use crate::model::{Model, Sampling, SpeedRange};
use crate::montecarlo::McOptions;
use crate::montecarlo::Split;
use crate::quadrature::QuadOptions;
use crate::settings::{self, ThreadsError};

/// The speeds of a request.
#[derive(Debug, Clone, Default)]
pub enum Speeds {
    /// The model's `[analysis] speed`.
    #[default]
    Model,
    /// A range `FROM:TO:STEP` (rad/s).
    Range(SpeedRange),
    /// Speeds one by one (rad/s).
    Values(Vec<f64>),
}

/// An analysis as asked for, before it is checked (see the module documentation).
#[derive(Debug, Clone)]
pub struct Request {
    pub speeds: Speeds,
    /// The tolerance cases to run by name (none: the model's cases, or its parameters' own
    /// tolerances).
    pub cases: Vec<String>,
    /// Monte Carlo samples (`None`: the model's `[analysis] samples`).
    pub samples: Option<usize>,
    /// The Monte Carlo seed (`None`: the model's).
    pub seed: Option<u64>,
    /// How the Monte Carlo samples (`None`: the model's choice).
    pub sampling: Option<Sampling>,
    /// Whether the Monte Carlo runs.
    pub monte_carlo: bool,
    /// Whether the quadrature runs.
    pub quadrature: bool,
    /// The quadrature's requested error, relative to each output's σ.
    pub quadrature_tolerance: f64,
    /// The most nodes the quadrature may sweep per case (`None`: its rule's own budget).
    pub quadrature_nodes: Option<usize>,
    /// Worker threads (`None`: one per core).
    pub threads: Option<usize>,
    /// This run as shard `k` (from 0) of `n` of the Monte Carlo.
    pub shard: Option<(usize, usize)>,
    /// Base samples of the Sobol indices (`None`: none computed).
    pub sobol: Option<usize>,
    /// The target yield (`None`: the model's `[allocation] target_yield`).
    pub target_yield: Option<f64>,
}

impl Default for Request {
    /// The model's speeds, cases and Monte Carlo settings, both methods, the quadrature to
    /// 1e-3 of σ, one thread per core, the whole run.
    fn default() -> Self {
        Request {
            speeds: Speeds::Model,
            cases: Vec::new(),
            samples: None,
            seed: None,
            sampling: None,
            monte_carlo: true,
            quadrature: true,
            quadrature_tolerance: QuadOptions::default().tolerance,
            quadrature_nodes: None,
            threads: None,
            shard: None,
            sobol: None,
            target_yield: None,
        }
    }
}

/// The setting a refusal is about, for the front end to name in its own spelling.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    Speeds,
    Cases,
    Samples,
    QuadratureTolerance,
    QuadratureNodes,
    Threads,
    Shard,
    Sobol,
    TargetYield,
}

/// Why a request is refused. Each message leaves the setting unnamed ([`RequestError::setting`]
/// names it).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RequestError {
    #[error("{0}")]
    QuadratureTolerance(String),
    #[error("{0}")]
    QuadratureNodes(String),
    #[error("{0}")]
    Threads(ThreadsError),
    #[error("no speeds given and the model has no [analysis] speed")]
    NoSpeeds,
    /// The speeds given are refused.
    #[error("{0}")]
    Speeds(String),
    /// The model's own `[analysis] speed` is refused.
    #[error("the model's [analysis] speed: {0}")]
    ModelSpeeds(String),
    #[error("{0}")]
    Cases(String),
    #[error("{0}")]
    Samples(String),
    /// The Sobol indices' base samples are refused.
    #[error("{0}")]
    Sobol(String),
    #[error("{0}")]
    TargetYield(String),
    /// Sobol indices asked of a shard: they are not split across shards.
    #[error("is not split across shards: run the Sobol indices in a whole run (without the shard)")]
    SobolInShard,
    #[error("splits the Monte Carlo; it cannot go without the Monte Carlo")]
    ShardWithoutMonteCarlo,
    #[error(
        "{shards} shards of {samples} samples would leave shards without a sample; use at most \
         {samples} shards"
    )]
    TooManyShards { shards: usize, samples: usize },
}

impl RequestError {
    /// The setting refused.
    pub fn setting(&self) -> Setting {
        match self {
            RequestError::QuadratureTolerance(_) => Setting::QuadratureTolerance,
            RequestError::QuadratureNodes(_) => Setting::QuadratureNodes,
            RequestError::Threads(_) => Setting::Threads,
            RequestError::NoSpeeds | RequestError::Speeds(_) | RequestError::ModelSpeeds(_) => {
                Setting::Speeds
            }
            RequestError::Cases(_) => Setting::Cases,
            RequestError::Samples(_) => Setting::Samples,
            RequestError::Sobol(_) | RequestError::SobolInShard => Setting::Sobol,
            RequestError::TargetYield(_) => Setting::TargetYield,
            RequestError::ShardWithoutMonteCarlo | RequestError::TooManyShards { .. } => {
                Setting::Shard
            }
        }
    }
}

/// A request whose model-free settings passed [`Request::check`], ready to be resolved
/// against its model.
#[derive(Debug, Clone)]
pub struct Checked(Request);

/// A request resolved against its model: the options to run, and the speed range asked for
/// where one was (a shard's fingerprint records it).
#[derive(Debug, Clone)]
pub struct Resolved {
    pub options: AnalyzeOptions,
    pub range: Option<SpeedRange>,
    /// The target yield asked for, to replace the model's
    /// ([`crate::compiled::Compiled::with_target_yield`]); `None`: the model's.
    pub target_yield: Option<f64>,
}

impl Request {
    /// The rules that need no model: the quadrature's tolerance and nodes, then the thread
    /// count (which the operating system may refuse: [`ThreadsError::Refused`]).
    pub fn check(self) -> Result<Checked, RequestError> {
        settings::quadrature_tolerance(self.quadrature_tolerance)
            .map_err(RequestError::QuadratureTolerance)?;
        if let Some(n) = self.quadrature_nodes {
            settings::quadrature_nodes(n).map_err(RequestError::QuadratureNodes)?;
        }
        settings::threads(self.threads).map_err(RequestError::Threads)?;
        if let Some(n) = self.sobol {
            settings::samples(n).map_err(RequestError::Sobol)?;
            if self.shard.is_some() {
                return Err(RequestError::SobolInShard);
            }
        }
        if let Some(y) = self.target_yield {
            settings::target_yield(y).map_err(RequestError::TargetYield)?;
        }
        Ok(Checked(self))
    }
}

impl Checked {
    /// Resolves the request against `model`: its speeds
    /// (at most [`settings::MAX_ANALYSIS_SPEEDS`]), its cases, the Monte Carlo's settings (the
    /// model's where not given) and the split. A shard runs the Monte Carlo only (`merge` runs
    /// the quadrature). `cancel` is the run's cancellation.
    pub fn resolve(self, model: &Model, cancel: Cancel) -> Result<Resolved, RequestError> {
        let Checked(request) = self;
        let (speeds, range) = judged_speeds(request.speeds, model)?;
        let cases = model
            .tolerance_cases(&request.cases)
            .map_err(|e| RequestError::Cases(e.to_string()))?;
        if let Some(n) = request.samples {
            settings::samples(n).map_err(RequestError::Samples)?;
        }
        let monte_carlo = request.monte_carlo.then(|| McOptions {
            samples: request.samples.unwrap_or(model.analysis.samples),
            seed: request.seed.unwrap_or(model.analysis.seed),
            sampling: request.sampling.unwrap_or(model.analysis.sampling),
        });
        let split = match (request.shard, &monte_carlo) {
            (None, _) => Split::Whole,
            (Some(_), None) => return Err(RequestError::ShardWithoutMonteCarlo),
            (Some((_, n)), Some(mc)) if n > mc.samples => {
                return Err(RequestError::TooManyShards {
                    shards: n,
                    samples: mc.samples,
                });
            }
            (Some((k, n)), Some(_)) => Split::Shard(k, n),
        };
        let quadrature = (request.quadrature && request.shard.is_none()).then_some(QuadOptions {
            tolerance: request.quadrature_tolerance,
            nodes: request.quadrature_nodes,
        });
        Ok(Resolved {
            options: AnalyzeOptions {
                speeds,
                cases,
                quadrature,
                monte_carlo,
                split,
                threads: request.threads,
                cancel,
                sobol: request.sobol.map(|samples| crate::sobol::SobolOptions {
                    samples,
                    seed: request.seed.unwrap_or(model.analysis.seed),
                }),
            },
            range,
            target_yield: request.target_yield,
        })
    }
}

/// The speeds asked for (at most [`settings::MAX_ANALYSIS_SPEEDS`]), every requirement judged
/// over its range (refused where the speeds cannot: see `Model::check_requirement_speeds`) with
/// its ends added ([`Model::judged_speeds`]); with the range asked for, where one was.
fn judged_speeds(
    speeds: Speeds,
    model: &Model,
) -> Result<(Vec<f64>, Option<SpeedRange>), RequestError> {
    let from_model = matches!(speeds, Speeds::Model);
    let (speeds, range) = match speeds {
        Speeds::Model => {
            let r = model.analysis.speed.ok_or(RequestError::NoSpeeds)?;
            settings::analysis_speeds(r.len()).map_err(RequestError::ModelSpeeds)?;
            (r.speeds().collect(), Some(r))
        }
        Speeds::Range(r) => {
            settings::analysis_speeds(r.len()).map_err(RequestError::Speeds)?;
            (r.speeds().collect(), Some(r))
        }
        Speeds::Values(v) => {
            let v = settings::values(v).map_err(RequestError::Speeds)?;
            settings::analysis_speeds(v.len()).map_err(RequestError::Speeds)?;
            (v, None)
        }
    };
    model.check_requirement_speeds(&speeds).map_err(|e| {
        if from_model {
            RequestError::ModelSpeeds(e)
        } else {
            RequestError::Speeds(e)
        }
    })?;
    Ok((model.judged_speeds(&speeds), range))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn governor() -> Model {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/governor.toml");
        Model::from_file(&path).expect("the shipped governor")
    }

    fn resolve(request: Request) -> Result<Resolved, RequestError> {
        request.check()?.resolve(&governor(), Cancel::new())
    }

    #[test]
    fn a_default_request_takes_the_models_speeds_cases_and_monte_carlo_settings() {
        let m = governor();
        let r = resolve(Request::default()).unwrap();
        let range = m.analysis.speed.unwrap();
        assert_eq!(r.range, Some(range));
        assert_eq!(r.options.speeds, range.speeds().collect::<Vec<_>>());
        assert_eq!(r.options.cases.len(), m.tolerance_cases(&[]).unwrap().len());
        let mc = r.options.monte_carlo.unwrap();
        assert_eq!(
            (mc.samples, mc.seed, mc.sampling),
            (m.analysis.samples, m.analysis.seed, m.analysis.sampling)
        );
        assert!(r.options.quadrature.is_some());
        assert!(matches!(r.options.split, Split::Whole));
    }

    #[test]
    fn each_refusal_names_its_setting() {
        let refused = |request: Request| resolve(request).unwrap_err();
        let e = refused(Request {
            quadrature_tolerance: 1.5,
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::QuadratureTolerance);
        let e = refused(Request {
            quadrature_nodes: Some(0),
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::QuadratureNodes);
        let e = refused(Request {
            threads: Some(0),
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::Threads);
        let e = refused(Request {
            speeds: Speeds::Values(vec![1.0, f64::NAN]),
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::Speeds);
        let e = refused(Request {
            speeds: Speeds::Values(vec![0.0; settings::MAX_ANALYSIS_SPEEDS + 1]),
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::Speeds);
        let e = refused(Request {
            cases: vec!["no such case".into()],
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::Cases);
        let e = refused(Request {
            samples: Some(1),
            ..Request::default()
        });
        assert_eq!(e.setting(), Setting::Samples);
    }

    #[test]
    fn a_shard_runs_the_monte_carlo_alone_and_needs_a_sample_each() {
        let r = resolve(Request {
            shard: Some((1, 4)),
            samples: Some(100),
            ..Request::default()
        })
        .unwrap();
        assert!(matches!(r.options.split, Split::Shard(1, 4)));
        assert!(r.options.quadrature.is_none(), "merge runs the quadrature");
        let e = resolve(Request {
            shard: Some((0, 101)),
            samples: Some(100),
            ..Request::default()
        })
        .unwrap_err();
        assert_eq!(
            e,
            RequestError::TooManyShards {
                shards: 101,
                samples: 100
            }
        );
        let e = resolve(Request {
            shard: Some((0, 2)),
            monte_carlo: false,
            ..Request::default()
        })
        .unwrap_err();
        assert_eq!(e, RequestError::ShardWithoutMonteCarlo);
    }

    #[test]
    fn given_speeds_and_settings_override_the_models() {
        let r = resolve(Request {
            speeds: Speeds::Values(vec![0.5, 2.0]),
            samples: Some(50),
            seed: Some(9),
            sampling: Some(Sampling::Sobol),
            quadrature: false,
            ..Request::default()
        })
        .unwrap();
        assert_eq!(r.options.speeds, vec![0.5, 2.0]);
        assert_eq!(r.range, None);
        let mc = r.options.monte_carlo.unwrap();
        assert_eq!((mc.samples, mc.seed, mc.sampling), (50, 9, Sampling::Sobol));
        assert!(r.options.quadrature.is_none());
    }
}
