//! Cut joints: one spatial mechanism, a spinning RSUR four-bar (a crank on a revolute, a coupler
//! with a ball joint at the crank and a universal joint at the rocker, a rocker on a revolute),
//! written as three different spanning trees closed by different cut joints (`revolute` at the
//! rocker's hinge, `point` at the ball, `revolute` at the crank's hinge). All three are the same
//! physics, so they must give the same eigenvalues; and turning the whole model's reference
//! configuration by a rotation must change nothing.

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;

type M3 = [[f64; 3]; 3];

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn mul(r: &M3, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| r[i][k] * v[k]).sum())
}

/// Rotation by `angle` about the unit vector `n`.
fn rotation(n: [f64; 3], angle: f64) -> M3 {
    let (s, c) = angle.sin_cos();
    let l = n.iter().map(|x| x * x).sum::<f64>().sqrt();
    let [x, y, z] = n.map(|v| v / l);
    let v = 1.0 - c;
    [
        [c + x * x * v, x * y * v - z * s, x * z * v + y * s],
        [y * x * v + z * s, c + y * y * v, y * z * v - x * s],
        [z * x * v - y * s, z * y * v + x * s, c + z * z * v],
    ]
}

/// Which spanning tree, and so which cut joint.
#[derive(Clone, Copy)]
enum Cut {
    /// Tree frame–crank–ball–coupler–universal–rocker; cut: the rocker's hinge.
    RockerHinge,
    /// Trees frame–crank and frame–rocker–universal–coupler; cut: the ball (a point joint).
    Ball,
    /// Tree frame–rocker–universal–coupler–ball–crank; cut: the crank's hinge.
    CrankHinge,
}

/// The mechanism's model text with its reference configuration turned by `r`.
fn rsur(cut: Cut, r: &M3) -> String {
    let v = |x: [f64; 3]| {
        let y = mul(r, x);
        format!("[{:e}, {:e}, {:e}]", y[0], y[1], y[2])
    };
    // Inertia about the centre of mass, principal values along the reference axes, turned.
    let inertia = |d: [f64; 3]| {
        let m: M3 = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum())
        });
        let row = |r: [f64; 3]| format!("[{:e}, {:e}, {:e}]", r[0], r[1], r[2]);
        format!("[{}, {}, {}]", row(m[0]), row(m[1]), row(m[2]))
    };
    let (a0, a, b0, b) = (
        [0.0, 0.0, 0.0],
        [0.2, 0.0, 0.0],
        [0.5, 0.3, 0.15],
        [0.5, 0.3, 0.45],
    );
    let (x, z) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    // The universal joint's pin fixed in the coupler, perpendicular to the coupler and to the
    // rocker's pin (x).
    let pin = [0.0, 0.45, -0.3];
    let mut t = format!(
        r#"
name = "RSUR"
gravity = {g}
[[bodies]]
name = "frame"
mass = 2
inertia = {i_frame}
cm = [0.25, 0.15, 0]
[[bodies]]
name = "crank"
mass = 0.5
inertia = {i_crank}
cm = {c_crank}
[[bodies]]
name = "coupler"
mass = 0.8
inertia = {i_coupler}
cm = {c_coupler}
[[bodies]]
name = "rocker"
mass = 0.6
inertia = {i_rocker}
cm = {c_rocker}
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "frame"
at = {o}
axis = {z}
drive = "speed"
[[forces]]
name = "crank_spring"
type = "spring_damper"
body1 = "frame"
point1 = {s1}
body2 = "crank"
point2 = {a}
stiffness = 400
damping = 2
[[forces]]
name = "rocker_spring"
type = "spring_damper"
body1 = "frame"
point1 = {s2}
body2 = "rocker"
point2 = {b}
stiffness = 250
damping = 1.5
"#,
        g = v([0.0, 0.0, -9.80665]),
        i_frame = inertia([0.05, 0.04, 0.08]),
        i_crank = inertia([1e-4, 2e-3, 2e-3]),
        c_crank = v([0.1, 0.0, 0.0]),
        i_coupler = inertia([3e-3, 4e-3, 2e-3]),
        c_coupler = v([0.35, 0.15, 0.225]),
        i_rocker = inertia([5e-3, 5e-3, 2e-4]),
        c_rocker = v([0.5, 0.3, 0.3]),
        o = v(a0),
        z = v(z),
        s1 = v([0.2, 0.25, 0.0]),
        a = v(a),
        s2 = v([0.5, 0.05, 0.45]),
        b = v(b),
    );
    let joint = |name: &str, kind: &str, parent: &str, child: &str, geometry: String| {
        format!(
            "[[joints]]\nname = \"{name}\"\ntype = \"{kind}\"\nparent = \"{parent}\"\nchild = \"{child}\"\n{geometry}\n"
        )
    };
    let closure = |name: &str, kind: &str, b1: &str, b2: &str, geometry: String| {
        format!(
            "[[constraints]]\nname = \"{name}\"\ntype = \"{kind}\"\nbody1 = \"{b1}\"\nbody2 = \"{b2}\"\n{geometry}\n"
        )
    };
    let hinge = |at: [f64; 3], axis: [f64; 3]| format!("at = {}\naxis = {}", v(at), v(axis));
    let ball = |at: [f64; 3]| format!("at = {}", v(at));
    let universal = |axis: [f64; 3], axis2: [f64; 3]| {
        format!("at = {}\naxis = {}\naxis2 = {}", v(b), v(axis), v(axis2))
    };
    let point = |at: [f64; 3]| format!("point1 = {}", v(at));
    let hinge_cut =
        |at: [f64; 3], axis: [f64; 3]| format!("point1 = {}\naxis = {}", v(at), v(axis));
    match cut {
        Cut::RockerHinge => {
            t += &joint("crank_hinge", "revolute", "frame", "crank", hinge(a0, z));
            t += &joint("ball", "spherical", "crank", "coupler", ball(a));
            t += &joint("cross", "universal", "coupler", "rocker", universal(pin, x));
            t += &closure(
                "rocker_hinge",
                "revolute",
                "frame",
                "rocker",
                hinge_cut(b0, x),
            );
        }
        Cut::Ball => {
            t += &joint("crank_hinge", "revolute", "frame", "crank", hinge(a0, z));
            t += &joint("rocker_hinge", "revolute", "frame", "rocker", hinge(b0, x));
            t += &joint("cross", "universal", "rocker", "coupler", universal(x, pin));
            t += &closure("ball", "point", "crank", "coupler", point(a));
        }
        Cut::CrankHinge => {
            t += &joint("rocker_hinge", "revolute", "frame", "rocker", hinge(b0, x));
            t += &joint("cross", "universal", "rocker", "coupler", universal(x, pin));
            t += &joint("ball", "spherical", "coupler", "crank", ball(a));
            t += &closure(
                "crank_hinge",
                "revolute",
                "frame",
                "crank",
                hinge_cut(a0, z),
            );
        }
    }
    t
}

const SPEEDS: [f64; 3] = [0.0, 3.0, 6.0];

#[test]
fn one_mechanism_cut_at_three_places_gives_the_same_eigenvalues() {
    let models: Vec<Compiled> = [Cut::RockerHinge, Cut::Ball, Cut::CrankHinge]
        .map(|c| {
            Compiled::from_str(&rsur(c, &IDENTITY), "rsur.toml").unwrap_or_else(|e| panic!("{e}"))
        })
        .into();
    assert_eq!(
        models
            .iter()
            .map(|m| (
                m.model().coordinates.len(),
                m.model().n_constraints(),
                m.model().dof()
            ))
            .collect::<Vec<_>>(),
        [(7, 5, 1), (5, 3, 1), (7, 5, 1)]
    );
    for w in SPEEDS {
        for direct in [false, true] {
            let reference = roots(&solve(&models[0], w, direct));
            assert_eq!(reference.len(), 2);
            for m in &models[1..] {
                same_roots(&roots(&solve(m, w, direct)), &reference, 1e-9);
            }
        }
    }
}

#[test]
fn turning_the_reference_configuration_changes_nothing() {
    let turn = rotation([0.3, -0.8, 0.5], 1.1);
    for cut in [Cut::RockerHinge, Cut::Ball, Cut::CrankHinge] {
        let a = Compiled::from_str(&rsur(cut, &IDENTITY), "rsur.toml").unwrap();
        let b = Compiled::from_str(&rsur(cut, &turn), "turned.toml").unwrap();
        for w in SPEEDS {
            same_roots(
                &roots(&solve(&b, w, false)),
                &roots(&solve(&a, w, false)),
                1e-9,
            );
        }
    }
}

#[test]
fn the_shipped_example_is_this_mechanism() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/spinning_spatial_fourbar.toml");
    let example = Compiled::from_file(&file).unwrap_or_else(|e| panic!("{e}"));
    let ball = Compiled::from_str(&rsur(Cut::Ball, &IDENTITY), "rsur.toml").unwrap();
    for w in SPEEDS {
        same_roots(
            &roots(&solve(&example, w, false)),
            &roots(&solve(&ball, w, false)),
            1e-9,
        );
    }
}
