//! `stable`: no root with a positive real part (margin `−max Re λ`, 1/s).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Stable;

impl RequirementType for Stable {
    const NAME: &'static str = "stable";
    const FIELDS: &'static [&'static str] = &[];
    const READS: Reads = Reads::Growth;
    const UNIT: MarginUnit = MarginUnit::PerSecond;

    fn read(_: &Fields) -> Result<Self, Invalid> {
        Ok(Stable)
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        match at {
            Reading::Growth(g) => -g,
            _ => S::from(f64::NAN),
        }
    }

    fn describe(&self, _mode: &str) -> String {
        "no unstable root".into()
    }

    fn tightest(&self, _mode: &str, q: f64, _transfer: &str) -> String {
        format!("every root's real part ≤ {} 1/s", g(-q))
    }
}
