//! The Taylor methods as one propagation method: first order (the paper's), second order and,
//! for ω_d, the invariant method, all read off the study's local models (exact gradients and
//! Hessians at the nominal point; see [`crate::tolerance`] for the formulas).
//!
//! They share the local model and cost nothing beside it, so they are one object; each keeps
//! its own result, or the reason it has none.

mod table;
pub mod yields;

use crate::modal::cluster::Split;
use crate::output::Missing;
use crate::output::Quantity;
use crate::propagate::{Estimate, Propagation, Run, Study, Termination};
use crate::tolerance::{
    LocalModel, Spread, Stat, discriminant, first_order, invariant, second_order, split_first_order,
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
                let first = match (&lm.grad[k], split_of(lm, o.mode)) {
                    (Err(why), Some((split, upper))) => {
                        split_member(v, o.quantity, split, upper, s).ok_or(why.clone())
                    }
                    (grad, _) => grad.clone().map(|g| first_order(v, &g, s)),
                };
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

/// The split double root (with whether it is the upper member) that mode `mode` belongs to.
fn split_of(lm: &LocalModel, mode: Option<usize>) -> Option<(&Split, bool)> {
    let m = mode?;
    (lm.splits.iter())
        .find(|sp| sp.modes.contains(&m))
        .map(|sp| (sp, sp.modes[1] == m))
}

/// First order at a member of a split conservative double root: its ω_d by
/// [`split_first_order`]; its ζ stays zero to first order (the pair stays on the imaginary
/// axis), with no spread. `None` where the split's distribution is not the normal one's.
fn split_member(
    value: f64,
    quantity: Quantity,
    split: &Split,
    upper: bool,
    s: &Spread,
) -> Option<(Stat, Shares)> {
    match quantity {
        Quantity::DampedFrequency => split_first_order(value, split, upper, s),
        Quantity::DampingRatio => Some((
            Stat {
                mean: value,
                std: 0.0,
            },
            vec![0.0; split.mean.len()],
        )),
        _ => None,
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
