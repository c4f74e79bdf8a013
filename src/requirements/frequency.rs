//! `frequency`: ω_d within `[min, max]` (either may be absent; rad/s).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Frequency {
    pub min: Option<f64>,
    pub max: Option<f64>,
}

impl RequirementType for Frequency {
    const NAME: &'static str = "frequency";
    const FIELDS: &'static [&'static str] = &["min", "max"];
    const READS: Reads = Reads::Mode;
    const UNIT: MarginUnit = MarginUnit::RadPerSecond;

    fn read(f: &Fields) -> Result<Self, Invalid> {
        let min = f.min.map(|v| f.finite(v, "min", false)).transpose()?;
        let max = f.max.map(|v| f.finite(v, "max", false)).transpose()?;
        match (min, max) {
            (None, None) => return Err(f.missing("min' or 'max")),
            (Some(a), Some(b)) if a > b => {
                return Err(f.invalid(f.kind.span(), format!("min ({a}) is above max ({b})")));
            }
            _ => {}
        }
        Ok(Frequency { min, max })
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        let Reading::Mode { wd, .. } = at else {
            return S::from(f64::NAN);
        };
        let lo = self.min.map(|a| wd - a);
        let hi = self.max.map(|b| S::from(b) - wd);
        match (lo, hi) {
            (Some(a), Some(b)) => {
                if a.re() <= b.re() {
                    a
                } else {
                    b
                }
            }
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => S::from(f64::INFINITY),
        }
    }

    fn describe(&self, mode: &str) -> String {
        match (self.min, self.max) {
            (Some(a), Some(b)) => format!("{mode}: {a} ≤ ω_d ≤ {b} rad/s"),
            (Some(a), None) => format!("{mode}: ω_d ≥ {a} rad/s"),
            (None, Some(b)) => format!("{mode}: ω_d ≤ {b} rad/s"),
            (None, None) => mode.to_string(),
        }
    }

    fn tightest(&self, mode: &str, q: f64, _transfer: &str) -> String {
        match (self.min, self.max) {
            (Some(a), Some(b)) => format!("{mode}: {} ≤ ω_d ≤ {} rad/s", g(a + q), g(b - q)),
            (Some(a), None) => format!("{mode}: ω_d ≥ {} rad/s", g(a + q)),
            (None, Some(b)) => format!("{mode}: ω_d ≤ {} rad/s", g(b - q)),
            (None, None) => String::new(),
        }
    }
}
