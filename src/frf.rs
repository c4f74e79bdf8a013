//! Transfer functions of the linearised system.
//!
//! ```text
//! H(jω) = R (K̂ − ω² M̂ + jω Ĉ)⁻¹ Rᵀ
//! ```
//!
//! maps a generalised force on one free coordinate to the response of another (independent of
//! the choice of basis `R`); between physical points ([`crate::mechanics::ports`]) the force
//! and response vectors `b` take the place of the unit vectors. For one degree of freedom this is Kim & Yoo (2007) eq. 25. The
//! complex solve is done as the real block system `[A −B; B A]`, `A = K̂ − ω²M̂`, `B = ωĈ`, over
//! any [`Real`], so the same function gives `H` and its exact derivatives (including the move of
//! the equilibrium and of the basis `R`).

use crate::linalg::solve;
use crate::linearize::Linearization;
use crate::model::Channel;
use crate::real::{Real, cst, re};
use nalgebra::DMatrix;

/// A complex value over `T`.
#[derive(Debug, Clone, Copy)]
pub struct Complex<T> {
    pub re: T,
    pub im: T,
}

impl<T: Real> Complex<T> {
    /// |H|.
    pub fn magnitude(&self) -> T {
        (self.re * self.re + self.im * self.im).sqrt()
    }
    /// arg H (rad).
    pub fn phase(&self) -> T {
        self.im.atan2(self.re)
    }
}

/// `H(jω)` from `input` to `output`: a generalised force on a free coordinate or a force or
/// torque at a port in, the coordinate's value or the port's displacement or rotation out
/// (`b_outᵀ R (K̂ − ω² M̂ + jω Ĉ)⁻¹ Rᵀ b_in`, with `b` a unit vector for a coordinate and the
/// port's vector otherwise). An unbalance in gives the response itself: its load `Ω² f` at its
/// body's spin rate `Ω` (the excitation frequency in place of `omega`, which may move with the
/// parameters, and does so exactly here). `None` when a coordinate is not free, the
/// linearisation has no vectors for the ports, an unbalance is an output, or the dynamic
/// stiffness is singular (undamped resonance).
pub fn transfer<T: Real>(
    lin: &Linearization<T>,
    input: Channel,
    output: Channel,
    omega: f64,
) -> Option<Complex<T>> {
    transfer_at(lin, input, output, cst::<T>(omega))
}

/// [`transfer`] at an excitation frequency `omega` over `T`: where it moves with what `T`
/// differentiates along (`order × speed`, with the speed a jet, [`crate::peaks`]).
pub fn transfer_at<T: Real>(
    lin: &Linearization<T>,
    input: Channel,
    output: Channel,
    omega: T,
) -> Option<Complex<T>> {
    let zero = cst::<T>(0.0);
    let Loads {
        output: bo,
        re: bi,
        im: bi_im,
        omega: w,
    } = loads(lin, input, output, omega)?;
    let n = lin.m.nrows();
    let mut z = DMatrix::from_element(2 * n, 2 * n, zero);
    for r in 0..n {
        for c in 0..n {
            let a = lin.k[(r, c)] - w * w * lin.m[(r, c)];
            let b = w * lin.c[(r, c)];
            z[(r, c)] = a;
            z[(r + n, c + n)] = a;
            z[(r, c + n)] = -b;
            z[(r + n, c)] = b;
        }
    }
    let mut rhs = DMatrix::from_element(2 * n, 1, zero);
    for k in 0..n {
        rhs[(k, 0)] = bi[k];
        rhs[(k + n, 0)] = bi_im[k];
    }
    let load: Vec<T> = bi.iter().chain(&bi_im).copied().collect();
    let x = solve(&z, &rhs)?;
    if !resolved(lin, re(w), &load, &x) {
        return None;
    }
    let (mut hr, mut hi) = (zero, zero);
    for k in 0..n {
        hr += bo[k] * x[(k, 0)];
        hi += bo[k] * x[(k + n, 0)];
    }
    Some(Complex { re: hr, im: hi })
}

/// What a transfer function contracts, in the linearisation's reduced coordinates: the
/// output's vector, the load's real and imaginary parts and the excitation's frequency.
pub struct Loads<T> {
    pub output: Vec<T>,
    pub re: Vec<T>,
    pub im: Vec<T>,
    pub omega: T,
}

/// The [`Loads`] of the transfer function from `input` to `output` excited at `omega` (an
/// unbalance's at its spin rate, `Ω² f`); `None` where [`transfer`] has none for want of them.
pub fn loads<T: Real>(
    lin: &Linearization<T>,
    input: Channel,
    output: Channel,
    omega: T,
) -> Option<Loads<T>> {
    let reduced = |c: Channel| -> Option<Vec<T>> {
        match c {
            Channel::Coordinate(c) => {
                let i = lin.free.iter().position(|&f| f == c)?;
                Some(lin.basis.row(i).iter().copied().collect())
            }
            Channel::Port(k) => lin.ports.get(k).cloned(),
            Channel::Unbalance(_) => None,
        }
    };
    let bo = reduced(output)?;
    let (re, im, omega) = match input {
        Channel::Unbalance(k) => {
            let u = lin.unbalances.get(k)?;
            let s2 = u.spin * u.spin;
            let scale = |v: &[T]| v.iter().map(|&x| x * s2).collect::<Vec<T>>();
            (scale(&u.re), scale(&u.im), u.spin)
        }
        c => (reduced(c)?, vec![cst::<T>(0.0); bo.len()], omega),
    };
    Some(Loads {
        output: bo,
        re,
        im,
        omega,
    })
}

/// The frequency (rad/s) at which `input` excites: `omega`, or an unbalance's spin rate.
pub fn excitation<T: Real>(lin: &Linearization<T>, input: Channel, omega: f64) -> f64 {
    match input {
        Channel::Unbalance(k) => lin.unbalances.get(k).map_or(omega, |u| re(u.spin)),
        _ => omega,
    }
}

/// The relative accuracy below which `H` is not given: a response `x = Z⁻¹b` that large is
/// decided by the rounding of the dynamic stiffness `Z`, not by the mechanism.
pub const RESOLUTION: f64 = 1e-6;

/// Is the response `x` to the load `b` resolved by the dynamic stiffness at `omega`, or is `Z`
/// singular to working precision (an undamped mode at the excitation frequency, up to the
/// rounding of its frequency)? `Z`'s entries carry rounding errors of about `ε·S`, with `S`
/// the largest row sum of `|K̂| + ω²|M̂| + ω|Ĉ|` taken before the cancellation that makes a
/// resonance; they move `x` relatively by about `‖Z⁻¹‖·ε·S ≥ ‖x‖/‖b‖·ε·S` (Higham, *Accuracy
/// and Stability of Numerical Algorithms*, 2nd ed., §7.2). Where that exceeds [`RESOLUTION`],
/// |H| has no reliable digits: a resonance is exact (infinite) or beyond the precision of the
/// model's numbers, so a step of one ulp in the speed cannot turn it into a finite 10¹⁴.
fn resolved<T: Real>(lin: &Linearization<T>, omega: f64, b: &[T], x: &DMatrix<T>) -> bool {
    let n = lin.m.nrows();
    let scale = (0..n)
        .map(|r| {
            (0..n)
                .map(|c| {
                    re(lin.k[(r, c)]).abs()
                        + omega * omega * re(lin.m[(r, c)]).abs()
                        + omega.abs() * re(lin.c[(r, c)]).abs()
                })
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    let load = b.iter().fold(0.0f64, |s, v| s.max(re(*v).abs()));
    let response = x.iter().fold(0.0f64, |s, v| s.max(re(*v).abs()));
    response * f64::EPSILON * scale <= RESOLUTION * load
}

/// Why `H(jω)` has no finite value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoTransfer {
    /// The dynamic stiffness `K̂ − ω²M̂ + jωĈ` is singular, or singular to working precision
    /// ([`RESOLUTION`]): an undamped mode at the excitation frequency; |H| is infinite or
    /// beyond what the model's numbers resolve.
    Resonance,
    /// A number on the way (`ω²M̂`, `ωĈ`, or |H| itself) is beyond floating point.
    Overflow,
}

impl NoTransfer {
    /// What an output's message says.
    pub fn message(self) -> &'static str {
        match self {
            NoTransfer::Resonance => {
                "resonance: |H| is infinite or unresolved (an undamped mode at the excitation \
                 frequency, to working precision)"
            }
            NoTransfer::Overflow => {
                "overflow: |H| or the dynamic stiffness at this frequency is beyond floating point"
            }
        }
    }
}

/// Why the transfer value `h` computed at `omega` from `lin` ([`transfer`]) is not a finite
/// number; `None` where it is one (|H|, arg H and both parts finite).
pub fn transfer_defect(
    lin: &Linearization<f64>,
    omega: f64,
    h: Option<&Complex<f64>>,
) -> Option<NoTransfer> {
    if let Some(h) = h
        && [h.re, h.im, h.magnitude(), h.phase()]
            .iter()
            .all(|v| v.is_finite())
    {
        return None;
    }
    let stiffness_finite = (0..lin.m.nrows()).all(|r| {
        (0..lin.m.ncols()).all(|c| {
            (lin.k[(r, c)] - omega * omega * lin.m[(r, c)]).is_finite()
                && (omega * lin.c[(r, c)]).is_finite()
        })
    });
    match h {
        _ if !stiffness_finite => Some(NoTransfer::Overflow),
        Some(h) if h.re.is_finite() && h.im.is_finite() => Some(NoTransfer::Overflow),
        _ => Some(NoTransfer::Resonance),
    }
}
