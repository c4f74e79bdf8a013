//! The outputs whose spread is propagated: ω_d and ζ of every mode and the transfer magnitude.
//! A module of their own so that the derivative code ([`crate::hessian`]) and the statistics
//! ([`crate::tolerance`]) both name them without depending on each other.

use crate::modal::Smoothness;
use crate::model::Model;

/// Output kinds whose spread is propagated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    DampedFrequency,
    DampingRatio,
    TransferMagnitude,
}

/// Relative precision of one evaluated design's outputs (Newton's certified step and the
/// eigensolver are near 10⁻¹², a little amplified near a bifurcation), times the output's size.
pub const EVAL_PRECISION: f64 = 1e-9;

impl Quantity {
    /// What the evaluation resolves of an output of mean `mean` and σ `std`: ten times
    /// [`EVAL_PRECISION`] of its size (`|mean| + σ`) and, for a damping ratio, of 1 besides (ζ
    /// is a ratio of the root's parts, known to the root's relative precision whatever its
    /// value). A σ below it is rounding (the ζ of an undamped mode, 10⁻²¹ about 0): no method
    /// is compared with another there and no plot drawn of it.
    pub fn resolution(self, mean: f64, std: f64) -> f64 {
        let unit = if self == Quantity::DampingRatio {
            1.0
        } else {
            0.0
        };
        10.0 * EVAL_PRECISION * (mean.abs() + std + unit)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Quantity::DampedFrequency => "damped_frequency",
            Quantity::DampingRatio => "damping_ratio",
            Quantity::TransferMagnitude => "transfer_magnitude",
        }
    }
}

/// One output: a quantity of a mode (0-based), or the transfer magnitude (`mode = None`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Output {
    pub quantity: Quantity,
    pub mode: Option<usize>,
}

/// The outputs of a system with `modes` modes, with or without a transfer function.
pub fn outputs(modes: usize, transfer: bool) -> Vec<Output> {
    let mut out = Vec::new();
    for m in 0..modes {
        out.push(Output {
            quantity: Quantity::DampedFrequency,
            mode: Some(m),
        });
        out.push(Output {
            quantity: Quantity::DampingRatio,
            mode: Some(m),
        });
    }
    if transfer {
        out.push(Output {
            quantity: Quantity::TransferMagnitude,
            mode: None,
        });
    }
    out
}

/// The outputs of `model` at every speed: ω_d and ζ of each of its modes, one per degree of
/// freedom (every point that solves has that many), then |H| where its `[analysis]` names a
/// transfer function. The model's, not a point's: the analysis, its Monte Carlo and the shard
/// files all count these, so a run whose nominal design fails at every speed still has rows
/// (each saying why it is empty) and its shards merge.
pub fn of_model(model: &Model) -> Vec<Output> {
    outputs(model.dof(), model.analysis.transfer.is_some())
}

/// Why an output has no derivative, or a method no statistic, at a point: every empty cell of
/// a result carries one (in `tolerance.csv`, `summary.json`, the report and on stderr).
#[derive(Debug, Clone, PartialEq)]
pub enum Missing {
    /// The mode's roots are not differentiable here (see [`Smoothness`]), or (for ω_d) its
    /// two roots coincide, where ω_d has a kink.
    Mode { mode: usize, why: Smoothness },
    /// The damping ratio of a rigid-body mode is undefined (it has no frequency).
    RigidDamping { mode: usize },
    /// `|H|` passes through zero here, where it is not differentiable.
    TransferZero,
    /// `H` is unbounded at the excitation frequency (an undamped resonance) or overflows.
    TransferUnbounded,
    /// A derivative came out infinite or NaN (an overflow in the expansion).
    NotFinite,
    /// The bordered eigen-equations of a mode's root are exactly singular (a multiple root
    /// that the relative test did not see).
    SingularExpansion { mode: usize },
    /// The point's derivatives failed (the reason given).
    Failed(String),
    /// No node or sample of a sampling method gave a value.
    NoValue,
    /// One sample alone gave a value: a mean without a σ.
    OneSample,
    /// Not asked for (a first-order local model has no Hessians).
    NotComputed,
}

impl std::fmt::Display for Missing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Missing::Mode { mode, why } => {
                write!(f, "not differentiable: mode {}: {why}", mode + 1)
            }
            Missing::RigidDamping { mode } => write!(
                f,
                "undefined: mode {} is a rigid-body mode (no frequency, no damping ratio)",
                mode + 1
            ),
            Missing::TransferZero => write!(f, "not differentiable: |H| passes through zero"),
            Missing::TransferUnbounded => write!(
                f,
                "undefined: H is unbounded at the excitation frequency (an undamped resonance)"
            ),
            Missing::NotFinite => write!(f, "a derivative overflows double precision"),
            Missing::SingularExpansion { mode } => write!(
                f,
                "not differentiable: the eigen-equations of mode {} are singular (a multiple root)",
                mode + 1
            ),
            Missing::Failed(e) => write!(f, "derivatives failed: {e}"),
            Missing::NoValue => write!(f, "no node or sample gave a value"),
            Missing::OneSample => write!(f, "no σ: one sample alone gave a value"),
            Missing::NotComputed => write!(f, "not computed"),
        }
    }
}
