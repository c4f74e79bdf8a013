//! One operating point (equilibrium → linearisation → modes) and sweeps over speed.
//!
//! At each speed the equilibrium is found by Newton from the previous speed's solution
//! (continuation). If the equilibrium found is unstable through a real root (a static
//! divergence, as the hanging pendulum past `√(3g/2L)`), the branch has bifurcated: the solver
//! steps off along the diverging mode's shape, both ways and at growing amplitudes, and takes the
//! nearest stable equilibrium, noting the switch. Modes keep their identity across speeds by
//! the similarity of their shapes in the free coordinates, not by sorting.

mod continuation;
mod point;
mod solve;

pub use continuation::Sweep;
pub use point::{Branch, BranchKind, Origin, Point, PointError};
pub use solve::{Solver, point, point_at};

use crate::equilibrium::Settings;
use crate::model::{FieldError, Model};
use crate::program::Tier;

/// Options of a point solve.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Independent coordinates (coordinate indices), overriding the model's choice.
    pub independent: Option<Vec<usize>>,
    /// Newton settings.
    pub newton: Settings,
    /// Do not look for a stable branch when the equilibrium found is unstable.
    pub no_branch_switch: bool,
    /// How the recorded program's passes run: [`Tier::Many`] (a sweep's) by default; a single
    /// point asks for [`Tier::Few`], a Monte Carlo run for [`Tier::Native`]. The results are
    /// the same at every tier, only the time differs.
    pub tier: Tier,
}

impl Options {
    /// The defaults for a single point ([`Tier::Few`]).
    pub fn single() -> Options {
        Options {
            tier: Tier::Few,
            ..Options::default()
        }
    }
}

/// The model's initial guesses at parameters `p` and `speed` ([`Model::initial_guess`]).
pub fn initial_guess(model: &Model, p: &[f64], speed: f64) -> Result<Vec<f64>, FieldError> {
    model.initial_guess(p, speed)
}
