//! The equations of one operating point, whichever way they are evaluated.
//!
//! A model's equilibrium equations `F(q_R, λ)` and its linearisation at fixed parameters and
//! speed can be evaluated two ways that give the same numbers: directly, by the generic
//! mechanics over the caller's scalar ([`Direct`]), or through the model's recorded program
//! ([`crate::program`]), which is faster. Both implement [`Equations`], so the computations
//! above (the equilibrium solve, the sensitivities, the Hessians) are written once and never
//! choose between them; [`crate::compiled::Compiled::equations`] makes the choice.

use crate::linearize::{Linearization, LinearizeError, linearize};
use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, equilibrium_residual};
use crate::real::{D1, Real, lift1};
use nalgebra::DMatrix;
use std::cell::OnceCell;

/// The equilibrium equations and the linearisation of a model at fixed parameters and speed,
/// over the scalar `S` (dual numbers seeded in the parameters give their derivatives).
pub trait Equations<S: Real> {
    /// The free coordinates (indices), the unknowns `q_R`.
    fn free(&self) -> &[usize];

    /// Number of constraint equations (and multipliers).
    fn constraints(&self) -> usize;

    /// `F(q_R, λ) = [r_R + Φ_Rᵀλ; Φ]` at the coordinates `q` (all of them).
    fn residual(&self, q: &[S], lambda: &[S]) -> Vec<S>;

    /// The linearisation at `(q, λ)` reduced to the `independent` coordinates; `stiffness`,
    /// when known, is the tangent stiffness `∂(r_R + Φ_Rᵀλ)/∂q_R` there (Newton's Jacobian
    /// block), which a route may reuse.
    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError>;
}

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

    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError> {
        linearize(
            self.dual(),
            &self.free,
            q,
            &self.qd,
            lambda,
            independent,
            stiffness,
        )
    }
}
