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

use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, evaluate_rows};
use crate::program::Instance;
use crate::real::{D1, Real, cst, lift1};
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;
use std::cell::OnceCell;

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
type Evaluation = (Vec<f64>, DMatrix<f64>, Option<Rates>, Option<Vec<f64>>);

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

/// The equilibrium equations `F` for unknowns `q_R` (placed into `q`) and `λ`.
pub fn equations<T: Real>(
    l: &Lifted<T>,
    free: &[usize],
    q: &[T],
    qd: &[T],
    lambda: &[T],
) -> Vec<T> {
    let zero = vec![cst::<T>(0.0); q.len()];
    let d = evaluate_rows(l, q, qd, &zero, free);
    let g = d.with_multipliers(lambda);
    free.iter()
        .map(|&i| g[i])
        .chain(d.phi.iter().copied())
        .collect()
}

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

/// The least-squares solution of `a λ = b` (zero if that fails; empty when `a` has no
/// columns): by QR where `a` has full column rank, the usual case, else by SVD (the
/// minimum-norm solution).
fn least_squares(a: DMatrix<f64>, b: DVector<f64>) -> Vec<f64> {
    let m = a.ncols();
    if m == 0 {
        return Vec::new();
    }
    if a.nrows() >= m {
        let qr = a.clone().qr();
        let r = qr.r();
        let d = r.diagonal().map(f64::abs);
        if d.min() > 1e-12 * d.max() {
            let qtb = qr.q().tr_mul(&b);
            if let Some(l) = r.solve_upper_triangular(&qtb)
                && l.iter().all(|v| v.is_finite())
            {
                return l.iter().copied().collect();
            }
        }
    }
    match crate::linalg::svd(a, true, true).map(|svd| svd.solve(&b, 1e-12)) {
        Some(Ok(l)) if l.iter().all(|v| v.is_finite()) => l.iter().copied().collect(),
        _ => vec![0.0; m],
    }
}

/// The system lifted for the direct route's values, made on first use.
fn lift_value<'c>(sys: &System<f64>, cell: &'c OnceCell<Box<Lifted<f64>>>) -> &'c Lifted<f64> {
    cell.get_or_init(|| Box::new(Lifted::new(sys.clone())))
}

/// The system lifted for the direct route's first derivatives, made on first use.
fn lift_dual<'c>(sys: &System<f64>, cell: &'c OnceCell<Box<Lifted<Dual64>>>) -> &'c Lifted<Dual64> {
    cell.get_or_init(|| Box::new(Lifted::new(sys.map(lift1))))
}

/// How a [`Problem`] evaluates its equations.
enum Route<'a> {
    /// The model's recorded program at the problem's parameters and speed (same numbers as
    /// the direct route, less work).
    Recorded(Box<Instance<'a>>),
    /// The generic code over dual numbers, with the system lifted on first use.
    Direct {
        sys: Box<System<f64>>,
        value: OnceCell<Box<Lifted<f64>>>,
        dual: OnceCell<Box<Lifted<Dual64>>>,
    },
}

/// Everything needed to solve for the equilibrium of one instantiated system.
pub struct Problem<'a> {
    pub free: Vec<usize>,
    pub driven: Vec<usize>,
    /// Coordinate names, for messages.
    pub names: Vec<&'a str>,
    route: Route<'a>,
    /// Coordinate speeds at steady state.
    pub qd: Vec<f64>,
    /// Number of constraint equations.
    m: usize,
}

impl<'a> Problem<'a> {
    /// Prepares the solve for `sys`, evaluated directly; `free`/`driven` partition the
    /// coordinates.
    pub fn new(
        sys: System<f64>,
        free: Vec<usize>,
        driven: Vec<usize>,
        names: Vec<&'a str>,
    ) -> Self {
        Problem {
            free,
            driven,
            names,
            qd: sys.steady_speeds(),
            m: sys.m,
            route: Route::Direct {
                sys: Box::new(sys),
                value: OnceCell::new(),
                dual: OnceCell::new(),
            },
        }
    }

    /// Prepares the solve through the model's recorded program at the problem's parameters
    /// and speed; `qd` are the steady-state coordinate speeds.
    pub fn recorded(
        program: Instance<'a>,
        qd: Vec<f64>,
        free: Vec<usize>,
        driven: Vec<usize>,
        names: Vec<&'a str>,
    ) -> Self {
        Problem {
            m: program.constraints(),
            free,
            driven,
            names,
            qd,
            route: Route::Recorded(Box::new(program)),
        }
    }

    /// The system lifted for the direct route's first derivatives, also the linearisation's
    /// (`None` on the recorded route).
    pub fn dual(&self) -> Option<&Lifted<Dual64>> {
        match &self.route {
            Route::Direct { sys, dual, .. } => Some(lift_dual(sys, dual)),
            Route::Recorded(_) => None,
        }
    }

    fn n_unknowns(&self) -> usize {
        self.free.len() + self.m
    }

    /// `F` and its Jacobian with respect to the unknowns `x = [q_R; λ]`.
    ///
    /// One dual pass per free coordinate; `F` is linear in `λ`, so the `λ` columns are
    /// `[Φ_Rᵀ; 0]`, read off `Φ_q` from those same passes.
    pub fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        let dual = match &self.route {
            Route::Recorded(c) => return c.residual_and_jacobian(q, lambda),
            Route::Direct { sys, dual, .. } => lift_dual(sys, dual),
        };
        let nf = self.free.len();
        let m = lambda.len();
        let qd: Vec<D1<f64>> = self.qd.iter().map(|&v| lift1(v)).collect();
        let ld: Vec<D1<f64>> = lambda.iter().map(|&v| lift1(v)).collect();
        let zero = vec![lift1(0.0); q.len()];
        let base: Vec<D1<f64>> = q.iter().map(|&v| lift1(v)).collect();
        let mut value = Vec::new();
        let mut jac = DMatrix::zeros(nf + m, nf + m);
        for (k, &i) in self.free.iter().enumerate() {
            let mut qq = base.clone();
            qq[i] = Dual64::new(q[i], 1.0);
            let d = evaluate_rows(dual, &qq, &qd, &zero, &self.free);
            let g = d.with_multipliers(&ld);
            let f: Vec<D1<f64>> = self
                .free
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
                    for (r, &j) in self.free.iter().enumerate() {
                        jac[(r, nf + c)] = d.phi_q[(c, j)].re;
                    }
                }
            }
        }
        (value, jac)
    }

    /// `F` alone, in `f64` (one partial-velocity pass per free coordinate, no derivatives of
    /// them).
    pub fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        match &self.route {
            Route::Recorded(c) => c.residual(q, lambda),
            Route::Direct { sys, value, .. } => {
                equations(lift_value(sys, value), &self.free, q, &self.qd, lambda)
            }
        }
    }

    /// `F`, its exact Jacobian and, on the recorded route, `∂r_R/∂q̇_R` and `∂r_R/∂q̈_R`, at
    /// `(q, λ)`: everything the linearisation needs, so that a solve whose last Newton step
    /// is below the tolerance needs no further evaluation.
    fn evaluate(&self, q: &[f64], lambda: &[f64], drive: bool) -> Evaluation {
        match &self.route {
            Route::Recorded(c) => {
                let lin = c.linear(q, lambda, drive);
                (
                    lin.residual,
                    lin.jacobian,
                    Some((lin.damping, lin.mass)),
                    drive.then_some(lin.drive),
                )
            }
            Route::Direct { .. } => {
                let (f, j) = self.residual_and_jacobian(q, lambda);
                (f, j, None, None)
            }
        }
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
        let mut lu = jac.clone().lu();
        // Size of the last step (relative), for the contraction test.
        let mut last_step = f64::INFINITY;
        let mut converged = false;
        let mut iterations = 0;
        while iterations < settings.max_iterations {
            if f.iter().any(|v| !v.is_finite()) {
                return Err(EquilibriumError::NotFinite { iterations });
            }
            iterations += 1;
            let step = lu
                .solve(&DVector::from_column_slice(&f))
                .filter(|s| s.iter().all(|v| v.is_finite()));
            let Some(step) = step else {
                if fresh {
                    return Err(EquilibriumError::SingularJacobian { iterations });
                }
                (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                (lu, fresh, last_step) = (jac.clone().lu(), true, f64::INFINITY);
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
                    (lu, fresh, last_step) = (jac.clone().lu(), true, f64::INFINITY);
                    continue;
                }
                // Steps that do not contract fast: evaluate the Jacobian here.
                if size > 0.5 * last_step {
                    (f, jac, rates, drive) = self.evaluate(&q, &lambda, drive_wanted);
                    (lu, fresh, last_step) = (jac.clone().lu(), true, f64::INFINITY);
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
                (lu, fresh, last_step) = (jac.clone().lu(), true, f64::INFINITY);
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
        match (&self.route, drive) {
            _ if !settings.drive_force => {}
            // From the evaluation at the returned point (a converged solve ends on one).
            (Route::Recorded(c), rows) => {
                let rows = rows.unwrap_or_else(|| c.linear(&q, &lambda, true).drive);
                for (&i, v) in self.driven.iter().zip(rows) {
                    drive_force[i] = v;
                }
            }
            (Route::Direct { sys, value, .. }, _) => {
                let zero = vec![0.0; q.len()];
                let d = evaluate_rows(lift_value(sys, value), &q, &self.qd, &zero, &self.driven);
                let g = d.with_multipliers(&lambda);
                for &i in &self.driven {
                    drive_force[i] = g[i];
                }
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

    /// [`Problem::evaluate`] at `q` with the least-squares multipliers there (`Φ_Rᵀ λ ≈
    /// −r_R`), and those multipliers. On the recorded route this is one pass: the pass at
    /// `λ = 0` gives `r_R` and `Φ_R`, and is then shifted to the multipliers
    /// ([`crate::program::Linear::shift_multipliers`]).
    fn evaluate_fitted(&self, q: &[f64], drive: bool) -> (Vec<f64>, Evaluation) {
        let (nf, m) = (self.free.len(), self.m);
        match &self.route {
            Route::Recorded(c) => {
                let mut lin = c.linear(q, &vec![0.0; m], drive);
                let lambda = least_squares(
                    lin.jacobian.view((0, nf), (nf, m)).into_owned(),
                    DVector::from_iterator(nf, lin.residual[..nf].iter().map(|v| -v)),
                );
                lin.shift_multipliers(&lambda);
                (
                    lambda,
                    (
                        lin.residual,
                        lin.jacobian,
                        Some((lin.damping, lin.mass)),
                        drive.then_some(lin.drive),
                    ),
                )
            }
            Route::Direct { sys, value, .. } => {
                let zero = vec![0.0; q.len()];
                let d = evaluate_rows(lift_value(sys, value), q, &self.qd, &zero, &self.free);
                let lambda = least_squares(
                    DMatrix::from_fn(nf, m, |i, k| d.phi_q[(k, self.free[i])]),
                    DVector::from_iterator(nf, self.free.iter().map(|&i| -d.r[i])),
                );
                let e = self.evaluate(q, &lambda, drive);
                (lambda, e)
            }
        }
    }

    /// Fails when `F` depends on a driven coordinate's value: then `q_D = Ω t` makes the
    /// equilibrium drift and there is no steady state. Checked by `F` itself at three other
    /// values of each driven coordinate. With `F = 0` at the solution, that is four conditions:
    /// a dependence through one revolution's sine and cosine (gravity off a spin axis) cannot
    /// vanish at all four, wherever it is stationary.
    fn check_steady(
        &self,
        q: &[f64],
        lambda: &[f64],
        jac: &DMatrix<f64>,
    ) -> Result<(), EquilibriumError> {
        let x_scale = 1.0 + q.iter().chain(lambda).fold(0.0f64, |s, v| s.max(v.abs()));
        let tol = 1e-8 * jac.amax().max(1.0) * x_scale;
        const OFFSETS: [f64; 3] = [1.0, 2.5, -2.0];
        let mut qo = q.to_vec();
        for (d, &c) in self.driven.iter().enumerate() {
            let change = match &self.route {
                Route::Recorded(p) => p.residual_at_drive_offsets(q, lambda, d, OFFSETS),
                Route::Direct { .. } => OFFSETS.map(|offset| {
                    qo[c] = q[c] + offset;
                    let f = self.residual(&qo, lambda);
                    qo[c] = q[c];
                    f.iter().fold(0.0f64, |a, v| a.max(v.abs()))
                }),
            };
            let change = change.iter().fold(0.0f64, |a, &v| a.max(v));
            if change > tol {
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
        let nf = self.free.len();
        let phi_r = match &self.route {
            // The λ columns of the Jacobian are [Φ_Rᵀ; 0].
            Route::Recorded(c) => {
                let (_, j) = c.residual_and_jacobian(q, &vec![0.0; self.m]);
                j.view((0, nf), (nf, self.m)).transpose()
            }
            Route::Direct { sys, value, .. } => {
                let zero = vec![0.0; q.len()];
                let d = evaluate_rows(lift_value(sys, value), q, &self.qd, &zero, &self.free);
                DMatrix::from_fn(self.m, nf, |k, j| d.phi_q[(k, self.free[j])])
            }
        };
        crate::linalg::dependent_rows(&phi_r)
    }

    /// Newton unknowns.
    pub fn unknowns(&self) -> usize {
        self.n_unknowns()
    }
}
