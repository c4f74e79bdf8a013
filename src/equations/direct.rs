//! The direct route: the generic mechanics of an instantiated system evaluated over the caller's
//! scalar, the reference the recorded program is checked against and the route where a model
//! has no valid recording.

use super::{Equations, Evaluation, Fit};
use crate::linearize::{Linearization, LinearizeError, SteadyState, linearize};
use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, equilibrium_residual, evaluate_rows};
use crate::real::{D1, Real, lift1};
use nalgebra::{DMatrix, DVector};
use std::cell::OnceCell;

/// The direct route: the generic mechanics of an instantiated system, lifted into the scalars
/// of its passes on first use.
#[derive(Debug)]
pub struct Direct<S: Real> {
    system: System<S>,
    free: Vec<usize>,
    qd: Vec<S>,
    value: OnceCell<Box<Lifted<S>>>,
    dual: OnceCell<Box<Lifted<D1<S>>>>,
}

impl<S: Real> Direct<S> {
    /// The equations of `system` with the free coordinates `free`.
    pub fn new(system: System<S>, free: Vec<usize>) -> Self {
        Direct {
            qd: system.steady_speeds(),
            system,
            free,
            value: OnceCell::new(),
            dual: OnceCell::new(),
        }
    }

    /// Coordinate speeds at steady state: the drive speeds on driven coordinates, zero
    /// elsewhere.
    pub fn steady_speeds(&self) -> &[S] {
        &self.qd
    }

    /// The system lifted for values (one time pass and partial passes over `S`).
    pub fn lifted(&self) -> &Lifted<S> {
        self.value
            .get_or_init(|| Box::new(Lifted::new(self.system.clone())))
    }

    /// The system lifted for first derivatives (passes over dual numbers of `S`).
    pub fn dual(&self) -> &Lifted<D1<S>> {
        self.dual
            .get_or_init(|| Box::new(Lifted::new(self.system.map(lift1))))
    }
}

impl<S: Real> Equations<S> for Direct<S> {
    fn free(&self) -> &[usize] {
        &self.free
    }

    fn constraints(&self) -> usize {
        self.system.m
    }

    fn residual(&self, q: &[S], lambda: &[S]) -> Vec<S> {
        equilibrium_residual(self.lifted(), &self.free, q, &self.qd, lambda)
    }

    /// One dual pass per free coordinate; `F` is linear in `λ`, so the `λ` columns are
    /// `[Φ_Rᵀ; 0]`, read off `Φ_q` from those same passes.
    fn residual_and_jacobian(&self, q: &[S], lambda: &[S]) -> (Vec<S>, DMatrix<S>) {
        let dual = self.dual();
        let free = &self.free;
        let nf = free.len();
        let m = lambda.len();
        let qd: Vec<D1<S>> = self.qd.iter().map(|&v| lift1(v)).collect();
        let ld: Vec<D1<S>> = lambda.iter().map(|&v| lift1(v)).collect();
        let zero = vec![lift1(S::from(0.0)); q.len()];
        let base: Vec<D1<S>> = q.iter().map(|&v| lift1(v)).collect();
        let mut value = Vec::new();
        let mut jac = DMatrix::from_element(nf + m, nf + m, S::from(0.0));
        for (k, &i) in free.iter().enumerate() {
            let mut qq = base.clone();
            qq[i] = D1::new(q[i], S::from(1.0));
            let d = evaluate_rows(dual, &qq, &qd, &zero, free);
            let g = d.with_multipliers(&ld);
            let f: Vec<D1<S>> = free
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
                    for (r, &j) in free.iter().enumerate() {
                        jac[(r, nf + c)] = d.phi_q[(c, j)].re;
                    }
                }
            }
        }
        (value, jac)
    }

    /// The multipliers fitted from one value pass, then [`Equations::evaluate`] there.
    fn evaluate_fitted(&self, q: &[S], drive: bool, fit: Fit<'_, S>) -> (Vec<S>, Evaluation<S>) {
        let free = &self.free;
        let (nf, m) = (free.len(), self.system.m);
        let zero = vec![S::from(0.0); q.len()];
        let d = evaluate_rows(self.lifted(), q, &self.qd, &zero, free);
        let lambda = fit(
            DMatrix::from_fn(nf, m, |i, k| d.phi_q[(k, free[i])]),
            DVector::from_iterator(nf, free.iter().map(|&i| -d.r[i])),
        );
        let e = self.evaluate(q, &lambda, drive);
        (lambda, e)
    }

    fn drive_rows(&self, q: &[S], lambda: &[S], driven: &[usize]) -> Vec<S> {
        let zero = vec![S::from(0.0); q.len()];
        let d = evaluate_rows(self.lifted(), q, &self.qd, &zero, driven);
        let g = d.with_multipliers(lambda);
        driven.iter().map(|&i| g[i]).collect()
    }

    fn constraint_jacobian(&self, q: &[S]) -> DMatrix<S> {
        let free = &self.free;
        let zero = vec![S::from(0.0); q.len()];
        let d = evaluate_rows(self.lifted(), q, &self.qd, &zero, free);
        DMatrix::from_fn(self.system.m, free.len(), |k, j| d.phi_q[(k, free[j])])
    }

    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError> {
        let at = SteadyState {
            q,
            qd: &self.qd,
            lambda,
        };
        linearize(self.dual(), &self.free, at, independent, stiffness)
    }
}
