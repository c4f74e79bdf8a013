//! `avoid`: ω_d outside the band `[low, high]` (rad/s).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g, outside};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Avoid {
    pub low: f64,
    pub high: f64,
}

impl RequirementType for Avoid {
    const NAME: &'static str = "avoid";
    const FIELDS: &'static [&'static str] = &["band"];
    const READS: Reads = Reads::Mode;
    const UNIT: MarginUnit = MarginUnit::RadPerSecond;

    fn read(f: &Fields) -> Result<Self, Invalid> {
        let band = f.need(f.band, "band")?;
        match band.get_ref().as_slice() {
            &[low, high] if low.is_finite() && high.is_finite() && low < high => {
                Ok(Avoid { low, high })
            }
            _ => Err(f.invalid(
                band.span(),
                "band must be [low, high] in rad/s, low < high".into(),
            )),
        }
    }

    fn margin<S: Real>(&self, _speed: f64, at: Reading<S>) -> S {
        let Reading::Mode { wd, .. } = at else {
            return S::from(f64::NAN);
        };
        outside(S::from(self.low) - wd, wd - self.high)
    }

    fn describe(&self, mode: &str) -> String {
        format!("{mode}: ω_d outside [{}, {}] rad/s", self.low, self.high)
    }

    fn tightest(&self, mode: &str, q: f64, _transfer: &str) -> String {
        format!(
            "{mode}: ω_d outside [{}, {}] rad/s",
            g(self.low - q),
            g(self.high + q)
        )
    }
}
