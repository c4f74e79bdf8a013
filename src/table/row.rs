//! A line of `tolerance.csv`: a statistic of one output at one speed by one method, with the
//! method's own fields in one enum ([`Detail`]), so that a row cannot carry another method's.

use super::method::Method;
use crate::output::{Missing, Output, Quantity};

/// One line of the result: a statistic of one output at one speed by one method.
#[derive(Debug, Clone)]
pub struct Row {
    pub speed: f64,
    pub quantity: Quantity,
    /// 0-based mode, `None` for the transfer magnitude.
    pub mode: Option<usize>,
    pub case: usize,
    /// NaN where the method gives no answer (an output not differentiable there).
    pub mean: f64,
    pub std: f64,
    /// Why the method gives no mean and σ here (`mean`, `std` are then NaN).
    pub missing: Option<Missing>,
    /// The method and what it gives besides the mean and σ.
    pub detail: Detail,
}

/// The method of a row and its own fields.
#[derive(Debug, Clone)]
pub enum Detail {
    /// First order, with each variable's share of the variance where it has a value.
    FirstOrder {
        shares: Option<Vec<f64>>,
    },
    SecondOrder,
    Invariant,
    /// The quadrature, with its quantiles and error estimates where it has a value.
    Quadrature(Option<QuadDetail>),
    MonteCarlo(McStat),
    /// The answer to read ([`Method::Analytic`]): the method its mean and σ come from
    /// (`None` where none gives one) and, where that is the quadrature, its fields.
    Analytic {
        basis: Option<Method>,
        quadrature: Option<QuadDetail>,
    },
}

/// What the quadrature gives of an output besides its mean and σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadDetail {
    /// The 5, 50 and 95 % quantiles.
    pub quantiles: [f64; 3],
    /// Error estimates of the mean and σ.
    pub errors: (f64, f64),
    /// Whether those error estimates meet the requested accuracy (see
    /// [`crate::quadrature::QuadStat::within_request`]).
    pub within_request: bool,
}

impl Detail {
    /// The method the row is of.
    pub fn method(&self) -> Method {
        match self {
            Detail::FirstOrder { .. } => Method::FirstOrder,
            Detail::SecondOrder => Method::SecondOrder,
            Detail::Invariant => Method::Invariant,
            Detail::Quadrature(_) => Method::Quadrature,
            Detail::MonteCarlo(_) => Method::MonteCarlo,
            Detail::Analytic { .. } => Method::Analytic,
        }
    }

    /// The quadrature's fields, of a quadrature row or an analytic row taken from it.
    pub fn quadrature(&self) -> Option<&QuadDetail> {
        match self {
            Detail::Quadrature(q) | Detail::Analytic { quadrature: q, .. } => q.as_ref(),
            _ => None,
        }
    }
}

impl Row {
    /// The row of output `o` at `speed` in case `case` by the method of `detail`, from the
    /// method's mean and σ or the reason it has none; a statistic that is not finite (an
    /// overflow on the way: a Hessian of 10³⁰⁰'s) gives no value, and says why.
    pub fn new(
        speed: f64,
        case: usize,
        o: &Output,
        stat: Result<(f64, f64), Missing>,
        detail: Detail,
    ) -> Row {
        let (mean, std, missing) = match stat {
            Ok((mean, std)) if mean.is_finite() && std.is_finite() => (mean, std, None),
            Ok(_) => (f64::NAN, f64::NAN, Some(Missing::NotFinite)),
            Err(e) => (f64::NAN, f64::NAN, Some(e)),
        };
        Row {
            speed,
            quantity: o.quantity,
            mode: o.mode,
            case,
            mean,
            std,
            missing,
            detail,
        }
    }

    pub fn method(&self) -> Method {
        self.detail.method()
    }

    /// The Monte Carlo's statistics (Monte Carlo rows).
    pub fn mc(&self) -> Option<McStat> {
        match self.detail {
            Detail::MonteCarlo(m) => Some(m),
            _ => None,
        }
    }

    /// Each variable's share of the variance (first-order rows with a value).
    pub fn shares(&self) -> Option<&[f64]> {
        match &self.detail {
            Detail::FirstOrder { shares } => shares.as_deref(),
            _ => None,
        }
    }

    /// For [`Method::Analytic`]: the method its mean and σ come from.
    pub fn basis(&self) -> Option<Method> {
        match self.detail {
            Detail::Analytic { basis, .. } => basis,
            _ => None,
        }
    }

    /// The 5, 50 and 95 % quantiles (quadrature, Monte Carlo).
    pub fn quantiles(&self) -> Option<[f64; 3]> {
        match &self.detail {
            Detail::MonteCarlo(m) => m.quantiles,
            d => d.quadrature().map(|q| q.quantiles),
        }
    }

    /// Error estimates of the mean and σ (quadrature).
    pub fn errors(&self) -> Option<(f64, f64)> {
        self.detail.quadrature().map(|q| q.errors)
    }

    /// Whether those error estimates meet the requested accuracy (quadrature).
    pub fn within_request(&self) -> Option<bool> {
        self.detail.quadrature().map(|q| q.within_request)
    }
}

/// The Monte Carlo's statistics of one output at one speed.
#[derive(Debug, Clone, Copy, Default)]
pub struct McStat {
    /// Samples that gave a value.
    pub n: usize,
    pub mean: f64,
    pub std: f64,
    pub mean_ci: (f64, f64),
    pub std_ci: (f64, f64),
    /// Samples where the point failed.
    pub failed: usize,
    /// Samples whose mode had another class than the nominal one.
    pub class_changed: usize,
    /// Samples whose output's mode was overdamped (ω_d and ζ rows; 0 for the transfer).
    pub overdamped: usize,
    /// Samples whose equilibrium was unstable.
    pub unstable: usize,
    /// Samples on another equilibrium branch than the nominal design (another number of
    /// branch switches since the lowest speed).
    pub other_branch: usize,
    /// The 5, 50 and 95 % sample quantiles (linear interpolation between order statistics),
    /// where the run kept the values (see [`crate::montecarlo::MonteCarlo::quantiles`]).
    pub quantiles: Option<[f64; 3]>,
}
