//! The search for the allocation's `β` (see the [`super`] module documentation).

use super::MAX_ROUNDS;
use statrs::distribution::{ContinuousCDF, Normal};

/// The search for the smallest `β` whose allocation the quadrature verifies to meet the target
/// (the cost grows with `β`): the verified yield less its error, in reliability index,
/// `h(β) = Φ⁻¹(verified − error) − Φ⁻¹(target)`, is nearly `β − β*` (the first-order slope
/// is 1), so a step of `−h` from one end and regula falsi across a bracket, with a bisection
/// wherever two steps did not halve it, find the root in a few rounds; the search stops once
/// the design meeting the target costs at most [`COST_GAP`] more than one falling short.
pub(super) struct BetaSearch {
    start: f64,
    /// The smallest `β` verified to meet the target and the largest short of it: `(β, h, cost)`.
    met: Option<(f64, f64, f64)>,
    short: Option<(f64, f64, f64)>,
    rounds: usize,
    /// The bracket's widths after the last two rounds (the bisection safeguard).
    widths: [f64; 2],
}

/// The relative cost between the cheapest design meeting the target and the dearest falling
/// short of it at which the search stops: the optimum of the family lies between them (a
/// fifth of the 0.1 % asked of an allocation, leaving room for the family's own distance from
/// the optimum over every tolerance, 0.07 % in a two-variable case with an exact optimum).
pub const COST_GAP: f64 = 2e-4;

impl BetaSearch {
    pub(super) fn new(start: f64) -> BetaSearch {
        BetaSearch {
            start,
            met: None,
            short: None,
            rounds: 0,
            widths: [f64::INFINITY; 2],
        }
    }

    /// The `β` of the next round, `None` once done.
    pub(super) fn next(&self) -> Option<f64> {
        if self.rounds >= MAX_ROUNDS || self.cost_gap().is_some_and(|g| g <= COST_GAP) {
            return None;
        }
        // The least step: 10⁻³ of β (about 10⁻³ of the cost, which goes as β^e).
        let least = 1e-3 * self.start.abs().max(1.0);
        Some(match (self.short, self.met) {
            (None, None) => self.start,
            (Some(s), None) => s.0 + (-s.1).max(least).min(self.start.abs().max(1.0)),
            (None, Some(m)) => m.0 - m.1.max(least).min(self.start.abs().max(1.0)),
            (Some(s), Some(m)) => {
                let w = m.0 - s.0;
                let falsi = s.0 + w * (-s.1) / (m.1 - s.1);
                let slow = w > 0.5 * self.widths[0];
                if slow || !(falsi > s.0 + 0.01 * w && falsi < m.0 - 0.01 * w) {
                    0.5 * (s.0 + m.0)
                } else {
                    falsi
                }
            }
        })
    }

    /// Takes the round at `beta`: `h` from the verified yield less its error, and its cost.
    pub(super) fn take(&mut self, beta: f64, lower: f64, target: f64, cost: f64) {
        self.rounds += 1;
        let normal = Normal::standard();
        let probit = |p: f64| normal.inverse_cdf(p.clamp(1e-300, 1.0 - 1e-16));
        let h = if lower.is_nan() {
            f64::NEG_INFINITY
        } else {
            probit(lower) - probit(target)
        };
        if lower >= target {
            if self.met.is_none_or(|m| beta < m.0) {
                self.met = Some((beta, h.max(0.0), cost));
            }
        } else if self.short.is_none_or(|s| beta > s.0) {
            // A step of −h is ∞ where nothing is verified: the least step's limit applies.
            self.short = Some((beta, if h.is_finite() { h.min(0.0) } else { -1e300 }, cost));
        }
        if let (Some(s), Some(m)) = (self.short, self.met) {
            self.widths = [self.widths[1], m.0 - s.0];
        }
    }

    /// The relative cost of the cheapest design meeting the target above the dearest falling
    /// short of it.
    pub(super) fn cost_gap(&self) -> Option<f64> {
        Some(self.met?.2 / self.short?.2 - 1.0)
    }
}
