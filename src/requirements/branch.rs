//! `branch`: the design on the nominal design's equilibrium branch (pass or fail, no margin
//! with a distribution: its margin is ±1).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SameBranch;

impl RequirementType for SameBranch {
    const NAME: &'static str = "branch";
    const FIELDS: &'static [&'static str] = &[];
    const READS: Reads = Reads::Branch;
    const UNIT: MarginUnit = MarginUnit::None;

    fn read(_: &Fields) -> Result<Self, Invalid> {
        Ok(SameBranch)
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        match at {
            Reading::Branch(true) => S::one(),
            Reading::Branch(false) => -S::one(),
            _ => S::from(f64::NAN),
        }
    }

    fn describe(&self, _mode: &str) -> String {
        "on the nominal equilibrium branch".into()
    }

    fn tightest(&self, _mode: &str, _q: f64, _transfer: &str) -> String {
        String::new()
    }
}
