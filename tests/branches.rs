//! Which equilibrium a point is on. A conical pendulum (a rod on a ball joint under a spinning
//! shaft) with joint damping loses its hanging stability past Ω_c through a complex pair (its
//! two tilt directions make det K̂ touch zero without changing sign): the branch followed must
//! switch there whatever the sweep's step, land on the cone the closed form gives, and every
//! output must say which branch was taken and why.

mod common;

use common::run_with_deadline;
use modaltol::compiled::Compiled;
use modaltol::modal::ModeClass;
use modaltol::sweep::{Options, Sweep, point_at};
use nalgebra::{Matrix3, Vector3};
use std::time::Duration;

const G: f64 = 9.81;

/// The rod (mass `m`, length `l`, axial inertia `1e-3 m`) on a ball joint with damping `c`.
fn conical(m: f64, l: f64, c: f64) -> String {
    format!(
        "name = \"conical pendulum\"\ngravity = [0, -{G}, 0]\n[parameters]\nm = {m}\nL = {l}\n\
         [[bodies]]\nname = \"shaft\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\ncm = [0, 0.1, 0]\n\
         [[bodies]]\nname = \"rod\"\nmass = \"m\"\ninertia = [\"m*L^2/12\", \"1e-3*m\", \"m*L^2/12\"]\n\
         cm = [0, \"-L/2\", 0]\n\
         [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"shaft\"\n\
         at = [0, 0, 0]\naxis = [0, 1, 0]\ndrive = \"speed\"\n\
         [[joints]]\nname = \"ball\"\ntype = \"spherical\"\nparent = \"shaft\"\nchild = \"rod\"\n\
         at = [0, 0, 0]\ndamping = {c}\n"
    )
}

/// The rod's angle from the vertical from the ball joint's coordinates (scaled modified
/// Rodrigues parameters `p = 4 tan(θ/4) n`, docs/model-format.md).
fn tilt(p: &[f64]) -> f64 {
    let s = Vector3::new(p[0], p[1], p[2]) / 4.0;
    let k = s.cross_matrix();
    let n2 = s.norm_squared();
    let r = Matrix3::identity() + (k * k * 8.0 - k * (4.0 * (1.0 - n2))) / (1.0 + n2).powi(2);
    (r * Vector3::y()).y.clamp(-1.0, 1.0).acos()
}

/// The steady cone angle in the shaft's frame: `m g d sin θ = Ω² sin θ cos θ (I_t + m d² − I_a)`
/// with `d = L/2`, so hanging (θ = 0) below `Ω_c² = m g d / (I_t + m d² − I_a)` and
/// `cos θ = Ω_c²/Ω²` above.
fn cone(m: f64, l: f64, w: f64) -> f64 {
    let wc = critical(m, l);
    if w <= wc {
        0.0
    } else {
        (wc * wc / (w * w)).acos()
    }
}

/// `Ω_c` of [`cone`].
fn critical(m: f64, l: f64) -> f64 {
    let d = l / 2.0;
    (m * G * d / (m * l * l / 12.0 + m * d * d - 1e-3 * m)).sqrt()
}

#[test]
fn the_branch_followed_does_not_depend_on_the_step_and_is_the_stable_cone() {
    for (m, l, c) in [(1.0, 0.5, 0.01), (0.4, 1.0, 0.05), (3.0, 0.3, 0.002)] {
        let model = Compiled::from_str(&conical(m, l, c), "cone.toml").unwrap();
        let ball = model.model().coordinate("ball.rx").unwrap();
        let critical = critical(m, l);
        for step in [0.05, 0.1, 0.25] {
            let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
            let n = (1.6 * critical / step).round() as usize;
            for i in 0..=n {
                let w = step * i as f64;
                let pt = sweep.step(w).unwrap_or_else(|e| panic!("Ω = {w}: {e}"));
                let what = format!("m {m} L {l} c {c} step {step} Ω = {w} ({critical})");
                let q = &pt.equilibrium.q[ball..ball + 3];
                assert!(pt.stable(), "{what}: {:?}", pt.modes);
                assert!(
                    (tilt(q) - cone(m, l, w)).abs() < 1e-8,
                    "{what}: tilt {} against {}",
                    tilt(q),
                    cone(m, l, w)
                );
                // The rod's spin, and on the cone its azimuth, are held by nothing: rigid
                // modes, each with its own decay, and no spurious overdamped mode.
                let rigid = pt
                    .modes
                    .iter()
                    .filter(|x| x.class == ModeClass::Rigid)
                    .count();
                assert_eq!(rigid, if tilt(q) > 1e-3 { 2 } else { 1 }, "{what}");
                assert!(
                    pt.modes.iter().all(|x| x.class != ModeClass::Overdamped),
                    "{what}: {:?}",
                    pt.modes.iter().map(|x| x.class).collect::<Vec<_>>()
                );
                let first_past = w > critical && w - step <= critical;
                assert_eq!(
                    pt.branch.as_str(),
                    if first_past { "switched" } else { "stable" },
                    "{what}: {}",
                    pt.branch
                );
            }
        }
    }
}

#[test]
fn modal_takes_the_stable_branch_unless_asked_and_says_which_in_every_format() {
    let model = Compiled::from_str(&conical(1.0, 0.5, 0.01), "cone.toml").unwrap();
    let p = model.model().nominal();
    let stable = point_at(&model, &p, 6.0, &Options::default()).unwrap();
    assert!(stable.stable());
    assert_eq!(stable.branch.as_str(), "switched");
    let given = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    let hanging = point_at(&model, &p, 6.0, &given).unwrap();
    assert!(!hanging.stable());
    assert_eq!(hanging.branch.as_str(), "unstable");
    assert!(
        hanging.branch.to_string().contains("flutter"),
        "{}",
        hanging.branch
    );

    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cone.toml");
    std::fs::write(&file, conical(1.0, 0.5, 0.01)).unwrap();
    let f = file.to_str().unwrap();
    let run = |args: &[&str]| {
        let r = run_with_deadline(args, Duration::from_secs(60)).unwrap();
        assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
        r.stdout
    };
    for (branch, kind) in [("stable", "switched"), ("as-given", "unstable")] {
        let text = run(&["modal", f, "--speed", "6", "--branch", branch]);
        assert!(text.contains(&format!("branch: {kind}: ")), "{text}");
        let json: serde_json::Value = serde_json::from_str(&run(&[
            "modal", f, "--speed", "6", "--format", "json", "--branch", branch,
        ]))
        .unwrap();
        assert_eq!(json["branch"]["kind"], kind);
        assert_eq!(json["branch"]["origin"]["kind"], "initial_guess");
        assert!(
            json["branch"]["reason"]
                .as_str()
                .unwrap()
                .contains("initial guess")
        );
        let csv = run(&[
            "modal", f, "--speed", "6", "--format", "csv", "--branch", branch,
        ]);
        let mut rows = csv::Reader::from_reader(csv.as_bytes());
        let header = rows.headers().unwrap().clone();
        let (b, m) = (
            header.iter().position(|h| h == "branch").unwrap(),
            header.iter().position(|h| h == "message").unwrap(),
        );
        for row in rows.records() {
            let row = row.unwrap();
            assert_eq!(&row[b], kind);
            assert!(row[m].contains("unstable"), "{}", &row[m]);
        }
    }
    // A sweep says where it came from: the previous speed; and with `as-given` it stays on
    // the hanging equilibrium and says that it is unstable.
    let csv = run(&["sweep", f, "--speed", "5:6:0.5"]);
    assert!(
        csv.contains(
            ",switched,\"the equilibrium reached from the solution at 5 rad/s is unstable"
        ),
        "{csv}"
    );
    let csv = run(&["sweep", f, "--speed", "5:6:0.5", "--branch", "as-given"]);
    assert!(
        csv.contains(
            ",unstable,\"the equilibrium reached from the solution at 5.5 rad/s is unstable"
        ),
        "{csv}"
    );
}

/// On the stable cone no sample is on "another branch" and none is unstable, by the quadrature
/// or the Monte Carlo, whether the speeds start below Ω_c (the nominal sweep switches onto the
/// cone on the way) or past it (the nominal's first point is switched there from the model's
/// initial guess, and the samples, started from that point, make no switch of their own); the
/// cone's ω_d and ζ by the quadrature agree with Monte Carlo's 95 % interval.
#[test]
fn samples_on_the_cone_are_on_the_nominal_branch_and_stable() {
    use modaltol::analyze::{AnalyzeOptions, analyze};
    use modaltol::model::Sampling;
    use modaltol::montecarlo::McOptions;
    use modaltol::output::Quantity;
    use modaltol::quadrature::QuadOptions;
    use modaltol::table::Event;
    use modaltol::table::Method;
    let text = format!(
        "{}[[analysis.cases]]\nname = \"geometry\"\ntolerances = {{ m = \"3%\", L = \"2%\" }}\n",
        conical(1.0, 0.5, 0.01)
    );
    let model = Compiled::from_str(&text, "conical.toml").unwrap();
    for speeds in [vec![6.0, 7.0, 8.0], vec![0.0, 2.0, 4.0, 6.0, 7.0, 8.0]] {
        let opt = AnalyzeOptions {
            speeds: speeds.clone(),
            cases: model.model().analysis.cases.clone(),
            quadrature: Some(QuadOptions::default()),
            monte_carlo: Some(McOptions {
                samples: 200,
                seed: 5,
                sampling: Sampling::Lhs,
            }),
            threads: Some(1),
            ..Default::default()
        };
        let a = analyze(&model, &opt, &|_, _, _| {});
        assert!(a.failures.is_empty(), "{:?}", a.failures);
        for r in &a.probabilities {
            if matches!(r.event, Event::Unstable | Event::OtherBranch) && r.speed >= 6.0 {
                assert_eq!(r.probability, 0.0, "{speeds:?}: {r:?}");
            }
        }
        for speed in [7.0, 8.0] {
            // The one mode that is not rigid (numbered as the sweep tracks modes).
            let mode = a
                .rows
                .iter()
                .find(|r| {
                    r.speed == speed
                        && r.quantity == Quantity::DampedFrequency
                        && r.method() == Method::FirstOrder
                        && r.mean > 1.0
                })
                .unwrap()
                .mode;
            for q in [Quantity::DampedFrequency, Quantity::DampingRatio] {
                let find = |method| {
                    a.rows
                        .iter()
                        .find(|r| {
                            r.speed == speed
                                && r.quantity == q
                                && r.method() == method
                                && r.mode == mode
                        })
                        .unwrap()
                };
                let (quad, mc) = (find(Method::Quadrature), find(Method::MonteCarlo));
                let st = mc.mc().unwrap();
                assert!(
                    st.mean_ci.0 <= quad.mean && quad.mean <= st.mean_ci.1,
                    "{speeds:?} at {speed}: {quad:?} against {mc:?}"
                );
            }
        }
    }
}
