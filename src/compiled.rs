//! A model with its equations recorded: what every computation above the mechanics takes.
//!
//! A [`Model`] is the validated description of a mechanism. Solving thousands of operating
//! points of it (a sweep, a Monte Carlo run, the quadrature nodes) is faster through its
//! equations recorded once as a [`Program`]; [`Compiled`] holds the model and that recording,
//! made on first use, and hands out each point's equations
//! ([`Compiled::equations`], [`Compiled::problem`]) on the [`Route`] chosen when it is made.
//! It dereferences to the model, so everything that only describes the mechanism reads it as
//! before.

use crate::equilibrium::Problem;
use crate::mechanics::{System, steady_speeds};
use crate::model::{FieldError, Model, ModelError};
use crate::program::{Program, Recorded};
use crate::real::Real;
use crate::route::{Direct, Equations};
use std::ops::Deref;
use std::path::Path;
use std::sync::OnceLock;

/// How a model's equations are evaluated: chosen once, when the [`Compiled`] is made, and
/// used by every computation on it (the equilibrium solve, the linearisation, the
/// sensitivities and the Hessians). The two routes give the same numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Route {
    /// Through the program recorded on first use, where the recording is valid (else
    /// directly): the fast route, and the default.
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

impl Deref for Compiled {
    type Target = Model;

    fn deref(&self) -> &Model {
        &self.model
    }
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

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model's equations recorded as a program for fast operating-point solves, recorded
    /// on the first call (at these parameters, speed and coordinates); `None` on the
    /// [`Route::Direct`] and where the recording is not valid, and then the direct route
    /// serves.
    pub fn program(&self, p: &[f64], speed: f64, q: &[f64]) -> Option<&Program> {
        if self.route == Route::Direct {
            return None;
        }
        if let Some(recorded) = self.program.get() {
            return recorded.as_ref();
        }
        // Values at which the model does not evaluate cannot be recorded at; a later call may
        // bring better ones.
        if System::new(&self.model, p, speed).is_err() || q.iter().any(|v| !v.is_finite()) {
            return None;
        }
        self.program
            .get_or_init(|| Program::record(&self.model, p, speed, q))
            .as_ref()
    }

    /// The equations at parameters `p` and `speed` over any [`Real`], near the coordinates
    /// `q`, on the model's [`Route`] (the recorded program when the model has one).
    pub fn equations<S: Real>(
        &self,
        p: &[S],
        speed: S,
        q: &[f64],
    ) -> Result<Box<dyn Equations<S> + '_>, FieldError> {
        let p0: Vec<f64> = p.iter().map(|v| v.re()).collect();
        Ok(match self.program(&p0, speed.re(), q) {
            Some(program) => Box::new(Recorded {
                program,
                p: p.to_vec(),
                speed,
            }),
            None => Box::new(Direct::new(
                System::new(&self.model, p, speed)?,
                self.model.free(),
            )),
        })
    }

    /// The equilibrium solve at parameters `p` and `speed` from near `q0`, on the model's
    /// [`Route`].
    pub fn problem(&self, p: &[f64], speed: f64, q0: &[f64]) -> Result<Problem<'_>, FieldError> {
        let names = self.coordinates.iter().map(|c| c.name.as_str()).collect();
        let recorded = self.program(p, speed, q0).and_then(|pr| pr.at(p, speed));
        let mut problem = match recorded {
            Some(instance) => Problem::new(
                Box::new(instance),
                steady_speeds(&self.model, p, speed)?,
                self.driven(),
                names,
            ),
            None => {
                let system = System::new(&self.model, p, speed)?;
                let qd = system.steady_speeds();
                Problem::new(
                    Box::new(Direct::new(system, self.free())),
                    qd,
                    self.driven(),
                    names,
                )
            }
        };
        problem.symmetric = self.model.steady_by_symmetry(p, speed);
        Ok(problem)
    }
}
