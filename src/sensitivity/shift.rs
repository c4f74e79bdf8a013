//! The equilibrium's shift along each design variable and the linearisation over dual numbers
//! along it.

use super::{DesignPoint, DualLinearization};
use crate::compiled::Compiled;
use crate::dual4::Dual4;
use crate::implicit;
use crate::jet::Jet;
use crate::mechanics::ports::ports_at;
use crate::program::{Tier, Workspace};
use crate::sweep::{Point, PointError};
use num_dual::Dual64;

impl DesignPoint<'_> {
    /// `M̂, Ĉ, K̂` (and `R`) over dual numbers for each design variable in `wrt`: the equilibrium
    /// shift by the implicit function theorem, then the linearisation over dual numbers along
    /// `(b, dq*/db, dλ/db)`. Three or four variables share one evaluation over [`Dual4`], whose
    /// parts are bit for bit one `Dual64` evaluation each; one or two left over take a `Dual64`
    /// each (a `Dual4` with unused parts costs them the time and, on a big model, two and a half
    /// times a `Dual64`'s buffer).
    pub fn dual_linearizations(&self, wrt: &[usize]) -> Result<Vec<DualLinearization>, PointError> {
        let (model, p, pt) = (self.model, self.p, self.point);
        let lent = self.workspace();
        let workspace: &Workspace = &lent;
        let eq = &pt.equilibrium;
        let lu = eq.factor();
        // ∂F/∂p along all the variables in one pass where the model has a recorded program.
        let dp = model.parameter_jacobian(p, pt.speed, (&eq.q, &eq.lambda), wrt, workspace);
        let at = Shift {
            model,
            p,
            pt,
            lu: &lu,
            dp: dp.as_deref(),
            wrt,
            workspace,
        };
        let mut out = Vec::with_capacity(wrt.len());
        for group in wrt.chunks(4) {
            if group.len() > 2 {
                at.linearizations::<Dual4<f64>>(group, &mut out)?;
            } else {
                for b in group.chunks(1) {
                    at.linearizations::<Dual64>(b, &mut out)?;
                }
            }
        }
        Ok(out)
    }
}

/// What [`DesignPoint::dual_linearizations`] shares between its groups of variables.
struct Shift<'a> {
    model: &'a Compiled,
    p: &'a [f64],
    pt: &'a Point,
    /// Newton's Jacobian at the solution, factorised.
    lu: &'a crate::equilibrium::Factor,
    /// `∂F/∂p` (rows of `F` × the variables), where the model has a recorded program.
    dp: Option<&'a [f64]>,
    /// All the variables (the columns of `dp`).
    wrt: &'a [usize],
    /// Where the recorded program's passes run.
    workspace: &'a Workspace,
}

impl Shift<'_> {
    /// The dual linearisations of the variables `group` (at most `D::PARTS`), direction
    /// `k` along variable `group[k]`, appended to `out`.
    fn linearizations<D: Jet>(
        &self,
        group: &[usize],
        out: &mut Vec<DualLinearization>,
    ) -> Result<(), PointError> {
        let (pt, eq) = (self.pt, &self.pt.equilibrium);
        let (speed, free, nw) = (pt.speed, &pt.linear.free, self.wrt.len());
        let seeded = |values: &[f64], slope: &dyn Fn(usize, usize) -> f64| -> Vec<D> {
            (0..values.len())
                .map(|i| {
                    D::seeded(
                        values[i],
                        |k| if k < group.len() { slope(k, i) } else { 0.0 },
                    )
                })
                .collect()
        };
        let pd = seeded(self.p, &|k, i| if i == group[k] { 1.0 } else { 0.0 });
        let equations = (self.model).at(&pd, D::from(speed), (Tier::Few, self.workspace))?;
        // The shift `[dq_R; dλ]/db = −J⁻¹ ∂F/∂b`: one implicit step from the nominal solution,
        // with `∂F/∂b` from the recorded program where there is one.
        let nf = free.len();
        let mut z: Vec<D> = (free.iter().map(|&i| eq.q[i]))
            .chain(eq.lambda.iter().copied())
            .map(D::from)
            .collect();
        let mut q = seeded(&eq.q, &|_, _| 0.0);
        let singular =
            PointError::Equilibrium(crate::equilibrium::EquilibriumError::SingularJacobian {
                iterations: 0,
            });
        // The columns of `dp` of the group's variables, found once.
        let columns: Vec<usize> = (group.iter())
            .map(|&b| {
                self.wrt
                    .iter()
                    .position(|&w| w == b)
                    .expect("b is a variable")
            })
            .collect();
        implicit::correct(
            &mut z,
            1,
            |z| match self.dp {
                Some(dp) => (0..dp.len() / nw)
                    .map(|r| D::seeded(0.0, |k| columns.get(k).map_or(0.0, |&c| dp[r * nw + c])))
                    .collect(),
                None => {
                    for (k, &i) in free.iter().enumerate() {
                        q[i] = z[k];
                    }
                    equations.residual(&q, &z[nf..])
                }
            },
            |r| self.lu.solve(r),
        )
        .ok_or(singular)?;
        for (k, &i) in free.iter().enumerate() {
            q[i] = z[k];
        }
        let lambda = &z[nf..];
        let dq: Vec<Vec<f64>> = (0..group.len())
            .map(|k| {
                let mut d = vec![0.0; eq.q.len()];
                for &i in free {
                    d[i] = q[i].part(k);
                }
                d
            })
            .collect();
        let linear = equations
            .linearize(&q, lambda, &pt.linear.independent, None)?
            .with_ports(ports_at(self.model.model(), &pd, D::from(speed), &q, free)?);
        for (k, (&b, d_equilibrium)) in group.iter().zip(dq).enumerate() {
            out.push(DualLinearization {
                param: b,
                linear: linear.map(|v| Dual64::new(v.re(), v.part(k))),
                d_equilibrium,
            });
        }
        Ok(())
    }
}
