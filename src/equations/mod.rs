//! The equations of one operating point, whichever way they are evaluated: the one interface
//! the equilibrium solve, the linearisation, the sensitivities and the Hessians use.
//!
//! A model's equilibrium equations at fixed parameters and speed,
//!
//! ```text
//! F(q_R, λ) = [ r_R(q, q̇ = [Ω; 0], q̈ = 0) + Φ_Rᵀ λ ;  Φ(q) ]
//! ```
//!
//! with Newton's Jacobian `∂F/∂[q_R; λ] = [K Φ_Rᵀ; Φ_R 0]` and the rates `∂r_R/∂q̇_R`,
//! `∂r_R/∂q̈_R`, can be evaluated two ways that give the same numbers: directly, by the generic
//! mechanics over the caller's scalar ([`Direct`]), or through the model's recorded program
//! ([`crate::program`]), which is faster. Both implement [`Equations`] over any [`Real`]
//! (dual numbers seeded in the parameters give the derivatives with respect to them), so the
//! computations above are written once and never choose between them:
//! [`crate::compiled::Compiled::at`] makes the choice, once per model.

mod direct;

pub use direct::Direct;

use crate::linearize::{Linearization, LinearizeError};
use crate::real::Real;
use nalgebra::{DMatrix, DVector};

/// `∂r_R/∂q̇_R` and `∂r_R/∂q̈_R`: the linearisation's damping and mass matrices before
/// reduction, over the free coordinates.
#[derive(Debug, Clone)]
pub struct Rates<S: Real = f64> {
    /// `∂r_R/∂q̇_R`.
    pub damping: DMatrix<S>,
    /// `∂r_R/∂q̈_R`.
    pub mass: DMatrix<S>,
}

/// The equations evaluated at one point `(q, λ)`: what Newton's method needs, and, where the
/// route has them from the same pass, what the linearisation needs besides.
#[derive(Debug, Clone)]
pub struct Evaluation<S: Real = f64> {
    /// `F`.
    pub residual: Vec<S>,
    /// `∂F/∂[q_R; λ]`.
    pub jacobian: DMatrix<S>,
    /// The [`Rates`], on the recorded route.
    pub rates: Option<Rates<S>>,
    /// The driven coordinates' rows of `r + Φ_qᵀλ` (the drive forces), on the recorded route
    /// and when asked for.
    pub drive: Option<Vec<S>>,
}

/// `F` and the linearisation's full matrices along [`probe_directions`] at one point:
/// what [`Equations::probe_linearisation`] returns.
#[derive(Debug, Clone)]
pub struct Probed<S: Real = f64> {
    /// `F`.
    pub residual: Vec<S>,
    /// `K v`, `C w`, `M u` for the directions `[v, w, u]` (`K` with `λ` held).
    pub products: [Vec<S>; 3],
    /// `Φ_R` (constraint equations × free coordinates).
    pub phi: DMatrix<S>,
}

/// Three fixed directions over `n` free coordinates, `[v, w, u]`, along which
/// [`Equations::probe_linearisation`] multiplies `K`, `C` and `M`: entries of size ½ to 1 with
/// a sign, from SplitMix64 (Steele, Lea & Flood, OOPSLA 2014) over the direction and the
/// entry's index, so that no structure of a model lines up with them and every run is the
/// same.
pub fn probe_directions(n: usize) -> [Vec<f64>; 3] {
    [1u64, 2, 3].map(|seed| {
        (0..n as u64)
            .map(|i| {
                let mut z = (seed << 32 ^ i).wrapping_add(0x9E37_79B9_7F4A_7C15);
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                let size = 0.5 + 0.5 * (z >> 11) as f64 / (1u64 << 53) as f64;
                if z & 1 == 0 { size } else { -size }
            })
            .collect()
    })
}

/// How the multipliers of an unconverged point are fitted: from `Φ_Rᵀ` (free coordinates ×
/// constraint equations) and `−r_R`, the `λ` of `Φ_Rᵀ λ ≈ −r_R` (Newton passes a least-squares
/// solve).
pub type Fit<'a, S> = &'a dyn Fn(DMatrix<S>, DVector<S>) -> Vec<S>;

/// The equilibrium equations and the linearisation of a model at fixed parameters and speed,
/// over the scalar `S` (see the module documentation).
pub trait Equations<S: Real> {
    /// The free coordinates (indices), the unknowns `q_R`.
    fn free(&self) -> &[usize];

    /// Number of constraint equations (and multipliers).
    fn constraints(&self) -> usize;

    /// `F(q_R, λ)` at the coordinates `q` (all of them).
    fn residual(&self, q: &[S], lambda: &[S]) -> Vec<S>;

    /// `F` and its Jacobian with respect to the unknowns `x = [q_R; λ]`.
    fn residual_and_jacobian(&self, q: &[S], lambda: &[S]) -> (Vec<S>, DMatrix<S>);

    /// `F`, its exact Jacobian and, where the route has them from the same pass, the
    /// [`Rates`] and (with `drive`) the drive rows: everything the linearisation needs, so
    /// that a solve whose last Newton step is below the tolerance needs no further evaluation.
    fn evaluate(&self, q: &[S], lambda: &[S], drive: bool) -> Evaluation<S> {
        let _ = drive;
        let (residual, jacobian) = self.residual_and_jacobian(q, lambda);
        Evaluation {
            residual,
            jacobian,
            rates: None,
            drive: None,
        }
    }

    /// [`Equations::evaluate`] at `q` with the multipliers `fit` gives there, and those
    /// multipliers.
    fn evaluate_fitted(&self, q: &[S], drive: bool, fit: Fit<'_, S>) -> (Vec<S>, Evaluation<S>);

    /// The rows `driven` of `r + Φ_qᵀλ` (with `q̇` at steady state, `q̈ = 0`): the drive forces.
    fn drive_rows(&self, q: &[S], lambda: &[S], driven: &[usize]) -> Vec<S>;

    /// The largest `|F|` at each of the configurations the driven coordinates pass through
    /// in time: `q_c + rate · offsets[l]` for each `(d, c, rate)` of `shift` (`c` the `d`-th
    /// driven coordinate, `rate` its speed over the fastest's), the rest as given.
    fn residual_at_drive_offsets(
        &self,
        q: &[S],
        lambda: &[S],
        shift: &[(usize, usize, f64)],
        offsets: [f64; 3],
    ) -> [f64; 3] {
        residual_at_shifts(self, q, lambda, shift, offsets)
    }

    /// `Φ_R` (constraint equations × free coordinates) at `q`.
    fn constraint_jacobian(&self, q: &[S]) -> DMatrix<S>;

    /// The linearisation at `(q, λ)` reduced to the `independent` coordinates; `stiffness`,
    /// when known, is the tangent stiffness `∂(r_R + Φ_Rᵀλ)/∂q_R` there (Newton's Jacobian
    /// block), which a route may reuse.
    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError>;

    /// `F` at `(q, λ)`, the linearisation's full matrices there along [`probe_directions`]
    /// `[v, w, u]` (over the free coordinates), `[K v, C w, M u]`, and `Φ_R`. By default from
    /// [`Equations::residual`] and [`Equations::linearize`] (the `independent` coordinates
    /// choose its basis, not used here); a route may differentiate its equations along the
    /// three directions at once instead of along every coordinate.
    fn probe_linearisation(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
    ) -> Result<Probed<S>, LinearizeError> {
        let lin = self.linearize(q, lambda, independent, None)?;
        let times = |a: &DMatrix<S>, x: &[f64]| -> Vec<S> {
            (0..a.nrows())
                .map(|r| (0..a.ncols()).fold(S::from(0.0), |s, c| s + a[(r, c)] * S::from(x[c])))
                .collect()
        };
        let [v, w, u] = probe_directions(self.free().len());
        Ok(Probed {
            residual: self.residual(q, lambda),
            products: [
                times(&lin.k_full, &v),
                times(&lin.c_full, &w),
                times(&lin.m_full, &u),
            ],
            phi: lin.phi,
        })
    }
}

/// [`Equations::residual_at_drive_offsets`] by one evaluation of `F` per offset.
pub fn residual_at_shifts<S: Real, E: Equations<S> + ?Sized>(
    equations: &E,
    q: &[S],
    lambda: &[S],
    shift: &[(usize, usize, f64)],
    offsets: [f64; 3],
) -> [f64; 3] {
    let mut qo = q.to_vec();
    offsets.map(|offset| {
        for &(_, c, rate) in shift {
            qo[c] = q[c] + S::from(rate * offset);
        }
        let f = equations.residual(&qo, lambda);
        f.iter().fold(0.0f64, |a, v| a.max(v.re().abs()))
    })
}
