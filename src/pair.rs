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

use crate::real::Real;

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
