//! `underdamped`: the mode's roots complex, ζ below 1 (margin `1 − |ζ|`); a pair whose roots
//! are real whatever ζ (`p ≤ 0`) fails it.

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Underdamped;

impl RequirementType for Underdamped {
    const NAME: &'static str = "underdamped";
    const FIELDS: &'static [&'static str] = &[];
    const READS: Reads = Reads::Mode;
    const UNIT: MarginUnit = MarginUnit::One;

    fn read(_: &Fields) -> Result<Self, Invalid> {
        Ok(Underdamped)
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        match at {
            // Real roots whatever `s`: not underdamped, and ζ does not say it.
            Reading::Mode {
                real_pair: true, ..
            } => S::from(f64::NEG_INFINITY),
            Reading::Mode { zeta, .. } => S::one() - zeta.abs(),
            _ => S::from(f64::NAN),
        }
    }

    fn describe(&self, mode: &str) -> String {
        format!("{mode}: not overdamped")
    }

    fn tightest(&self, mode: &str, q: f64, _transfer: &str) -> String {
        format!("{mode}: ζ ≤ {}", g(1.0 - q))
    }
}
