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

use crate::equations::{Equations, Evaluation, Rates};
use crate::linalg::{Lu, least_squares};
use nalgebra::{DMatrix, DVector};

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

/// Newton's system `J = [K Φ_Rᵀ; Φ_R 0]` balanced: its rows are forces (the free coordinates'
/// residuals) and lengths (the constraints), its unknowns coordinates and multipliers (forces
/// per constraint unit). Scaling every mass, spring and damper of a model by a factor scales
/// `K` and `λ` by it and leaves `Φ_R` alone, so that the blocks drift apart: a spatial four-bar
/// scaled by 1e-9 had its force rows below the constraints' rounding and Newton stalled at a
/// residual of 1.5e-10. With the force scale `α = 2^round(log₂(‖K‖/‖Φ_R‖))` (`‖Φ_R‖ := 1`
/// without constraints) the balanced system
///
/// ```text
/// J' = D_r J D_c = [K/α Φ_Rᵀ; Φ_R 0],   F' = D_r F = [F_r/α; Φ],   x = D_c x',
/// D_r = diag(I/α, I), D_c = diag(I, αI)
/// ```
///
/// has blocks of one size whatever the model's scale, and its tolerances (steps, rounding
/// floors, the line search's norm, the steady-state check) are the same for a model and its
/// scaled copy. A power of two scales exactly: without constraints `J' = J/α` and the steps
/// are `J`'s to the bit.
#[derive(Debug, Clone, Copy)]
pub struct Balance {
    nf: usize,
    /// The force scale α (a power of two).
    pub alpha: f64,
}

impl Balance {
    /// The balance of Newton's Jacobian `jac` with `nf` free coordinates (its first `nf` rows
    /// and columns).
    pub fn of(jac: &DMatrix<f64>, nf: usize) -> Balance {
        let n = jac.nrows();
        let block = |r: std::ops::Range<usize>, c: std::ops::Range<usize>| {
            r.flat_map(|i| c.clone().map(move |j| (i, j)))
                .fold(0.0f64, |s, (i, j)| s.max(jac[(i, j)].abs()))
        };
        let k = block(0..nf, 0..nf);
        let phi = if n > nf { block(nf..n, 0..nf) } else { 1.0 };
        let ratio = k / phi;
        let alpha = if ratio.is_finite() && ratio > 0.0 {
            2f64.powi((ratio.log2().round() as i32).clamp(-1000, 1000))
        } else {
            1.0
        };
        Balance { nf, alpha }
    }

    /// `J' = D_r J D_c`.
    pub fn jacobian(&self, j: &DMatrix<f64>) -> DMatrix<f64> {
        let mut j = j.clone();
        if self.alpha.to_bits() != 1f64.to_bits() {
            let nf = self.nf;
            for c in 0..j.ncols() {
                for r in 0..j.nrows() {
                    if r < nf && c < nf {
                        j[(r, c)] /= self.alpha;
                    } else if r >= nf && c >= nf {
                        j[(r, c)] *= self.alpha;
                    }
                }
            }
        }
        j
    }

    /// `max |J'|` without forming `J'`.
    pub fn amax(&self, j: &DMatrix<f64>) -> f64 {
        let (n, nf, a) = (j.nrows(), self.nf, self.alpha);
        (0..j.ncols())
            .flat_map(|c| (0..n).map(move |r| (r, c)))
            .fold(0.0f64, |s, (r, c)| {
                let v = j[(r, c)].abs();
                s.max(if r < nf && c < nf {
                    v / a
                } else if r >= nf && c >= nf {
                    v * a
                } else {
                    v
                })
            })
    }

    /// `max |F'|` without forming `F'`.
    pub fn norm(&self, f: &[f64]) -> f64 {
        let nf = self.nf;
        f.iter().enumerate().fold(0.0f64, |s, (i, v)| {
            s.max(if i < nf {
                v.abs() / self.alpha
            } else {
                v.abs()
            })
        })
    }

    /// `F' = D_r F`.
    pub fn residual(&self, f: &[f64]) -> Vec<f64> {
        let mut f = f.to_vec();
        f[..self.nf].iter_mut().for_each(|v| *v /= self.alpha);
        f
    }

    /// `x = D_c x'`: the unknowns (or a step) from the balanced ones.
    pub fn unknowns(&self, mut x: Vec<f64>) -> Vec<f64> {
        x[self.nf..].iter_mut().for_each(|v| *v *= self.alpha);
        x
    }
}

/// Newton's Jacobian factorised balanced ([`Balance`]), for Newton's steps and the
/// sensitivities' and Hessians' implicit steps alike.
///
/// Where a coordinate is held by nothing (a rod spinning freely about its own axis, a cone that
/// may precess to any azimuth: a rigid-body mode) the equilibria form a continuum and `J` is
/// singular, exactly or to rounding. Partial pivoting then divides rounding by rounding: its
/// steps threw the free coordinate about by O(1), or it failed outright. Such a `J` is solved
/// in the least-squares sense instead, by its singular value decomposition truncated at
/// [`RANK_TOLERANCE`]: the minimum-norm step, which moves nothing along the continuum (where
/// the modes do not change, by the symmetry that makes it) and is the Newton step elsewhere
/// (Gauss–Newton for an underdetermined system; Nocedal & Wright §10.3).
#[derive(Debug, Clone)]
pub struct Factor {
    balance: Balance,
    solver: Solver,
}

/// How a [`Factor`] solves.
#[derive(Debug, Clone)]
enum Solver {
    Lu(Lu),
    /// `J'⁺ = V Σ⁺ Uᵀ` with the singular values below the tolerance dropped: `(V Σ⁺, U)`.
    Pseudo(DMatrix<f64>, DMatrix<f64>),
}

/// Singular values of the balanced Jacobian below this fraction of the largest count as zero:
/// the same 1e-12 below which a mode's stiffness counts as zero ([`crate::modal`]'s
/// `ZERO_ROOT²`).
pub const RANK_TOLERANCE: f64 = 1e-12;

/// LU pivots below this fraction of the largest send a factorisation to the singular value
/// decomposition (which then decides the rank): pivots overestimate the smallest singular value
/// by at most a modest factor on the matrices met here, so this catches every rank deficiency
/// at [`RANK_TOLERANCE`] and costs a well-conditioned `J` nothing.
const PIVOT_TOLERANCE: f64 = 1e-10;

impl Factor {
    /// Factorises Newton's Jacobian `jac` (`nf` free coordinates, the rest multipliers).
    pub fn new(jac: &DMatrix<f64>, nf: usize) -> Factor {
        Factor::with(Balance::of(jac, nf), jac)
    }

    /// Factorises `jac` with the balance `balance` (Newton keeps one through a solve).
    fn with(balance: Balance, jac: &DMatrix<f64>) -> Factor {
        let j = balance.jacobian(jac);
        let lu = Lu::new(j.clone());
        let solver = if lu.pivot_ratio() > PIVOT_TOLERANCE {
            Solver::Lu(lu)
        } else {
            Self::pseudo(j, balance.nf).map_or(Solver::Lu(lu), |(vs, u)| Solver::Pseudo(vs, u))
        };
        Factor { balance, solver }
    }

    /// `(V Σ⁺, U)` of `j` (`nf` free coordinates), the singular values below
    /// [`RANK_TOLERANCE`] of the largest dropped; `None` where the decomposition fails, or
    /// where a dropped direction moves the multipliers rather than the coordinates: redundant
    /// cut joints, which the solve reports by name rather than solving around.
    fn pseudo(j: DMatrix<f64>, nf: usize) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let svd = crate::linalg::svd(j, true, true)?;
        let (u, vt) = (svd.u?, svd.v_t?);
        let top = svd.singular_values.max();
        if !top.is_finite() {
            return None;
        }
        let mut vs = vt.transpose();
        for (k, &sv) in svd.singular_values.iter().enumerate() {
            if sv > RANK_TOLERANCE * top {
                vs.column_mut(k).scale_mut(1.0 / sv);
            } else {
                let coordinates = vs.column(k).rows(0, nf).norm_squared();
                if coordinates < 0.5 {
                    return None;
                }
                vs.column_mut(k).fill(0.0);
            }
        }
        Some((vs, u))
    }

    /// Is `J` rank-deficient (solved in the least-squares sense)?
    pub fn singular(&self) -> bool {
        matches!(self.solver, Solver::Pseudo(..))
    }

    /// `x` with `J x = b` (the minimum-norm least-squares `x` where `J` is rank-deficient), or
    /// `None` where an exactly singular `J` could not be decomposed.
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let b = self.balance.residual(b);
        let x = match &self.solver {
            Solver::Lu(lu) => lu.solve(&b)?,
            Solver::Pseudo(vs, u) => {
                let y = u.tr_mul(&DVector::from_vec(b));
                (vs * y).as_slice().to_vec()
            }
        };
        Some(self.balance.unknowns(x))
    }
}

impl Equilibrium {
    /// Newton's Jacobian at the solution, factorised ([`Factor`]).
    pub fn factor(&self) -> Factor {
        Factor::new(&self.jacobian, self.jacobian.nrows() - self.lambda.len())
    }
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
        }
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
    /// linearisation and the sensitivities use.
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
            return Err(EquilibriumError::NewtonDiverged {
                iterations,
                residual: max_abs(&it.f),
            });
        }
        if !start.steady_known {
            self.check_steady(&it.q, &it.lambda, &it.jac, it.balance)?;
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
        balance: Balance,
    ) -> Result<(), EquilibriumError> {
        // Scaled by the balanced Jacobian and unknowns, in force units (α), found once and
        // only when a drive is checked (a model whose drives are all steady by symmetry never
        // needs it).
        let tol = std::cell::LazyCell::new(|| {
            let alpha = balance.alpha;
            let x_scale = 1.0
                + q.iter()
                    .fold(0.0f64, |s, v| s.max(v.abs()))
                    .max(lambda.iter().fold(0.0f64, |s, v| s.max(v.abs())) / alpha);
            1e-8 * alpha * balance.amax(jac).max(1.0) * x_scale
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

/// `max |v|` (`‖·‖∞`), 0 for an empty slice.
fn max_abs(f: &[f64]) -> f64 {
    f.iter().fold(0.0f64, |s, v| s.max(v.abs()))
}

/// How one Newton–chord iteration ends ([`Problem::solve`]'s loop).
enum Step {
    /// The exact Jacobian's step at the current point is below the tolerance.
    Converged,
    /// On to the next iteration (if the iteration limit allows).
    Continue,
    /// The solve fails with this error.
    Failed(EquilibriumError),
}

/// Newton's state carried from one iteration to the next.
struct Iterate {
    /// All coordinates (the driven ones keep their values).
    q: Vec<f64>,
    /// The multipliers.
    lambda: Vec<f64>,
    /// `F` at `(q, λ)`.
    f: Vec<f64>,
    /// Newton's Jacobian: at `(q, λ)` when `fresh`, else kept from an earlier point.
    jac: DMatrix<f64>,
    /// The [`Rates`] at `(q, λ)`, where the last evaluation had them there.
    rates: Option<Rates>,
    /// The driven coordinates' rows of `r + Φ_qᵀλ` at `(q, λ)`, where the last evaluation had
    /// them there.
    drive: Option<Vec<f64>>,
    /// `jac` was evaluated at the current point.
    fresh: bool,
    /// The balance of Newton's system, fixed from its first Jacobian.
    balance: Balance,
    /// `jac` factorised.
    lu: Factor,
    /// Size of the last step (relative), for the contraction test.
    last_step: f64,
    /// Fresh Jacobians evaluated where F is at its rounding floor.
    at_floor: usize,
}

impl Iterate {
    /// Evaluates `F`, the Jacobian (with the rates and, with `drive_wanted`, the drive rows)
    /// at the current point and factorises it: the chord is dropped for a Newton step.
    fn refresh(&mut self, problem: &Problem, drive_wanted: bool) {
        let e = problem.evaluate(&self.q, &self.lambda, drive_wanted);
        (self.f, self.jac, self.rates, self.drive) = (e.residual, e.jacobian, e.rates, e.drive);
        (self.lu, self.fresh, self.last_step) =
            (Factor::with(self.balance, &self.jac), true, f64::INFINITY);
    }

    /// The convergence certificate, on a fresh Jacobian only: converged where its step `dir`
    /// is below the tolerance `tol` (unless a least-squares step on a singular `J` leaves `F`
    /// above its rounding floor `ROUNDING_FLOOR · (1 + max|J'|·max(q, λ scales))`: no
    /// equilibrium then), failed as not isolated where `F` has been at that floor on three
    /// fresh Jacobians whose steps stay above the tolerance. `None`: go on.
    fn certify(&mut self, dir: &Direction, iterations: usize, tol: f64) -> Option<Step> {
        let balance = self.balance;
        // F at its rounding floor, judged on a fresh Jacobian only (the chord steps'
        // contraction tells the rest).
        let at_rounding = self.fresh && {
            let floor = 1.0 + balance.amax(&self.jac) * dir.q_scale.max(dir.l_scale);
            balance.norm(&self.f) <= ROUNDING_FLOOR * floor
        };
        if self.fresh && dir.size <= tol {
            // A least-squares step is small on an inconsistent singular system too (a
            // free slider pushed by a constant force): there is no equilibrium then.
            if self.lu.singular() && !at_rounding {
                return Some(Step::Failed(EquilibriumError::SingularJacobian {
                    iterations,
                }));
            }
            return Some(Step::Converged);
        }
        // F satisfied to rounding while the exact Jacobian's steps stay above the tolerance:
        // the steps are rounding noise through a (nearly) singular Jacobian, and Newton
        // would wander to its iteration limit. After a few such evaluations, say so.
        if self.fresh && at_rounding {
            self.at_floor += 1;
            if self.at_floor >= 3 {
                return Some(Step::Failed(EquilibriumError::NotIsolated {
                    iterations,
                    residual: max_abs(&self.f),
                    step: dir.size,
                }));
            }
        }
        None
    }

    /// The contraction test of a chord step `dir` (a kept Jacobian): with a contraction rate
    /// `ρ = size/last_step`, the error left is about `ρ/(1−ρ)` times the step. Where that is
    /// below a thousandth of `tol` (or the steps stop contracting at the tolerance), the step
    /// is taken and the Jacobian evaluated there to certify it; where the steps shrink less
    /// than twofold, the Jacobian is evaluated here. `true` when it was (the iteration ends).
    fn chord(&mut self, problem: &Problem, dir: &Direction, tol: f64, drive_wanted: bool) -> bool {
        let size = dir.size;
        // The error left after a chord step contracting by ρ is about ρ/(1−ρ) times
        // its size; where the steps stop contracting at the tolerance, it is rounding.
        let rho = if self.last_step.is_finite() {
            size / self.last_step
        } else {
            1.0
        };
        let left = if rho < 1.0 {
            size * rho / (1.0 - rho)
        } else {
            size
        };
        if left <= 1e-3 * tol || (size <= tol && rho > 0.5) {
            dir.apply(&mut self.q, &mut self.lambda, 1.0);
            self.refresh(problem, drive_wanted);
            return true;
        }
        // Steps that do not contract fast: evaluate the Jacobian here.
        if size > 0.5 * self.last_step {
            self.refresh(problem, drive_wanted);
            return true;
        }
        false
    }

    /// The damped step along `dir`: `α` halves from 1 until the simplified Newton correction
    /// `J⁻¹F(x + αΔx)` is at most `(1 − α/4)` times `Δx` in [`Direction::length`], or
    /// `α < 1e-4`. The step is then taken, unless it did not decrease on a kept Jacobian, which
    /// is evaluated here instead.
    fn line_search(&mut self, problem: &Problem, dir: &Direction, drive_wanted: bool) {
        // Backtrack on the natural monotonicity test (Deuflhard 2004, §3.1): the simplified
        // Newton correction `J⁻¹F(x + αΔx)` (the same factorisation) against the step
        // `Δx = J⁻¹F(x)`, both in the scaled norm of `size`. Unlike `‖F‖`, whose rows are
        // forces and lengths, it is invariant under any scaling of the equations, so that
        // a model and its copy with every mass and spring scaled take the same steps.
        let f0 = dir.length(&dir.step);
        let mut alpha = 1.0;
        let (mut q_new, mut l_new, mut f_new);
        let mut decreased;
        loop {
            (q_new, l_new) = (self.q.clone(), self.lambda.clone());
            dir.apply(&mut q_new, &mut l_new, alpha);
            f_new = problem.residual(&q_new, &l_new);
            let f1 = self.lu.solve(&f_new).map_or(f64::NAN, |d| dir.length(&d));
            decreased = f1.is_finite() && f1 <= (1.0 - 0.25 * alpha) * f0;
            if decreased || alpha < 1e-4 {
                break;
            }
            alpha *= 0.5;
        }
        if !decreased && !self.fresh {
            self.refresh(problem, drive_wanted);
            return;
        }
        (self.q, self.lambda, self.f) = (q_new, l_new, f_new);
        (self.fresh, self.rates, self.drive) = (false, None, None);
        self.last_step = alpha * dir.size;
    }
}

/// A Newton (or chord) step `Δx = J⁻¹F` with the scales in which its size is measured.
struct Direction<'p> {
    /// The free coordinates (the first unknowns; the rest are multipliers).
    free: &'p [usize],
    /// `Δx = [Δq_R; Δλ]`.
    step: Vec<f64>,
    /// `1 + max|q_R|`.
    q_scale: f64,
    /// `1 + max|λ|/α`.
    l_scale: f64,
    /// The balance's force scale α.
    force: f64,
    /// The step's relative size ([`Problem::direction`]).
    size: f64,
}

impl Direction<'_> {
    /// `x ← x − α Δx` on the free coordinates of `q` and on `lambda`.
    fn apply(&self, q: &mut [f64], lambda: &mut [f64], alpha: f64) {
        let nf = self.free.len();
        for (k, &i) in self.free.iter().enumerate() {
            q[i] -= alpha * self.step[k];
        }
        for (k, l) in lambda.iter_mut().enumerate() {
            *l -= alpha * self.step[nf + k];
        }
    }

    /// The scaled 2-norm of a correction `d`, coordinates over `1 + max|q_R|` and multipliers
    /// over `α · 10³ (1 + max|λ|/α)`, the norm of the step's `size`. Unlike `‖F‖`, whose rows
    /// are forces and lengths, it is invariant under any scaling of the equations, so that a
    /// model and its copy with every mass and spring scaled take the same steps.
    fn length(&self, d: &[f64]) -> f64 {
        let (q_scale, l_scale, force) = (self.q_scale, self.l_scale, self.force);
        let (a, b) = d.split_at(self.free.len());
        let sq = a.iter().map(|v| (v / q_scale).powi(2)).sum::<f64>()
            + b.iter()
                .map(|v| (v / (force * 1e3 * l_scale)).powi(2))
                .sum::<f64>();
        sq.sqrt()
    }
}
