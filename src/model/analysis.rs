//! The `[analysis]` table: speeds, tolerances and their cases, sampling, the transfer
//! function.

/// A tolerance on a design variable, as written (`"3%"` or an absolute value in the
/// parameter's unit). By default it is read as ±3σ of a normal distribution.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Tolerance {
    /// Fraction of the nominal value (0.03 for "3%").
    Relative(f64),
    /// Absolute value in the parameter's unit.
    Absolute(f64),
}

impl Tolerance {
    /// The tolerance as an absolute half-width around `nominal`.
    pub fn absolute(&self, nominal: f64) -> f64 {
        match *self {
            Tolerance::Relative(f) => f * nominal.abs(),
            Tolerance::Absolute(a) => a,
        }
    }
}

/// Distribution of a toleranced variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    /// Normal, tolerance = ±3σ.
    Normal,
    /// Uniform on ±tolerance.
    Uniform,
}

/// Inclusive range of speeds `from:to:step` (rad/s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SpeedRange {
    pub from: f64,
    pub to: f64,
    pub step: f64,
}

impl SpeedRange {
    /// Parses `FROM:TO:STEP` (rad/s); `TO` is included when it lies on the grid.
    pub fn parse(s: &str) -> Result<SpeedRange, String> {
        let parts: Vec<&str> = s.split(':').collect();
        if parts.len() != 3 {
            return Err(format!("'{s}' is not FROM:TO:STEP"));
        }
        let num = |x: &str, what: &str| -> Result<f64, String> {
            let v: f64 = x
                .trim()
                .parse()
                .map_err(|_| format!("{what} '{x}' in '{s}' is not a number"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("{what} in '{s}' is not finite"))
            }
        };
        let r = SpeedRange {
            from: num(parts[0], "FROM")?,
            to: num(parts[1], "TO")?,
            step: num(parts[2], "STEP")?,
        };
        if r.step <= 0.0 {
            return Err(format!("STEP in '{s}' must be positive"));
        }
        if r.to < r.from {
            return Err(format!("TO is below FROM in '{s}'"));
        }
        if (r.to - r.from) / r.step > 1e9 {
            return Err(format!("'{s}' has more than 10^9 points"));
        }
        Ok(r)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        ((self.to - self.from) / self.step + 1e-9).floor() as usize + 1
    }

    /// Always false: a range has at least its first point.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The `i`-th speed, `from + i·step`, as the grid point it is: where `from` and `step`
    /// are decimals of at most 15 places (`0:5:0.05`), the double nearest to the decimal
    /// `from + i·step` (so that `1.9` prints as `1.9`, not `1.9000000000000001`), computed
    /// exactly in integers and rounded once; else `from + i·step` (no accumulated rounding).
    pub fn at(&self, i: usize) -> f64 {
        self.at_on(self.decimal(), i)
    }

    /// [`SpeedRange::at`] with the grid's decimal form already found.
    fn at_on(&self, decimal: Option<(f64, f64, f64)>, i: usize) -> f64 {
        match decimal {
            Some((f, s, scale)) => {
                let n = f + i as f64 * s;
                if n.abs() < 2f64.powi(53) {
                    n / scale
                } else {
                    self.from + i as f64 * self.step
                }
            }
            None => self.from + i as f64 * self.step,
        }
    }

    /// `(from·10^k, step·10^k, 10^k)` with integers for the smallest `k ≤ 15` at which
    /// `from` and `step` are decimals of `k` places, `None` where they are not.
    fn decimal(&self) -> Option<(f64, f64, f64)> {
        (0..=15).find_map(|k| {
            let scale = 10f64.powi(k);
            let exact = |x: f64| {
                let n = (x * scale).round();
                (n.abs() < 2f64.powi(53) && (n / scale).to_bits() == x.to_bits()).then_some(n)
            };
            Some((exact(self.from)?, exact(self.step)?, scale))
        })
    }

    /// All speeds.
    pub fn speeds(&self) -> impl Iterator<Item = f64> + '_ {
        let decimal = self.decimal();
        (0..self.len()).map(move |i| self.at_on(decimal, i))
    }
}

/// Monte Carlo sampling schemes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampling {
    Random,
    Lhs,
    Sobol,
}

impl Sampling {
    /// Every scheme, in the order they are listed to users.
    pub const ALL: [Sampling; 3] = [Sampling::Random, Sampling::Lhs, Sampling::Sobol];

    /// Name in the model file, on the command line and in Python (as serde writes it).
    pub fn name(self) -> &'static str {
        match self {
            Sampling::Random => "random",
            Sampling::Lhs => "lhs",
            Sampling::Sobol => "sobol",
        }
    }

    /// The scheme named `name`, or `None`.
    pub fn named(name: &str) -> Option<Sampling> {
        Sampling::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The names, for a message: `random, lhs or sobol` (`quoted`: `"random", "lhs" or
    /// "sobol"`).
    pub fn names(quoted: bool) -> String {
        let names: Vec<String> = (Sampling::ALL.iter())
            .map(|s| match quoted {
                true => format!("{:?}", s.name()),
                false => s.name().to_string(),
            })
            .collect();
        let (last, rest) = names.split_last().expect("schemes");
        format!("{} or {last}", rest.join(", "))
    }
}

/// One end of a transfer function: where the excitation enters or the response is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Channel {
    /// A free joint coordinate: a generalised force on it in, its value out.
    Coordinate(usize),
    /// A [`crate::model::Port`] (index into [`crate::model::Model::ports`]): a force or torque in, a displacement or
    /// rotation out.
    Port(usize),
    /// An [`crate::model::Unbalance`] (index into [`crate::model::Model::unbalances`]): its
    /// rotating force in (an input only); `H` is then the response itself, not per unit load.
    Unbalance(usize),
}

/// A transfer function `H(jω)` from `input` to `output` at the excitation frequency
/// `order × speed`.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Transfer {
    pub input: Channel,
    pub output: Channel,
    pub order: f64,
}

/// A correlation matrix between parameters (rows and columns in the order of `params`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Correlation {
    pub params: Vec<usize>,
    pub matrix: Vec<Vec<f64>>,
}

/// A named tolerance case: per-parameter tolerances and optional correlations.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Case {
    pub name: String,
    pub tolerances: Vec<(usize, Tolerance)>,
    pub correlation: Option<Correlation>,
}

/// The `[analysis]` table: what the model's author wants analysed by default.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Analysis {
    pub speed: Option<SpeedRange>,
    pub transfer: Option<Transfer>,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    pub cases: Vec<Case>,
}
