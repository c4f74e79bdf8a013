//! Degrees of freedom counted from the constraint rank where the equations' count says less:
//!
//! - the pin-closed parallelogram of the IFToMM benchmark drawn in a **tilted plane** (every
//!   point, axis and gravity turned by one rotation): its out-of-plane equations are no longer
//!   rows of zeros but rounding-level combinations, still found redundant; equal to the
//!   closed form as in the plane z = 0;
//! - **Bricard's orthogonal linkage**, six equal links along a skew hexagon of a cube's edges,
//!   six revolutes with consecutive axes perpendicular: 5 free coordinates and a revolute cut's 5
//!   equations count no degree of freedom, yet the loop moves with one (Bricard 1897; Baker,
//!   "The Bricard linkages", *Mech. Mach. Theory* 15, 1980). One equation is dropped, the
//!   linkage swings under gravity far from its drawing with every equation, dropped or not,
//!   holding; closed at another joint it is the same mechanism; a hexagon that is not Bricard's
//!   has no degree of freedom and is refused by the count.

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;
use nalgebra::{Rotation3, Unit, Vector3};

/// A vector as a TOML array.
fn arr(v: &Vector3<f64>) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

/// The benchmark parallelogram (m = l = 1, k = 25, free length √2, closed by a pin at the
/// rocker's ground end) with every position, axis and gravity turned by `r`.
fn tilted_fourbar(r: &Rotation3<f64>) -> String {
    let p = |x: f64, y: f64| arr(&(r * Vector3::new(x, y, 0.0)));
    let (ex, ey, ez) = (
        arr(&(r * Vector3::x())),
        arr(&(r * Vector3::y())),
        arr(&(r * Vector3::z())),
    );
    let rod = |name: &str, cm: String, along_y: bool| {
        let inertia = if along_y {
            "[0.08333333333333333, 0, 0.08333333333333333]"
        } else {
            "[0, 0.08333333333333333, 0.08333333333333333]"
        };
        format!(
            "[[bodies]]\nname = \"{name}\"\nmass = 1\ninertia = {inertia}\nx_axis = {ex}\ny_axis = {ey}\ncm = {cm}\n"
        )
    };
    let pin = |name: &str, parent: &str, child: &str, at: String, initial: f64| {
        format!(
            "[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nparent = \"{parent}\"\nchild = \"{child}\"\nat = {at}\naxis = {ez}\ninitial = {initial}\n"
        )
    };
    format!(
        r#"name = "tilted fourbar"
gravity = {gravity}
{crank}{coupler}{rocker}{j1}{j2}{j3}
[[constraints]]
name = "ground_pin"
type = "revolute"
body1 = "rocker"
point1 = {cut}
body2 = "ground"
axis = {ez}

[[forces]]
name = "diagonal"
type = "spring_damper"
body1 = "ground"
point1 = {o}
body2 = "coupler"
point2 = {b}
stiffness = 25
free = "sqrt(2)"
"#,
        gravity = arr(&(r * Vector3::new(0.0, -9.81, 0.0))),
        crank = rod("crank", p(0.0, 0.5), true),
        coupler = rod("coupler", p(0.5, 1.0), false),
        rocker = rod("rocker", p(1.0, 0.5), true),
        j1 = pin("crank_pin", "ground", "crank", p(0.0, 0.0), 0.6),
        j2 = pin("coupler_pin", "crank", "coupler", p(0.0, 1.0), -0.6),
        j3 = pin("rocker_pin", "coupler", "rocker", p(1.0, 1.0), 0.6),
        cut = p(1.0, 0.0),
        o = p(0.0, 0.0),
        b = p(1.0, 1.0),
    )
}

/// The parallelogram's closed form (see `tests/fourbar_benchmark.rs`): φ* and the undamped
/// roots `±i √(K/M)`.
fn parallelogram() -> (f64, [C64; 2]) {
    let (m, l, k, g) = (1.0, 1.0, 25.0, 9.81);
    let l0 = 2f64.sqrt() * l;
    let d = |p: f64| 2.0 * l * (p / 2.0).cos();
    let d1 = |p: f64| -l * (p / 2.0).sin();
    let d2 = |p: f64| -0.5 * l * (p / 2.0).cos();
    let v1 = |p: f64| 2.0 * m * g * l * p.cos() + k * (d(p) - l0) * d1(p);
    let v2 = |p: f64| -2.0 * m * g * l * p.sin() + k * (d1(p) * d1(p) + (d(p) - l0) * d2(p));
    let mut phi = 2.2;
    for _ in 0..50 {
        phi -= v1(phi) / v2(phi);
    }
    let w = (v2(phi) / (5.0 * m * l * l / 3.0)).sqrt();
    (phi, [C64::new(0.0, w), C64::new(0.0, -w)])
}

#[test]
fn a_pin_closed_planar_loop_in_a_tilted_plane_keeps_its_degree_of_freedom() {
    let (phi, exact) = parallelogram();
    for (axis, angle) in [
        (Vector3::new(1.0, 2.0, 3.0), 0.7),
        (Vector3::new(-0.3, 1.0, 0.1), 2.4),
        (Vector3::new(1.0, 0.0, 0.0), std::f64::consts::FRAC_PI_2),
    ] {
        let r = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle);
        let m = Compiled::from_str(&tilted_fourbar(&r), "tilted.toml")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.model().dof(), 1, "tilted by {angle} about {axis:?}");
        assert_eq!(m.model().constraints[0].dropped.len(), 3);
        let crank = m.model().coordinate("crank_pin").unwrap();
        for direct in [false, true] {
            let pt = solve(&m, 0.0, direct);
            let p = std::f64::consts::FRAC_PI_2 + pt.equilibrium.q[crank];
            assert!((p - phi).abs() < 1e-11, "φ* = {p} vs {phi}");
            same_roots(&roots(&pt), &exact, 1e-11);
        }
    }
}

/// The skew hexagon of a unit cube's edges: the joints' points and axes, joint `i` at `P_i`
/// with its axis perpendicular to both edges meeting there. Link `i` runs from `P_i` to
/// `P_{i+1}`; link 6 (from `P_6` to `P_1`) is the ground.
const HEXAGON: [([f64; 3], [f64; 3]); 6] = [
    ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
    ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ([1.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
    ([1.0, 1.0, 1.0], [0.0, 1.0, 0.0]),
    ([0.0, 1.0, 1.0], [0.0, 0.0, 1.0]),
    ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
];

/// Bricard's linkage with joint 4 moved by `shift` (zero: Bricard's), each moving link a rod of
/// 1 kg from its joint to the next, gravity along −z with a tilt so that no symmetry holds it,
/// a spring on joint 1, and the loop cut at joint `cut` (2..=5, 0-based: the cut joint's
/// index): the tree runs from the ground both ways round to the links meeting there.
fn bricard(cut: usize, shift: f64) -> String {
    let mut pts: Vec<Vector3<f64>> = HEXAGON.iter().map(|(p, _)| Vector3::from(*p)).collect();
    pts[3].z += shift;
    let axes: Vec<Vector3<f64>> = HEXAGON.iter().map(|(_, a)| Vector3::from(*a)).collect();
    let mut text =
        String::from("name = \"Bricard's orthogonal linkage\"\ngravity = [0.5, 0.3, -9.81]\n");
    let link = |i: usize| format!("link{}", i + 1);
    for i in 0..5 {
        let mid = (pts[i] + pts[i + 1]) / 2.0;
        text += &format!(
            "[[bodies]]\nname = \"{}\"\nmass = 1\ninertia = [0.08, 0.08, 0.08]\ncm = {}\n",
            link(i),
            arr(&mid)
        );
    }
    // Joint i joins link i−1 (link 6: the ground) and link i. Below the cut the tree runs
    // forward from joint 0; from the cut on it runs backward from joint 5 (ground → link 5).
    let body = |i: usize| {
        if i == 5 {
            "ground".to_string()
        } else {
            link(i)
        }
    };
    for i in 0..6 {
        let at = arr(&pts[i]);
        let axis = arr(&axes[i]);
        let spring = if i == 0 { "stiffness = 40\n" } else { "" };
        let prev = body((i + 5) % 6);
        if i == cut {
            text += &format!(
                "[[constraints]]\nname = \"j{i}\"\ntype = \"revolute\"\nbody1 = \"{}\"\npoint1 = {at}\nbody2 = \"{prev}\"\naxis = {axis}\n",
                body(i)
            );
        } else {
            let (parent, child) = if i < cut {
                (prev, body(i))
            } else {
                (body(i), prev)
            };
            text += &format!(
                "[[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\nparent = \"{parent}\"\nchild = \"{child}\"\nat = {at}\naxis = {axis}\n{spring}"
            );
        }
    }
    text
}

#[test]
fn bricards_linkage_moves_with_the_degree_of_freedom_its_count_denies() {
    let mut results = Vec::new();
    for cut in [2, 5] {
        let m = Compiled::from_str(&bricard(cut, 0.0), "bricard.toml")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.model().dof(), 1, "cut at joint {cut}");
        assert_eq!(m.model().constraints[0].dropped.len(), 1);
        let j0 = m.model().coordinate("j0").unwrap();
        for direct in [false, true] {
            let pt = solve(&m, 0.0, direct);
            // Far from the drawing (gravity and the spring fold it), every equation holds.
            let q = &pt.equilibrium.q;
            assert!(q[j0].abs() > 0.1, "joint 0 at {}", q[j0]);
            use modaltol::mechanics::{System, dynamics, kinematics};
            let sys = System::new(m.model(), &m.model().nominal(), 0.0).unwrap();
            let phi = dynamics::constraints_at(&sys, q);
            let dropped = dynamics::dropped_values(&sys, &kinematics::poses(&sys, q));
            assert_eq!(dropped.len(), 1);
            let worst = phi
                .iter()
                .chain(dropped.iter().map(|(_, v)| v))
                .fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(
                worst < 1e-12,
                "cut at {cut}: a closure equation is off by {worst}"
            );
            results.push((q[j0], roots(&pt)));
        }
    }
    // Closed at joint 2 or at joint 5, the same mechanism: joint 0's angle and the roots.
    let (q0, r0) = &results[0];
    for (q, r) in &results[1..] {
        assert!((q - q0).abs() < 1e-11, "{q} vs {q0}");
        same_roots(r, r0, 1e-10);
    }
    // A hexagon that is not Bricard's (joint 3 moved up 0.1): rigid, refused by the count.
    let e = match Compiled::from_str(&bricard(5, 0.1), "bricard.toml") {
        Ok(_) => panic!("a rigid hexagon accepted"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("no degree of freedom"), "{e}");
}
