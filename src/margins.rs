//! The requirements' margins at one speed of one design: positive where the design meets it.
//!
//! Requirements ([`crate::model::Requirement`], `[[requirements]]` in the model file, one kind
//! per file in [`crate::requirements`]) are read from what every propagation method already has
//! at a point: the pair invariants `s, p` of every mode (the quadrature's carriers,
//! [`carriers`]), |H|, and whether the design is on the nominal design's branch. Each kind's
//! margin has a unit and is continuous where the quantity it reads is, so that its zero, the
//! boundary between designs that pass and designs that fail, can be located along a quadrature
//! line by bisection. A requirement over an operating range is met by a design when its margin
//! is ≥ 0 at every analysed speed of the range; a point that failed, or a quantity without a
//! value (|H| at an undamped resonance), fails it.
//!
//! A per-mode kind's margin is written once over any scalar ([`Real`](crate::real::Real)), so
//! that the first-order method differentiates it exactly ([`mode_margin_gradient`]).

use crate::model::Requirement;
use crate::model::judged::same_speed;
use crate::pair::{self, Carriers};
use crate::requirements::{Reading, Reads};
use crate::sensitivity::TransferAt;
use crate::sweep::Point;
use num_dual::Dual64;

/// Relative growth rate below which a pair counts as stable (as in [`crate::modal`]).
const GROWTH_TOL: f64 = 1e-9;

/// What a requirement reads at one speed of one design.
#[derive(Debug, Clone, Copy)]
pub struct State<'a> {
    /// The speed, rad/s.
    pub speed: f64,
    /// `s, p` of every mode, then |H| (NaN where it has no value): see [`carriers`].
    pub carriers: Carriers<'a>,
    /// Is the design on the nominal design's equilibrium branch here?
    pub same_branch: bool,
}

/// The carriers of a point: `s = λ₁ + λ₂` and `p = λ₁λ₂` of every mode, then |H| at `tf`
/// (0 without a transfer function, NaN where |H| has no value).
pub fn carriers(pt: &Point, tf: Option<TransferAt>) -> Vec<f64> {
    let mut c = vec![0.0; Carriers::width(pt.modes.len())];
    write_carriers(pt, tf, &mut c);
    c
}

/// Writes the carriers of a point into `out` (of [`Carriers::width`] values): see
/// [`carriers`].
pub fn write_carriers(pt: &Point, tf: Option<TransferAt>, out: &mut [f64]) {
    let h = match tf {
        Some(t) => crate::sensitivity::nominal_transfer(pt, &t)
            .map(|h| h.magnitude())
            .filter(|h| h.is_finite())
            .unwrap_or(f64::NAN),
        None => 0.0,
    };
    let roots = pt.modes.iter().map(|m| (m.root.lambda, m.partner.lambda));
    Carriers::write(roots, h, out);
}

/// Is `speed` in the requirement's operating range (its ends to within [`same_speed`])?
pub fn covers(req: &Requirement, speed: f64) -> bool {
    req.speeds.is_none_or(|(a, b)| {
        (a <= speed || same_speed(a, speed)) && (speed <= b || same_speed(b, speed))
    })
}

/// Is `speed` at or above the start of the requirement's operating range? The speeds where the
/// largest operating range it meets is sought (from the range's start up, beyond its end).
pub fn reaches(req: &Requirement, speed: f64) -> bool {
    req.speeds
        .is_none_or(|(a, _)| a <= speed || same_speed(a, speed))
}

/// Does the requirement have a margin with a distribution (every kind but the branch, which is
/// pass or fail)?
pub fn has_margin(req: &Requirement) -> bool {
    req.kind.reads() != Reads::Branch
}

/// The requirement's unit of margin, for the outputs (`transfer` names |H|'s unit).
pub fn unit(req: &Requirement, transfer: &str) -> String {
    req.kind.unit().symbol(transfer)
}

/// The margin of `req` at `state` (≥ 0: met). `−∞` where the design fails it without a value
/// (|H| unbounded, no mode with the quantity asked); the caller passes no state where the point
/// failed.
pub fn margin(req: &Requirement, st: &State) -> f64 {
    let c = st.carriers;
    let m = match req.kind.reads() {
        Reads::Branch => req.kind.margin(st.speed, Reading::Branch(st.same_branch)),
        Reads::Growth => {
            let g = c
                .pairs()
                .map(|(s, p)| growth(s, p))
                .fold(f64::NEG_INFINITY, f64::max);
            req.kind.margin(st.speed, Reading::Growth(g))
        }
        Reads::Transfer => req.kind.margin(st.speed, Reading::Transfer(c.transfer())),
        Reads::Mode => {
            let of = |m: usize| {
                let (s, p) = c.pair(m);
                mode_margin(req, st.speed, s, p)
            };
            match req.mode {
                Some(m) => of(m),
                // The worst mode where the quantity has a value (a rigid-body mode has none).
                None => (0..c.modes())
                    .map(of)
                    .filter(|v| !v.is_nan())
                    .fold(f64::NAN, |a, b| if a.is_nan() { b } else { a.min(b) }),
            }
        }
    };
    if m.is_nan() { f64::NEG_INFINITY } else { m }
}

/// The largest real part of a pair's roots less [`GROWTH_TOL`] of its size: positive when the
/// pair is unstable (a rigid-body mode's zero root is not).
fn growth(s: f64, p: f64) -> f64 {
    let d = pair::discriminant(s, p);
    let top = if d > 0.0 {
        0.5 * s
    } else {
        0.5 * s + (-d).sqrt()
    };
    top - GROWTH_TOL * p.abs().sqrt()
}

/// The margin of a per-mode requirement from the mode's invariants `s, p` at `speed`: NaN for a
/// rigid-body mode (both roots exactly zero, [`crate::modal::ModeClass::Rigid`]), which has no
/// frequency and no damping ratio. Read as `ω_d = 0` it would enter a frequency, band or
/// separation requirement as a mode far below every excitation.
pub fn mode_margin(req: &Requirement, speed: f64, s: f64, p: f64) -> f64 {
    if s == 0.0 && p == 0.0 {
        return f64::NAN;
    }
    let reading = Reading::Mode {
        wd: pair::damped_frequency(s, p),
        zeta: pair::damping_ratio(s, p),
        real_pair: p <= 0.0,
    };
    req.kind.margin(speed, reading)
}

/// The derivatives of a per-mode requirement's margin with respect to the mode's ω_d and ζ at
/// `(wd, zeta)`, exact (dual numbers); NaN where the margin has none.
pub fn mode_margin_gradient(req: &Requirement, speed: f64, wd: f64, zeta: f64) -> (f64, f64) {
    let at = |wd, zeta| Reading::Mode {
        wd,
        zeta,
        real_pair: false,
    };
    let d_wd = req
        .kind
        .margin(speed, at(Dual64::new(wd, 1.0), Dual64::from(zeta)))
        .eps;
    let d_zeta = req
        .kind
        .margin(speed, at(Dual64::from(wd), Dual64::new(zeta, 1.0)))
        .eps;
    (d_wd, d_zeta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::requirements::Kind;
    use crate::requirements::avoid::Avoid;
    use crate::requirements::damping::Damping;
    use crate::requirements::frequency::Frequency;
    use crate::requirements::separation::{Separation, SeparationMargin};
    use crate::requirements::stable::Stable;
    use crate::requirements::underdamped::Underdamped;

    fn req(kind: Kind) -> Requirement {
        Requirement {
            name: "r".into(),
            kind,
            speeds: None,
            mode: Some(0),
        }
    }

    /// `s, p` of a mode with `ω_n` and ζ.
    fn pair_of(wn: f64, zeta: f64) -> (f64, f64) {
        (-2.0 * zeta * wn, wn * wn)
    }

    #[test]
    fn separation_margins_follow_api_684() {
        // AF = 1/(2ζ) = 5 at ζ = 0.1: 17(1 − 1/3.5) = 12.14 % below, 22.14 % above.
        let r = req(Kind::Separation(Separation {
            orders: vec![1.0],
            margin: SeparationMargin::Api684,
        }));
        let (s, p) = pair_of(10.0, 0.1);
        let wd = pair::damped_frequency(s, p);
        let g = 0.17 * (1.0 - 1.0 / 3.5);
        // Excitation just above the mode: the mode must lie below by `g`.
        let e = wd / (1.0 - g);
        assert!(mode_margin(&r, e, s, p).abs() < 1e-12);
        // Just below: above by 10 % + g.
        let e = wd / (1.1 + g);
        assert!(mode_margin(&r, e, s, p).abs() < 1e-12);
        // Heavily damped (AF < 2.5): no margin, met at any speed.
        let (s, p) = pair_of(10.0, 0.3);
        assert!(mode_margin(&r, pair::damped_frequency(s, p), s, p) >= 0.0);
        // Light damping: the 16 % and 26 % caps.
        let (s, p) = pair_of(10.0, 0.001);
        let wd = pair::damped_frequency(s, p);
        assert!(mode_margin(&r, wd / 0.84, s, p).abs() < 1e-12);
        assert!(mode_margin(&r, wd / 1.26, s, p).abs() < 1e-12);
    }

    #[test]
    fn gradients_match_finite_differences() {
        let kinds = [
            Kind::Separation(Separation {
                orders: vec![1.0, 2.0],
                margin: SeparationMargin::Api684,
            }),
            Kind::Separation(Separation {
                orders: vec![1.0],
                margin: SeparationMargin::Fraction(0.15),
            }),
            Kind::Frequency(Frequency {
                min: Some(3.0),
                max: Some(20.0),
            }),
            Kind::Avoid(Avoid {
                low: 8.0,
                high: 12.0,
            }),
            Kind::Damping(Damping { min: 0.02 }),
            Kind::Underdamped(Underdamped),
        ];
        for kind in kinds {
            let r = req(kind);
            for &(speed, wd, zeta) in &[(9.0, 7.3, 0.08), (4.0, 15.0, 0.12), (12.0, 9.1, 0.05)] {
                let (gw, gz) = mode_margin_gradient(&r, speed, wd, zeta);
                let h = 1e-6;
                let f = |wd: f64, zeta: f64| {
                    let at = Reading::Mode {
                        wd,
                        zeta,
                        real_pair: false,
                    };
                    r.kind.margin(speed, at)
                };
                let fw = (f(wd + h, zeta) - f(wd - h, zeta)) / (2.0 * h);
                let fz = (f(wd, zeta + h) - f(wd, zeta - h)) / (2.0 * h);
                assert!((gw - fw).abs() < 1e-6, "{:?}: {gw} vs {fw}", r.kind);
                assert!((gz - fz).abs() < 1e-5, "{:?}: {gz} vs {fz}", r.kind);
            }
        }
    }

    #[test]
    fn stability_and_underdamping_margins_change_sign_at_their_boundaries() {
        let stable = req(Kind::Stable(Stable));
        fn st(c: &[f64]) -> State<'_> {
            State {
                speed: 1.0,
                carriers: Carriers::new(c),
                same_branch: true,
            }
        }
        assert!(margin(&stable, &st(&[-1.0, 4.0, 0.0])) > 0.0);
        assert!(margin(&stable, &st(&[1.0, 4.0, 0.0])) < 0.0);
        // A positive real root (p < 0) whatever s.
        assert!(margin(&stable, &st(&[-1.0, -4.0, 0.0])) < 0.0);
        // A rigid-body mode (a zero root) is not unstable.
        assert!(margin(&stable, &st(&[-1.0, 0.0, 0.0])) >= 0.0);
        let under = req(Kind::Underdamped(Underdamped));
        let (s, p) = pair_of(2.0, 0.99);
        assert!(mode_margin(&under, 1.0, s, p) > 0.0);
        let (s, p) = pair_of(2.0, 1.01);
        assert!(mode_margin(&under, 1.0, s, p) < 0.0);
        assert!(mode_margin(&under, 1.0, 0.5, -1.0) < 0.0);
    }
}
