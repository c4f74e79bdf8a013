//! `transfer`: |H| at most `max` (the transfer function's unit; needs `[analysis] transfer`).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Transfer {
    pub max: f64,
}

impl RequirementType for Transfer {
    const NAME: &'static str = "transfer";
    const FIELDS: &'static [&'static str] = &["max"];
    const READS: Reads = Reads::Transfer;
    const UNIT: MarginUnit = MarginUnit::Transfer;

    fn read(f: &Fields) -> Result<Self, Invalid> {
        Ok(Transfer {
            max: f.finite(f.need(f.max, "max")?, "max", true)?,
        })
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        match at {
            Reading::Transfer(h) => S::from(self.max) - h,
            _ => S::from(f64::NAN),
        }
    }

    fn describe(&self, _mode: &str) -> String {
        format!("|H| ≤ {}", self.max)
    }

    fn tightest(&self, _mode: &str, q: f64, transfer: &str) -> String {
        format!("|H| ≤ {} {transfer}", g(self.max - q))
    }
}
