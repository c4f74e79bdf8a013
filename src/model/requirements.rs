//! What a design must meet (`[[requirements]]`) and what tolerances cost (`[allocation]`).

use super::analysis::Tolerance;

/// A requirement on the modes of every design over an operating range (`[[requirements]]`):
/// its margin at a speed is positive where it is met (see [`crate::requirement`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Requirement {
    pub name: String,
    pub kind: RequirementKind,
    /// The operating range `[from, to]` (rad/s, inclusive); `None`: every speed analysed.
    pub speeds: Option<(f64, f64)>,
    /// 0-based mode; `None`: every mode (the worst one decides).
    pub mode: Option<usize>,
}

/// What a requirement asks, with the unit of its margin.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub enum RequirementKind {
    /// ω_d clear of every engine order `k·Ω` by the margin (rad/s).
    Separation {
        orders: Vec<f64>,
        margin: SeparationMargin,
    },
    /// ω_d within `[min, max]` (either may be absent; rad/s).
    Frequency { min: Option<f64>, max: Option<f64> },
    /// ω_d outside `[low, high]` (rad/s).
    Avoid { low: f64, high: f64 },
    /// ζ at least `min` (dimensionless).
    Damping { min: f64 },
    /// The mode's roots complex: ζ below 1 (margin `1 − ζ`).
    Underdamped,
    /// No root with a positive real part (margin `−max Re λ`, 1/s).
    Stable,
    /// On the nominal design's equilibrium branch (pass or fail, no margin).
    SameBranch,
    /// |H| at most `max` (the transfer function's unit).
    Transfer { max: f64 },
}

/// The separation a [`RequirementKind::Separation`] asks.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum SeparationMargin {
    /// A fraction of the excitation frequency `k·Ω`, below and above (0.15 for "15%").
    Fraction(f64),
    /// API 684's margin from the amplification factor `AF = 1/(2ζ)`: none below AF 2.5, else
    /// `min(16, 17(1 − 1/(AF − 1.5)))` % below and `min(26, 10 + 17(1 − 1/(AF − 1.5)))` %
    /// above the excitation.
    Api684,
}

/// Tolerance allocation's settings (`[allocation]`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Allocation {
    /// The probability of meeting every requirement the allocated tolerances must reach.
    pub target_yield: f64,
    /// The tolerance case whose variables are allocated (`None`: the parameters' own).
    pub case: Option<String>,
    /// Per parameter (index): its cost model; parameters not listed cost `1/T`.
    pub costs: Vec<(usize, Cost)>,
}

/// A cost–tolerance model `a + b / T^k`, `T` the tolerance in the parameter's unit (Chase &
/// Greenwood 1988), with the largest tolerance allowed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cost {
    pub a: f64,
    pub b: f64,
    pub k: f64,
    pub max: Option<Tolerance>,
}

impl Cost {
    /// The cost of tolerance `t`: `a + b / t^k`.
    pub fn of(&self, t: f64) -> f64 {
        self.a + self.b / t.powf(self.k)
    }
}

impl Default for Cost {
    fn default() -> Self {
        Cost {
            a: 0.0,
            b: 1.0,
            k: 1.0,
            max: None,
        }
    }
}
