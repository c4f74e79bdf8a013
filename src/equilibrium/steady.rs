//! The check that the equilibrium found is a steady motion: neither the equations nor their
//! linearisation may depend on the driven coordinates' values (gravity off a spin axis makes
//! the motion unsteady though `F = 0` at the solution).

use super::max_abs;
use super::{Balance, EquilibriumError, Problem};
use crate::equations::{Probed, Rates, probe_directions};
use crate::linearize::{LinearizeError, null_basis};
use nalgebra::{DMatrix, DVector};

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
        rates: Option<&Rates>,
        balance: Balance,
    ) -> Result<(), EquilibriumError> {
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
        // Scaled by the balanced Jacobian and unknowns, in force units (α).
        let x_scale = 1.0
            + q.iter()
                .fold(0.0f64, |s, v| s.max(v.abs()))
                .max(lambda.iter().fold(0.0f64, |s, v| s.max(v.abs())) / balance.alpha);
        let tol = STEADY_TOLERANCE * balance.alpha * balance.amax(jac).max(1.0) * x_scale;
        let names = self.turning(&shift);
        // The linearisation at the solution, and at each offset `F` with the linearisation
        // along the check's directions (one pass each on the recorded route).
        let base = Steady::at(self, q, lambda, (jac, rates), balance);
        let probed = base.as_ref().map(|base| {
            let mut qo = q.to_vec();
            OFFSETS.map(|offset| {
                for &(_, c, rate) in &shift {
                    qo[c] = q[c] + rate * offset;
                }
                self.route
                    .probe_linearisation(&qo, lambda, &base.independent)
            })
        });
        let change = match &probed {
            Some([Ok(a), Ok(b), Ok(c)]) => [a, b, c].map(|p| max_abs(&p.residual)),
            _ => (self.route).residual_at_drive_offsets(q, lambda, &shift, OFFSETS),
        };
        let change = change.iter().fold(0.0f64, |a, &v| a.max(v));
        if change > tol {
            return Err(EquilibriumError::NoSteadyState {
                coordinate: names,
                sensitivity: change,
            });
        }
        if let (Some(base), Some(probed)) = (&base, probed) {
            self.check_steady_linearisation(base, probed, &names)?;
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
    /// `λ` held) or its null-space basis `R` change as the driven coordinates turn by `OFFSETS`
    /// (`probed` at each; see [`Problem::check_steady`]), beyond [`STEADY_TOLERANCE`] of their
    /// scales ([`Steady`]); `names` says which turn.
    ///
    /// The matrices are compared by their products with fixed pseudo-random directions
    /// (Freivalds, *Probabilistic machines can use less running time*, IFIP 1977): `A ≠ B` and
    /// `A x = B x` only for `x` in a subspace of measure zero, and a change by a fraction `δ` of
    /// the scale moves the product by about `δ` (the directions' entries are of size ½ to 1
    /// with signs at random, [`probe_directions`]). One evaluation along three directions
    /// replaces a linearisation (three lanes per coordinate) at each offset. `R` is compared
    /// whole, from `Φ_R`.
    fn check_steady_linearisation(
        &self,
        base: &Steady,
        probed: [Result<Probed, LinearizeError>; 3],
        names: &str,
    ) -> Result<(), EquilibriumError> {
        for probed in probed {
            let unsteady = |change: String| EquilibriumError::UnsteadyLinearisation {
                coordinate: names.to_string(),
                change,
            };
            let probed = probed.and_then(|p| {
                null_basis(&self.free, &base.independent, &p.phi).map(|r| (p.products, r))
            });
            let Ok((products, basis)) = probed else {
                // Φ_R lost the rank it has at the solution: the constraints turn with it.
                return Err(unsteady(
                    "the constraint Jacobian Φ_R loses its rank".to_string(),
                ));
            };
            let change = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            };
            let [kv, cw, mu] = &products;
            let [bk, bc, bm] = &base.products;
            for (matrix, change, scale) in [
                ("stiffness matrix K", change(kv, bk), base.scale.k),
                ("damping matrix C", change(cw, bc), base.scale.c),
                ("mass matrix M", change(mu, bm), base.scale.m),
                (
                    "constraints' null-space basis R",
                    (&basis - &base.basis).amax(),
                    base.scale.basis,
                ),
            ] {
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
/// values of the driven coordinates: its full matrices along the check's directions, its basis
/// and the scale of each.
struct Steady {
    /// The independent coordinates chosen at the solution (those of the basis `R` compared).
    independent: Vec<usize>,
    /// `[K v, C w, M u]` at the solution.
    products: [Vec<f64>; 3],
    /// `R` at the solution.
    basis: DMatrix<f64>,
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
    /// The linearisation of `problem` at the solution `(q, λ)`: from Newton's Jacobian `jac`
    /// (balanced by `balance`) and the `rates` evaluated with it where the route gave them,
    /// else evaluated here; `None` where it fails or is not finite there (the linearisation
    /// of the point says why, later).
    fn at(
        problem: &Problem,
        q: &[f64],
        lambda: &[f64],
        (jac, rates): (&DMatrix<f64>, Option<&Rates>),
        balance: Balance,
    ) -> Option<Steady> {
        let nf = problem.free.len();
        // `Φ_R` from the multipliers' columns of Newton's Jacobian, `[Φ_Rᵀ; 0]`.
        let phi_r = DMatrix::from_fn(problem.m, nf, |k, j| jac[(j, nf + k)]);
        let independent = if problem.m == 0 {
            problem.free.clone()
        } else {
            crate::linearize::choose_independent(&phi_r, &problem.free, None).ok()?
        };
        let stiffness = jac.view((0, 0), (nf, nf)).into_owned();
        let [m_full, c_full, k_full] = match rates {
            Some(r) => [r.mass.clone(), r.damping.clone(), stiffness],
            None => {
                let lin = (problem.route)
                    .linearize(q, lambda, &independent, Some(&stiffness))
                    .ok()?;
                [lin.m_full, lin.c_full, lin.k_full]
            }
        };
        let basis = null_basis(&problem.free, &independent, &phi_r).ok()?;
        let finite = |a: &DMatrix<f64>| a.iter().all(|v| v.is_finite());
        if ![&k_full, &c_full, &m_full, &basis].into_iter().all(finite) {
            return None;
        }
        let directions = probe_directions(nf);
        let products = [&k_full, &c_full, &m_full]
            .into_iter()
            .zip(&directions)
            .map(|(a, x)| (a * DVector::from_column_slice(x)).as_slice().to_vec());
        let products: [Vec<f64>; 3] = products.collect::<Vec<_>>().try_into().ok()?;
        let k = balance.alpha * balance.amax(jac).max(1.0);
        let m = m_full.amax();
        let scale = SteadyScale {
            k,
            m,
            c: c_full.amax().max((k * m).sqrt()),
            basis: basis.amax().max(1.0),
        };
        Some(Steady {
            independent,
            products,
            basis,
            scale,
        })
    }
}
