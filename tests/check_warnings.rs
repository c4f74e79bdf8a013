//! `check`'s warnings: modelling mistakes that load without an error but leave every answer
//! saying less than its author meant (issue 58), each detected on a model that makes it, with
//! its fix in the message, and absent from the shipped examples that do not make it. And the
//! requirements `check` lists.

mod common;

use common::{example, example_text};
use modaltol::compiled::Compiled;
use modaltol::report::{check_report, check_summary, solved_warnings};
use statrs::distribution::{ContinuousCDF, Normal};

fn model(text: &str) -> Compiled {
    Compiled::from_str(text, "user.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// The number before `%` in the warning `w` that says what fraction crosses zero.
fn percent(w: &str) -> f64 {
    let at = w.find(" % of").expect("a percentage");
    let start = w[..at].rfind(' ').unwrap() + 1;
    w[start..at].parse().unwrap()
}

#[test]
fn the_shipped_examples_warn_of_nothing() {
    for entry in std::fs::read_dir("examples").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let name = path.file_name().unwrap().to_str().unwrap().to_string();
            let m = example(&name);
            assert!(
                m.model().warnings().is_empty(),
                "{name}: {:?}",
                m.model().warnings()
            );
            let solved = solved_warnings(&m);
            if name == "conical_pendulum.toml" {
                // Its rod's spin about its own axis is meant free: the warning names it.
                assert!(
                    solved.len() == 1
                        && solved[0].contains("mode 1 is a rigid-body mode")
                        && solved[0].contains("ball.ry"),
                    "{name}: {solved:?}"
                );
            } else {
                assert!(solved.is_empty(), "{name}: {solved:?}");
            }
        }
    }
}

/// The governor with its spindle's drive taken away: every speed analysed is the mechanism at
/// rest. The same model analysed at rest only says nothing (a structure at rest is meant).
#[test]
fn a_model_whose_speed_drives_nothing_is_warned_of() {
    let text = example_text("governor.toml");
    let undriven = text.replacen("drive = \"speed\"\n", "", 1);
    assert_ne!(undriven, text);
    let warnings = model(&undriven).model().warnings();
    assert!(
        warnings.len() == 1
            && warnings[0].contains("no joint is driven by the speed")
            && warnings[0].contains("drive = \"speed\""),
        "{warnings:?}"
    );
    assert!(check_summary(model(&undriven).model()).contains("  warning: no joint is driven"));
    let at_rest = undriven.replace("speed = \"0:5:0.01\"", "speed = \"0:0:1\"");
    assert_ne!(at_rest, undriven);
    assert!(model(&at_rest).model().warnings().is_empty());
}

/// A ±200 % tolerance on the spring rate: its band reaches −1000 N/m, and the share of samples
/// below zero is the closed form `Φ(−3 k/T)` for a normal whose tolerance is 3σ (Φ(−1.5) here),
/// `(T − k)/(2T)` for a uniform one. A case's tolerance is looked at too, once per value; a
/// tolerance of 99 % says nothing.
#[test]
fn a_tolerance_through_zero_is_warned_of_with_the_share_of_samples_beyond_it() {
    let text = example_text("governor.toml");
    let own = "spring_k = { value = 1000.0, tolerance = \"3%\" }";
    assert!(text.contains(own));
    for (tolerance, distribution, share) in [
        ("200%", "", Normal::standard().cdf(-1.5)),
        ("200%", ", distribution = \"uniform\"", 0.25),
        ("1500", "", Normal::standard().cdf(-2.0)),
    ] {
        let changed = text.replace(
            own,
            &format!("spring_k = {{ value = 1000.0, tolerance = \"{tolerance}\"{distribution} }}"),
        );
        let changed = changed.replace("tolerance = \"1500\"", "tolerance = 1500");
        let warnings = model(&changed).model().warnings();
        assert_eq!(warnings.len(), 1, "{tolerance}: {warnings:?}");
        let w = &warnings[0];
        assert!(
            w.contains("'spring_k'") && w.contains("below its value"),
            "{w}"
        );
        assert!(
            (percent(w) - 100.0 * share).abs() < 1e-3,
            "{tolerance}: {w} vs {share}"
        );
    }
    let in_case = text.replace(
        "tolerances = { spring_k = \"12%\" }",
        "tolerances = { spring_k = \"120%\" }",
    );
    assert_ne!(in_case, text);
    let warnings = model(&in_case).model().warnings();
    assert!(
        warnings.len() == 1 && warnings[0].contains("in case 'k12'"),
        "{warnings:?}"
    );
    let below = text.replace(own, "spring_k = { value = 1000.0, tolerance = \"99%\" }");
    assert!(model(&below).model().warnings().is_empty());
}

/// A requirement whose range was written in rpm (150–200 for 1.5–2 rad/s): beyond the
/// `[analysis]` speeds, which `analyze` would refuse; `check` says so, naming it, in rad/s
/// and rpm. `check` lists every requirement in words.
#[test]
fn a_requirement_beyond_the_analysed_speeds_is_warned_of_and_requirements_are_listed() {
    let text = example_text("governor_specification.toml");
    let summary = check_summary(model(&text).model());
    assert!(summary.contains("  requirements (3):"), "{summary}");
    for name in ["clear_of_1x_2x", "damped", "stable"] {
        assert!(summary.contains(&format!("    {name} ")), "{summary}");
    }
    assert!(summary.contains("for 1.5 ≤ Ω ≤ 2 rad/s"), "{summary}");
    let rpm = text.replacen("speeds = [1.5, 2.0]", "speeds = [150, 200]", 1);
    assert_ne!(rpm, text);
    let warnings = model(&rpm).model().warnings();
    assert!(
        warnings.len() == 1
            && warnings[0].contains("'clear_of_1x_2x'")
            && warnings[0].contains("rpm")
            && warnings[0].contains("`analyze` refuses"),
        "{warnings:?}"
    );
}

/// `check` says which frame each joint's modes are seen from: the governor's arms and sleeve
/// turn with its driven spindle; the Friswell rotor's nodes are measured from ground (their
/// spin comes after their translations and tilts), so its whirl is seen from the fixed frame.
#[test]
fn check_names_the_frame_of_each_joint_s_modes() {
    let governor = common::example("governor.toml");
    let text = check_summary(governor.model());
    assert!(
        text.contains("    rotating with 'spin': arm1, arm2, slide\n"),
        "{text}"
    );
    assert!(!text.contains("fixed (ground)"), "{text}");
    let rotor = common::example("friswell_5_9_1.toml");
    let text = check_summary(rotor.model());
    assert!(
        text.contains(
            "    fixed (ground): shaft_0, shaft_1, shaft_2, shaft_3, shaft_4, shaft_5, shaft_6\n"
        ),
        "{text}"
    );
    assert!(!text.contains("rotating with"), "{text}");
}

/// The tutorial's pendulum with a collar on its shaft. Free to turn about the shaft (an
/// axisymmetric body nothing holds), the collar is a rigid-body mode that `check` names by its
/// joint, with the fix; free to slide along it under gravity, the model has no equilibrium,
/// and `check` says so with where to look. The pendulum alone warns of neither.
#[test]
fn check_solves_the_model_and_names_a_rigid_body_mode_or_a_missing_equilibrium() {
    let pendulum = example_text("tutorial/pendulum.toml");
    assert!(solved_warnings(&model(&pendulum)).is_empty());
    let collar = |kind: &str| {
        format!(
            "{pendulum}\n[[bodies]]\nname = \"collar\"\nmass = 0.2\ninertia = [0.001, 0.002, 0.001]\n\
             cm = [0, 0.1, 0]\n\n[[joints]]\nname = \"collar_joint\"\ntype = \"{kind}\"\n\
             parent = \"shaft\"\nchild = \"collar\"\nat = [0, 0.1, 0]\naxis = [0, 1, 0]\n"
        )
    };
    let turning = model(&collar("revolute"));
    let w = solved_warnings(&turning);
    assert!(
        w.len() == 1
            && w[0].contains("is a rigid-body mode (a zero root)")
            && w[0].contains("collar_joint")
            && w[0].contains("restrain it"),
        "{w:?}"
    );
    let report = check_report(&turning);
    assert!(
        report.contains("  warning: at rest (the model gives no [analysis] speed) mode "),
        "{report}"
    );
    let sliding = model(&collar("prismatic"));
    let w = solved_warnings(&sliding);
    assert!(
        w.len() == 1 && w[0].contains("the model has no result") && w[0].contains("modaltol modal"),
        "{w:?}"
    );
}
