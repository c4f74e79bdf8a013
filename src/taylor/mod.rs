//! The Taylor methods as one propagation method: first order (the paper's), second order and,
//! for ω_d, the invariant method, all read off the study's local models (exact gradients and
//! Hessians at the nominal point; see [`crate::tolerance`] for the formulas).
//!
//! They share the local model and cost nothing beside it, so they are one object; each keeps
//! its own result, or the reason it has none.

mod table;
pub mod yields;

use crate::output::Missing;
use crate::output::Quantity;
use crate::propagate::{Estimate, Propagation, Run, Study, Termination};
use crate::tolerance::{
    LocalModel, Spread, Stat, discriminant, first_order, invariant, second_order,
};

/// First-order variance shares: each variable's share of the variance.
pub type Shares = Vec<f64>;

/// The Taylor methods' statistics of one output at one speed.
#[derive(Debug, Clone)]
pub struct TaylorStats {
    /// First order, with each variable's share of the variance.
    pub first_order: Result<(Stat, Shares), Missing>,
    pub second_order: Result<Stat, Missing>,
    /// ω_d only: the invariant method's statistics of ω_d and of the pair discriminant `D`
    /// (how close the spread comes to a change of class).
    pub invariant: Option<Result<(Stat, Stat), Missing>>,
}

/// First order, second order and the invariant method (see the module documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct Taylor;

impl Taylor {
    /// The statistics of every output of one local model.
    pub fn at(lm: &LocalModel, s: &Spread) -> Vec<TaylorStats> {
        lm.outputs
            .iter()
            .enumerate()
            .map(|(k, o)| {
                let v = lm.value[k];
                let first = lm.grad[k].clone().map(|g| first_order(v, &g, s));
                let second = lm.grad[k]
                    .clone()
                    .and_then(|g| lm.hess[k].clone().map(|h| second_order(v, &g, &h, s)));
                let inv = match (o.quantity, o.mode) {
                    (Quantity::DampedFrequency, Some(m)) => {
                        let (d, g, h) = &lm.disc[m];
                        Some(g.clone().map(|g| {
                            let h = h.as_ref().ok();
                            (invariant(*d, &g, h, s), discriminant(*d, &g, h, s))
                        }))
                    }
                    _ => None,
                };
                TaylorStats {
                    first_order: first,
                    second_order: second,
                    invariant: inv,
                }
            })
            .collect()
    }
}

/// What the Taylor methods give of one case.
#[derive(Debug, Clone)]
pub struct TaylorResult {
    /// Per speed (`None` without a local model), per output.
    pub stats: Vec<Option<Vec<TaylorStats>>>,
}

impl Propagation for Taylor {
    type Value = TaylorResult;

    fn propagate(&self, study: &Study, spread: &Spread, _run: &Run) -> Estimate<Self::Value> {
        let stats = study
            .locals
            .iter()
            .map(|lm| lm.as_ref().map(|lm| Taylor::at(lm, spread)))
            .collect();
        Estimate {
            value: TaylorResult { stats },
            termination: Termination::Completed,
        }
    }
}
