//! A mode's characteristics from the invariants of its pair of roots, written once over any
//! scalar: values in `f64`, and Hessians through hyper-dual numbers, come from the same maps.
//!
//! With `s = λ₁ + λ₂` and `p = λ₁λ₂` (real for a conjugate or a real pair of roots of a real
//! eigenproblem):
//!
//! ```text
//! ω_n = √|p|,   ζ = −s / (2 ω_n),   D = p − s²/4,   ω_d = √max(0, D)
//! ```
//!
//! `D > 0` for an underdamped pair (`λ = s/2 ± j√D`), `D ≤ 0` for an overdamped one. The
//! invariants are smooth where the roots are not (at a coalescence), which is why the
//! quadrature interpolates them and the Taylor methods differentiate them.
//!
//! A design's state at one speed, as the quadrature interpolates it and the requirements read
//! it, is its carriers: `s, p` of every mode, then |H| ([`Carriers`]).

use crate::real::Real;
use nalgebra::Complex;

/// A design's carriers at one speed, `[s₀, p₀, s₁, p₁, …, |H|]`: each mode's pair invariants
/// `s = λ₁ + λ₂` and `p = λ₁λ₂`, then |H| (0 without a transfer function, NaN where |H| has no
/// value): what the quadrature interpolates between nodes and the requirements read. The one
/// place their layout is known; every reader goes through this view.
#[derive(Debug, Clone, Copy)]
pub struct Carriers<'a>(&'a [f64]);

impl<'a> Carriers<'a> {
    /// The number of carriers of a design with `modes` modes.
    pub const fn width(modes: usize) -> usize {
        2 * modes + 1
    }

    /// The view of `c` (of [`Carriers::width`] values).
    pub fn new(c: &'a [f64]) -> Self {
        debug_assert!(c.len() % 2 == 1, "carriers are two per mode and |H|");
        Carriers(c)
    }

    /// The number of modes.
    pub fn modes(self) -> usize {
        self.0.len() / 2
    }

    /// `s = λ₁ + λ₂` and `p = λ₁λ₂` of mode `m`.
    pub fn pair(self, m: usize) -> (f64, f64) {
        (self.0[2 * m], self.0[2 * m + 1])
    }

    /// `p = λ₁λ₂` of mode `m`.
    pub fn product(self, m: usize) -> f64 {
        self.0[2 * m + 1]
    }

    /// |H| (0 without a transfer function, NaN where it has no value).
    pub fn transfer(self) -> f64 {
        self.0[self.0.len() - 1]
    }

    /// The pairs `(s, p)` of every mode, in order.
    pub fn pairs(self) -> impl Iterator<Item = (f64, f64)> + 'a {
        self.0[..self.0.len() - 1]
            .chunks_exact(2)
            .map(|c| (c[0], c[1]))
    }

    /// Writes into `out` (of [`Carriers::width`] values) the carriers of the modes whose roots
    /// are `roots` (each mode's root and its partner) and of |H| `transfer`.
    pub fn write(
        roots: impl Iterator<Item = (Complex<f64>, Complex<f64>)>,
        transfer: f64,
        out: &mut [f64],
    ) {
        let mut n = 0;
        for (m, (a, b)) in roots.enumerate() {
            out[2 * m] = (a + b).re;
            out[2 * m + 1] = (a * b).re;
            n = m + 1;
        }
        out[2 * n] = transfer;
    }
}

/// `ω_n = √|p|`.
pub fn natural_frequency<S: Real>(p: S) -> S {
    p.abs().sqrt()
}

/// `ζ = −s / (2√|p|)` (infinite or NaN where `p = 0`: a rigid-body mode has none).
pub fn damping_ratio<S: Real>(s: S, p: S) -> S {
    -s / (natural_frequency(p) * 2.0)
}

/// The discriminant `D = p − s²/4`.
pub fn discriminant<S: Real>(s: S, p: S) -> S {
    p - s * s * 0.25
}

/// `ω_d = √max(0, D)`: zero for an overdamped pair.
pub fn damped_frequency<S: Real>(s: S, p: S) -> S {
    let d = discriminant(s, p);
    if d.re() > 0.0 { d.sqrt() } else { S::zero() }
}

/// The derivative of `ω_n` from that of `p`: `dω_n = sign(p) dp / (2ω_n)` (NaN at `ω_n = 0`).
pub fn d_natural_frequency(p: f64, wn: f64, dp: f64) -> f64 {
    if wn > 0.0 {
        p.signum() * dp / (2.0 * wn)
    } else {
        f64::NAN
    }
}

/// The derivative of `ζ` from those of `s` and `ω_n`: `dζ = −ds/(2ω_n) + s dω_n/(2ω_n²)`.
pub fn d_damping_ratio(s: f64, wn: f64, ds: f64, dwn: f64) -> f64 {
    -ds / (2.0 * wn) + s * dwn / (2.0 * wn * wn)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    #[test]
    fn maps_of_a_known_pair_and_their_derivatives_agree_with_dual_numbers() {
        // λ = −0.3 ± 2j: s = −0.6, p = 4.09, ω_n = √4.09, ζ = 0.3/√4.09, ω_d = 2.
        let (s, p) = (-0.6, 4.09);
        assert!((natural_frequency(p) - 4.09f64.sqrt()).abs() < 1e-15);
        assert!((damping_ratio(s, p) - 0.3 / 4.09f64.sqrt()).abs() < 1e-15);
        assert!((damped_frequency(s, p) - 2.0).abs() < 1e-15);
        assert!(damped_frequency(-5.0f64, 4.0).abs() < f64::MIN_POSITIVE);
        // The hand-written derivatives are the dual numbers' along any direction.
        let (ds, dp) = (0.7, -1.3);
        let (sd, pd) = (Dual64::new(s, ds), Dual64::new(p, dp));
        let wn = natural_frequency(p);
        let dwn = d_natural_frequency(p, wn, dp);
        assert!((natural_frequency(pd).eps - dwn).abs() < 1e-14);
        let dz = d_damping_ratio(s, wn, ds, dwn);
        assert!((damping_ratio(sd, pd).eps - dz).abs() < 1e-14);
        assert!((damping_ratio(sd, pd).re - damping_ratio(s, p)).abs() < 1e-15);
    }
}
