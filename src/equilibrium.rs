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
//! systems in dynamic equilibrium*, eq. 13; Nocedal & Wright, *Numerical Optimization*, §11.

use crate::linalg::{Lu, amax, least_squares};
use crate::mechanics::dynamics::evaluate_rows;
use crate::real::{D1, lift1};
use crate::route::{Direct, Equations};
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;

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
    #[error("redundant cut joints: {} duplicate(s) the others here (the constraint Jacobian has rank {rank} for {equations} equations); remove it or them", names.join(", "))]
    RedundantConstraints {
        names: Vec<String>,
        rank: usize,
        equations: usize,
    },
    #[error(
        "no steady state: the equilibrium equations depend on the value of the driven coordinate '{coordinate}' (residual change {sensitivity:.3e}); is gravity along the drive axis?"
    )]
    NoSteadyState {
        coordinate: String,
        sensitivity: f64,
    },
}

/// `∂r_R/∂q̇_R` and `∂r_R/∂q̈_R` (the linearisation's damping and mass matrices before
/// reduction).
pub type Rates = (DMatrix<f64>, DMatrix<f64>);

/// `F`, its Jacobian and, on the recorded route, the [`Rates`] and the driven coordinates'
/// rows of `r + Φ_qᵀλ`, at one point.
pub type Evaluation = (Vec<f64>, DMatrix<f64>, Option<Rates>, Option<Vec<f64>>);

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
    /// `∂r_R/∂q̇_R` and `∂r_R/∂q̈_R` at the solution, when the recorded program computed
    /// them with the Jacobian (the linearisation takes them from here rather than computing
    /// them again; a [`crate::sweep::Point`]'s are in its linearisation).
    #[serde(skip)]
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

/// The equations of a point as Newton's method uses them: [`Equations`] in `f64` with the
/// exact Jacobian and what a converged point needs besides. Implemented by the direct route
/// ([`Direct`], here) and by the recorded program ([`crate::program::Instance`]).
pub trait Solvable: Equations<f64> {
    /// `F` and its Jacobian with respect to the unknowns `x = [q_R; λ]`.
    fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>);

    /// `F`, its exact Jacobian and, where the route has them from the same pass, the
    /// [`Rates`] and (with `drive`) the driven coordinates' rows of `r + Φ_qᵀλ`: everything
    /// the linearisation needs, so that a solve whose last Newton step is below the tolerance
    /// needs no further evaluation.
    fn evaluate(&self, q: &[f64], lambda: &[f64], drive: bool) -> Evaluation {
        let _ = drive;
        let (f, j) = self.residual_and_jacobian(q, lambda);
        (f, j, None, None)
    }

    /// [`Solvable::evaluate`] at `q` with the least-squares multipliers there
    /// (`Φ_Rᵀ λ ≈ −r_R`), and those multipliers.
    fn evaluate_fitted(&self, q: &[f64], drive: bool) -> (Vec<f64>, Evaluation);

    /// The rows `driven` of `r + Φ_qᵀλ` (with `q̇` at steady state, `q̈ = 0`): the drive forces.
    fn drive_rows(&self, q: &[f64], lambda: &[f64], driven: &[usize]) -> Vec<f64>;

    /// The largest `|F|` at each of the values `q_c + offsets[l]` of the driven coordinate `c`
    /// (the `d`-th driven one), the rest as given.
    fn residual_at_drive_offsets(
        &self,
        q: &[f64],
        lambda: &[f64],
        d: usize,
        c: usize,
        offsets: [f64; 3],
    ) -> [f64; 3] {
        let _ = d;
        let mut qo = q.to_vec();
        offsets.map(|offset| {
            qo[c] = q[c] + offset;
            let f = self.residual(&qo, lambda);
            f.iter().fold(0.0f64, |a, v| a.max(v.abs()))
        })
    }

    /// `Φ_R` (constraint equations × free coordinates) at `q`.
    fn constraint_jacobian(&self, q: &[f64]) -> DMatrix<f64>;
}

impl Solvable for Direct<f64> {
    /// One dual pass per free coordinate; `F` is linear in `λ`, so the `λ` columns are
    /// `[Φ_Rᵀ; 0]`, read off `Φ_q` from those same passes.
    fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        let dual = self.dual();
        let free = self.free();
        let nf = free.len();
        let m = lambda.len();
        let qd: Vec<D1<f64>> = self.steady_speeds().iter().map(|&v| lift1(v)).collect();
        let ld: Vec<D1<f64>> = lambda.iter().map(|&v| lift1(v)).collect();
        let zero = vec![lift1(0.0); q.len()];
        let base: Vec<D1<f64>> = q.iter().map(|&v| lift1(v)).collect();
        let mut value = Vec::new();
        let mut jac = DMatrix::zeros(nf + m, nf + m);
        for (k, &i) in free.iter().enumerate() {
            let mut qq = base.clone();
            qq[i] = Dual64::new(q[i], 1.0);
            let d = evaluate_rows(dual, &qq, &qd, &zero, free);
            let g = d.with_multipliers(&ld);
            let f: Vec<D1<f64>> = free
                .iter()
                .map(|&j| g[j])
                .chain(d.phi.iter().copied())
                .collect();
            for (r, v) in f.iter().enumerate() {
                jac[(r, k)] = v.eps;
            }
            if k == 0 {
                value = f.iter().map(|v| v.re).collect();
                for c in 0..m {
                    for (r, &j) in free.iter().enumerate() {
                        jac[(r, nf + c)] = d.phi_q[(c, j)].re;
                    }
                }
            }
        }
        (value, jac)
    }

    fn evaluate_fitted(&self, q: &[f64], drive: bool) -> (Vec<f64>, Evaluation) {
        let free = self.free();
        let (nf, m) = (free.len(), self.constraints());
        let zero = vec![0.0; q.len()];
        let d = evaluate_rows(self.lifted(), q, self.steady_speeds(), &zero, free);
        let lambda = least_squares(
            DMatrix::from_fn(nf, m, |i, k| d.phi_q[(k, free[i])]),
            DVector::from_iterator(nf, free.iter().map(|&i| -d.r[i])),
        );
        let e = self.evaluate(q, &lambda, drive);
        (lambda, e)
    }

    fn drive_rows(&self, q: &[f64], lambda: &[f64], driven: &[usize]) -> Vec<f64> {
        let zero = vec![0.0; q.len()];
        let d = evaluate_rows(self.lifted(), q, self.steady_speeds(), &zero, driven);
        let g = d.with_multipliers(lambda);
        driven.iter().map(|&i| g[i]).collect()
    }

    fn constraint_jacobian(&self, q: &[f64]) -> DMatrix<f64> {
        let free = self.free();
        let zero = vec![0.0; q.len()];
        let d = evaluate_rows(self.lifted(), q, self.steady_speeds(), &zero, free);
        DMatrix::from_fn(self.constraints(), free.len(), |k, j| d.phi_q[(k, free[j])])
    }
}

/// Everything needed to solve for the equilibrium of one instantiated system.
pub struct Problem<'a> {
    pub free: Vec<usize>,
    pub driven: Vec<usize>,
    /// Coordinate names, for messages.
    pub names: Vec<&'a str>,
    /// The equations, evaluated by either route.
    route: Box<dyn Solvable + 'a>,
    /// Coordinate speeds at steady state.
    pub qd: Vec<f64>,
    /// Number of constraint equations.
    m: usize,
    /// Driven coordinates on which `F` cannot depend, by the model's symmetry
    /// ([`crate::model::Model::steady_by_symmetry`]): the steady-state check skips them.
    pub symmetric: Vec<usize>,
}

impl<'a> Problem<'a> {
    /// Prepares the solve of the equations `route`; `qd` are the steady-state coordinate
    /// speeds, `driven` the driven coordinates and `names` all coordinates' names.
    pub fn new(
        route: Box<dyn Solvable + 'a>,
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
        }
    }

    /// The equations being solved.
    pub fn equations(&self) -> &dyn Solvable {
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
    /// linearisation and the sensitivities use.
    pub fn solve(
        &self,
        speed: f64,
        q0: &[f64],
        start: Start,
        settings: Settings,
    ) -> Result<Equilibrium, EquilibriumError> {
        let nf = self.free.len();
        let m = self.m;
        let nx = nf + m;
        let tol = settings.step_tolerance;
        let drive_wanted = settings.drive_force;
        let mut q = q0.to_vec();
        let norm = |f: &[f64]| f.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let given = start.lambda.filter(|l| l.len() == m);
        let (mut lambda, (mut f, mut jac, mut rates, mut drive), mut fresh) =
            match (given, start.jacobian) {
                (Some(l), Some(j)) if j.nrows() == nx && j.ncols() == nx => (
                    l.to_vec(),
                    (self.residual(&q, l), j.clone(), None, None),
                    false,
                ),
                (Some(l), _) => (l.to_vec(), self.evaluate(&q, l, drive_wanted), true),
                (None, _) => {
                    let (l, e) = self.evaluate_fitted(&q, drive_wanted);
                    (l, e, true)
                }
            };
        let mut lu = Lu::new(jac.clone());
        // Size of the last step (relative), for the contraction test.
        let mut last_step = f64::INFINITY;
        let mut converged = false;
        let mut iterations = 0;
        // Fresh Jacobians evaluated where F is at its rounding floor.
        let mut at_floor = 0;
        while iterations < settings.max_iterations {
            if f.iter().any(|v| !v.is_finite()) {
                return Err(EquilibriumError::NotFinite { iterations });
            }
            iterations += 1;
            let step = lu.solve(&f).filter(|s| s.iter().all(|v| v.is_finite()));
            let Some(step) = step else {
                if fresh {
                    return Err(EquilibriumError::SingularJacobian { iterations });
                }
                (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                (lu, fresh, last_step) = (Lu::new(jac.clone()), true, f64::INFINITY);
                continue;
            };
            let q_scale = 1.0 + self.free.iter().fold(0.0f64, |s, &i| s.max(q[i].abs()));
            let l_scale = 1.0 + norm(&lambda);
            let dq = (0..nf).fold(0.0f64, |s, k| s.max(step[k].abs()));
            let dl = (0..m).fold(0.0f64, |s, k| s.max(step[nf + k].abs()));
            let size = (dq / q_scale).max(dl / (1e3 * l_scale));
            let apply = |q: &mut [f64], lambda: &mut [f64], alpha: f64| {
                for (k, &i) in self.free.iter().enumerate() {
                    q[i] -= alpha * step[k];
                }
                for (k, l) in lambda.iter_mut().enumerate() {
                    *l -= alpha * step[nf + k];
                }
            };
            if fresh && size <= tol {
                converged = true;
                break;
            }
            // F satisfied to rounding while the exact Jacobian's steps stay above the tolerance:
            // the steps are rounding noise through a (nearly) singular Jacobian, and Newton
            // would wander to its iteration limit. After a few such evaluations, say so.
            if fresh && norm(&f) <= ROUNDING_FLOOR * (1.0 + amax(&jac) * q_scale.max(l_scale)) {
                at_floor += 1;
                if at_floor >= 3 {
                    return Err(EquilibriumError::NotIsolated {
                        iterations,
                        residual: norm(&f),
                        step: size,
                    });
                }
            }
            if !fresh {
                // The error left after a chord step contracting by ρ is about ρ/(1−ρ) times
                // its size; where the steps stop contracting at the tolerance, it is rounding.
                let rho = if last_step.is_finite() {
                    size / last_step
                } else {
                    1.0
                };
                let left = if rho < 1.0 {
                    size * rho / (1.0 - rho)
                } else {
                    size
                };
                if left <= 1e-3 * tol || (size <= tol && rho > 0.5) {
                    apply(&mut q, &mut lambda, 1.0);
                    (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                    (lu, fresh, last_step) = (Lu::new(jac.clone()), true, f64::INFINITY);
                    continue;
                }
                // Steps that do not contract fast: evaluate the Jacobian here.
                if size > 0.5 * last_step {
                    (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                    (lu, fresh, last_step) = (Lu::new(jac.clone()), true, f64::INFINITY);
                    continue;
                }
            }
            // Backtrack on ‖F‖₂.
            let f0 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
            let mut alpha = 1.0;
            let (mut q_new, mut l_new, mut f_new);
            let mut decreased;
            loop {
                (q_new, l_new) = (q.clone(), lambda.clone());
                apply(&mut q_new, &mut l_new, alpha);
                f_new = self.residual(&q_new, &l_new);
                let f1 = f_new.iter().map(|v| v * v).sum::<f64>().sqrt();
                decreased = f1.is_finite() && f1 <= (1.0 - 1e-4 * alpha) * f0;
                if decreased || alpha < 1e-4 {
                    break;
                }
                alpha *= 0.5;
            }
            if !decreased && !fresh {
                (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                (lu, fresh, last_step) = (Lu::new(jac.clone()), true, f64::INFINITY);
                continue;
            }
            (q, lambda, f) = (q_new, l_new, f_new);
            (fresh, rates, drive) = (false, None, None);
            last_step = alpha * size;
        }
        if f.iter().any(|v| !v.is_finite()) {
            return Err(EquilibriumError::NotFinite { iterations });
        }
        if !converged {
            return Err(EquilibriumError::NewtonDiverged {
                iterations,
                residual: norm(&f),
            });
        }
        if !start.steady_known {
            self.check_steady(&q, &lambda, &jac)?;
        }
        let mut drive_force = vec![0.0; if settings.drive_force { q.len() } else { 0 }];
        if settings.drive_force {
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
        let constraint_violation = norm(&f[nf..]);
        Ok(Equilibrium {
            speed,
            constraint_violation,
            rates,
            residual: norm(&f),
            jacobian: jac,
            q,
            qd: self.qd.clone(),
            lambda,
            drive_force,
            iterations,
        })
    }

    fn evaluate_fitted(&self, q: &[f64], drive: bool) -> (Vec<f64>, Evaluation) {
        self.route.evaluate_fitted(q, drive)
    }

    /// Fails when `F` depends on a driven coordinate's value: then `q_D = Ω t` makes the
    /// equilibrium drift and there is no steady state. Checked by `F` itself at three other
    /// values of each driven coordinate. With `F = 0` at the solution, that is four conditions:
    /// a dependence through one revolution's sine and cosine (gravity off a spin axis) cannot
    /// vanish at all four, wherever it is stationary. Coordinates on which `F` cannot depend by
    /// the model's symmetry (`symmetric`) are not evaluated.
    fn check_steady(
        &self,
        q: &[f64],
        lambda: &[f64],
        jac: &DMatrix<f64>,
    ) -> Result<(), EquilibriumError> {
        // Scaled by the Jacobian and the unknowns, found once and only when a drive is checked
        // (a model whose drives are all steady by symmetry never needs it).
        let tol = std::cell::LazyCell::new(|| {
            let x_scale = 1.0 + q.iter().chain(lambda).fold(0.0f64, |s, v| s.max(v.abs()));
            1e-8 * amax(jac).max(1.0) * x_scale
        });
        const OFFSETS: [f64; 3] = [1.0, 2.5, -2.0];
        for (d, &c) in self.driven.iter().enumerate() {
            if self.symmetric.contains(&c) {
                continue;
            }
            let change = self
                .route
                .residual_at_drive_offsets(q, lambda, d, c, OFFSETS);
            let change = change.iter().fold(0.0f64, |a, &v| a.max(v));
            if change > *tol {
                return Err(EquilibriumError::NoSteadyState {
                    coordinate: self.names[c].to_string(),
                    sensitivity: change,
                });
            }
        }
        Ok(())
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
