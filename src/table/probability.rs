//! A line of `probabilities.csv`: the probability of a change of character (an overdamped
//! mode, an unstable equilibrium, another branch) at one speed by one method, and the Wilson
//! interval of a probability counted in samples (here and in the yield).

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

/// The 95 % Wilson score interval of `k` successes in `n` trials.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054;
    let (none, all) = (k == 0, k == n);
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    // At k = 0 and k = n the ends are 0 and 1 exactly (rounding would leave 10⁻¹⁹).
    (
        if none { 0.0 } else { (c - h).max(0.0) },
        if all { 1.0 } else { (c + h).min(1.0) },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_its_closed_form() {
        // 81 of 100: the textbook interval [0.7222, 0.8749].
        let (lo, hi) = wilson(81, 100);
        assert!(
            (lo - 0.722_2).abs() < 1e-4 && (hi - 0.874_9).abs() < 1e-4,
            "{lo} {hi}"
        );
        // All pass: the upper end is 1, the lower end n/(n + z²); none pass: the lower end 0.
        let (lo, hi) = wilson(50, 50);
        assert!(hi.to_bits() == 1f64.to_bits());
        assert!(wilson(0, 50).0.to_bits() == 0f64.to_bits());
        assert!((lo - 50.0 / (50.0 + 1.959_963_984_540_054f64.powi(2))).abs() < 1e-12);
    }
}
