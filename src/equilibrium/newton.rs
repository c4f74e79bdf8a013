//! Newton–chord's state from one iteration to the next: the iterate with its Jacobian and
//! factorisation, the step direction, the convergence certificate, the chord and the line
//! search.

use super::balance::{Balance, Factor};
use super::{EquilibriumError, Problem, ROUNDING_FLOOR, max_abs};
use crate::equations::Rates;
use nalgebra::DMatrix;

/// The slowest contraction `ρ` per step for which chord steps (a kept Jacobian) go on: the
/// steps must at least halve.
const CHORD_RATE: f64 = 0.5;

/// The most chord steps a contraction rate `ρ` may still need to reach the certificate (an
/// error left below a thousandth of the tolerance), else the Jacobian is evaluated: a sweep's
/// chord from the previous speed's Jacobian contracts by 1e-3 or faster and needs one or two,
/// while a chord that contracts by 0.07 from a Jacobian far from the solution needed twelve
/// where Newton's steps need three or four.
const CHORD_STEPS: f64 = 2.0;

/// How one Newton–chord iteration ends ([`Problem::solve`]'s loop).
pub(super) enum Step {
    /// The exact Jacobian's step at the current point is below the tolerance.
    Converged,
    /// On to the next iteration (if the iteration limit allows).
    Continue,
    /// The solve fails with this error.
    Failed(EquilibriumError),
}

/// Newton's state carried from one iteration to the next.
pub(super) struct Iterate {
    /// All coordinates (the driven ones keep their values).
    pub(super) q: Vec<f64>,
    /// The multipliers.
    pub(super) lambda: Vec<f64>,
    /// `F` at `(q, λ)`.
    pub(super) f: Vec<f64>,
    /// Newton's Jacobian: at `(q, λ)` when `fresh`, else kept from an earlier point.
    pub(super) jac: DMatrix<f64>,
    /// The [`Rates`] at `(q, λ)`, where the last evaluation had them there.
    pub(super) rates: Option<Rates>,
    /// The driven coordinates' rows of `r + Φ_qᵀλ` at `(q, λ)`, where the last evaluation had
    /// them there.
    pub(super) drive: Option<Vec<f64>>,
    /// `jac` was evaluated at the current point.
    pub(super) fresh: bool,
    /// The balance of Newton's system, fixed from its first Jacobian.
    pub(super) balance: Balance,
    /// `jac` factorised.
    pub(super) lu: Factor,
    /// Size of the last step (relative), for the contraction test.
    pub(super) last_step: f64,
    /// Fresh Jacobians evaluated where F is at its rounding floor.
    pub(super) at_floor: usize,
    /// The current point is where chord steps put the error left below a thousandth of the
    /// tolerance ([`Iterate::chord`]), and `jac` was evaluated there to certify it.
    pub(super) chord_certified: bool,
}

impl Iterate {
    /// Evaluates `F`, the Jacobian (with the rates and, with `drive_wanted`, the drive rows)
    /// at the current point and factorises it: the chord is dropped for a Newton step.
    pub(super) fn refresh(&mut self, problem: &Problem, drive_wanted: bool) {
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
    pub(super) fn certify(&mut self, dir: &Direction, iterations: usize, tol: f64) -> Option<Step> {
        let balance = self.balance;
        // F at its rounding floor, judged on a fresh Jacobian only (the chord steps'
        // contraction tells the rest).
        let at_rounding = self.fresh && {
            let floor = 1.0 + balance.amax(&self.jac) * dir.q_scale.max(dir.l_scale);
            balance.norm(&self.f) <= ROUNDING_FLOOR * floor
        };
        // Where the chord's contraction put the error left below a thousandth of the
        // tolerance and F is zero to rounding, the point is converged although the exact
        // Jacobian's step is not small: that step is rounding through a Jacobian nearly
        // singular along a continuum of equilibria (a cone's azimuth) that its factorisation
        // did not flag, and Newton would wander along the continuum.
        let by_chord = self.chord_certified && at_rounding;
        if self.fresh && (dir.size <= tol || by_chord) {
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
    /// is taken and the Jacobian evaluated there to certify it. Where the steps shrink less
    /// than twofold, the Jacobian is evaluated here. Where they contract, but so slowly that
    /// more than [`CHORD_STEPS`] further steps would be needed (the chord converges only
    /// linearly, at the rate `ρ`, which its Jacobian's distance from the solution sets), the
    /// step is taken and the Jacobian evaluated there: Newton's steps, quadratic near the
    /// solution, go on from it. `true` when the Jacobian was evaluated (the iteration ends).
    pub(super) fn chord(
        &mut self,
        problem: &Problem,
        dir: &Direction,
        tol: f64,
        drive_wanted: bool,
    ) -> bool {
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
        // The chord steps still needed at the rate ρ to bring the error left below a
        // thousandth of the tolerance (where the step is certified).
        let slow = rho < CHORD_RATE && (1e-3 * tol / left).ln() / rho.ln() > CHORD_STEPS;
        if left <= 1e-3 * tol || (size <= tol && rho > CHORD_RATE) || slow {
            dir.apply(&mut self.q, &mut self.lambda, 1.0);
            self.refresh(problem, drive_wanted);
            self.chord_certified = left <= 1e-3 * tol;
            return true;
        }
        // Steps that do not contract fast: evaluate the Jacobian here.
        if size > CHORD_RATE * self.last_step {
            self.refresh(problem, drive_wanted);
            return true;
        }
        false
    }

    /// The damped step along `dir`: `α` halves from 1 until the simplified Newton correction
    /// `J⁻¹F(x + αΔx)` is at most `(1 − α/4)` times `Δx` in [`Direction::length`], or
    /// `α < 1e-4`. The step is then taken, unless it did not decrease on a kept Jacobian, which
    /// is evaluated here instead.
    pub(super) fn line_search(&mut self, problem: &Problem, dir: &Direction, drive_wanted: bool) {
        // Backtrack on the natural monotonicity test (Deuflhard 2004, §3.1): the simplified
        // Newton correction `J⁻¹F(x + αΔx)` (the same factorisation) against the step
        // `Δx = J⁻¹F(x)`, both in the scaled norm of `size`. Unlike `‖F‖`, whose rows are
        // forces and lengths, it is invariant under any scaling of the equations, so that
        // a model and its copy with every mass and spring scaled take the same steps.
        let f0 = dir.length(&dir.step);
        let mut alpha = match problem.step_limit {
            Some(limit) => {
                let dq = dir.step[..dir.free.len()]
                    .iter()
                    .fold(0.0f64, |s, v| s.max(v.abs()));
                (limit * dir.q_scale / dq).min(1.0)
            }
            None => 1.0,
        };
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
        self.chord_certified = false;
        self.last_step = alpha * dir.size;
    }
}

/// A Newton (or chord) step `Δx = J⁻¹F` with the scales in which its size is measured.
pub(super) struct Direction<'p> {
    /// The free coordinates (the first unknowns; the rest are multipliers).
    pub(super) free: &'p [usize],
    /// `Δx = [Δq_R; Δλ]`.
    pub(super) step: Vec<f64>,
    /// `1 + max|q_R|`.
    pub(super) q_scale: f64,
    /// `1 + max|λ|/α`.
    pub(super) l_scale: f64,
    /// The balance's force scale α.
    pub(super) force: f64,
    /// The step's relative size ([`Problem::direction`]).
    pub(super) size: f64,
}

impl Direction<'_> {
    /// `x ← x − α Δx` on the free coordinates of `q` and on `lambda`.
    pub(super) fn apply(&self, q: &mut [f64], lambda: &mut [f64], alpha: f64) {
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
    pub(super) fn length(&self, d: &[f64]) -> f64 {
        let (q_scale, l_scale, force) = (self.q_scale, self.l_scale, self.force);
        let (a, b) = d.split_at(self.free.len());
        let sq = a.iter().map(|v| (v / q_scale).powi(2)).sum::<f64>()
            + b.iter()
                .map(|v| (v / (force * 1e3 * l_scale)).powi(2))
                .sum::<f64>();
        sq.sqrt()
    }
}
