//! Force elements against closed forms and against the joint springs they can stand for, on
//! the recorded and the direct route.
//!
//! * `rotational_spring_damper`: about the hinge axis it is the hinge's own spring and damper
//!   (same equilibrium and eigenvalues to 1e-9, deflected by a free angle, on a spinning
//!   shaft); on a disk, λ = −ζω ± iω√(1−ζ²) with ω² = k/J, ζ = c/(2√(kJ)); about an axis at an
//!   angle to the hinge it measures the projected angle, so ω² = k (a·h)²/J.
//! * `bushing`: a body held by a bushing alone (three slides and a ball joint at its centre of
//!   mass) has the six roots of six uncoupled oscillators, k/m and k_r/J per axis; on a frame
//!   spinning at Ω, an isotropic bushing's whirl roots are i(√(k/m) ± Ω); and ∂ω/∂k by the
//!   analytic sensitivities equals 1/(2√(km)).
//! * `free` joint: the same body on one six-coordinate joint has the same roots as on the
//!   three slides and the ball joint, at rest and spinning.

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;
use modaltol::sensitivity::DesignPoint;

/// Equal roots on both routes at each speed, and equal values of the named coordinates.
fn equivalent(a: &Compiled, b: &Compiled, speeds: &[f64], coordinates: &[&str]) {
    for &w in speeds {
        for direct in [false, true] {
            let (pa, pb) = (solve(a, w, direct), solve(b, w, direct));
            same_roots(&roots(&pa), &roots(&pb), 1e-9);
            for name in coordinates {
                let qa = pa.equilibrium.q[a.model().coordinate(name).unwrap()];
                let qb = pb.equilibrium.q[b.model().coordinate(name).unwrap()];
                assert!(
                    (qa - qb).abs() <= 1e-10,
                    "{name}: {qa} vs {qb} at {w} rad/s"
                );
            }
        }
    }
}

fn model(text: &str) -> Compiled {
    Compiled::from_str(text, "forces.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// An arm with a full inertia on an inclined hinge of a shaft spinning about y; `hinge` holds
/// the hinge's spring fields and `forces` any force elements.
fn arm(hinge: &str, forces: &str) -> Compiled {
    model(&common::spinning_arm(
        "inertia = [[0.004, 0.001, 0], [0.001, 0.006, 0.0005], [0, 0.0005, 0.005]]",
        hinge,
        forces,
    ))
}

#[test]
fn a_rotational_spring_damper_about_the_hinge_is_the_hinge_spring() {
    let a = arm("stiffness = 4\nfree = 0.3\ndamping = 0.05", "");
    let b = arm(
        "",
        r#"
[[forces]]
name = "torsion"
type = "rotational_spring_damper"
body1 = "shaft"
body2 = "arm"
axis = [0.2, 0.3, 1]
stiffness = 4
free = 0.3
damping = 0.05
"#,
    );
    equivalent(&a, &b, &[0.0, 2.0, 4.5], &["hinge"]);
    // The body order does not matter: turned end for end, the element measures −θ about −a.
    let c = arm(
        "",
        r#"
[[forces]]
name = "torsion"
type = "rotational_spring_damper"
body1 = "arm"
body2 = "shaft"
axis = [-0.2, -0.3, -1]
stiffness = 4
free = 0.3
damping = 0.05
"#,
    );
    equivalent(&a, &c, &[0.0, 4.5], &["hinge"]);
}

/// A disk of inertia `J` about the z axis on a hinge about `hinge`, held by a rotational
/// spring-damper about `axis` to ground; no gravity.
fn disk(hinge: [f64; 3], axis: [f64; 3]) -> Compiled {
    model(&format!(
        r#"
name = "disk"
gravity = [0, 0, 0]
[parameters]
k = 3.0
[[bodies]]
name = "disk"
mass = 2
inertia = [[0.02, 0.003, 0.001], [0.003, 0.03, 0.002], [0.001, 0.002, 0.04]]
cm = [0, 0, 0]
[[joints]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "disk"
at = [0, 0, 0]
axis = {hinge:?}
[[forces]]
name = "torsion"
type = "rotational_spring_damper"
body1 = "ground"
body2 = "disk"
axis = {axis:?}
stiffness = "k"
damping = 0.01
"#
    ))
}

/// `J = hᵀ I h` for a unit `h` of the disk above.
fn inertia_about(h: [f64; 3]) -> f64 {
    let i = [
        [0.02, 0.003, 0.001],
        [0.003, 0.03, 0.002],
        [0.001, 0.002, 0.04],
    ];
    (0..3)
        .map(|r| (0..3).map(|c| h[r] * i[r][c] * h[c]).sum::<f64>())
        .sum()
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.map(|x| x / n)
}

/// The roots of `J s² + c s + k = 0`.
fn oscillator(j: f64, c: f64, k: f64) -> [C64; 2] {
    let (re, disc) = (-c / (2.0 * j), k / j - (c / (2.0 * j)).powi(2));
    [C64::new(re, disc.sqrt()), C64::new(re, -disc.sqrt())]
}

#[test]
fn a_disk_on_a_torsion_spring_has_the_closed_form_roots() {
    let h = unit([0.3, -0.2, 1.0]);
    let j = inertia_about(h);
    for direct in [false, true] {
        let pt = solve(&disk(h, h), 0.0, direct);
        same_roots(&roots(&pt), &oscillator(j, 0.01, 3.0), 1e-10);
    }
    // About an axis at an angle to the hinge, the element measures the angle projected onto
    // its plane, dθ/dφ = a·h: stiffness and damping both scale by (a·h)².
    let a = unit([0.0, 0.6, 1.0]);
    let cos = a.iter().zip(&h).map(|(x, y)| x * y).sum::<f64>();
    for direct in [false, true] {
        let pt = solve(&disk(h, a), 0.0, direct);
        let expected = oscillator(j, 0.01 * cos * cos, 3.0 * cos * cos);
        same_roots(&roots(&pt), &expected, 1e-10);
    }
}

/// A body of mass `m` and principal inertias `J` along the global axes, free in translation
/// (three slides through massless bodies) and rotation (a ball joint at its centre of mass),
/// held at that centre by a bushing to a frame; `spin` drives that frame about y.
fn held_by_a_bushing(spin: &str, stiffness: &str, damping: &str) -> Compiled {
    model(&held_by_a_bushing_text(spin, stiffness, damping))
}

fn held_by_a_bushing_text(spin: &str, stiffness: &str, damping: &str) -> String {
    format!(
        r#"
name = "bushed body"
gravity = [0, 0, 0]
[parameters]
k = 500.0
[[bodies]]
name = "frame"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0, 0, 0]
[[bodies]]
name = "sx"
mass = 0
inertia = [0, 0, 0]
cm = [0, 0, 0]
[[bodies]]
name = "sy"
mass = 0
inertia = [0, 0, 0]
cm = [0, 0, 0]
[[bodies]]
name = "sz"
mass = 0
inertia = [0, 0, 0]
cm = [0, 0, 0]
[[bodies]]
name = "body"
mass = 3
inertia = [0.05, 0.08, 0.11]
cm = [0.2, 0.1, -0.1]
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "frame"
at = [0, 0, 0]
axis = [0, 1, 0]
{spin}
[[joints]]
name = "x"
type = "prismatic"
parent = "frame"
child = "sx"
axis = [1, 0, 0]
[[joints]]
name = "y"
type = "prismatic"
parent = "sx"
child = "sy"
axis = [0, 1, 0]
[[joints]]
name = "z"
type = "prismatic"
parent = "sy"
child = "sz"
axis = [0, 0, 1]
[[joints]]
name = "ball"
type = "spherical"
parent = "sz"
child = "body"
at = [0.2, 0.1, -0.1]
[[forces]]
name = "mount"
type = "bushing"
body1 = "frame"
body2 = "body"
point1 = [0.2, 0.1, -0.1]
stiffness = {stiffness}
damping = {damping}
"#
    )
}

#[test]
fn a_body_held_by_a_bushing_has_six_uncoupled_oscillators() {
    let m = held_by_a_bushing(
        "drive = 0",
        "[\"k\", 700, 900, 20, 30, 40]",
        "[0.5, 0.6, 0.7, 0.01, 0.02, 0.03]",
    );
    let (k, c) = (
        [500.0, 700.0, 900.0, 20.0, 30.0, 40.0],
        [0.5, 0.6, 0.7, 0.01, 0.02, 0.03],
    );
    let mass = [3.0, 3.0, 3.0, 0.05, 0.08, 0.11];
    let expected: Vec<C64> = (0..6)
        .flat_map(|i| oscillator(mass[i], c[i], k[i]))
        .collect();
    for direct in [false, true] {
        let pt = solve(&m, 0.0, direct);
        same_roots(&roots(&pt), &expected, 1e-10);
    }
    // ∂ω_d/∂k of the x mode, exactly: ω_d = √(k/m − (c/2m)²).
    let pt = solve(&m, 0.0, false);
    let p = m.model().nominal();
    let s = DesignPoint::new(&m, &p, &pt)
        .analytic(&[m.model().parameter("k").unwrap()])
        .unwrap();
    let wd = (500.0 / 3.0 - (0.5f64 / 6.0).powi(2)).sqrt();
    let x_mode = pt
        .modes
        .iter()
        .position(|md| (md.damped_frequency - wd).abs() < 1e-8)
        .expect("the x mode");
    let d = s.variables[0].modes[x_mode].d_damped_frequency;
    let exact = 1.0 / (2.0 * 3.0 * wd);
    assert!((d - exact).abs() <= 1e-9 * exact, "{d} vs {exact}");
}

#[test]
fn an_isotropic_bushing_on_a_spinning_frame_whirls_at_the_natural_frequency_plus_and_minus_the_speed()
 {
    // In the frame spinning at Ω about y, with the bushing at the centre of mass (off the axis,
    // so the equilibrium is deflected outwards; the spring is linear, so the motion about it is
    // not changed), translation and rotation do not couple, and
    // m (ẍ − 2Ωż − Ω²x) + k x = 0,  m (z̈ + 2Ωẋ − Ω²z) + k z = 0,  m ÿ + k y = 0:
    // roots ±i(ω_n + Ω), ±i(ω_n − Ω) and ±iω_n with ω_n = √(k/m), whatever the rotations do.
    let m = held_by_a_bushing(
        "drive = \"speed\"",
        "[500, 500, 500, 20, 30, 40]",
        "[0, 0, 0, 0.01, 0.02, 0.03]",
    );
    let wn = (500.0f64 / 3.0).sqrt();
    for w in [3.0, 20.0] {
        for direct in [false, true] {
            let pt = solve(&m, w, direct);
            let found = roots(&pt);
            for f in [wn + w, (wn - w).abs(), wn] {
                for expected in [C64::new(0.0, f), C64::new(0.0, -f)] {
                    let d = found
                        .iter()
                        .map(|r| (r - expected).norm())
                        .fold(f64::INFINITY, f64::min);
                    assert!(d <= 1e-9 * f, "{expected} not among {found:?} at {w} rad/s");
                }
            }
        }
    }
}

#[test]
fn a_free_joint_is_three_slides_and_a_ball() {
    for spin in ["drive = 0", "drive = \"speed\""] {
        let stiffness = "[500, 700, 900, 20, 30, 40]";
        let damping = "[0.5, 0.6, 0.7, 0.01, 0.02, 0.03]";
        let chain = held_by_a_bushing(spin, stiffness, damping);
        let text = held_by_a_bushing_text(spin, stiffness, damping);
        let start = text.find("[[joints]]\nname = \"x\"").unwrap();
        let end = text.find("[[forces]]").unwrap();
        let mut bodies = text[..start].to_string();
        for slide in ["sx", "sy", "sz"] {
            bodies = bodies.replace(
                &format!("[[bodies]]\nname = \"{slide}\"\nmass = 0\ninertia = [0, 0, 0]\ncm = [0, 0, 0]\n"),
                "",
            );
        }
        let free = bodies
            + "[[joints]]\nname = \"float\"\ntype = \"free\"\nparent = \"frame\"\nchild = \"body\"\nat = [0.2, 0.1, -0.1]\n"
            + &text[end..];
        let free = model(&free);
        assert_eq!(free.model().coordinates.len(), 7);
        for w in [0.0, 3.0] {
            for direct in [false, true] {
                same_roots(
                    &roots(&solve(&free, w, direct)),
                    &roots(&solve(&chain, w, direct)),
                    1e-9,
                );
            }
        }
    }
}
