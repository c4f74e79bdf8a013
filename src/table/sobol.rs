//! A line of `sobol.csv`: the Sobol indices of one target (an output at one speed, a
//! requirement's worst margin) and one variable, with their intervals.

/// What an index is of: an output at one speed, or a requirement's worst margin over its
/// range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// `(speed index, output index)`.
    Output(usize, usize),
    /// Requirement index.
    Margin(usize),
}

impl Target {
    /// The target in words: `margin of NAME`, or `QUANTITY[ mode K] at SPEED rad/s` with the
    /// speed as `speed` writes it.
    pub fn describe(
        &self,
        requirements: &[crate::model::Requirement],
        speeds: &[f64],
        outputs: &[crate::output::Output],
        speed: impl Fn(f64) -> String,
    ) -> String {
        match *self {
            Target::Margin(r) => format!("margin of {}", requirements[r].name),
            Target::Output(i, o) => {
                let out = outputs[o];
                format!(
                    "{}{} at {} rad/s",
                    out.quantity.as_str(),
                    out.mode
                        .map_or(String::new(), |m| format!(" mode {}", m + 1)),
                    speed(speeds[i])
                )
            }
        }
    }
}

/// The indices of one target and one variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SobolIndex {
    pub target: Target,
    /// Index into the study's variables.
    pub variable: usize,
    pub first: f64,
    pub first_ci: (f64, f64),
    pub total: f64,
    pub total_ci: (f64, f64),
    /// The derivative-based upper bound on the total index (outputs only; `None` where a
    /// derivative is missing).
    pub bound: Option<f64>,
    /// Rows used (designs with a value in `A`, `B` and `A_B^(i)`).
    pub rows: usize,
}
