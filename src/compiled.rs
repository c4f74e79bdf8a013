//! A model with its equations recorded: what every computation above the mechanics takes.
//!
//! A [`Model`] is the validated description of a mechanism. Solving thousands of operating
//! points of it (a sweep, a Monte Carlo run, the quadrature nodes) is faster through its
//! equations recorded once as a [`Program`]; [`Compiled`] holds the model and that recording,
//! made on first use at one of the model's own reference points (so that it does not depend
//! on who asks first), and hands out each point's equations ([`Compiled::at`], and the solve of
//! them, [`Compiled::problem`]) on the [`Route`] chosen when it is made.
//! It dereferences to the model, so everything that only describes the mechanism reads it as
//! before.

use crate::equations::{Direct, Equations};
use crate::equilibrium::Problem;
use crate::jet::Jet;
use crate::mechanics::{System, steady_speeds};
use crate::model::{FieldError, Model, ModelError};
use crate::program::{Program, Recorded, Tier, Workspace};
use crate::real::Real;
use std::path::Path;
use std::sync::OnceLock;

/// How a model's equations are evaluated: chosen once, when the [`Compiled`] is made, and
/// used by every computation on it (the equilibrium solve, the linearisation, the
/// sensitivities and the Hessians). The two routes give the same numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Route {
    /// Through the program recorded on first use ([`Compiled::program`]), where the
    /// recording is valid (else directly): the fast route, and the default.
    #[default]
    Recorded,
    /// Always through the generic mechanics: the reference the recorded route is checked
    /// against, in tests and timings.
    Direct,
}

/// A model and its recorded equations (see the module documentation).
#[derive(Debug, Clone)]
pub struct Compiled {
    model: Model,
    route: Route,
    program: OnceLock<Option<Program>>,
}

impl From<Model> for Compiled {
    fn from(model: Model) -> Self {
        Compiled::new(model)
    }
}

impl Compiled {
    /// The model, its equations to be recorded on first use.
    pub fn new(model: Model) -> Self {
        Compiled {
            model,
            route: Route::default(),
            program: OnceLock::new(),
        }
    }

    /// The same model evaluated on `route` (its recording kept where the route is the same,
    /// else nothing recorded yet).
    pub fn with_route(self, route: Route) -> Self {
        if route == self.route {
            return self;
        }
        Compiled {
            model: self.model,
            route,
            program: OnceLock::new(),
        }
    }

    /// Reads and validates a model file ([`Model::from_file`]).
    pub fn from_file(path: &Path) -> Result<Self, ModelError> {
        Model::from_file(path).map(Compiled::new)
    }

    /// Reads and validates a model file with some parameters' nominal values replaced
    /// ([`Model::from_file_with`]).
    pub fn from_file_with(path: &Path, overrides: &[(String, f64)]) -> Result<Self, ModelError> {
        Model::from_file_with(path, overrides).map(Compiled::new)
    }

    /// Validates a model given as bytes with some parameters' nominal values replaced
    /// ([`Model::from_bytes_with`]).
    pub fn from_bytes_with(
        bytes: &[u8],
        file: &str,
        overrides: &[(String, f64)],
    ) -> Result<Self, ModelError> {
        Model::from_bytes_with(bytes, file, overrides).map(Compiled::new)
    }

    /// Validates a model given as bytes ([`Model::from_bytes`]).
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Self, ModelError> {
        Model::from_bytes(bytes, file).map(Compiled::new)
    }

    /// Validates a model given as text ([`Model::from_str`]).
    pub fn from_str(text: &str, file: &str) -> Result<Self, ModelError> {
        Model::from_str(text, file).map(Compiled::new)
    }

    /// The model with its target yield (`[allocation] target_yield`) replaced by one the
    /// caller has checked ([`crate::settings::target_yield`]): what every yield output is judged
    /// against, the margins met at it and the reaches.
    pub fn with_target_yield(mut self, target: f64) -> Self {
        self.model.allocation.target_yield = target;
        self
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model's equations recorded as a program for fast operating-point solves: recorded
    /// once, whoever asks first, at the first of the model's own reference points
    /// ([`Model::reference_points`]) where the model evaluates and the recording is valid, so
    /// that the route every later computation takes depends on the model alone; `None` on the
    /// [`Route::Direct`] and where no reference point gives a valid recording (a value the
    /// recording branched on everywhere, a model that does not evaluate), and then the direct
    /// route serves.
    pub fn program(&self) -> Option<&Program> {
        if self.route == Route::Direct {
            return None;
        }
        self.program
            .get_or_init(|| {
                self.model
                    .reference_points()
                    .into_iter()
                    .find_map(|(p, speed, q)| {
                        let evaluates = System::new(&self.model, &p, speed).is_ok()
                            && q.iter().all(|v| v.is_finite());
                        evaluates
                            .then(|| Program::record(&self.model, &p, speed, &q))
                            .flatten()
                    })
            })
            .as_ref()
    }

    /// The equations at parameters `p` and `speed` over any [`Scalar`], on the model's
    /// [`Route`]: the recorded program where the model has a valid one ([`Compiled::program`]),
    /// else the generic mechanics. The one object the equilibrium
    /// solve, the linearisation, the sensitivities and the Hessians evaluate. The recorded
    /// program's passes run at the caller's [`Tier`] in the caller's [`Workspace`].
    pub fn at<'a, S: Scalar>(
        &'a self,
        p: &[S],
        speed: S,
        (tier, workspace): (Tier, &'a Workspace),
    ) -> Result<Box<dyn Equations<S> + 'a>, FieldError> {
        let recorded = self
            .program()
            .and_then(|program| S::recorded(program, p, speed, (tier, workspace)));
        Ok(match recorded {
            Some(equations) => equations,
            None => Box::new(Direct::new(
                System::new(&self.model, p, speed)?,
                self.model.free(),
            )),
        })
    }

    /// `∂F/∂p_b` for the parameters `b` of `wrt` at parameters `p`, `speed`, coordinates `q`
    /// and multipliers `λ` (rows of `F` × `wrt`, row-major), in one forward pass where the model
    /// has a recorded program; `None` on the direct route, where the caller differentiates
    /// [`Equations::residual`] over dual numbers instead.
    pub fn parameter_jacobian(
        &self,
        p: &[f64],
        speed: f64,
        (q, lambda): (&[f64], &[f64]),
        wrt: &[usize],
        workspace: &Workspace,
    ) -> Option<Vec<f64>> {
        self.program()
            .map(|program| program.parameter_derivatives(p, speed, (q, lambda), wrt, workspace))
    }

    /// The equilibrium solve at parameters `p` and `speed`, of the equations [`Compiled::at`]
    /// gives at `tier` in `workspace`.
    pub fn problem<'a>(
        &'a self,
        p: &[f64],
        speed: f64,
        run: (Tier, &'a Workspace),
    ) -> Result<Problem<'a>, FieldError> {
        let names = self
            .model
            .coordinates
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        let qd = steady_speeds(&self.model, p, speed)?;
        let mut problem = Problem::new(self.at(p, speed, run)?, qd, self.model.driven(), names);
        problem.symmetric = self.model.steady_by_symmetry(p, speed);
        if self.model.constraints.iter().any(|c| !c.dropped.is_empty()) {
            problem.limit_steps(REDUNDANT_LOOP_STEP);
        }
        Ok(problem)
    }
}

/// The largest relative change of a free coordinate in one Newton step where a loop has
/// equations dropped as redundant ([`crate::equilibrium::Problem::limit_steps`]): 0.2 rad on
/// angles of order one, about Adams's 10°.
const REDUNDANT_LOOP_STEP: f64 = 0.2;

/// A scalar the equations are evaluated over, and how the recorded program evaluates it: in
/// `f64` as an [`crate::program::Instance`] (what depends on the parameters and the speed evaluated once),
/// over the Taylor numbers of the derivatives as [`Recorded`].
pub trait Scalar: Real {
    /// The recorded equations at `p` and `speed`, their passes run in `workspace` (the `f64`
    /// passes at `tier`; the jets' are interpreted at every tier); `None` where the program
    /// cannot serve there (then the direct route does).
    fn recorded<'a>(
        program: &'a Program,
        p: &[Self],
        speed: Self,
        run: (Tier, &'a Workspace),
    ) -> Option<Box<dyn Equations<Self> + 'a>>;
}

impl Scalar for f64 {
    /// `None` where the values that depend on the parameters and the speed are not finite.
    fn recorded<'a>(
        program: &'a Program,
        p: &[f64],
        speed: f64,
        (tier, workspace): (Tier, &'a Workspace),
    ) -> Option<Box<dyn Equations<f64> + 'a>> {
        program
            .at(p, speed, tier, workspace)
            .map(|i| Box::new(i) as Box<dyn Equations<f64>>)
    }
}

impl<J: Jet> Scalar for J {
    fn recorded<'a>(
        program: &'a Program,
        p: &[J],
        speed: J,
        (_, workspace): (Tier, &'a Workspace),
    ) -> Option<Box<dyn Equations<J> + 'a>> {
        Some(Box::new(Recorded {
            program,
            p: p.to_vec(),
            speed,
            workspace,
        }))
    }
}
