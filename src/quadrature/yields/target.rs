//! The root of `P(M ≥ q) = Y`, the worst margin met at the target yield: bracketed, then
//! regula falsi on `Φ⁻¹(P)` with a bisection safeguard (see the module documentation above).

use super::{ROOT_FRACTION, ROOT_ITERATIONS};
use statrs::distribution::{ContinuousCDF, Normal};

/// One sought root of a decreasing `P(q)` (`P(M ≥ q)`): `P(q) = goal`, with the bracket
/// found so far (`q` where `P ≥ goal`, and where `P < goal`, each with its `P`).
pub(super) struct Root {
    goal: f64,
    /// Where the search starts and its scale.
    start: f64,
    scale: f64,
    /// `|P − goal|` at which the root is taken as found.
    tolerance: f64,
    above: Option<(f64, f64)>,
    below: Option<(f64, f64)>,
    /// Where the root is (once known), `±∞` where the goal is beyond what `P` reaches.
    pub(super) found: Option<f64>,
    /// Steps taken, and the bracket's widths after the last two (the bisection safeguard).
    steps: usize,
    widths: [f64; 2],
}

impl Root {
    /// The root of `P(q) = goal` given `P(−∞) = reached`, searched from `start` on `scale`
    /// (a scale of 0: every design with a margin has the same, `start`).
    pub(super) fn new(goal: f64, reached: f64, start: f64, scale: f64, request: f64) -> Root {
        let found = if goal <= 0.0 {
            Some(f64::INFINITY)
        } else if goal >= reached || goal >= 1.0 {
            // More than 1 − goal of the designs fail without a margin.
            Some(f64::NEG_INFINITY)
        } else if scale.is_nan() || scale <= 0.0 {
            // The step from `reached` to 0 is there.
            Some(start)
        } else {
            None
        };
        Root {
            goal,
            start,
            scale,
            // Relative to the goal near 0 or 1, where the request is coarser than the goal.
            tolerance: ROOT_FRACTION * request.min(goal).min(1.0 - goal),
            above: None,
            below: None,
            found,
            steps: 0,
            widths: [f64::INFINITY; 2],
        }
    }

    /// `−dP/dq` across the last bracket, where there is one.
    pub(super) fn slope(&self) -> Option<f64> {
        let (a, b) = (self.above?, self.below?);
        let s = (a.1 - b.1) / (b.0 - a.0);
        (s.is_finite() && s > 0.0).then_some(s)
    }

    /// The next `q` to integrate at, `None` once found.
    pub(super) fn next(&mut self) -> Option<f64> {
        if self.found.is_some() {
            return None;
        }
        let grow = self.scale * 2f64.powi(self.steps as i32);
        Some(match (self.above, self.below) {
            (None, None) => self.start,
            (Some(a), None) => a.0 + grow,
            (None, Some(b)) => b.0 - grow,
            (Some(a), Some(b)) => {
                let w = b.0 - a.0;
                // Regula falsi on Φ⁻¹(P) − Φ⁻¹(goal), nearly linear in q for a nearly
                // normal margin; bisection where it does not shrink the bracket fast enough.
                let nd = Normal::standard();
                let g = |p: f64| nd.inverse_cdf(p.clamp(1e-300, 1.0 - 1e-16));
                let (ga, gb) = (g(a.1) - g(self.goal), g(b.1) - g(self.goal));
                let falsi = a.0 + w * ga / (ga - gb);
                let slow = w > 0.5 * self.widths[0];
                if slow || !(falsi > a.0 + 1e-3 * w && falsi < b.0 - 1e-3 * w) {
                    0.5 * (a.0 + b.0)
                } else {
                    falsi
                }
            }
        })
    }

    /// Takes `p = P(q)`.
    pub(super) fn take(&mut self, q: f64, p: f64) {
        self.steps += 1;
        if (p - self.goal).abs() <= self.tolerance {
            self.found = Some(q);
            return;
        }
        if p >= self.goal {
            self.above = Some((q, p));
        } else {
            self.below = Some((q, p));
        }
        if let (Some(a), Some(b)) = (self.above, self.below) {
            let w = b.0 - a.0;
            self.widths = [self.widths[1], w];
            if w <= 4.0 * f64::EPSILON * (a.0.abs() + b.0.abs() + self.scale) {
                // The bracket is at rounding: a step of P there (an atom of the margin).
                self.found = Some(if (a.1 - self.goal) < (self.goal - b.1) {
                    a.0
                } else {
                    b.0
                });
            }
        }
        if self.steps >= ROOT_ITERATIONS && self.found.is_none() {
            self.found = Some(match (self.above, self.below) {
                (Some(a), Some(b)) => 0.5 * (a.0 + b.0),
                (Some(_), None) => f64::INFINITY,
                _ => f64::NEG_INFINITY,
            });
        }
    }
}

/// Every root of `roots`, each integration `eval(q)` giving `P` at every root's `q` (roots
/// already found keep theirs).
pub(super) fn find_roots(mut roots: Vec<Root>, eval: impl Fn(&[f64]) -> Vec<f64>) -> Vec<Root> {
    loop {
        let qs: Vec<Option<f64>> = roots.iter_mut().map(Root::next).collect();
        if qs.iter().all(Option::is_none) {
            break;
        }
        let at: Vec<f64> = roots
            .iter()
            .zip(&qs)
            .map(|(r, q)| q.unwrap_or_else(|| r.found.filter(|f| f.is_finite()).unwrap_or(0.0)))
            .collect();
        let p = eval(&at);
        for ((root, q), p) in roots.iter_mut().zip(&qs).zip(p) {
            if let Some(q) = q {
                root.take(*q, p);
            }
        }
    }
    roots
}
