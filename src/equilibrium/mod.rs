//! Dynamic equilibrium at constant drive speed (Kim & Yoo 2007, eq. 13).
//!
//! With the driven coordinates turning at constant speed and the free ones at rest,
//!
//! ```text
//! F(q_R, λ) = [ r_R(q, q̇ = [Ω; 0], q̈ = 0) + Φ_{q_R}ᵀ λ ;  Φ(q) ] = 0
//! ```
//!
//! is solved by Newton's method with a backtracking line search and the exact Jacobian of `F`
//! (one dual-number pass per unknown). The driven coordinates are held at their initial values;
//! if `F` depends on them (gravity not along the spin axis, say), the motion is not steady and
//! the solve says so. The drive force on each driven coordinate is `r_D + Φ_{q_D}ᵀ λ`.
//!
//! # Reference
//! Kim, Yoo (2007), *Analytical tolerance analysis of the modal characteristics of multibody
//! systems in dynamic equilibrium*, eq. 13; Nocedal & Wright, *Numerical Optimization*, §11;
//! Deuflhard, *Newton Methods for Nonlinear Problems* (2004), §3.1 (the natural monotonicity
//! test, affine covariant).

mod balance;
mod newton;
mod steady;

pub use balance::{Balance, Factor, RANK_TOLERANCE};

use crate::equations::{Equations, Evaluation, Rates};
use crate::linalg::least_squares;
use nalgebra::DMatrix;
use newton::{Direction, Iterate, Step};

/// Why an equilibrium was not found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EquilibriumError {
    #[error("Newton did not converge in {iterations} iterations (residual {residual:.3e})")]
    NewtonDiverged { iterations: usize, residual: f64 },
    #[error(
        "singular Jacobian after {iterations} iterations (a bifurcation point or a locked mechanism)"
    )]
    SingularJacobian { iterations: usize },
    #[error(
        "equilibrium not isolated: the residual is at rounding level ({residual:.1e}) after {iterations} iterations but Newton's steps do not shrink (relative step {step:.1e}), so the Jacobian is singular or nearly so there: a coordinate that no force or constraint holds (a hinge whose axis is the spin axis, without a spring) or a bifurcation point"
    )]
    NotIsolated {
        iterations: usize,
        residual: f64,
        step: f64,
    },
    #[error(
        "non-finite residual after {iterations} iterations (a number of the model overflows at this speed, or two points that define a direction coincide)"
    )]
    NotFinite { iterations: usize },
    #[error(
        "the drive force on '{coordinate}' is not a finite number (it overflows double precision)"
    )]
    NotFiniteDrive { coordinate: String },
    #[error("redundant cut joints or couplers: {} duplicate(s) the others here (the constraint Jacobian has rank {rank} for {equations} equations); remove it or them", names.join(", "))]
    RedundantConstraints {
        names: Vec<String>,
        rank: usize,
        equations: usize,
    },
    #[error(
        "the cut joint '{name}' has an equation that is redundant as drawn (and so not imposed) but {violation} at the equilibrium: the loop's constraint rank changes there (a singular configuration, or another assembly); close the loop without the redundancy"
    )]
    RankChanged {
        name: String,
        /// How the equation fails: `is violated by …`, or has no finite value.
        violation: String,
    },
    #[error(
        "no steady state: the equilibrium equations depend on the value of the driven coordinate {coordinate} (residual change {sensitivity:.3e}); is gravity along the drive axis, and is no load fixed in ground axes on what it turns (frame = \"body\" turns a load with its body)?"
    )]
    NoSteadyState {
        coordinate: String,
        sensitivity: f64,
    },
    #[error(
        "no steady state: the linearisation depends on the value of the driven coordinate {coordinate} although the equilibrium does not (as the coordinate turns, {change}), so the modes would be those of a periodic system; is gravity along the drive axis, and is no load fixed in ground axes on what it turns (frame = \"body\" turns a load with its body)?"
    )]
    UnsteadyLinearisation {
        coordinate: String,
        /// What changes, and by how much against what scale.
        change: String,
    },
}

/// A converged dynamic equilibrium.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Equilibrium {
    /// Operating speed (rad/s).
    pub speed: f64,
    /// All coordinates (rad or m).
    pub q: Vec<f64>,
    /// Coordinate speeds: drive speeds on driven coordinates, zero elsewhere.
    pub qd: Vec<f64>,
    /// Lagrange multipliers of the constraint equations.
    pub lambda: Vec<f64>,
    /// Generalised drive force on each coordinate (N·m or N; zero on free coordinates; empty
    /// when [`Settings::drive_force`] is off).
    pub drive_force: Vec<f64>,
    /// Newton iterations used.
    pub iterations: usize,
    /// Final residual ‖F‖∞.
    pub residual: f64,
    /// Largest constraint violation |Φ| at the solution.
    pub constraint_violation: f64,
    /// Newton's Jacobian `∂F/∂[q_R; λ]` at the solution. Its `q_R` block is the tangent
    /// stiffness `∂(r_R + Φ_Rᵀλ)/∂q_R` (λ held fixed), reused as the linearisation's K; the
    /// whole matrix is reused by the implicit-function step of the sensitivities.
    #[serde(skip)]
    pub jacobian: DMatrix<f64>,
}

/// What a solve hands on to the linearisation: the equilibrium and, where the route computed
/// them with the last Jacobian, the [`Rates`] there (the linearisation takes them rather than
/// computing them again).
#[derive(Debug, Clone)]
pub struct Solution {
    pub equilibrium: Equilibrium,
    /// `∂r_R/∂q̇_R` and `∂r_R/∂q̈_R` at the solution, on the recorded route.
    pub rates: Option<Rates>,
}

/// `‖F‖∞` at or below this times `1 + max|J|·max|x|` is rounding: `F`'s terms are of that
/// size, and double precision resolves their sum to a few hundred ulps of it.
const ROUNDING_FLOOR: f64 = 256.0 * f64::EPSILON;

/// Settings of the equilibrium solve.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    pub max_iterations: usize,
    /// Relative step size at which the solve has converged.
    pub step_tolerance: f64,
    /// Compute the drive forces (else `Equilibrium::drive_force` is empty).
    pub drive_force: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            max_iterations: 60,
            step_tolerance: 1e-12,
            drive_force: true,
        }
    }
}

/// What Newton may start from besides the coordinates.
#[derive(Debug, Clone, Copy, Default)]
pub struct Start<'a> {
    /// Multipliers (least squares at the start when absent).
    pub lambda: Option<&'a [f64]>,
    /// Jacobian of a nearby solution, kept for chord steps while they contract.
    pub jacobian: Option<&'a DMatrix<f64>>,
    /// The steady-state check has passed for this model and these parameters (at the previous
    /// speed of a sweep); it is not repeated.
    pub steady_known: bool,
}

/// Everything needed to solve for the equilibrium of one instantiated system.
pub struct Problem<'a> {
    pub free: Vec<usize>,
    pub driven: Vec<usize>,
    /// Coordinate names, for messages.
    pub names: Vec<&'a str>,
    /// The equations, evaluated by either route.
    route: Box<dyn Equations<f64> + 'a>,
    /// Coordinate speeds at steady state.
    pub qd: Vec<f64>,
    /// Number of constraint equations.
    m: usize,
    /// Driven coordinates on which `F` cannot depend, by the model's symmetry
    /// ([`crate::model::Model::steady_by_symmetry`]): the steady-state check skips them.
    pub symmetric: Vec<usize>,
    /// The largest change of a free coordinate in one step, relative to `1 + max|q_R|`, where
    /// one is set ([`Problem::limit_steps`]).
    step_limit: Option<f64>,
}

impl<'a> Problem<'a> {
    /// Prepares the solve of the equations `route` (either route's [`Equations`]); `qd` are the steady-state coordinate
    /// speeds, `driven` the driven coordinates and `names` all coordinates' names.
    pub fn new(
        route: Box<dyn Equations<f64> + 'a>,
        qd: Vec<f64>,
        driven: Vec<usize>,
        names: Vec<&'a str>,
    ) -> Self {
        Problem {
            free: route.free().to_vec(),
            m: route.constraints(),
            driven,
            names,
            qd,
            route,
            symmetric: Vec::new(),
            step_limit: None,
        }
    }

    /// Limits every step to change no free coordinate by more than `limit` times
    /// `1 + max|q_R|` (rad or m). For loops with equations dropped as redundant: the kept
    /// equations hold on the loop near its drawing but also on other sets away from it, which
    /// a long tangent step can reach (Newton then converges there, or stalls where the kept
    /// equations turn singular); short steps follow the loop. The limit of Adams's static
    /// solver (`ALIMIT`, 10° by default) plays the same part.
    pub fn limit_steps(&mut self, limit: f64) {
        self.step_limit = Some(limit);
    }

    /// The equations being solved.
    pub fn equations(&self) -> &dyn Equations<f64> {
        &*self.route
    }

    fn n_unknowns(&self) -> usize {
        self.free.len() + self.m
    }

    /// `F` and its Jacobian with respect to the unknowns `x = [q_R; λ]`.
    pub fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        self.route.residual_and_jacobian(q, lambda)
    }

    /// `F` alone, in `f64`.
    pub fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.route.residual(q, lambda)
    }

    fn evaluate(&self, q: &[f64], lambda: &[f64], drive: bool) -> Evaluation {
        self.route.evaluate(q, lambda, drive)
    }

    /// Solves from the guess `q0` (all coordinates; driven ones keep their values).
    ///
    /// Newton–chord: a Jacobian is kept while the steps it gives shrink at least twofold
    /// (each step then costs one `f64` residual instead of a Jacobian), and re-evaluated when
    /// they do not, or when the line search fails with it. `start` may supply the multipliers
    /// and the Jacobian of a nearby solution (the previous speed of a sweep).
    ///
    /// Converged means: the Newton step with the exact Jacobian *at the returned point* is
    /// below the step tolerance. When chord steps estimate the error left at a thousandth of
    /// the tolerance (ρ/(1−ρ) times the last step, for a contraction rate ρ; rounding where
    /// the steps stop contracting), the Jacobian is evaluated there, with the linearisation's
    /// other matrices, and its step confirms it (else Newton goes on from there). So the
    /// returned Jacobian, and the rates, are those of the returned point, which the
    /// linearisation and the sensitivities use. Where `F` is zero to rounding there but that
    /// Jacobian is nearly singular along a continuum of equilibria its factorisation did not
    /// flag, its step is rounding and the chord's estimate certifies the point alone.
    pub fn solve(
        &self,
        speed: f64,
        q0: &[f64],
        start: Start,
        settings: Settings,
    ) -> Result<Solution, EquilibriumError> {
        let mut it = self.start(q0, start, settings.drive_force);
        let mut converged = false;
        let mut iterations = 0;
        while iterations < settings.max_iterations {
            if it.f.iter().any(|v| !v.is_finite()) {
                return Err(EquilibriumError::NotFinite { iterations });
            }
            iterations += 1;
            match self.iterate(&mut it, iterations, settings) {
                Step::Converged => {
                    converged = true;
                    break;
                }
                Step::Continue => {}
                Step::Failed(err) => return Err(err),
            }
        }
        if it.f.iter().any(|v| !v.is_finite()) {
            return Err(EquilibriumError::NotFinite { iterations });
        }
        if !converged {
            // The limit reached: the exact Jacobian's step at the last point decides, by the
            // one criterion of convergence, so that a point the last iteration reached (a
            // chord's step, say) is not reported as a failure when it has converged.
            if !it.fresh {
                it.refresh(self, settings.drive_force);
            }
            converged = it.lu.solve(&it.f).is_some_and(|step| {
                let dir = self.direction(&it, step);
                matches!(
                    it.certify(&dir, iterations, settings.step_tolerance),
                    Some(Step::Converged)
                )
            });
        }
        if !converged {
            return Err(EquilibriumError::NewtonDiverged {
                iterations,
                residual: max_abs(&it.f),
            });
        }
        if !start.steady_known {
            self.check_steady(&it.q, &it.lambda, &it.jac, it.rates.as_ref(), it.balance)?;
        }
        self.finish(speed, it, iterations, settings.drive_force)
    }

    /// Newton's first iterate from the guess `q0`: the multipliers and the Jacobian from
    /// `start` where it has them (a kept Jacobian is not fresh: only `F` is evaluated), else
    /// evaluated at `q0` (the multipliers fitted by least squares when `start` has none). The
    /// system is balanced once, from this first Jacobian (see [`Balance`]), and factorised.
    fn start(&self, q0: &[f64], start: Start, drive_wanted: bool) -> Iterate {
        let nf = self.free.len();
        let m = self.m;
        let nx = nf + m;
        let q = q0.to_vec();
        let given = start.lambda.filter(|l| l.len() == m);
        let (lambda, e, fresh) = match (given, start.jacobian) {
            (Some(l), Some(j)) if j.nrows() == nx && j.ncols() == nx => (
                l.to_vec(),
                Evaluation {
                    residual: self.residual(&q, l),
                    jacobian: j.clone(),
                    rates: None,
                    drive: None,
                },
                false,
            ),
            (Some(l), _) => (l.to_vec(), self.evaluate(&q, l, drive_wanted), true),
            (None, _) => {
                let (l, e) = self.evaluate_fitted(&q, drive_wanted);
                (l, e, true)
            }
        };
        // Newton's system balanced once, from its first Jacobian (see [`Balance`]).
        let balance = Balance::of(&e.jacobian, nf);
        let lu = Factor::with(balance, &e.jacobian);
        Iterate {
            q,
            lambda,
            f: e.residual,
            jac: e.jacobian,
            rates: e.rates,
            drive: e.drive,
            fresh,
            balance,
            lu,
            last_step: f64::INFINITY,
            at_floor: 0,
            chord_certified: false,
        }
    }

    /// One iteration of Newton–chord from `it` (the `iterations`-th): the step `Δx = J⁻¹F`
    /// with the current factorisation (a fresh Jacobian where it fails and the Jacobian was
    /// kept), the convergence certificate ([`Iterate::certify`]), the chord steps' contraction
    /// test ([`Iterate::chord`]) and the line search ([`Iterate::line_search`]).
    fn iterate(&self, it: &mut Iterate, iterations: usize, settings: Settings) -> Step {
        let tol = settings.step_tolerance;
        let drive_wanted = settings.drive_force;
        let step = it
            .lu
            .solve(&it.f)
            .filter(|s| s.iter().all(|v| v.is_finite()));
        let Some(step) = step else {
            if it.fresh {
                return Step::Failed(EquilibriumError::SingularJacobian { iterations });
            }
            it.refresh(self, drive_wanted);
            return Step::Continue;
        };
        let dir = self.direction(it, step);
        if let Some(outcome) = it.certify(&dir, iterations, tol) {
            return outcome;
        }
        if !it.fresh && it.chord(self, &dir, tol, drive_wanted) {
            return Step::Continue;
        }
        it.line_search(self, &dir, drive_wanted);
        Step::Continue
    }

    /// The step `step` from `it` with its relative size: the largest coordinate change over
    /// `1 + max|q_R|` against the largest multiplier change over a thousand times
    /// `1 + max|λ|/α`, both multipliers in the balanced units (forces over α).
    fn direction(&self, it: &Iterate, step: Vec<f64>) -> Direction<'_> {
        let nf = self.free.len();
        let m = self.m;
        let force = it.balance.alpha;
        let q_scale = 1.0 + self.free.iter().fold(0.0f64, |s, &i| s.max(it.q[i].abs()));
        // The multipliers in the balanced units (forces over α).
        let l_scale = 1.0 + max_abs(&it.lambda) / force;
        let dq = (0..nf).fold(0.0f64, |s, k| s.max(step[k].abs()));
        let dl = (0..m).fold(0.0f64, |s, k| s.max(step[nf + k].abs())) / force;
        let size = (dq / q_scale).max(dl / (1e3 * l_scale));
        Direction {
            free: &self.free,
            step,
            q_scale,
            l_scale,
            force,
            size,
        }
    }

    /// The converged point as an [`Equilibrium`]: the drive forces (from the evaluation at the
    /// returned point where it has them, when `drive_wanted`), every reported number checked
    /// finite, and the constraint violation `max|Φ|`.
    fn finish(
        &self,
        speed: f64,
        it: Iterate,
        iterations: usize,
        drive_wanted: bool,
    ) -> Result<Solution, EquilibriumError> {
        let nf = self.free.len();
        let Iterate {
            q,
            lambda,
            f,
            jac,
            rates,
            drive,
            ..
        } = it;
        let mut drive_force = vec![0.0; if drive_wanted { q.len() } else { 0 }];
        if drive_wanted {
            // From the evaluation at the returned point where it has them (a converged solve
            // ends on one).
            let rows = drive.unwrap_or_else(|| self.route.drive_rows(&q, &lambda, &self.driven));
            for (&i, v) in self.driven.iter().zip(rows) {
                drive_force[i] = v;
            }
        }
        // Every number reported must be finite: a drive force that overflows (a huge inertia
        // or speed) fails the point with its reason rather than printing ±inf.
        if let Some(k) = drive_force.iter().position(|v| !v.is_finite()) {
            return Err(EquilibriumError::NotFiniteDrive {
                coordinate: self.names.get(k).map_or(String::new(), |n| n.to_string()),
            });
        }
        if q.iter().chain(&lambda).any(|v| !v.is_finite()) {
            return Err(EquilibriumError::NotFinite { iterations });
        }
        let constraint_violation = max_abs(&f[nf..]);
        Ok(Solution {
            equilibrium: Equilibrium {
                speed,
                constraint_violation,
                residual: max_abs(&f),
                jacobian: jac,
                q,
                qd: self.qd.clone(),
                lambda,
                drive_force,
                iterations,
            },
            rates,
        })
    }

    fn evaluate_fitted(&self, q: &[f64], drive: bool) -> (Vec<f64>, Evaluation) {
        self.route.evaluate_fitted(q, drive, &least_squares)
    }

    /// Constraint equations (indices) that are linear combinations of the others at `q`, so
    /// that the equilibrium Jacobian is singular whatever the speed.
    pub fn redundant_equations(&self, q: &[f64]) -> Vec<usize> {
        if self.m == 0 {
            return Vec::new();
        }
        let phi_r = self.route.constraint_jacobian(q);
        crate::linalg::dependent_rows(&phi_r)
    }

    /// Newton unknowns.
    pub fn unknowns(&self) -> usize {
        self.n_unknowns()
    }
}

/// `max |v|` (`‖·‖∞`), 0 for an empty slice.
fn max_abs(f: &[f64]) -> f64 {
    f.iter().fold(0.0f64, |s, v| s.max(v.abs()))
}
