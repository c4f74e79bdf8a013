//! A line of `probabilities.csv`: the probability of a change of character (an overdamped
//! mode, an unstable equilibrium, another branch) at one speed by one method.

use super::method::Method;

/// Probability of a change of character at one speed, by one method.
#[derive(Debug, Clone)]
pub struct ProbabilityRow {
    pub speed: f64,
    pub case: usize,
    /// [`Method::Quadrature`] or [`Method::MonteCarlo`].
    pub method: Method,
    pub event: Event,
    /// 0-based mode (overdamped only).
    pub mode: Option<usize>,
    pub probability: f64,
    /// Quadrature: probability ± its error estimate (clamped to [0, 1]); Monte Carlo: the
    /// 95 % Wilson score interval.
    pub ci: (f64, f64),
}

/// A change of character whose probability is reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The mode's roots are real (and not unstable).
    Overdamped,
    /// The equilibrium is unstable (a root with positive real part).
    Unstable,
    /// The design is on another equilibrium branch than the nominal one at this speed.
    OtherBranch,
}

impl Event {
    pub fn as_str(self) -> &'static str {
        match self {
            Event::Overdamped => "overdamped",
            Event::Unstable => "unstable",
            Event::OtherBranch => "other_branch",
        }
    }
}

/// The 95 % Wilson score interval of `k` successes in `n > 0` trials, as the probabilities
/// have computed it (without [`super::yield_row::wilson`]'s exact ends).
pub fn wilson_unguarded(k: usize, n: usize) -> (f64, f64) {
    let z = 1.959_963_984_540_054;
    let (n, p) = (n as f64, k as f64 / n as f64);
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}
