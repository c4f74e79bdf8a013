//! The recorded program as the [`Equations`] of a point: over any scalar ([`Recorded`]) and in
//! `f64` with what depends on the parameters and the speed evaluated once ([`Instance`]).

use super::linear::Linear;
use super::{Instance, Program, Workspace};
use crate::equations::{Equations, Evaluation, Fit, Probed};
use crate::linearize::{Linearization, LinearizeError};
use crate::real::Real;
use nalgebra::{DMatrix, DVector};

/// The recorded program at parameters `p` and `speed` over any [`Real`]: the
/// [`Equations`] the sensitivities and the Hessians evaluate over dual numbers (in `f64`,
/// [`Instance`] evaluates what depends on the parameters and the speed once).
pub struct Recorded<'a, S: Real> {
    pub program: &'a Program,
    pub p: Vec<S>,
    pub speed: S,
    /// Where its passes run.
    pub workspace: &'a Workspace,
}

impl<S: Real> Recorded<'_, S> {
    fn linear(&self, q: &[S], lambda: &[S]) -> Linear<S> {
        self.program
            .linear_over(&self.p, self.speed, (q, lambda), self.workspace)
    }
}

impl<S: Real> Equations<S> for Recorded<'_, S> {
    fn free(&self) -> &[usize] {
        &self.program.free
    }

    fn constraints(&self) -> usize {
        self.program.m
    }

    fn residual(&self, q: &[S], lambda: &[S]) -> Vec<S> {
        self.program.residual_over(&self.p, self.speed, q, lambda)
    }

    fn residual_and_jacobian(&self, q: &[S], lambda: &[S]) -> (Vec<S>, DMatrix<S>) {
        let lin = self.linear(q, lambda);
        (lin.residual, lin.jacobian)
    }

    fn evaluate(&self, q: &[S], lambda: &[S], drive: bool) -> Evaluation<S> {
        self.linear(q, lambda).evaluation(drive)
    }

    /// The pass at `λ = 0` gives `r_R` and `Φ_R`; a second pass is at the fitted multipliers.
    fn evaluate_fitted(&self, q: &[S], drive: bool, fit: Fit<'_, S>) -> (Vec<S>, Evaluation<S>) {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let lin = self.linear(q, &vec![S::from(0.0); m]);
        let lambda = fit(
            lin.jacobian.view((0, nf), (nf, m)).into_owned(),
            DVector::from_iterator(nf, lin.residual[..nf].iter().map(|&v| -v)),
        );
        let e = self.evaluate(q, &lambda, drive);
        (lambda, e)
    }

    /// The recorded drive rows are those of the model's driven coordinates, in order.
    fn drive_rows(&self, q: &[S], lambda: &[S], _driven: &[usize]) -> Vec<S> {
        self.linear(q, lambda).drive
    }

    /// The `λ` columns of the Jacobian are `[Φ_Rᵀ; 0]`.
    fn constraint_jacobian(&self, q: &[S]) -> DMatrix<S> {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (_, j) = self.residual_and_jacobian(q, &vec![S::from(0.0); m]);
        j.view((0, nf), (nf, m)).transpose()
    }

    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        _stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError> {
        self.linear(q, lambda)
            .reduce(&self.program.free, independent)
    }
}

impl Equations<f64> for Instance<'_> {
    fn free(&self) -> &[usize] {
        &self.program.free
    }

    fn constraints(&self) -> usize {
        self.program.m
    }

    fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        Instance::residual(self, q, lambda)
    }

    fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        Instance::residual_and_jacobian(self, q, lambda)
    }

    fn evaluate(&self, q: &[f64], lambda: &[f64], drive: bool) -> Evaluation {
        self.linear_plain(q, lambda).evaluation(drive)
    }

    /// One pass: the pass at `λ = 0` gives `r_R` and `Φ_R`, and is then shifted to the
    /// multipliers ([`Linear::shift_multipliers`]).
    fn evaluate_fitted(&self, q: &[f64], drive: bool, fit: Fit<'_, f64>) -> (Vec<f64>, Evaluation) {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (lambda, lin) = self.full_pass(q, &vec![0.0; m], |f, d| {
            let mut lin = Linear::from_forward(f, d, nf, m, false);
            let lambda = fit(
                lin.jacobian.view((0, nf), (nf, m)).into_owned(),
                DVector::from_iterator(nf, lin.residual[..nf].iter().map(|v| -v)),
            );
            // The curvature read where the pass left it, not gathered into matrices first.
            lin.shift(&lambda, 3, |k, j| d.row(nf + m + k * nf + j));
            (lambda, lin)
        });
        (lambda, lin.evaluation(drive))
    }

    /// The recorded drive rows are those of the model's driven coordinates, in order.
    fn drive_rows(&self, q: &[f64], lambda: &[f64], _driven: &[usize]) -> Vec<f64> {
        self.linear_plain(q, lambda).drive
    }

    /// One driven coordinate turning alone is one pass over the recorded residual with that
    /// input varied; several turning together, an evaluation per offset.
    fn residual_at_drive_offsets(
        &self,
        q: &[f64],
        lambda: &[f64],
        shift: &[(usize, usize, f64)],
        offsets: [f64; 3],
    ) -> [f64; 3] {
        match shift {
            // Alone, it is the fastest: its rate is one.
            [(d, _, _)] => Instance::residual_at_drive_offsets(self, q, lambda, *d, offsets),
            _ => crate::equations::residual_at_shifts(self, q, lambda, shift, offsets),
        }
    }

    /// The `λ` columns of the Jacobian are `[Φ_Rᵀ; 0]`.
    fn constraint_jacobian(&self, q: &[f64]) -> DMatrix<f64> {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (_, j) = Instance::residual_and_jacobian(self, q, &vec![0.0; m]);
        j.view((0, nf), (nf, m)).transpose()
    }

    fn linearize(
        &self,
        q: &[f64],
        lambda: &[f64],
        independent: &[usize],
        _stiffness: Option<&DMatrix<f64>>,
    ) -> Result<Linearization<f64>, LinearizeError> {
        self.linear_plain(q, lambda)
            .reduce(&self.program.free, independent)
    }

    fn probe_linearisation(
        &self,
        q: &[f64],
        lambda: &[f64],
        _independent: &[usize],
    ) -> Result<Probed, LinearizeError> {
        Ok(self.probe(q, lambda))
    }
}
