//! The check that the equilibrium found is a steady motion: neither the equations nor their
//! linearisation may depend on the driven coordinates' values (gravity off a spin axis makes
//! the motion unsteady though `F = 0` at the solution).

use super::{Balance, EquilibriumError, Problem};
use nalgebra::DMatrix;

impl Problem<'_> {
    /// Fails when the motion at the solution is not steady: `q_D = Ω t` turns each driven
    /// coordinate, so the equations of the free coordinates must not depend on its value,
    /// neither `F` (else the equilibrium drifts as it turns) nor its linearisation (else the
    /// modes are those of a periodic system, `K = −(mgL/2) cos ψ` for a rod with gravity
    /// across the drive axis, although its equilibrium may not move).
    ///
    /// Checked by evaluation at three other values of the driven coordinates, all turned
    /// together as time turns them: `F` first. With
    /// `F = 0` at the solution that is four conditions: a dependence through one revolution's
    /// sine and cosine (gravity off a spin axis) cannot vanish at all four, wherever it is
    /// stationary. Then the linearisation ([`Problem::check_steady_linearisation`]). Skipped
    /// are the coordinates on which the equations cannot depend by the model's symmetry
    /// (`symmetric`, a proof for the whole equations of motion) and those that do not turn at
    /// this speed (a drive at speed 0: nothing turns, and any load is steady).
    pub(super) fn check_steady(
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
            STEADY_TOLERANCE * alpha * balance.amax(jac).max(1.0) * x_scale
        });
        // The linearisation at the solution, made once where a drive is checked.
        let base = std::cell::LazyCell::new(|| Steady::at(self, q, lambda, jac, balance));
        // The driven coordinates that turn, each at its speed over the fastest's: the motion
        // is `q_D + Ω_D t` for all of them at once, so the equations must not change along
        // that path (several drives at one speed may be coupled, as the nodes of a spinning
        // shaft are by its twist). Those steady by symmetry turn with the rest, harmlessly.
        let fastest = (self.driven.iter()).fold(0.0f64, |a, &c| a.max(self.qd[c].abs()));
        let shift: Vec<(usize, usize, f64)> = (self.driven.iter().enumerate())
            .filter(|&(_, &c)| self.qd[c] != 0.0)
            .map(|(d, &c)| (d, c, self.qd[c] / fastest))
            .collect();
        if shift.iter().all(|(_, c, _)| self.symmetric.contains(c)) {
            return Ok(());
        }
        let names = self.turning(&shift);
        let change = self
            .route
            .residual_at_drive_offsets(q, lambda, &shift, OFFSETS);
        let change = change.iter().fold(0.0f64, |a, &v| a.max(v));
        if change > *tol {
            return Err(EquilibriumError::NoSteadyState {
                coordinate: names,
                sensitivity: change,
            });
        }
        if let Some(base) = &*base {
            self.check_steady_linearisation(base, q, lambda, &shift, &names)?;
        }
        Ok(())
    }

    /// The driven coordinates of `shift` as messages name them: `'s'`, or the first three and
    /// how many more turn with them.
    fn turning(&self, shift: &[(usize, usize, f64)]) -> String {
        let quoted: Vec<String> = (shift.iter().take(3))
            .map(|&(_, c, _)| format!("'{}'", self.names[c]))
            .collect();
        match shift.len() {
            0..=3 => quoted.join(", "),
            n => format!("{} and {} more turning with them", quoted.join(", "), n - 3),
        }
    }

    /// Fails when the linearisation's full matrices `K`, `C`, `M` (over the free coordinates,
    /// `λ` held) or its null-space basis `R` change as the driven coordinates of `shift` turn
    /// by `OFFSETS` (see [`Problem::check_steady`]), beyond [`STEADY_TOLERANCE`] of their
    /// scales ([`Steady`]); `names` says which turn.
    fn check_steady_linearisation(
        &self,
        base: &Steady,
        q: &[f64],
        lambda: &[f64],
        shift: &[(usize, usize, f64)],
        names: &str,
    ) -> Result<(), EquilibriumError> {
        let mut qo = q.to_vec();
        for offset in OFFSETS {
            for &(_, c, rate) in shift {
                qo[c] = q[c] + rate * offset;
            }
            let unsteady = |change: String| EquilibriumError::UnsteadyLinearisation {
                coordinate: names.to_string(),
                change,
            };
            let Ok(lin) = self.route.linearize(&qo, lambda, &base.independent, None) else {
                // Φ_R lost the rank it has at the solution: the constraints turn with it.
                return Err(unsteady(
                    "the constraint Jacobian Φ_R loses its rank".to_string(),
                ));
            };
            for (matrix, a, b, scale) in [
                (
                    "stiffness matrix K",
                    &lin.k_full,
                    &base.lin.k_full,
                    base.scale.k,
                ),
                (
                    "damping matrix C",
                    &lin.c_full,
                    &base.lin.c_full,
                    base.scale.c,
                ),
                ("mass matrix M", &lin.m_full, &base.lin.m_full, base.scale.m),
                (
                    "constraints' null-space basis R",
                    &lin.basis,
                    &base.lin.basis,
                    base.scale.basis,
                ),
            ] {
                let change = (a - b).amax();
                if change.is_nan() || change > STEADY_TOLERANCE * scale {
                    return Err(unsteady(format!(
                        "its {matrix} changes by {change:.3e}, on a scale of {scale:.3e}"
                    )));
                }
            }
        }
        Ok(())
    }
}

/// The values of a driven coordinate, as offsets from the solution's (rad or m), at which the
/// steady-state check evaluates the equations: with the solution's own, four values, at which
/// no dependence through one revolution's sine and cosine vanishes at once.
const OFFSETS: [f64; 3] = [1.0, 2.5, -2.0];

/// A change of the equations or their linearisation with a driven coordinate's value beyond
/// this fraction of their scale is a dependence: rounding changes them by ~1e-15 of it, and a
/// physical dependence (gravity off the spin axis) by order one.
const STEADY_TOLERANCE: f64 = 1e-8;

/// The linearisation at the solution that the steady-state check compares with those at other
/// values of the driven coordinates, and the scale of each of its matrices.
struct Steady {
    /// The independent coordinates chosen at the solution (those of the basis `R` compared).
    independent: Vec<usize>,
    lin: crate::linearize::Linearization<f64>,
    scale: SteadyScale,
}

/// What a change of each matrix is measured against: `K` against Newton's balanced Jacobian
/// (`α max(max|J'|, 1)`, the residual check's scale per unit coordinate), `M` against its
/// largest entry, `C` against the larger of its own and `√(K M)` (the damping of a mode of
/// that stiffness and mass at ζ of order one), `R` against `max(max|R|, 1)`.
struct SteadyScale {
    k: f64,
    c: f64,
    m: f64,
    basis: f64,
}

impl Steady {
    /// The linearisation of `problem` at the solution `(q, λ)` (Newton's Jacobian `jac`
    /// balanced by `balance`); `None` where it fails or is not finite there (the
    /// linearisation of the point says why, later).
    fn at(
        problem: &Problem,
        q: &[f64],
        lambda: &[f64],
        jac: &DMatrix<f64>,
        balance: Balance,
    ) -> Option<Steady> {
        let independent = if problem.m == 0 {
            problem.free.clone()
        } else {
            let phi_r = problem.route.constraint_jacobian(q);
            crate::linearize::choose_independent(&phi_r, &problem.free, None).ok()?
        };
        let lin = problem
            .route
            .linearize(q, lambda, &independent, None)
            .ok()?;
        let finite = |a: &DMatrix<f64>| a.iter().all(|v| v.is_finite());
        if ![&lin.k_full, &lin.c_full, &lin.m_full, &lin.basis]
            .into_iter()
            .all(finite)
        {
            return None;
        }
        let k = balance.alpha * balance.amax(jac).max(1.0);
        let m = lin.m_full.amax();
        let scale = SteadyScale {
            k,
            m,
            c: lin.c_full.amax().max((k * m).sqrt()),
            basis: lin.basis.amax().max(1.0),
        };
        Some(Steady {
            independent,
            lin,
            scale,
        })
    }
}
