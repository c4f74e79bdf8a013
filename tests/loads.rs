//! Applied loads (`[[loads]]`) against closed forms of the rotating pendulum (a uniform rod of
//! mass m, length L on a hinge about z, the shaft spinning about y; hinge damping c):
//!
//! - a **dead** horizontal force F at the tip (ground axes), at rest: `V(θ) = −(mgL/2) cos θ −
//!   F L sin θ`, so `tan θ* = 2F/(mg)` and the stiffness `k = (mgL/2) cos θ* + F L sin θ*` (the
//!   load's own geometric stiffness included); the roots of `I s² + c s + k` with `I = mL²/3`;
//! - a **follower** force F at the tip, perpendicular to the rod and turning with it, at speed
//!   Ω: a constant hinge moment F L, so `(mgL/2) sin θ − IΩ² sin θ cos θ = F L` and
//!   `k = (mgL/2) cos θ − IΩ² cos 2θ` (no load stiffness);
//! - a torque on the rod about the hinge axis (in either frame) equals a generalised force on
//!   the hinge coordinate; a tolerance on the load's magnitude gives the exact derivative.
//!
//! Both routes (direct and recorded program) are checked.

mod common;

use common::{example_text, roots, same_roots, solve};
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;
use modaltol::model::Case;
use modaltol::output::Quantity;
use modaltol::sweep::{Options, Sweep};
use modaltol::table::Method;
use num_dual::{Dual64, DualNum};

const G: f64 = 9.80665;
const M: f64 = 3.0;
const L: f64 = 1.0;
const C: f64 = 3.0;

/// The pendulum with `extra` (TOML) appended.
fn pendulum(extra: &str) -> Compiled {
    let text = format!("{}\n{extra}", example_text("rotating_pendulum.toml"));
    Compiled::from_str(&text, "loads.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// The same rod hinged to the ground (no spin: a load fixed in ground axes stays steady), with
/// `extra` (TOML) appended.
fn hinged(extra: &str) -> Compiled {
    let text = format!(
        r#"
name = "hinged rod"
gravity = [0, -9.80665, 0]

[parameters]
m = 3.0
L = 1.0
c = 3.0

[[bodies]]
name = "rod"
mass = "m"
inertia = ["m*L^2/12", 0, "m*L^2/12"]
cm = [0, "-L/2", 0]

[[joints]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "rod"
at = [0, 0, 0]
axis = [0, 0, 1]
initial = 0.3
damping = "c"
{extra}"#
    );
    Compiled::from_str(&text, "hinged.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// The roots of `I s² + c s + k`.
fn pair(k: f64) -> [C64; 2] {
    let i = M * L * L / 3.0;
    let d = C * C - 4.0 * i * k;
    let (re, im) = if d < 0.0 {
        (-C / (2.0 * i), (-d).sqrt() / (2.0 * i))
    } else {
        panic!("overdamped: choose another load")
    };
    [C64::new(re, im), C64::new(re, -im)]
}

/// The hinge angle and roots at `speed` by both routes.
fn check(model: &Compiled, speed: f64, theta: f64, k: f64) {
    for direct in [false, true] {
        let pt = solve(model, speed, direct);
        let q = pt.equilibrium.q[model.model().coordinate("hinge").unwrap()];
        assert!(
            (q - theta).abs() < 1e-10,
            "θ* {q} vs {theta} (direct: {direct})"
        );
        same_roots(&roots(&pt), &pair(k), 1e-10);
    }
}

#[test]
fn a_dead_tip_force_at_rest_equals_its_closed_form() {
    let f = 5.0;
    let m = hinged(&format!(
        r#"
[[loads]]
name = "pull"
type = "force"
body = "rod"
point = [0, "-L", 0]
force = [{f}, 0, 0]
"#
    ));
    let theta = (2.0 * f / (M * G)).atan();
    let k = 0.5 * M * G * L * theta.cos() + f * L * theta.sin();
    check(&m, 0.0, theta, k);
}

/// A dead load on the spinning pendulum's rod is steady where nothing turns: at speed 0 it
/// equals the hinged rod's closed form; at a turning speed it is refused, also in a sweep that
/// started at rest.
#[test]
fn a_dead_load_on_a_driven_body_is_accepted_at_rest_and_refused_turning() {
    let f = 5.0;
    let load = format!(
        r#"
[[loads]]
name = "pull"
type = "force"
body = "rod"
point = [0, "-L", 0]
force = [{f}, 0, 0]
"#
    );
    let m = pendulum(&load);
    let theta = (2.0 * f / (M * G)).atan();
    let k = 0.5 * M * G * L * theta.cos() + f * L * theta.sin();
    check(&m, 0.0, theta, k);
    let mut sweep = Sweep::new(&m, m.model().nominal(), Options::default());
    assert!(sweep.step(0.0).is_ok());
    for speed in [0.5, 1.0] {
        let e = sweep.step(speed).expect_err("turning").to_string();
        assert!(e.contains("no steady state"), "{speed}: {e}");
    }
}

#[test]
fn a_follower_tip_force_while_spinning_equals_its_closed_form() {
    let (f, w) = (4.0, 5.0);
    let m = pendulum(&format!(
        r#"
[[loads]]
name = "follow"
type = "force"
body = "rod"
point = [0, "-L", 0]
force = [{f}, 0, 0]
frame = "body"
"#
    ));
    let i = M * L * L / 3.0;
    // The swung-out root of (mgL/2) sin θ − IΩ² sin θ cos θ − F L, by Newton from the
    // unloaded angle.
    let g = |t: f64| 0.5 * M * G * L * t.sin() - i * w * w * t.sin() * t.cos() - f * L;
    let dg = |t: f64| 0.5 * M * G * L * t.cos() - i * w * w * (2.0 * t).cos();
    let mut theta = (3.0 * G / (2.0 * L * w * w)).acos();
    for _ in 0..50 {
        theta -= g(theta) / dg(theta);
    }
    assert!(g(theta).abs() < 1e-13);
    check(&m, w, theta, dg(theta));
}

#[test]
fn a_torque_about_the_hinge_is_a_generalised_force_on_it_and_its_tolerance_is_exact() {
    let torque = |frame: &str| {
        pendulum(&format!(
            r#"
[[loads]]
name = "twist"
type = "torque"
body = "rod"
torque = [0, 0, 2.5]
frame = "{frame}"
"#
        ))
    };
    let generalised = pendulum(
        r#"
[[loads]]
name = "twist"
type = "coordinate"
coordinate = "hinge"
value = 2.5
"#,
    );
    let same = |a: &Compiled, b: &Compiled, w: f64| {
        for direct in [false, true] {
            let (pa, pb) = (solve(a, w, direct), solve(b, w, direct));
            let hinge = |m: &Compiled, p: &modaltol::sweep::Point| {
                p.equilibrium.q[m.model().coordinate("hinge").unwrap()]
            };
            let (qa, qb) = (hinge(a, &pa), hinge(b, &pb));
            assert!((qa - qb).abs() < 1e-11, "at {w}: {qa} vs {qb}");
            same_roots(&roots(&pa), &roots(&pb), 1e-10);
        }
    };
    // Turning with the rod, on the spinning pendulum.
    for w in [0.0, 3.0, 5.0] {
        same(&torque("body"), &generalised, w);
    }
    // In ground axes, on the rod hinged to the ground (the hinge axis is z there).
    let load = |kind: &str| {
        if kind == "torque" {
            "[[loads]]\nname = \"t\"\ntype = \"torque\"\nbody = \"rod\"\ntorque = [0, 0, 2.5]\n"
        } else {
            "[[loads]]\nname = \"t\"\ntype = \"coordinate\"\ncoordinate = \"hinge\"\nvalue = 2.5\n"
        }
    };
    same(&hinged(load("torque")), &hinged(load("coordinate")), 0.0);
    // A tolerance on the torque T: at rest sin θ* = 2T/(mgL), k = (mgL/2) cos θ*, and the
    // first-order σ of ω_d is |dω_d/dT| σ_T with the derivative of the closed form.
    let text = format!(
        "{}\n[[loads]]\nname = \"twist\"\ntype = \"coordinate\"\ncoordinate = \"hinge\"\nvalue = \"T\"\n",
        example_text("rotating_pendulum.toml")
            .replacen(
                "[parameters]\n",
                "[parameters]\nT = { value = 2.5, tolerance = \"6%\" }\n",
                1
            )
            // T alone toleranced.
            .replacen("L = { value = 1.0, tolerance = \"3%\" }", "L = 1.0", 1)
    );
    let m = Compiled::from_str(&text, "loads.toml").unwrap();
    let case = Case::from_parameters(m.model());
    let opt = AnalyzeOptions {
        speeds: vec![0.0],
        cases: vec![case],
        quadrature: None,
        monte_carlo: None,
        ..Default::default()
    };
    let a = analyze(&m, &opt, &|_, _, _| {});
    let row = a
        .rows
        .iter()
        .find(|r| {
            r.method() == Method::FirstOrder
                && r.quantity == Quantity::DampedFrequency
                && r.mode == Some(0)
        })
        .expect("a first-order row");
    let wd = |t: Dual64| {
        let i = M * L * L / 3.0;
        let s = t * (2.0 / (M * G * L));
        let k = (-(s * s) + 1.0).sqrt() * (0.5 * M * G * L);
        ((k * (4.0 * i) - C * C).sqrt()) / (2.0 * i)
    };
    let d = wd(Dual64::new(2.5, 1.0));
    let sigma_t = 2.5 * 0.06 / 3.0;
    let std = d.eps.abs() * sigma_t;
    assert!(
        (row.mean - d.re).abs() < 1e-10 && (row.std - std).abs() < 1e-10 * std,
        "{} ± {} vs {} ± {std}",
        row.mean,
        row.std,
        d.re
    );
}

#[test]
fn bad_loads_are_refused_at_their_place() {
    for (load, expect) in [
        ("type = \"push\"\nbody = \"rod\"", "unknown type 'push'"),
        (
            "type = \"force\"\nbody = \"rod\"\nforce = [1, 0, 0]",
            "needs 'point'",
        ),
        (
            "type = \"force\"\nbody = \"rod\"\npoint = [0, 0, 0]\nforce = [1, 0, 0]\ntorque = [0, 0, 1]",
            "has no 'torque'",
        ),
        (
            "type = \"torque\"\nbody = \"ground\"\ntorque = [0, 0, 1]",
            "give a body",
        ),
        (
            "type = \"torque\"\nbody = \"rod\"\ntorque = [0, 0, 1]\nframe = \"world\"",
            "unknown frame 'world'",
        ),
        (
            "type = \"coordinate\"\ncoordinate = \"spin\"\nvalue = 1",
            "is driven",
        ),
        (
            "type = \"coordinate\"\ncoordinate = \"nope\"\nvalue = 1",
            "no joint coordinate 'nope'",
        ),
        (
            "type = \"coordinate\"\ncoordinate = \"hinge\"",
            "needs 'value'",
        ),
        (
            "type = \"coordinate\"\ncoordinate = \"hinge\"\nvalue = \"1/0\"",
            "division by zero",
        ),
    ] {
        let text = format!(
            "{}\n[[loads]]\nname = \"bad\"\n{load}\n",
            example_text("rotating_pendulum.toml")
        );
        let e = match Compiled::from_str(&text, "bad.toml") {
            Ok(_) => panic!("accepted: {load}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(expect) && e.contains("bad.toml:"), "{load}: {e}");
    }
}
