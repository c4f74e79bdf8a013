//! The spherical spring-damper (`type = "spherical_spring_damper"`): a viscous torque on the
//! relative angular velocity of two bodies, against hand derivations.
//!
//! **The damped conical pendulum on its cone.** A rod (mass m, centre of mass at d below a ball
//! joint, transverse inertia A = I_t + m d² about the joint, axial I_a) hangs from a shaft driven
//! at Ω about the vertical; a viscous torque `−c ω_rel` acts between shaft and rod. Above
//! `Ω_c² = m g d / (A − I_a)` the rod rides a cone `cos θ₀ = Ω_c²/Ω²`. With Euler angles in the
//! shaft's frame (precession φ about the vertical, nutation θ from the downward vertical, spin ψ
//! about the rod) the rod's angular velocity is `(Ω + φ̇) ŷ + θ̇ n̂ + ψ̇ â`,
//!
//! ```text
//! T = ½ A (θ̇² + (Ω + φ̇)² sin²θ) + ½ I_a (ψ̇ − (Ω + φ̇) cos θ)²,   V = −m g d cos θ,
//! D = ½ c |ω_rel|² = ½ c (θ̇² + φ̇² + ψ̇² − 2 φ̇ ψ̇ cos θ),
//! ```
//!
//! and linearising Lagrange's equations about (θ₀, φ̇ = ψ̇ = 0) by hand (s = sin θ₀, k = cos θ₀):
//!
//! ```text
//! M = [A, 0, 0; 0, A s² + I_a k², −I_a k; 0, −I_a k, I_a]
//! G = [0, −2(A − I_a)Ω s k, −I_a Ω s; 2(A − I_a)Ω s k, 0, 0; I_a Ω s, 0, 0]
//! C = c [1, 0, 0; 0, 1, −k; 0, −k, 1],     K = diag((A − I_a) Ω² s², 0, 0)
//! ```
//!
//! whose roots (two zero: φ and ψ are cyclic) the model's must equal, whatever coordinates it
//! uses (the ball joint's Rodrigues parameters).

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;
use nalgebra::{DMatrix, Matrix3};

const M: f64 = 1.0;
const G: f64 = 9.81;

/// The conical pendulum (the shipped example's geometry) with the ball joint's fields
/// `ball` and further tables `rest`.
fn cone(ball: &str, rest: &str) -> String {
    format!(
        r#"
name = "damped conical pendulum"
gravity = [0, -9.81, 0]

[parameters]
m = 1.0
L = 0.5
c = 0.05

[[bodies]]
name = "shaft"
mass = 1.0
inertia = [0.01, 0.01, 0.01]
cm = [0, 0.1, 0]

[[bodies]]
name = "rod"
mass = "m"
inertia = ["m*L^2/12", "1e-3*m", "m*L^2/12"]
cm = [0, "-L/2", 0]

[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "shaft"
at = [0, 0, 0]
axis = [0, 1, 0]
drive = "speed"

[[joints]]
name = "ball"
type = "spherical"
parent = "shaft"
child = "rod"
at = [0, 0, 0]
{ball}
{rest}"#
    )
}

const VISCOUS: &str = r#"
[[forces]]
name = "viscous"
type = "spherical_spring_damper"
body1 = "shaft"
body2 = "rod"
damping = "c"
"#;

/// `A`, `I_a` and `Ω_c²` of the rod of length `l`.
fn rod_of(l: f64) -> (f64, f64, f64) {
    let d = l / 2.0;
    let a = M * l * l / 12.0 + M * d * d;
    let ia = 1e-3 * M;
    (a, ia, M * G * d / (a - ia))
}

/// [`rod_of`] the model's rod, 0.5 m long.
fn rod() -> (f64, f64, f64) {
    rod_of(0.5)
}

/// The hand-derived roots on the cone at `omega` (module documentation).
fn cone_roots(omega: f64, c: f64) -> Vec<C64> {
    cone_roots_of(omega, c, 0.5)
}

/// [`cone_roots`] with a rod of length `l`.
fn cone_roots_of(omega: f64, c: f64, l: f64) -> Vec<C64> {
    let (a, ia, wc2) = rod_of(l);
    let k = wc2 / (omega * omega);
    let s = (1.0 - k * k).sqrt();
    let mass = Matrix3::new(
        a,
        0.0,
        0.0,
        0.0,
        a * s * s + ia * k * k,
        -ia * k,
        0.0,
        -ia * k,
        ia,
    );
    let g = 2.0 * (a - ia) * omega * s * k;
    let gyro = Matrix3::new(
        0.0,
        -g,
        -ia * omega * s,
        g,
        0.0,
        0.0,
        ia * omega * s,
        0.0,
        0.0,
    );
    let damp = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, -k, 0.0, -k, 1.0) * c;
    let stiff = Matrix3::from_diagonal(&nalgebra::Vector3::new(
        (a - ia) * omega * omega * s * s,
        0.0,
        0.0,
    ));
    let inv = mass.try_inverse().unwrap();
    let (kk, cc) = (-(inv * stiff), -(inv * (gyro + damp)));
    let mut state = DMatrix::zeros(6, 6);
    for i in 0..3 {
        state[(i, i + 3)] = 1.0;
        for j in 0..3 {
            state[(i + 3, j)] = kk[(i, j)];
            state[(i + 3, j + 3)] = cc[(i, j)];
        }
    }
    state
        .complex_eigenvalues()
        .iter()
        .map(|z| C64::new(z.re, z.im))
        .collect()
}

/// The roots away from zero, and how many were at zero (the cyclic coordinates' double root,
/// which a solver resolves only to the square root of the rounding).
fn nonzero(r: &[C64]) -> (Vec<C64>, usize) {
    let kept: Vec<C64> = r.iter().copied().filter(|z| z.norm() > 1e-6).collect();
    let zeros = r.len() - kept.len();
    (kept, zeros)
}

/// The model with the ball joint started near the cone `cos θ₀ = Ω_c²/Ω²` (its coordinate a
/// rotation about x: `4 tan(θ/4)`), so Newton converges onto the cone.
fn on_cone(omega: f64, ball: &str, rest: &str) -> Compiled {
    let theta = (rod().2 / (omega * omega)).acos();
    let start = 4.0 * (theta / 4.0).tan() + 0.05;
    let text = cone(&format!("initial = [{start}, 0, 0]\n{ball}"), rest);
    Compiled::from_str(&text, "cone.toml").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_viscous_torque_on_the_cone_equals_the_hand_derivation() {
    for omega in [6.0, 7.0, 8.0] {
        let model = on_cone(omega, "", VISCOUS);
        let (exact, zeros) = nonzero(&cone_roots(omega, 0.05));
        assert_eq!(zeros, 2);
        for direct in [false, true] {
            let pt = solve(&model, omega, direct);
            let theta = (rod().2 / (omega * omega)).acos();
            let rx = pt.equilibrium.q[1];
            assert!(
                (rx - 4.0 * (theta / 4.0).tan()).abs() < 1e-12,
                "on the cone at {omega}: {rx}"
            );
            let (got, zeros) = nonzero(&roots(&pt));
            assert_eq!(zeros, 2, "{:?}", roots(&pt));
            same_roots(&got, &exact, 1e-10);
        }
    }
}

#[test]
fn a_ball_joints_own_damping_is_not_the_viscous_torque_off_the_reference() {
    // The joint's damper acts on the Rodrigues rates: on the cone its damping ratio is well
    // above the viscous torque's (which the hand derivation gives), so the element is needed.
    let zeta = |pt: &modaltol::sweep::Point| {
        let z = roots(pt)
            .into_iter()
            .filter(|z| z.im > 1.0)
            .max_by(|a, b| a.im.total_cmp(&b.im))
            .unwrap();
        -z.re / z.norm()
    };
    let omega = 8.0;
    let viscous = solve(&on_cone(omega, "", VISCOUS), omega, false);
    let joint = solve(&on_cone(omega, "damping = \"c\"", ""), omega, false);
    let (zv, zj) = (zeta(&viscous), zeta(&joint));
    assert!(zj > 1.1 * zv, "joint ζ {zj} vs viscous ζ {zv}");
    // Hanging (q = 0, below Ω_c) the rates are the angular velocity: the two are one damper.
    let hanging = |ball: &str, rest: &str| {
        let m = Compiled::from_str(&cone(ball, rest), "cone.toml").unwrap();
        roots(&solve(&m, 3.0, false))
    };
    same_roots(
        &hanging("", VISCOUS),
        &hanging("damping = \"c\"", ""),
        1e-12,
    );
}

#[test]
fn the_elements_spring_is_the_ball_joints_spring() {
    // The same measure (4 tan(θ/4) n): a spring on the element equals the joint's own spring,
    // equilibrium and roots, on a cone it tilts.
    let omega = 8.0;
    let with_element = on_cone(
        omega,
        "",
        &VISCOUS.replace("damping = \"c\"", "damping = \"c\"\nstiffness = 0.4"),
    );
    let with_joint = on_cone(omega, "stiffness = 0.4", VISCOUS);
    for direct in [false, true] {
        let (a, b) = (
            solve(&with_element, omega, direct),
            solve(&with_joint, omega, direct),
        );
        assert!(
            (a.equilibrium.q[1] - b.equilibrium.q[1]).abs() < 1e-12,
            "{} vs {}",
            a.equilibrium.q[1],
            b.equilibrium.q[1]
        );
        assert!(
            a.equilibrium.q[1]
                < solve(&on_cone(omega, "", VISCOUS), omega, direct)
                    .equilibrium
                    .q[1]
                    - 0.01
        );
        let ((ra, za), (rb, zb)) = (nonzero(&roots(&a)), nonzero(&roots(&b)));
        // The spring holds the rod's spin: only the precession's zero root is left.
        assert_eq!((za, zb), (1, 1));
        same_roots(&ra, &rb, 1e-10);
    }
}

/// A body on a free joint, held by a bushing at its centre of mass (translation only) and a
/// spherical spring-damper to the ground, components per axis, with `ends` naming the two
/// bodies of the element.
fn puck(ends: &str) -> String {
    format!(
        r#"
name = "puck"
gravity = [0, 0, 0]

[[bodies]]
name = "puck"
mass = 2.0
inertia = [0.3, 0.5, 0.7]
cm = [0.1, 0.2, 0.3]

[[joints]]
name = "float"
type = "free"
parent = "ground"
child = "puck"
at = [0.1, 0.2, 0.3]

[[forces]]
name = "mount"
type = "bushing"
body1 = "ground"
body2 = "puck"
point1 = [0.1, 0.2, 0.3]
stiffness = [800, 1800, 3200, 0, 0, 0]

[[forces]]
name = "rotational"
type = "spherical_spring_damper"
{ends}
stiffness = [30, 20, 10]
damping = [0.6, 1.5, 0.7]
"#
    )
}

#[test]
fn on_a_free_joint_each_axis_has_its_own_spring_and_damper() {
    let quadratic = |m: f64, c: f64, k: f64| {
        let disc = C64::new(c * c - 4.0 * m * k, 0.0).sqrt();
        [(-c + disc) / (2.0 * m), (-c - disc) / (2.0 * m)]
    };
    let mut exact = Vec::new();
    for (m, c, k) in [
        (2.0, 0.0, 800.0),
        (2.0, 0.0, 1800.0),
        (2.0, 0.0, 3200.0),
        (0.3, 0.6, 30.0),
        (0.5, 1.5, 20.0),
        (0.7, 0.7, 10.0),
    ] {
        exact.extend(quadratic(m, c, k));
    }
    for ends in [
        "body1 = \"ground\"\nbody2 = \"puck\"",
        "body1 = \"puck\"\nbody2 = \"ground\"",
    ] {
        let model = Compiled::from_str(&puck(ends), "puck.toml").unwrap_or_else(|e| panic!("{e}"));
        for direct in [false, true] {
            same_roots(&roots(&solve(&model, 0.0, direct)), &exact, 1e-12);
        }
    }
}

#[test]
fn the_first_order_spread_of_the_damping_ratio_equals_the_hand_derivations() {
    // Tolerances on the damper and the rod's length (3σ): the first-order σ of ζ on the cone is
    // the root-sum-square of ∂ζ/∂c σ_c and ∂ζ/∂L σ_L, by central differences of the hand form.
    use modaltol::analyze::{AnalyzeOptions, analyze};
    use modaltol::model::Case;
    use modaltol::output::Quantity;
    use modaltol::table::Method;
    let omega = 8.0;
    let theta = (rod().2 / (omega * omega)).acos();
    let text = cone(
        &format!("initial = [{}, 0, 0]", 4.0 * (theta / 4.0).tan()),
        VISCOUS,
    )
    .replace("c = 0.05", "c = { value = 0.05, tolerance = \"20%\" }")
    .replace("L = 0.5", "L = { value = 0.5, tolerance = \"2%\" }");
    let m = Compiled::from_str(&text, "cone.toml").unwrap_or_else(|e| panic!("{e}"));
    let opt = AnalyzeOptions {
        speeds: vec![omega],
        cases: vec![Case::from_parameters(m.model())],
        quadrature: None,
        monte_carlo: None,
        ..Default::default()
    };
    let a = analyze(&m, &opt, &|_, _, _| {});
    let zeta = |c: f64, l: f64| {
        let z = cone_roots_of(omega, c, l)
            .into_iter()
            .filter(|z| z.im > 1.0)
            .max_by(|a, b| a.im.total_cmp(&b.im))
            .unwrap();
        -z.re / z.norm()
    };
    let (c, l) = (0.05, 0.5);
    let (sc, sl) = (c * 0.2 / 3.0, l * 0.02 / 3.0);
    let (hc, hl) = (c * 1e-4, l * 1e-5);
    let dc = (zeta(c + hc, l) - zeta(c - hc, l)) / (2.0 * hc);
    let dl = (zeta(c, l + hl) - zeta(c, l - hl)) / (2.0 * hl);
    let std = ((dc * sc).powi(2) + (dl * sl).powi(2)).sqrt();
    let row = a
        .rows
        .iter()
        .find(|r| {
            r.method() == Method::FirstOrder
                && r.quantity == Quantity::DampingRatio
                && r.mode == Some(2)
        })
        .expect("a first-order row of the whirl mode");
    assert!(
        (row.mean - zeta(c, l)).abs() < 1e-10 && (row.std - std).abs() < 1e-6 * std,
        "{} ± {} vs {} ± {std}",
        row.mean,
        row.std,
        zeta(c, l)
    );
    // Both variables matter (the check is not one term's).
    assert!(dc.abs() * sc > 0.1 * std && dl.abs() * sl > 0.1 * std);
}
