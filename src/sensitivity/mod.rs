//! Exact sensitivities of the damped modes and transfer functions with respect to design
//! variables, carried through the move of the equilibrium (Kim & Yoo 2007, eqs. 24–27, done with
//! automatic differentiation instead of finite differences, and for non-symmetric systems).
//!
//! For each design variable `b`:
//!
//! 1. equilibrium shift by the implicit function theorem on `F(x, b) = 0`, `x = [q_R; λ]`:
//!    `dx/db = −F_x⁻¹ ∂F/∂b` (`F_x` is Newton's Jacobian at the solution, `∂F/∂b` one dual pass);
//! 2. `M̂', Ĉ', K̂'` from the linearisation evaluated over dual numbers seeded along
//!    `(b, dq*/db, dλ/db)`, which includes the change of the independent-coordinate basis `R`;
//! 3. eigenvalue derivative with right and left vectors (`yᵀ(λ²M̂ + λĈ + K̂) = 0`):
//!
//!    ```text
//!    dλ/db = − yᵀ (λ² M̂' + λ Ĉ' + K̂') x / ( yᵀ (2λ M̂ + Ĉ) x )
//!    ```
//!
//!    then `dω_d = Im dλ` (root with `Im λ > 0`), `dω_n`, `dζ` from the pair invariants
//!    `λ₁λ₂` and `λ₁+λ₂`;
//! 4. `H(jω)` evaluated over the same dual numbers: `d|H| = Re(H̄ dH)/|H|`.
//!
//! Where roots coalesce (a mode changing between underdamped and overdamped) the derivative of
//! ω_d does not exist, nor those of a root repeated in two modes or of a rigid-body mode; such
//! entries carry [`Status::NotDifferentiable`] instead of a number
//! ([`crate::modal::smoothness`] says why).
//! [`DesignPoint::finite_difference`] re-runs the whole pipeline at perturbed values as a
//! cross-check.
//!
//! Every derivative at a point is a method of [`DesignPoint`]: the compiled model, the design's
//! parameters, its solved point, the transfer function asked there and the working memory
//! lent for the passes, given once (after faer's parameter structs) rather than threaded
//! through each call. [`crate::hessian`] and [`crate::tolerance`] add the second derivatives and
//! the local model as methods of the same context.
//!
//! # Reference
//! Kim, Yoo (2007) eq. 24; Adhikari, *Rates of change of eigenvalues and eigenvectors in damped
//! dynamic systems*, AIAA J. 37 (1999).

mod analytic;
mod finite;
mod roots;
mod shift;

pub use roots::eigenvalue_derivative;
pub(crate) use roots::{RootDerivatives, mode_derivative};

use crate::compiled::Compiled;
use crate::frf::{Complex, transfer};
use crate::linearize::Linearization;
use crate::model::{Channel, Transfer};
use crate::program::Workspace;
use crate::sweep::{Point, PointError};
use num_dual::Dual64;

/// Whether a derivative exists at this point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Ok,
    /// Roots coalescing or the mode changing class: ω_d (and ζ) are not differentiable here.
    NotDifferentiable,
}

/// Derivatives of one mode with respect to one design variable.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ModeSensitivity {
    pub status: Status,
    pub d_eigen_re: f64,
    pub d_eigen_im: f64,
    pub d_damped_frequency: f64,
    pub d_natural_frequency: f64,
    pub d_damping_ratio: f64,
    /// Derivatives of the pair invariants `λ₁ + λ₂` and `λ₁ λ₂`, smooth even where the roots
    /// coalesce (for one degree of freedom they are `−ĉ/m̂` and `k̂/m̂`, taken from the matrices).
    pub d_sum: f64,
    pub d_product: f64,
}

/// Derivatives with respect to one design variable.
#[derive(Debug, Clone, serde::Serialize)]
pub struct VariableSensitivity {
    /// Parameter index.
    pub param: usize,
    pub modes: Vec<ModeSensitivity>,
    /// d|H|/db and d(arg H)/db, when a transfer function was asked for and the derivative
    /// exists (`None` where `H` passes through zero).
    pub d_transfer_magnitude: Option<f64>,
    pub d_transfer_phase: Option<f64>,
    /// dq*/db for every coordinate.
    pub d_equilibrium: Vec<f64>,
}

/// All sensitivities at one point.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sensitivity {
    /// Nominal |H| and arg H at the excitation frequency.
    pub transfer_magnitude: Option<f64>,
    pub transfer_phase: Option<f64>,
    pub variables: Vec<VariableSensitivity>,
}

/// A transfer function request: coordinates and excitation frequency (rad/s).
#[derive(Debug, Clone, Copy)]
pub struct TransferAt {
    pub input: Channel,
    pub output: Channel,
    pub omega: f64,
}

impl TransferAt {
    /// The model's transfer spec at `speed` (excitation `order × speed`).
    pub fn at_speed(t: &Transfer, speed: f64) -> Self {
        TransferAt {
            input: t.input,
            output: t.output,
            omega: t.order * speed,
        }
    }
}

/// A design at one operating point with what its derivatives need: the compiled model, the
/// design's parameters, its solved point, the transfer function asked there (if any) and the
/// working memory the recorded program's passes use (a fresh one where none is lent).
#[derive(Clone, Copy)]
pub struct DesignPoint<'a> {
    pub model: &'a Compiled,
    /// The design's parameters (every parameter of the model).
    pub p: &'a [f64],
    /// The solved point at these parameters.
    pub point: &'a Point,
    /// The transfer function whose derivatives are asked, at its excitation frequency.
    pub transfer: Option<TransferAt>,
    workspace: Option<&'a Workspace>,
}

impl<'a> DesignPoint<'a> {
    /// The design of parameters `p` at its solved `point`, without a transfer function.
    pub fn new(model: &'a Compiled, p: &'a [f64], point: &'a Point) -> Self {
        DesignPoint {
            model,
            p,
            point,
            transfer: None,
            workspace: None,
        }
    }

    /// With the transfer function `transfer` at its excitation frequency.
    pub fn with_transfer(self, transfer: Option<TransferAt>) -> Self {
        DesignPoint { transfer, ..self }
    }

    /// With the model's transfer function (`[analysis] transfer`) at the point's speed.
    pub fn with_model_transfer(self, transfer: Option<&Transfer>) -> Self {
        let speed = self.point.speed;
        self.with_transfer(transfer.map(|t| TransferAt::at_speed(t, speed)))
    }

    /// With `workspace` lent for the passes (one per thread).
    pub fn with_workspace(self, workspace: &'a Workspace) -> Self {
        DesignPoint {
            workspace: Some(workspace),
            ..self
        }
    }

    /// The workspace lent, or a fresh one.
    pub(crate) fn workspace(&self) -> Lent<'a> {
        match self.workspace {
            Some(w) => Lent::Borrowed(w),
            None => Lent::Own(Box::default()),
        }
    }

    /// The sensitivities of the point to the design variables `wrt`, computed `how`.
    pub fn sensitivities(
        &self,
        wrt: &[usize],
        how: Derivatives,
    ) -> Result<Sensitivity, PointError> {
        match how {
            Derivatives::Exact => self.analytic(wrt),
            Derivatives::FiniteDifference => self.finite_difference(wrt),
        }
    }

    /// The frequency response from `input` to `output` over `frequencies`, with the exact
    /// derivatives of |H| with respect to the design variables `wrt`.
    pub fn frequency_response(
        &self,
        (input, output): (Channel, Channel),
        wrt: &[usize],
        frequencies: impl Iterator<Item = f64>,
    ) -> Result<Vec<ResponseRow>, PointError> {
        let duals = self.dual_linearizations(wrt)?;
        Ok(frequencies
            .map(|f| ResponseRow {
                frequency: f,
                h: transfer(&self.point.linear, input, output, f),
                d_magnitude: duals
                    .iter()
                    .map(|d| {
                        transfer(&d.linear, input, output, f)
                            .and_then(|h| transfer_derivative(&h).0)
                    })
                    .collect(),
            })
            .collect())
    }
}

/// The working memory of a [`DesignPoint`]'s passes: the caller's, or its own.
pub(crate) enum Lent<'a> {
    Borrowed(&'a Workspace),
    Own(Box<Workspace>),
}

impl std::ops::Deref for Lent<'_> {
    type Target = Workspace;

    fn deref(&self) -> &Workspace {
        match self {
            Lent::Borrowed(w) => w,
            Lent::Own(w) => w,
        }
    }
}

/// Nominal |H| and arg H at a point.
pub fn nominal_transfer(pt: &Point, t: &TransferAt) -> Option<Complex<f64>> {
    transfer(&pt.linear, t.input, t.output, t.omega)
}

/// The linearisation over dual numbers seeded along one design variable, with the equilibrium
/// shift `dq*/db` (all coordinates).
pub struct DualLinearization {
    pub param: usize,
    pub linear: Linearization<Dual64>,
    pub d_equilibrium: Vec<f64>,
}

/// How derivatives are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Derivatives {
    /// Exact, by automatic differentiation through the equilibrium
    /// ([`DesignPoint::analytic`]).
    #[default]
    Exact,
    /// Central finite differences of the whole pipeline, Richardson-extrapolated
    /// ([`DesignPoint::finite_difference`], a cross-check).
    FiniteDifference,
}

/// One excitation frequency of a frequency response: `H` and `d|H|/db` for each design
/// variable (`None` where undefined: an undamped resonance, or `H` passing through zero).
#[derive(Debug, Clone)]
pub struct ResponseRow {
    /// Excitation frequency (rad/s).
    pub frequency: f64,
    pub h: Option<Complex<f64>>,
    pub d_magnitude: Vec<Option<f64>>,
}

/// d|H|/db and d(arg H)/db from `H` over dual numbers; `None` where the derivative does not
/// exist (`H` passing through zero).
pub fn transfer_derivative(h: &Complex<Dual64>) -> (Option<f64>, Option<f64>) {
    let mag = h.magnitude();
    if mag.re > 0.0 {
        (
            Some(mag.eps).filter(|v| v.is_finite()),
            Some(h.phase().eps).filter(|v| v.is_finite()),
        )
    } else if h.re.eps == 0.0 && h.im.eps == 0.0 {
        // H ≡ 0 to first order: |H| = o(Δb), its derivative is 0; the phase is undefined.
        (Some(0.0), None)
    } else {
        (None, None)
    }
}
