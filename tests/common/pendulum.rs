//! The known answer of `examples/rotating_pendulum.toml`, once: a uniform rod of mass `m` and
//! length `L` hinged at the spin axis, swinging in the rotating plane with a viscous hinge `c`,
//!
//! ```text
//! I θ̈ + c θ̇ + (m g L/2) sin θ − I Ω² sin θ cos θ = 0,   I = m L²/3.
//! ```
//!
//! It hangs (`θ* = 0`) while `Ω² ≤ 3g/2L` and swings out to `cos θ* = 3g/(2LΩ²)` above; the
//! linearised stiffness there is `k = mgL/2 − IΩ²` hanging and `IΩ²(1 − cos²θ*)` swung out.
//! Generic over the scalar, so that dual and hyper-dual numbers in `L` give its exact
//! derivatives, the independent truth every stage's derivatives are checked against.

use modaltol::real::Real;

/// Standard gravity, as the example gives it.
pub const G: f64 = 9.80665;
/// The rod's mass (kg) and the hinge's damping (N m s/rad), as the example gives them.
pub const M: f64 = 3.0;
pub const C: f64 = 3.0;

/// The pendulum at rod length `l` (m) and speed `w` (rad/s), on the branch the sweep follows.
#[derive(Debug, Clone, Copy)]
pub struct Pendulum<D> {
    /// `θ*` (rad).
    pub theta: D,
    /// `I = mL²/3` (kg m²).
    pub inertia: D,
    /// The linearised stiffness `k` (N m/rad).
    pub stiffness: D,
    /// The pair discriminant `4Ik − c²`: negative where the mode is overdamped.
    pub discriminant: D,
    /// `ω_d = √max(0, 4Ik − c²)/(2I)` (rad/s).
    pub damped_frequency: D,
    /// `|H(jΩ)|` of the hinge torque to the angle at the spin frequency (rad/(N m)).
    pub transfer: D,
}

/// Whether the rod hangs at `l`, `w` (`Ω² ≤ 3g/2L`).
pub fn hangs(l: f64, w: f64) -> bool {
    w * w <= 3.0 * G / (2.0 * l)
}

/// The known answer at rod length `l` and speed `w`.
pub fn pendulum<D: Real>(l: D, w: f64) -> Pendulum<D> {
    let inertia = l * l * (M / 3.0);
    let (theta, stiffness) = if hangs(l.re(), w) {
        (D::from(0.0), l * (M * G / 2.0) - inertia * w * w)
    } else {
        let cos = (l * w * w * 2.0).recip() * (3.0 * G);
        (cos.acos(), inertia * w * w * (-cos * cos + 1.0))
    };
    let discriminant = inertia * stiffness * 4.0 - C * C;
    let damped_frequency = if discriminant.re() > 0.0 {
        discriminant.sqrt() / (inertia * 2.0)
    } else {
        D::from(0.0)
    };
    let real = stiffness - inertia * w * w;
    let transfer = (real * real + (w * C) * (w * C)).sqrt().recip();
    Pendulum {
        theta,
        inertia,
        stiffness,
        discriminant,
        damped_frequency,
        transfer,
    }
}
