//! The exact first derivatives: the roots', the modes' and |H|'s along each design variable.

use super::roots::{RootDerivatives, mode_derivative};
use super::{
    DesignPoint, DualLinearization, Sensitivity, VariableSensitivity, nominal_transfer,
    transfer_derivative,
};
use crate::frf::transfer;
use crate::modal::C64;
use crate::modal::cluster::{Split, as_one, conservative_split};
use crate::modal::smoothness;
use crate::sweep::PointError;
use nalgebra::DMatrix;
use num_dual::Dual64;

impl DesignPoint<'_> {
    /// Exact sensitivities by automatic differentiation through the equilibrium.
    pub fn analytic(&self, wrt: &[usize]) -> Result<Sensitivity, PointError> {
        Ok(self.analytic_with_splits(wrt)?.0)
    }

    /// [`DesignPoint::analytic`], and the first-order splits of the conservative double roots
    /// that some variable of `wrt` splits ([`Split`], from the same passes).
    pub(crate) fn analytic_with_splits(
        &self,
        wrt: &[usize],
    ) -> Result<(Sensitivity, Vec<Split>), PointError> {
        let (pt, tf) = (self.point, self.transfer);
        let nominal = tf.and_then(|t| nominal_transfer(pt, &t));
        let mut variables = Vec::with_capacity(wrt.len());
        let smooth = smoothness(&pt.modes);
        let lin = &pt.linear;
        let roots = RootDerivatives::new(&pt.modes, &smooth, (&lin.m, &lin.c, &lin.k));
        // Each cluster's projections, variable by variable.
        let mut projections: Vec<Vec<Option<DMatrix<C64>>>> =
            vec![Vec::with_capacity(wrt.len()); roots.projections_count()];
        for DualLinearization {
            param: b,
            linear: lin,
            d_equilibrium: dq,
        } in self.dual_linearizations(wrt)?
        {
            let eps = |a: &DMatrix<Dual64>| a.map(|v| v.eps);
            let (dm, dc, dk) = (eps(&lin.m), eps(&lin.c), eps(&lin.k));
            let (m, c) = (&pt.linear.m, &pt.linear.c);
            // One degree of freedom: λ₁ + λ₂ = −ĉ/m̂ and λ₁λ₂ = k̂/m̂ exactly.
            let invariants = (m.nrows() == 1).then(|| {
                let (m0, c0, k0) = (m[(0, 0)], c[(0, 0)], pt.linear.k[(0, 0)]);
                let ds = -(dc[(0, 0)] * m0 - c0 * dm[(0, 0)]) / (m0 * m0);
                let dp = (dk[(0, 0)] * m0 - k0 * dm[(0, 0)]) / (m0 * m0);
                (ds, dp)
            });
            for (g, t) in roots.projections((&dm, &dc, &dk)).into_iter().enumerate() {
                projections[g].push(t);
            }
            let modes = (pt.modes.iter().zip(&smooth))
                .zip(roots.along((&dm, &dc, &dk)))
                .map(|((md, &why), d)| mode_derivative(md, why, d, invariants))
                .collect();
            let (dmag, dphase) = match (tf, nominal) {
                (Some(t), Some(_)) => transfer(&lin, t.input, t.output, t.omega)
                    .map_or((None, None), |h| transfer_derivative(&h)),
                _ => (None, None),
            };
            variables.push(VariableSensitivity {
                param: b,
                modes,
                d_transfer_magnitude: dmag,
                d_transfer_phase: dphase,
                d_equilibrium: dq,
            });
        }
        // A pair of modes' roots that some variable splits, where it stays conservative.
        let splits = (projections.into_iter().enumerate())
            .filter_map(|(g, t)| {
                let t: Vec<DMatrix<C64>> = t.into_iter().collect::<Option<_>>()?;
                let modes: [usize; 2] = roots.members(g).try_into().ok()?;
                if t.iter().all(|ta| as_one(ta).is_some()) {
                    return None;
                }
                let (mean, split) = conservative_split(&t)?;
                Some(Split { modes, mean, split })
            })
            .collect();
        let s = Sensitivity {
            transfer_magnitude: nominal.map(|h| h.magnitude()),
            transfer_phase: nominal.map(|h| h.phase()),
            variables,
        };
        Ok((s, splits))
    }
}
