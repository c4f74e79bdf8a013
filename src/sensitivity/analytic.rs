//! The exact first derivatives: the roots', the modes' and |H|'s along each design variable.

use super::roots::{RootDerivatives, mode_derivative};
use super::{
    DesignPoint, DualLinearization, Sensitivity, VariableSensitivity, nominal_transfer,
    transfer_derivative,
};
use crate::frf::transfer;
use crate::modal::smoothness;
use crate::sweep::PointError;
use nalgebra::DMatrix;
use num_dual::Dual64;

impl DesignPoint<'_> {
    /// Exact sensitivities by automatic differentiation through the equilibrium.
    pub fn analytic(&self, wrt: &[usize]) -> Result<Sensitivity, PointError> {
        let (pt, tf) = (self.point, self.transfer);
        let nominal = tf.and_then(|t| nominal_transfer(pt, &t));
        let mut variables = Vec::with_capacity(wrt.len());
        let smooth = smoothness(&pt.modes);
        let lin = &pt.linear;
        let roots = RootDerivatives::new(&pt.modes, &smooth, (&lin.m, &lin.c, &lin.k));
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
        Ok(Sensitivity {
            transfer_magnitude: nominal.map(|h| h.magnitude()),
            transfer_phase: nominal.map(|h| h.phase()),
            variables,
        })
    }
}
