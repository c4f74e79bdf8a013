//! What a design must meet (`[[requirements]]`) and what tolerances cost (`[allocation]`).

use super::analysis::Tolerance;
use crate::requirements::Kind;

/// A requirement on the modes of every design over an operating range (`[[requirements]]`):
/// its margin at a speed is positive where it is met (see [`crate::requirements`] and [`crate::margins`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Requirement {
    pub name: String,
    pub kind: Kind,
    /// The operating range `[from, to]` (rad/s, inclusive); `None`: every speed analysed.
    pub speeds: Option<(f64, f64)>,
    /// 0-based mode; `None`: every mode (the worst one decides).
    pub mode: Option<usize>,
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
