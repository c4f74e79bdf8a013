//! The outputs whose spread is propagated: ω_d and ζ of every mode and the transfer magnitude.
//! A module of their own so that the derivative code ([`crate::hessian`]) and the statistics
//! ([`crate::tolerance`]) both name them without depending on each other.

/// Output kinds whose spread is propagated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    DampedFrequency,
    DampingRatio,
    TransferMagnitude,
}

impl Quantity {
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
