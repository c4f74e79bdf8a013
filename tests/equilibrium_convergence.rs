//! Newton's method for the equilibrium converges, quadratically near the solution, where the
//! equilibrium exists: a disk on a ball joint, hanging from a shaft spinning about the vertical,
//! with a torsional spring on the ball joint's coordinates and two dead loads (vertical, so
//! steady) at its rim, tilts far out at 9 and 9.5 rad/s.
//!
//! **Independent equilibrium.** In the shaft's frame the disk is at rest, so its equilibrium is
//! a stationary point of the effective potential (gravity and the loads along the spin axis are
//! the same in every turned frame)
//!
//! ```text
//! V(p) = ½ k |p|² + m g c_y + Σ F_i (R x_i)_y − ½ Ω² ŷᵀ (R I_c Rᵀ + m (|c|² I − c cᵀ)) ŷ,
//! c = R c₀,
//! ```
//!
//! with `R(p)` the rotation of the ball joint's coordinates `p = 4 tan(θ/4) n` (the modified
//! Rodrigues parameters σ = p/4: `R = I + (8[σ×]² + 4(1 − σ²)[σ×])/(1 + σ²)²`), `x_i` the loads'
//! points and `F_i` their downward magnitudes. It is found here by Newton's method on `∇V` with
//! the Hessian from hyper-dual numbers, by continuation in Ω from the hanging disk.

mod common;

use common::solve;
use modaltol::compiled::Compiled;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use nalgebra::{Matrix3, SVector};
use num_dual::{Dual2SVec64, DualNum, hessian};

const G: f64 = 9.81;
const MASS: f64 = 2.0;
const R: f64 = 0.2;
const D: f64 = 0.3;
const K: f64 = 2.0;
const F1: f64 = 5.0;
const F2: f64 = 3.0;

const MODEL: &str = r#"
name = "disk on a ball joint with dead loads"
gravity = [0, -9.81, 0]

[parameters]
m = 2.0
r = 0.2
d = 0.3
k = 2.0
F1 = 5.0
F2 = 3.0

[[bodies]]
name = "shaft"
mass = 1.0
inertia = [0.01, 0.01, 0.01]
cm = [0, 0.1, 0]

[[bodies]]
name = "disk"
mass = "m"
inertia = ["m*r^2/4", "m*r^2/2", "m*r^2/4"]
cm = [0, "-d", 0]

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
child = "disk"
at = [0, 0, 0]
stiffness = "k"
damping = 0.01

[[loads]]
name = "rim"
type = "force"
body = "disk"
point = ["r", "-d", 0]
force = [0, "-F1", 0]

[[loads]]
name = "edge"
type = "force"
body = "disk"
point = [0, "-d", "r"]
force = [0, "-F2", 0]
"#;

/// A hyper-dual number in the three coordinates (value, gradient, Hessian).
type H = Dual2SVec64<3>;

/// `a b` for 3×3 matrices.
fn mul(a: &[[H; 3]; 3], b: &[[H; 3]; 3]) -> [[H; 3]; 3] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..3).fold(H::from(0.0), |s, k| s + a[i][k] * b[k][j]))
    })
}

/// `a x`.
fn apply(a: &[[H; 3]; 3], x: [f64; 3]) -> [H; 3] {
    std::array::from_fn(|i| (0..3).fold(H::from(0.0), |s, k| s + a[i][k] * x[k]))
}

/// The rotation of the ball joint's coordinates `p` (module documentation).
fn rotation(p: &[H; 3]) -> [[H; 3]; 3] {
    let s = p.map(|v| v * 0.25);
    let s2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    let zero = H::from(0.0);
    let x = [
        [zero, -s[2], s[1]],
        [s[2], zero, -s[0]],
        [-s[1], s[0], zero],
    ];
    let xx = mul(&x, &x);
    let den = (s2 + 1.0).powi(2);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let id = if i == j { 1.0 } else { 0.0 };
            (xx[i][j] * 8.0 + x[i][j] * ((-s2 + 1.0) * 4.0)) / den + id
        })
    })
}

/// The effective potential `V(p)` at the speed `w` with the spring rate `k` (module
/// documentation).
fn potential(p: SVector<H, 3>, w: f64, k: f64) -> H {
    let p = [p[0], p[1], p[2]];
    let rot = rotation(&p);
    let c = apply(&rot, [0.0, -D, 0.0]);
    let rim = apply(&rot, [R, -D, 0.0]);
    let edge = apply(&rot, [0.0, -D, R]);
    let inertia = [MASS * R * R / 4.0, MASS * R * R / 2.0, MASS * R * R / 4.0];
    // (R I_c Rᵀ)_yy with I_c diagonal.
    let turned = (0..3).fold(H::from(0.0), |s, k| s + rot[1][k] * rot[1][k] * inertia[k]);
    let spin_inertia = turned + (c[0] * c[0] + c[2] * c[2]) * MASS;
    let pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    pp * (0.5 * k) + c[1] * (MASS * G) + rim[1] * F1 + edge[1] * F2 - spin_inertia * (0.5 * w * w)
}

/// `∇V` and its Hessian at `p`.
fn gradient_and_hessian(p: &SVector<f64, 3>, w: f64, k: f64) -> (SVector<f64, 3>, Matrix3<f64>) {
    let (_, g, h) = hessian(|x: SVector<H, 3>| potential(x, w, k), p);
    (g, h)
}

/// The equilibrium at `w`, by Newton's method on `∇V` continued in Ω from the hanging disk
/// (small speed steps, each started from the last).
fn independent_equilibrium(w: f64) -> SVector<f64, 3> {
    independent_equilibrium_with(w, K)
}

/// [`independent_equilibrium`] with the spring rate `k`.
fn independent_equilibrium_with(w: f64, k: f64) -> SVector<f64, 3> {
    let mut p = SVector::<f64, 3>::zeros();
    let steps = 200;
    for s in 0..=steps {
        let ws = w * s as f64 / steps as f64;
        for _ in 0..50 {
            let (g, h) = gradient_and_hessian(&p, ws, k);
            let dp = h.lu().solve(&g).expect("a regular Hessian along the path");
            p -= dp;
            if dp.norm() < 1e-15 {
                break;
            }
        }
    }
    let (g, h) = gradient_and_hessian(&p, w, k);
    assert!(g.norm() < 1e-12, "∇V = {g}");
    assert!(
        h.symmetric_eigenvalues().min() > 0.0,
        "a stable equilibrium: {h}"
    );
    p
}

/// The ball joint's coordinates in a solved point.
fn ball(model: &Compiled, pt: &modaltol::sweep::Point) -> [f64; 3] {
    let i = model.model().coordinate("ball.rx").unwrap();
    [0, 1, 2].map(|k| pt.equilibrium.q[i + k])
}

/// The largest difference of the ball joint's coordinates from the independent equilibrium.
fn error(q: [f64; 3], exact: &SVector<f64, 3>) -> f64 {
    (0..3).fold(0.0f64, |s, i| s.max((q[i] - exact[i]).abs()))
}

/// Newton's iterations from a guess near the equilibrium (a tilt of about half a radian): a
/// few fresh Jacobians and chord steps, not a chord's linear convergence over twenty or more.
const NEAR: usize = 10;

/// At 9 and 9.5 rad/s from a nearby guess (the ball joint's `initial`), on both routes: Newton
/// converges in a few iterations to the independent equilibrium, which tilts the disk by more
/// than half a radian.
#[test]
fn a_disk_on_a_ball_joint_with_dead_loads_converges_fast_from_a_nearby_guess() {
    let text = MODEL.replace(
        "stiffness = \"k\"",
        "stiffness = \"k\"\ninitial = [0.3, 0, -0.5]",
    );
    let model = Compiled::from_str(&text, "disk.toml").unwrap_or_else(|e| panic!("{e}"));
    for w in [9.0, 9.5] {
        let exact = independent_equilibrium(w);
        assert!(4.0 * (exact.norm() / 4.0).atan() > 0.5);
        for direct in [false, true] {
            let pt = solve(&model, w, direct);
            let q = ball(&model, &pt);
            let n = pt.equilibrium.iterations;
            assert!(
                error(q, &exact) < 1e-12,
                "Ω = {w}: {q:?} vs {exact} (direct: {direct})"
            );
            assert!(n <= NEAR, "Ω = {w}: {n} iterations (direct: {direct})");
        }
    }
}

/// A sweep from 8 to 10 rad/s, started from the hanging disk: every speed converges to the
/// independent equilibrium, each continued one in a few iterations.
#[test]
fn a_sweep_of_the_disk_on_a_ball_joint_converges_at_every_speed() {
    let model = Compiled::from_str(MODEL, "disk.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    for s in 0..=8 {
        let w = 8.0 + 0.25 * s as f64;
        let pt = sweep.step(w).unwrap_or_else(|e| panic!("Ω = {w}: {e}"));
        let exact = independent_equilibrium(w);
        let q = ball(&model, &pt);
        assert!(error(q, &exact) < 1e-12, "Ω = {w}: {q:?} vs {exact}");
        if s > 0 {
            let n = pt.equilibrium.iterations;
            assert!(n <= 8, "Ω = {w}: {n} iterations");
        }
    }
}

/// A design swept beside the nominal one (as a Monte Carlo sample or a quadrature node is: its
/// predictor extrapolates its offsets from the nominal points) reaches its own independent
/// equilibrium at every speed, in fewer Newton iterations over the sweep than its own
/// continuation takes.
#[test]
fn a_design_swept_beside_the_nominal_converges_to_its_own_equilibrium_in_fewer_iterations() {
    let model = Compiled::from_str(MODEL, "disk.toml").unwrap_or_else(|e| panic!("{e}"));
    let nominal = model.model().nominal();
    let mut design = nominal.clone();
    let k = 1.03 * K;
    design[model.model().parameter("k").unwrap()] = k;
    let speeds: Vec<f64> = (0..=8).map(|s| 8.0 + 0.25 * s as f64).collect();
    let mut sweep = Sweep::new(&model, nominal, Options::default());
    let reference: Vec<_> = (speeds.iter())
        .map(|&w| sweep.step(w).unwrap_or_else(|e| panic!("Ω = {w}: {e}")))
        .collect();
    let (mut own, mut beside) = (
        Sweep::new(&model, design.clone(), Options::default()),
        Sweep::new(&model, design, Options::default()),
    );
    own.warm_start(&reference[0]);
    beside.warm_start(&reference[0]);
    let (mut by_own, mut by_beside) = (0, 0);
    for (&w, nom) in speeds.iter().zip(&reference) {
        let exact = independent_equilibrium_with(w, k);
        let a = own.step(w).unwrap_or_else(|e| panic!("Ω = {w}: {e}"));
        let b = beside
            .step_beside(w, nom)
            .unwrap_or_else(|e| panic!("Ω = {w}: {e}"));
        for pt in [&a, &b] {
            let q = ball(&model, pt);
            assert!(error(q, &exact) < 1e-12, "Ω = {w}: {q:?} vs {exact}");
        }
        by_own += a.equilibrium.iterations;
        by_beside += b.equilibrium.iterations;
    }
    assert!(
        by_beside < by_own,
        "{by_beside} iterations beside the nominal, {by_own} by its own continuation"
    );
}

/// The iteration limit does not turn a converged point into a failure: with the limit at the
/// iterations a solve used less one (its last iteration certified the point its previous one
/// reached), the solve still converges there, the exact Jacobian's step at the last point
/// deciding; with fewer, it converges to the same point or says that it did not.
#[test]
fn the_iteration_limit_does_not_fail_a_converged_point() {
    let text = MODEL.replace(
        "stiffness = \"k\"",
        "stiffness = \"k\"\ninitial = [0.3, 0, -0.5]",
    );
    let model = Compiled::from_str(&text, "disk.toml").unwrap_or_else(|e| panic!("{e}"));
    let p = model.model().nominal();
    let q0 = initial_guess(model.model(), &p, 9.0).unwrap();
    let exact = independent_equilibrium(9.0);
    let n = point(&model, &p, 9.0, &q0, &Options::default())
        .unwrap()
        .equilibrium
        .iterations;
    for limit in 1..n {
        let mut opt = Options::default();
        opt.newton.max_iterations = limit;
        match point(&model, &p, 9.0, &q0, &opt) {
            Ok(pt) => {
                assert!(error(ball(&model, &pt), &exact) < 1e-12, "limit {limit}");
            }
            Err(e) => {
                assert!(limit + 1 < n, "limit {limit} of {n}: {e}");
                assert!(e.to_string().contains("did not converge"), "{e}");
            }
        }
    }
}

/// From the default start (the hanging disk) a single solve at each speed from 7 to 12 rad/s,
/// on both routes, reaches the independent equilibrium (the stable one continued from rest),
/// not a failure and not another stationary point.
#[test]
fn a_single_solve_from_the_hanging_disk_reaches_the_equilibrium_at_every_speed() {
    let model = Compiled::from_str(MODEL, "disk.toml").unwrap_or_else(|e| panic!("{e}"));
    for w in [7.0, 8.0, 8.5, 9.0, 9.5, 10.0, 12.0] {
        let exact = independent_equilibrium(w);
        for direct in [false, true] {
            let pt = solve(&model, w, direct);
            let q = ball(&model, &pt);
            assert!(
                error(q, &exact) < 1e-12,
                "Ω = {w}: {q:?} vs {exact} (direct: {direct})"
            );
        }
    }
}
