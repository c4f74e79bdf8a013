//! `separation`: ω_d clear of every engine order `k·Ω` by a margin (rad/s), a fixed fraction or
//! API 684's (*Rotordynamic Tutorial*, 2nd ed., 2005, §2.8): a mode's frequency must lie below
//! the excitation `k·Ω` by `SM_below` or above it by `SM_above`. With a fixed margin both are
//! that fraction. With `api684` they follow from the amplification factor, here `AF = 1/(2ζ)`
//! (the half-power estimate `ω_n/(ω₂ − ω₁)` of a single mode): no margin below AF 2.5, else
//! `SM_below = min(16, 17(1 − 1/(AF − 1.5)))` % and `SM_above = min(26, 10 + 17(1 − 1/(AF −
//! 1.5)))` %. The frequency compared is ω_d (the frequency of the response peak for light
//! damping, the only case where the margin applies).

use super::{Fields, Invalid, MarginUnit, Reading, Reads, RequirementType, g, outside};
use crate::real::Real;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Separation {
    /// The engine orders `k` (> 0).
    pub orders: Vec<f64>,
    pub margin: SeparationMargin,
}

/// The separation a [`Separation`] asks.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum SeparationMargin {
    /// A fraction of the excitation frequency `k·Ω`, below and above (0.15 for "15%").
    Fraction(f64),
    /// API 684's margin from the amplification factor (see the module documentation).
    Api684,
}

impl RequirementType for Separation {
    const NAME: &'static str = "separation";
    const FIELDS: &'static [&'static str] = &["orders", "margin"];
    const READS: Reads = Reads::Mode;
    const UNIT: MarginUnit = MarginUnit::RadPerSecond;

    fn read(f: &Fields) -> Result<Self, Invalid> {
        let orders = f.need(f.orders, "orders")?;
        if orders.get_ref().is_empty()
            || orders.get_ref().iter().any(|o| !o.is_finite() || *o <= 0.0)
        {
            return Err(f.invalid(
                orders.span(),
                "orders must be a non-empty list of numbers > 0".into(),
            ));
        }
        let m = f.need(f.margin, "margin")?;
        let text = m.get_ref().trim();
        let margin = if text.eq_ignore_ascii_case("api684") {
            SeparationMargin::Api684
        } else {
            match text.strip_suffix('%').map(|p| p.trim().parse::<f64>()) {
                Some(Ok(p)) if p.is_finite() && (0.0..100.0).contains(&p) => {
                    SeparationMargin::Fraction(p / 100.0)
                }
                _ => {
                    return Err(f.invalid(
                        m.span(),
                        "margin must be \"P%\" (0 ≤ P < 100) or \"api684\"".into(),
                    ));
                }
            }
        };
        Ok(Separation {
            orders: orders.get_ref().clone(),
            margin,
        })
    }

    fn margin<S: Real>(&self, speed: f64, at: Reading<S>) -> S {
        let Reading::Mode { wd, zeta, .. } = at else {
            return S::from(f64::NAN);
        };
        let (below, above) = match self.margin {
            SeparationMargin::Fraction(f) => (S::from(f), S::from(f)),
            SeparationMargin::Api684 => api684(zeta),
        };
        self.orders
            .iter()
            .map(|&k| {
                let e = k * speed;
                let under = (S::one() - below) * e - wd;
                let over = wd - (S::one() + above) * e;
                outside(under, over)
            })
            .reduce(|a, b| if b.re() < a.re() { b } else { a })
            .unwrap_or(S::from(f64::INFINITY))
    }

    fn describe(&self, mode: &str) -> String {
        format!(
            "{mode}: ω_d clear of {} × Ω by {}",
            self.orders
                .iter()
                .map(|o| o.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            match self.margin {
                SeparationMargin::Fraction(f) => format!("{} %", f * 100.0),
                SeparationMargin::Api684 => "API 684's margin".into(),
            }
        )
    }

    fn tightest(&self, mode: &str, q: f64, _transfer: &str) -> String {
        format!(
            "{mode}: ω_d clear of the required separation by {} rad/s",
            g(q)
        )
    }
}

/// API 684's separation margins `(below, above)` as fractions, from `AF = 1/(2ζ)`.
fn api684<S: Real>(zeta: S) -> (S, S) {
    if zeta.re() >= 0.2 {
        // AF ≤ 2.5: no separation required.
        return (S::zero(), S::zero());
    }
    if zeta.re().is_nan() || zeta.re() <= 0.0 {
        // Undamped or unstable: the largest margins.
        return (S::from(0.16), S::from(0.26));
    }
    let af = (zeta * 2.0).recip();
    let g = (S::one() - (af - 1.5).recip()) * 0.17;
    let below = if g.re() < 0.16 { g } else { S::from(0.16) };
    let up = g + 0.10;
    let above = if up.re() < 0.26 { up } else { S::from(0.26) };
    (below, above)
}
