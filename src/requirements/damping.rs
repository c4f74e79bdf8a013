//! `damping`: ζ at least `min` (dimensionless).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Damping {
    pub min: f64,
}

impl RequirementType for Damping {
    const NAME: &'static str = "damping";
    const FIELDS: &'static [&'static str] = &["min"];
    const READS: Reads = Reads::Mode;
    const UNIT: MarginUnit = MarginUnit::One;

    fn read(f: &Fields) -> Result<Self, Invalid> {
        Ok(Damping {
            min: f.finite(f.need(f.min, "min")?, "min", false)?,
        })
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        let Reading::Mode { zeta, .. } = at else {
            return S::from(f64::NAN);
        };
        zeta - self.min
    }

    fn describe(&self, mode: &str) -> String {
        format!("{mode}: ζ ≥ {}", self.min)
    }

    fn tightest(&self, mode: &str, q: f64, _transfer: &str) -> String {
        format!("{mode}: ζ ≥ {}", g(self.min + q))
    }
}
