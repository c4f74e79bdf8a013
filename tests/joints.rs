//! Multi-coordinate tree joints against closed forms and against the chains of one-coordinate
//! joints they stand for.
//!
//! * `universal`, `cylindrical`, `planar`: the same mechanism written with the joint and with
//!   revolute and prismatic joints through massless intermediate bodies has the same
//!   equilibrium and the same eigenvalues (to 1e-9), on the recorded and the direct route.
//! * `spherical`: an axisymmetric pendulum on a ball joint under a spinning shaft, against hand
//!   derivations: at rest, tilt ω² = m g L / J and twist ω² = k / A; below the critical speed the
//!   gyroscopic tilt frequencies of a hanging spinning top seen from the shaft's frame; above it,
//!   the conical equilibrium cos θ = m g L / ((J − A) Ω²).

mod common;

use common::{example_text, roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::sweep::Point;

/// Both models give the same roots on both routes, and the same values of the coordinates named
/// in `pairs` (name in `a`, name in `b`).
fn equivalent(a: &Compiled, b: &Compiled, speeds: &[f64], pairs: &[(&str, &str)]) {
    for &w in speeds {
        for direct in [false, true] {
            let (pa, pb) = (solve(a, w, direct), solve(b, w, direct));
            same_roots(&roots(&pa), &roots(&pb), 1e-9);
            for (na, nb) in pairs {
                let qa = pa.equilibrium.q[a.model().coordinate(na).unwrap()];
                let qb = pb.equilibrium.q[b.model().coordinate(nb).unwrap()];
                assert!(
                    (qa - qb).abs() <= 1e-10,
                    "{na} = {qa} vs {nb} = {qb} at {w} rad/s"
                );
            }
        }
    }
}

/// The spinning universal-joint pendulum example with a massless yoke and hinge springs whose
/// free angles tilt the equilibrium.
fn two_hinges() -> String {
    example_text("spinning_universal_pendulum.toml")
        .replace(
            "mass = 0.2\ninertia = [1e-3, 2e-3, 1e-3]",
            "mass = 0\ninertia = [0, 0, 0]",
        )
        .replace("stiffness = \"kx\"", "stiffness = \"kx\"\nfree = 0.2")
        .replace("stiffness = \"kz\"", "stiffness = \"kz\"\nfree = -0.1")
}

#[test]
fn a_universal_joint_is_two_revolutes_through_one_point() {
    let text = two_hinges();
    let a = Compiled::from_str(&text, "two_hinges.toml").unwrap();
    let start = text.find("[[joints]]\nname = \"tilt_x\"").unwrap();
    let end = text.find("[analysis]").unwrap();
    let universal = text[..start].replace(
        "[[bodies]]\nname = \"yoke\"\nmass = 0\ninertia = [0, 0, 0]\ncm = [0, 0, 0]\n",
        "",
    ) + "[[joints]]\nname = \"cross\"\ntype = \"universal\"\nparent = \"shaft\"\nchild = \"bob\"\nat = [0, 0, 0]\naxis = [1, 0, 0]\naxis2 = [0, 0, 1]\nstiffness = [\"kx\", \"kz\"]\nfree = [0.2, -0.1]\ndamping = \"c\"\n\n"
        + &text[end..].replace(
            "input = \"tilt_x\", output = \"tilt_z\"",
            "input = \"cross.angle1\", output = \"cross.angle2\"",
        );
    let b = Compiled::from_str(&universal, "universal.toml").unwrap();
    assert_eq!(b.model().coordinates.len(), 3);
    equivalent(
        &a,
        &b,
        &[0.0, 2.5, 5.5],
        &[("tilt_x", "cross.angle1"), ("tilt_z", "cross.angle2")],
    );
}

/// A shaft spinning about y carrying a collar on a joint along an inclined axis through an
/// offset point; `joint` is the TOML of that joint (or chain of joints) from `shaft` to `collar`.
fn collar(joint: &str, extra_bodies: &str) -> Compiled {
    let text = format!(
        r#"
name = "collar"
gravity = [0, -9.80665, 0]
[[bodies]]
name = "shaft"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0, 0.1, 0]
[[bodies]]
name = "collar"
mass = 0.7
inertia = [[0.004, 0.001, 0], [0.001, 0.006, 0.0005], [0, 0.0005, 0.005]]
cm = [0.3, 0.2, 0.05]
{extra_bodies}
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "shaft"
at = [0, 0, 0]
axis = [0, 1, 0]
drive = "speed"
{joint}
"#
    );
    Compiled::from_str(&text, "collar.toml").unwrap_or_else(|e| panic!("{e}"))
}

const MASSLESS: &str = "mass = 0\ninertia = [0, 0, 0]\ncm = [0, 0, 0]";

#[test]
fn a_cylindrical_joint_is_a_revolute_and_a_prismatic_on_one_axis() {
    let a = collar(
        r#"
[[joints]]
name = "sleeve"
type = "cylindrical"
parent = "shaft"
child = "collar"
at = [0.1, 0.2, 0]
axis = [1, 0.5, 0.2]
stiffness = [4, 60]
free = [0.3, 0.05]
damping = [0.02, 0.5]
initial = [0.3, 0.05]
"#,
        "",
    );
    let b = collar(
        r#"
[[joints]]
name = "turn"
type = "revolute"
parent = "shaft"
child = "carrier"
at = [0.1, 0.2, 0]
axis = [1, 0.5, 0.2]
stiffness = 4
free = 0.3
damping = 0.02
initial = 0.3
[[joints]]
name = "slide"
type = "prismatic"
parent = "carrier"
child = "collar"
axis = [1, 0.5, 0.2]
stiffness = 60
free = 0.05
damping = 0.5
initial = 0.05
"#,
        &format!("[[bodies]]\nname = \"carrier\"\n{MASSLESS}"),
    );
    equivalent(
        &a,
        &b,
        &[0.0, 3.0, 7.0],
        &[("sleeve.angle", "turn"), ("sleeve.slide", "slide")],
    );
}

#[test]
fn a_planar_joint_is_two_prismatics_and_a_revolute() {
    let a = collar(
        r#"
[[joints]]
name = "plate"
type = "planar"
parent = "shaft"
child = "collar"
at = [0.1, 0.2, 0]
axis = [0.2, 0.1, 1]
axis2 = [1, 0, 0]
stiffness = [50, 70, 3]
free = [0.02, -0.03, 0.2]
damping = [0.3, 0.3, 0.01]
"#,
        "",
    );
    // e₁ = the part of axis2 perpendicular to axis, e₂ = axis × e₁, written out.
    let n = [0.2f64, 0.1, 1.0];
    let nn = n.iter().map(|x| x * x).sum::<f64>().sqrt();
    let n = n.map(|x| x / nn);
    let e1 = [1.0 - n[0] * n[0], -n[0] * n[1], -n[0] * n[2]];
    let l = e1.iter().map(|x| x * x).sum::<f64>().sqrt();
    let e1 = e1.map(|x| x / l);
    let e2 = [
        n[1] * e1[2] - n[2] * e1[1],
        n[2] * e1[0] - n[0] * e1[2],
        n[0] * e1[1] - n[1] * e1[0],
    ];
    let v = |x: [f64; 3]| format!("[{:e}, {:e}, {:e}]", x[0], x[1], x[2]);
    let b = collar(
        &format!(
            r#"
[[joints]]
name = "x"
type = "prismatic"
parent = "shaft"
child = "p1"
axis = {}
stiffness = 50
free = 0.02
damping = 0.3
[[joints]]
name = "y"
type = "prismatic"
parent = "p1"
child = "p2"
axis = {}
stiffness = 70
free = -0.03
damping = 0.3
[[joints]]
name = "turn"
type = "revolute"
parent = "p2"
child = "collar"
at = [0.1, 0.2, 0]
axis = [0.2, 0.1, 1]
stiffness = 3
free = 0.2
damping = 0.01
"#,
            v(e1),
            v(e2)
        ),
        &format!("[[bodies]]\nname = \"p1\"\n{MASSLESS}\n[[bodies]]\nname = \"p2\"\n{MASSLESS}"),
    );
    equivalent(
        &a,
        &b,
        &[0.0, 2.0, 6.0],
        &[("plate.x", "x"), ("plate.y", "y"), ("plate.angle", "turn")],
    );
}

// The ball-jointed pendulum: mass m, centre of mass L below the ball, inertia It across and A
// about its axis (at the centre of mass), twist spring k; J = It + m L² about the ball.
const M: f64 = 2.0;
const L: f64 = 0.5;
const IT: f64 = 0.02;
const A: f64 = 0.01;
const K: f64 = 3.0;
const G: f64 = 9.80665;

fn ball_pendulum() -> Compiled {
    let text = format!(
        r#"
name = "ball pendulum"
gravity = [0, 0, -{G}]
[[bodies]]
name = "shaft"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0, 0, 0.1]
[[bodies]]
name = "bob"
mass = {M}
inertia = [{IT}, {IT}, {A}]
cm = [0, 0, -{L}]
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "shaft"
at = [0, 0, 0]
axis = [0, 0, 1]
drive = "speed"
[[joints]]
name = "ball"
type = "spherical"
parent = "shaft"
child = "bob"
at = [0, 0, 0]
stiffness = [0, 0, {K}]
initial = [0.8, 0, 0]
"#
    );
    Compiled::from_str(&text, "ball.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// Damped frequencies of the point's modes, ascending.
fn frequencies(pt: &Point) -> Vec<f64> {
    let mut f: Vec<f64> = pt.modes.iter().map(|m| m.damped_frequency).collect();
    f.sort_by(f64::total_cmp);
    f
}

fn close(a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= tol * y.abs().max(1.0), "{a:?} vs {b:?}");
    }
}

#[test]
fn a_ball_jointed_pendulum_hanging_still_and_spinning() {
    let model = ball_pendulum();
    assert_eq!(
        model
            .model()
            .coordinates
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>(),
        ["spin", "ball.rx", "ball.ry", "ball.rz"]
    );
    let j = IT + M * L * L;
    let mgl = M * G * L;
    // Below the critical speed (m g L = (J − A) Ω²) it hangs straight down. Seen from the
    // ground it is a hanging top spinning at Ω: J ü + A Ω ẑ×u̇ + m g L u = 0 whirls forward at
    // ω₁ and backward at ω₂, (√(A²Ω² + 4 J m g L) ± A Ω) / 2J; from the shaft's frame, where the
    // coordinates are, ω₁ − Ω and ω₂ + Ω. The twist (decoupled by symmetry) has ω² = k / A.
    for w in [0.0, 1.5, 3.0, 4.2] {
        assert!((j - A) * w * w < mgl);
        for direct in [false, true] {
            let pt = solve(&model, w, direct);
            for &q in &pt.equilibrium.q[1..] {
                assert!(q.abs() <= 1e-12, "{:?}", pt.equilibrium.q);
            }
            let root = (A * A * w * w + 4.0 * j * mgl).sqrt();
            let (f1, f2) = ((root + A * w) / (2.0 * j), (root - A * w) / (2.0 * j));
            let mut expected = vec![(f1 - w).abs(), f2 + w, (K / A).sqrt()];
            expected.sort_by(f64::total_cmp);
            close(&frequencies(&pt), &expected, 1e-9);
        }
    }
    // Above it, the conical equilibrium: cos θ = m g L / ((J − A) Ω²), a tilt about the
    // shaft's x axis, with p = 4 tan(θ/4) along it.
    for w in [5.0, 6.0, 7.0, 8.0] {
        let cos = mgl / ((j - A) * w * w);
        assert!(cos < 1.0);
        for direct in [false, true] {
            let q = solve(&model, w, direct).equilibrium.q;
            let theta = 4.0 * (q[1].abs() / 4.0).atan();
            assert!(
                (theta.cos() - cos).abs() <= 1e-11,
                "{q:?}: cos θ {} vs {cos}",
                theta.cos()
            );
            assert!(q[2].abs() <= 1e-12 && q[3].abs() <= 1e-12, "{q:?}");
        }
    }
}
