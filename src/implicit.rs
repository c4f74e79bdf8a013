//! Derivatives of an implicitly defined solution, without differentiating the solver.
//!
//! A solution `z*(b)` of `G(z, b) = 0` (the equilibrium, a root of the eigenproblem) is found in
//! `f64`; its derivatives with respect to the seeded parameters `b` then follow from chord steps
//! on the derivative parts alone, with the nominal Jacobian `J₀ = ∂G/∂z` factorised once:
//!
//! ```text
//! z ← z + J₀⁻¹ (−G(z, b))      (parts only; the value stays the f64 solution)
//! ```
//!
//! Each step removes one order of the error (`e_{k+1} = (I − J₀⁻¹J) e_k + O(e_k²)` with
//! `J − J₀ = O(ε)`): one step makes the first-order parts exact (the implicit function theorem,
//! `dz/db = −J₀⁻¹ ∂G/∂b`), a second the second-order parts. Newton's iterations are never
//! differentiated through.
//!
//! # Reference
//! num-dual, `src/implicit.rs` (`ImplicitDerivative`); Griewank & Walther, *Evaluating
//! Derivatives* (2008), §15 (derivatives of iterative solvers).

use crate::jet::Jet;

/// `steps` chord steps on the parts of `z`: `residual(z)` is `G(z, b)` (as many rows as `z`
/// has unknowns) and `solve(r)` is `J₀⁻¹ r`, `None` where `J₀` is singular (then so is the
/// result). Each part `k` is corrected from its own right-hand side, `−G`'s part `k`.
pub fn correct<J: Jet>(
    z: &mut [J],
    steps: usize,
    mut residual: impl FnMut(&[J]) -> Vec<J>,
    solve: impl Fn(&[f64]) -> Option<Vec<f64>>,
) -> Option<()> {
    for _ in 0..steps {
        let g = residual(z);
        for k in 0..J::PARTS {
            let rhs: Vec<f64> = g.iter().map(|v| -v.part(k)).collect();
            let d = solve(&rhs)?;
            for (zi, di) in z.iter_mut().zip(d) {
                let v = zi.part(k) + di;
                zi.set_part(k, v);
            }
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{Dual2_64, DualNum, HyperDual64};

    /// `z³ + b z − 3 = 0` at `b = 2` has `z = 1`; implicitly `z' = −z/(3z² + b)` and
    /// `z'' = −(2z' + 6z z'²)/(3z² + b)`: at `z = 1`, `z' = −1/5` and `z'' = −(−2/5 + 6/25)/5`.
    #[test]
    fn two_steps_give_the_implicit_first_and_second_derivatives() {
        let jac = 3.0 + 2.0;
        let b = Dual2_64::new(2.0, 1.0, 0.0);
        let mut z = [Dual2_64::from_re(1.0)];
        correct(
            &mut z,
            2,
            |z| vec![z[0].powi(3) + b * z[0] - 3.0],
            |r| Some(vec![r[0] / jac]),
        )
        .unwrap();
        let (d1, d2) = (-0.2, -(-0.4 + 6.0 / 25.0) / 5.0);
        assert!((z[0].v1 - d1).abs() < 1e-15, "{}", z[0].v1);
        assert!((z[0].v2 - d2).abs() < 1e-15, "{} vs {d2}", z[0].v2);
        assert_eq!(z[0].re.to_bits(), 1.0f64.to_bits());
    }

    /// One step is exact to first order only: the mixed part needs the second.
    #[test]
    fn one_step_leaves_the_second_order_part_inexact() {
        let jac = 5.0;
        let b = HyperDual64::new(2.0, 1.0, 1.0, 0.0);
        let run = |steps| {
            let mut z = [HyperDual64::from_re(1.0)];
            correct(
                &mut z,
                steps,
                |z| vec![z[0].powi(3) + b * z[0] - 3.0],
                |r| Some(vec![r[0] / jac]),
            )
            .unwrap();
            z[0]
        };
        let exact = -(-0.4 + 6.0 / 25.0) / 5.0;
        assert!((run(1).eps1 + 0.2).abs() < 1e-15);
        assert!((run(1).eps1eps2 - exact).abs() > 1e-3);
        assert!((run(2).eps1eps2 - exact).abs() < 1e-15);
    }

    #[test]
    fn a_singular_jacobian_gives_none() {
        let mut z = [Dual2_64::from_re(1.0)];
        assert!(correct(&mut z, 1, |z| z.to_vec(), |_| None).is_none());
    }
}
