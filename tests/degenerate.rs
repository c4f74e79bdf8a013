//! Degenerate mechanisms: each is reported per speed (never a panic or a silent NaN) and the
//! rest of the run goes on.

mod common;

use common::{example, example_text};
use modaltol::compiled::Compiled;
use modaltol::modal::ModeClass;
use modaltol::sweep::{Options, Sweep, initial_guess, point};

/// The governor with one more body (a small flap hinged on the collar), and, with `duplicate`,
/// a second copy of the link1 cut joint: its equation is a combination of the others.
fn flapped_governor(duplicate: bool) -> Compiled {
    let mut text = example_text("governor.toml");
    let link3 = text[text.find("[[constraints]]\nname = \"link1\"").unwrap()
        ..text.find("[[constraints]]\nname = \"link2\"").unwrap()]
        .replace("link1", "link3");
    let link3 = if duplicate { link3 } else { String::new() };
    text.push_str(&format!(
        "\n[[bodies]]\nname = \"flap\"\nmass = 0.1\ninertia = [1e-3, 1e-3, 1e-3]\ncm = [0.05, 0.05, 0]\n\n[[joints]]\nname = \"flap_hinge\"\ntype = \"revolute\"\nparent = \"collar\"\nchild = \"flap\"\nat = [0, 0.05, 0]\naxis = [0, 0, 1]\nstiffness = 5\ndamping = 0.1\n\n{link3}"
    ));
    Compiled::from_str(&text, "redundant.toml").unwrap()
}

#[test]
fn a_duplicated_cut_joint_is_dropped_as_redundant() {
    // Its equation is dependent on the others as drawn: dropped, the degrees of freedom counted
    // from the rank (the governor's 1 and the flap's), and the mechanism the one without it.
    let model = flapped_governor(true);
    let dropped: usize = model
        .model()
        .constraints
        .iter()
        .map(|c| c.dropped.len())
        .sum();
    assert_eq!(dropped, 1);
    assert_eq!(model.model().dof(), 2);
    let plain = flapped_governor(false);
    let mut a = Sweep::new(&model, model.model().nominal(), Options::default());
    let mut b = Sweep::new(&plain, plain.model().nominal(), Options::default());
    for w in [0.5, 1.0, 2.0] {
        let (pa, pb) = (a.step(w).unwrap(), b.step(w).unwrap());
        assert_eq!(pa.modes.len(), pb.modes.len());
        for (x, y) in pa.modes.iter().zip(&pb.modes) {
            let (x, y) = (x.root.lambda, y.root.lambda);
            assert!(
                (x - y).norm() <= 1e-9 * y.norm().max(1.0),
                "{x} vs {y} at {w}"
            );
        }
    }
}

#[test]
fn a_loop_that_cannot_close_fails_cleanly() {
    // Two 0.5 m links from the origin cannot reach a distance of 1 m from the point (3, 0, 0).
    let text = r#"
gravity = [0, -9.81, 0]
[[bodies]]
name = "a"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0.25, 0, 0]
[[bodies]]
name = "b"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0.75, 0, 0]
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "a"
at = [0, 0, 0]
axis = [0, 1, 0]
drive = "speed"
[[joints]]
name = "j1"
type = "revolute"
parent = "a"
child = "b"
at = [0.5, 0, 0]
axis = [0, 0, 1]
[[bodies]]
name = "c"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [1.0, 0, 0]
[[joints]]
name = "j2"
type = "revolute"
parent = "b"
child = "c"
at = [1.0, 0, 0]
axis = [0, 0, 1]
[[constraints]]
name = "unreachable"
type = "distance"
body1 = "ground"
point1 = [3, 0, 0]
body2 = "c"
point2 = [1.0, 0, 0]
length = 0.2
"#;
    let model = Compiled::from_str(text, "open_loop.toml").unwrap();
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    for w in [0.0, 0.5, 1.0] {
        let err = sweep.step(w).expect_err("the loop cannot close");
        let msg = err.to_string();
        assert!(msg.contains("equilibrium"), "{msg}");
    }
}

#[test]
fn repeated_eigenvalues_give_two_identical_modes() {
    // Isotropic hinges and a massless yoke: at rest the two swing modes coincide.
    let text = example_text("spinning_universal_pendulum.toml")
        .replace(
            "kx = { value = 30.0, tolerance = \"5%\" }",
            "kx = { value = 45.0, tolerance = \"5%\" }",
        )
        .replace(
            "mass = 0.2\ninertia = [1e-3, 2e-3, 1e-3]",
            "mass = 0\ninertia = [0, 0, 0]",
        );
    let model = Compiled::from_str(&text, "isotropic.toml").unwrap();
    let p = model.model().nominal();
    let pt = point(
        &model,
        &p,
        0.0,
        &initial_guess(model.model(), &p, 0.0).unwrap(),
        &Options::default(),
    )
    .unwrap();
    assert_eq!(pt.modes.len(), 2);
    let (a, b) = (&pt.modes[0], &pt.modes[1]);
    assert!(
        (a.damped_frequency - b.damped_frequency).abs() < 1e-9 * a.damped_frequency,
        "{} {}",
        a.damped_frequency,
        b.damped_frequency
    );
    for m in &pt.modes {
        assert_eq!(m.class, ModeClass::Underdamped);
        assert!(
            m.root
                .right
                .iter()
                .all(|z| z.re.is_finite() && z.im.is_finite())
        );
    }
    // Spinning splits them (gyroscopic coupling) and the sweep tracks both without failing.
    let mut sweep = Sweep::new(&model, p, Options::default());
    for i in 0..=20 {
        let pt = sweep.step(0.2 * i as f64).unwrap();
        assert!(pt.modes.iter().all(|m| m.damped_frequency.is_finite()));
    }
}

#[test]
fn an_unstable_equilibrium_is_reported_as_such() {
    // Past √(3g/2L) without the branch switch, the hanging pendulum is reported unstable.
    let model = example("rotating_pendulum.toml");
    let opt = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    let pt = point(&model, &model.model().nominal(), 4.5, &[0.0, 0.0], &opt).unwrap();
    assert_eq!(pt.modes[0].class, ModeClass::Unstable);
    assert!(pt.modes[0].root.lambda.re > 0.0 && !pt.stable());
}

#[test]
fn an_arm_hinged_about_the_spin_axis_is_a_rigid_body_mode_solved_fast() {
    // Found by the long fuzz run: one arm of the 13-variable governor hinged about a direction
    // within 1e-15 of the spin axis has a neutral coordinate: the equilibria form a continuum.
    // Newton's residual reaches rounding level while LU steps (noise through a nearly singular
    // Jacobian) never met the step test; it ran to its 60-iteration limit at every node of the
    // quadrature, then failed fast as "not isolated". The least-squares step through the
    // singular Jacobian now converges at once, and the neutral coordinate is a rigid-body mode.
    let text = example_text("multi_arm_governor_13_variables.toml");
    let at = text.find("name = \"hinge3\"").unwrap();
    let axis = "axis = [0.866025403784439, 0, 0.5]";
    let k = at + text[at..].find(axis).unwrap();
    let text = format!(
        "{}axis = [0.866025403784439, 1e15, 0.5]{}",
        &text[..k],
        &text[k + axis.len()..]
    );
    let model = Compiled::from_str(&text, "neutral.toml").unwrap();
    let p = model.model().nominal();
    for w in [0.5, 1.0, 2.0] {
        let q0 = initial_guess(model.model(), &p, w).unwrap();
        let pt = point(&model, &p, w, &q0, &Options::default()).expect("a neutral equilibrium");
        assert!(
            pt.equilibrium.iterations < 20,
            "{}",
            pt.equilibrium.iterations
        );
        let rigid = pt
            .modes
            .iter()
            .filter(|m| m.class == ModeClass::Rigid)
            .count();
        assert_eq!(
            rigid,
            1,
            "Ω = {w}: {:?}",
            pt.modes.iter().map(|m| m.class).collect::<Vec<_>>()
        );
        assert!(pt.stable(), "a rigid-body mode is not an instability");
    }
}
