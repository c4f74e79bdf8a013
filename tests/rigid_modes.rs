//! Zero-frequency (rigid-body) modes of symmetric spinning bodies: a rod on a ball joint free
//! to spin about its own axis, a disk on a free joint whose bushing leaves its spin free, a
//! flywheel on an undriven bearing. Each has a root that is zero up to rounding; none may be
//! called unstable, underdamped at a rounding-level frequency or given a damping ratio, by
//! `modal`, `sweep`, the quadrature or the Monte Carlo. Generated over masses, lengths, dampers
//! and speeds (all below the speeds where the bodies' own equilibria lose stability).

use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::modal::ModeClass;
use modaltol::model::Sampling;
use modaltol::montecarlo::McOptions;
use modaltol::output::Quantity;
use modaltol::quadrature::QuadOptions;
use modaltol::sweep::{Options, Point, Sweep, initial_guess, point};
use modaltol::table::Event;
use modaltol::table::Method;

const SHAFT: &str = "[[bodies]]\nname = \"shaft\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\n\
    cm = [0, 0.1, 0]\n[[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\n\
    child = \"shaft\"\nat = [0, 0, 0]\naxis = [0, 1, 0]\ndrive = \"speed\"\n";

/// A rod hanging on a ball joint under a spinning shaft, axisymmetric about its own axis (y):
/// its spin about that axis is held by nothing. Critical speed about √(3g/2L).
fn ball_rod(m: f64, l: f64, damping: f64) -> String {
    format!(
        "gravity = [0, -9.81, 0]\n[parameters]\nm = {{ value = {m}, tolerance = \"3%\" }}\n\
         L = {{ value = {l}, tolerance = \"3%\" }}\n{SHAFT}\
         [[bodies]]\nname = \"rod\"\nmass = \"m\"\ninertia = [\"m*L^2/12\", \"1e-3*m\", \"m*L^2/12\"]\n\
         cm = [0, \"-L/2\", 0]\n[[joints]]\nname = \"ball\"\ntype = \"spherical\"\nparent = \"shaft\"\n\
         child = \"rod\"\nat = [0, 0, 0]\ndamping = {damping}\n\
         [[analysis.cases]]\nname = \"all\"\ntolerances = {{ m = \"3%\", L = \"3%\" }}\n"
    )
}

/// A disk on a free joint under the shaft, held by a bushing in every direction but its spin
/// about its own (vertical) axis.
fn free_disk(m: f64, k: f64, damping: f64) -> String {
    format!(
        "gravity = [0, -9.81, 0]\n[parameters]\nm = {{ value = {m}, tolerance = \"3%\" }}\n\
         k = {{ value = {k}, tolerance = \"5%\" }}\n{SHAFT}\
         [[bodies]]\nname = \"disk\"\nmass = \"m\"\ninertia = [\"0.01*m\", \"0.02*m\", \"0.01*m\"]\n\
         cm = [0, -0.2, 0]\n[[joints]]\nname = \"float\"\ntype = \"free\"\nparent = \"shaft\"\n\
         child = \"disk\"\nat = [0, -0.2, 0]\n\
         [[forces]]\nname = \"mount\"\ntype = \"bushing\"\nbody1 = \"shaft\"\nbody2 = \"disk\"\n\
         point1 = [0, -0.2, 0]\nstiffness = [\"k\", \"k\", \"k\", \"k/10\", 0, \"k/10\"]\n\
         damping = {damping}\n\
         [[analysis.cases]]\nname = \"all\"\ntolerances = {{ m = \"3%\", k = \"5%\" }}\n"
    )
}

/// A flywheel on an undriven bearing along the spin axis, beside an arm on a spring hinge (so
/// that the model has a mode with a frequency too).
fn flywheel(m: f64, k: f64, damping: f64) -> String {
    format!(
        "gravity = [0, -9.81, 0]\n[parameters]\nm = {{ value = {m}, tolerance = \"3%\" }}\n\
         k = {{ value = {k}, tolerance = \"5%\" }}\n{SHAFT}\
         [[bodies]]\nname = \"wheel\"\nmass = \"m\"\ninertia = [\"0.1*m\", \"0.2*m\", \"0.1*m\"]\n\
         cm = [0, 0.3, 0]\n[[joints]]\nname = \"bearing\"\ntype = \"revolute\"\nparent = \"shaft\"\n\
         child = \"wheel\"\nat = [0, 0.3, 0]\naxis = [0, 1, 0]\ndamping = {damping}\n\
         [[bodies]]\nname = \"arm\"\nmass = 0.5\ninertia = [0.001, 0.001, 0.001]\ncm = [0.2, 0, 0]\n\
         [[joints]]\nname = \"hinge\"\ntype = \"revolute\"\nparent = \"shaft\"\nchild = \"arm\"\n\
         at = [0, 0, 0]\naxis = [0, 0, 1]\nstiffness = \"k\"\ndamping = 0.01\n\
         [[analysis.cases]]\nname = \"all\"\ntolerances = {{ m = \"3%\", k = \"5%\" }}\n"
    )
}

/// The generated models with their number of rigid-body modes and speeds where they are
/// stable.
fn models() -> Vec<(String, usize, Vec<f64>)> {
    let mut out = Vec::new();
    for (m, l) in [(1.0f64, 0.5f64), (0.3, 1.2), (20.0, 0.2)] {
        let critical = (3.0 * 9.81 / (2.0 * l)).sqrt();
        let speeds: Vec<f64> = (0..5).map(|i| 0.19 * critical * i as f64).collect();
        for c in [0.0, 0.01, 1.0] {
            out.push((ball_rod(m, l, c), 1, speeds.clone()));
        }
    }
    for (m, k) in [(1.0, 1e4), (5.0, 3e3)] {
        for c in [0.0, 0.5] {
            out.push((free_disk(m, k, c), 1, vec![0.0, 2.0, 5.0, 10.0]));
            out.push((flywheel(m, k, c), 1, vec![0.0, 2.0, 5.0, 10.0]));
        }
    }
    out
}

/// Rigid-body modes are exactly `rigid` in number, with zero frequencies and no damping ratio;
/// no mode is unstable.
fn check(pt: &Point, rigid: usize, what: &str) {
    let classes: Vec<ModeClass> = pt.modes.iter().map(|m| m.class).collect();
    assert_eq!(
        classes.iter().filter(|&&c| c == ModeClass::Rigid).count(),
        rigid,
        "{what}: {classes:?} {:?}",
        pt.modes.iter().map(|m| m.root.lambda).collect::<Vec<_>>()
    );
    assert!(pt.stable(), "{what}: {classes:?}");
    for m in pt.modes.iter().filter(|m| m.class == ModeClass::Rigid) {
        assert_eq!(m.natural_frequency.to_bits(), 0f64.to_bits(), "{what}");
        assert_eq!(m.damped_frequency.to_bits(), 0f64.to_bits(), "{what}");
        assert!(m.damping_ratio.is_nan(), "{what}");
    }
    for m in pt.modes.iter().filter(|m| m.class != ModeClass::Rigid) {
        assert!(
            m.natural_frequency > 1e-3 && m.damping_ratio.is_finite(),
            "{what}: {m:?}"
        );
    }
}

#[test]
fn symmetric_spinning_bodies_have_rigid_modes_and_no_spurious_instability_in_modal_and_sweep() {
    for (text, rigid, speeds) in models() {
        let model = Compiled::from_str(&text, "rigid.toml").unwrap_or_else(|e| panic!("{e}"));
        let p = model.model().nominal();
        let mut sweep = Sweep::new(&model, p.clone(), Options::default());
        for &w in &speeds {
            let what = format!("{} Ω = {w}", &text[..60].replace('\n', " "));
            let pt = sweep.step(w).unwrap_or_else(|e| panic!("{what}: {e}"));
            check(&pt, rigid, &format!("sweep {what}"));
            let q0 = initial_guess(model.model(), &p, w).unwrap();
            let pt = point(&model, &p, w, &q0, &Options::default())
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            check(&pt, rigid, &format!("modal {what}"));
        }
    }
}

#[test]
fn the_quadrature_and_the_monte_carlo_see_no_instability_in_a_rigid_body_mode() {
    for (text, _, speeds) in models().into_iter().step_by(3) {
        let model = Compiled::from_str(&text, "rigid.toml").unwrap();
        let opt = AnalyzeOptions {
            speeds: speeds.clone(),
            cases: model.model().analysis.cases.clone(),
            quadrature: Some(QuadOptions::default()),
            monte_carlo: Some(McOptions {
                samples: 64,
                seed: 3,
                sampling: Sampling::Lhs,
            }),
            threads: Some(1),
            ..Default::default()
        };
        let a = analyze(&model, &opt, &|_, _, _| {});
        assert!(a.failures.is_empty(), "{:?}", a.failures);
        let unstable: Vec<_> = a
            .probabilities
            .iter()
            .filter(|r| r.event == Event::Unstable && r.probability > 0.0)
            .collect();
        assert!(unstable.is_empty(), "{unstable:?}");
        let quadrature = a
            .probabilities
            .iter()
            .filter(|r| r.event == Event::Unstable && r.method == Method::Quadrature)
            .count();
        assert_eq!(
            quadrature,
            speeds.len(),
            "the quadrature reports P(unstable)"
        );
        // The rigid mode (the first, ω_n = 0) has no damping ratio by any method, and says
        // why; its ω_d is 0 in every sample, and the Taylor methods, which have no derivative
        // of it, say so.
        let sampling = [Method::Quadrature, Method::MonteCarlo, Method::Analytic];
        for r in a.rows.iter().filter(|r| r.mode == Some(0)) {
            if r.quantity == modaltol::output::Quantity::DampingRatio
                || !sampling.contains(&r.method())
            {
                assert!(r.mean.is_nan() && r.missing.is_some(), "{r:?}");
            } else {
                assert_eq!((r.mean, r.std), (0.0, 0.0), "{r:?}");
            }
        }
    }
}

/// A node of the quadrature whose |H| has no value (a rigid-body mode is a resonance at zero
/// excitation frequency, so at rest |H| is unbounded at every node) keeps its modes: their ω_d
/// and ζ rows are filled (at rest the two tilt modes are a double pair, which the Taylor
/// methods cannot expand), within the order of σ² of the nominal values, and |H| alone is
/// left empty with the resonance as its reason, never read as 0.
#[test]
fn a_node_without_a_transfer_value_keeps_its_modes() {
    let text = format!(
        "{}[analysis]\ntransfer = {{ input = \"ball.rx\", output = \"ball.rx\", order = 1 }}\n",
        ball_rod(1.0, 0.5, 0.01)
    );
    let model = Compiled::from_str(&text, "ball_rod_transfer.toml").unwrap();
    let opt = AnalyzeOptions {
        speeds: vec![0.0, 1.0],
        cases: model.model().analysis.cases.clone(),
        quadrature: Some(QuadOptions::default()),
        monte_carlo: None,
        ..Default::default()
    };
    let a = analyze(&model, &opt, &|_, _, _| {});
    let row = |speed: f64, q: Quantity, mode: Option<usize>, method: Method| {
        a.rows
            .iter()
            .find(|r| r.speed == speed && r.quantity == q && r.mode == mode && r.method() == method)
            .unwrap_or_else(|| panic!("no row {speed} {q:?} {mode:?} {method:?}"))
    };
    for method in [Method::Quadrature, Method::Analytic, Method::FirstOrder] {
        let h = row(0.0, Quantity::TransferMagnitude, None, method);
        assert!(h.mean.is_nan() && h.missing.is_some(), "{h:?}");
        let h = row(1.0, Quantity::TransferMagnitude, None, method);
        assert!(h.mean > 0.0 && h.missing.is_none(), "{h:?}");
    }
    let p = model.model().nominal();
    for speed in [0.0, 1.0] {
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        let nominal = point(&model, &p, speed, &q0, &Options::default()).unwrap();
        // The analysis numbers modes as its sweep tracks them: compared with the nearest.
        for mode in [1, 2] {
            for q in [Quantity::DampedFrequency, Quantity::DampingRatio] {
                let quad = row(speed, q, Some(mode), Method::Quadrature);
                assert!(quad.missing.is_none(), "{quad:?}");
                let near = nominal.modes[1..].iter().any(|m| {
                    let value = match q {
                        Quantity::DampedFrequency => m.damped_frequency,
                        _ => m.damping_ratio,
                    };
                    (quad.mean - value).abs() <= 1e-3 * value.abs()
                });
                assert!(
                    near && quad.std > 0.0,
                    "{quad:?} against {:?}",
                    nominal.modes
                );
            }
        }
    }
}

/// A rigid-body mode has no frequency, so it does not enter a frequency requirement: on the
/// flywheel (its wheel free on its bearing, an arm on a spring hinge beside it) a separation
/// requirement over every mode is decided by the arm's mode alone, whose margin is the
/// separation of its ω_d from the engine order by hand; read as ω_d = 0, the rigid mode
/// would have given `0.85 Ω`. A `frequency` requirement likewise, and one asked of the rigid
/// mode by number fails: it has no frequency to meet it with.
#[test]
fn a_rigid_body_mode_enters_no_frequency_requirement() {
    use modaltol::margins::{State, carriers, margin};
    use modaltol::pair::Carriers;
    let requirements = "[[requirements]]\nname = \"clear\"\nkind = \"separation\"\n\
        orders = [1]\nmargin = \"15%\"\n\
        [[requirements]]\nname = \"floor\"\nkind = \"frequency\"\nmin = 1.0\n\
        [[requirements]]\nname = \"wheel\"\nkind = \"frequency\"\nmin = 1.0\nmode = 1\n";
    let text = format!("{}{requirements}", flywheel(1.0, 1e4, 0.0));
    let model = Compiled::from_str(&text, "rigid.toml").unwrap();
    let p = model.model().nominal();
    for speed in [2.0, 10.0, 400.0] {
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        let pt = point(&model, &p, speed, &q0, &Options::default()).unwrap();
        check(&pt, 1, "flywheel");
        assert_eq!(pt.modes[0].class, ModeClass::Rigid);
        let arm = pt.modes[1].damped_frequency;
        let c = carriers(&pt, None);
        let st = State {
            speed,
            carriers: Carriers::new(&c),
            same_branch: true,
        };
        let [clear, floor, wheel] = [0, 1, 2].map(|r| margin(&model.model().requirements[r], &st));
        let by_hand = (0.85 * speed - arm).max(arm - 1.15 * speed);
        assert!(
            (clear - by_hand).abs() <= 1e-12 * speed,
            "{speed}: {clear} vs {by_hand}"
        );
        assert!(
            (floor - (arm - 1.0)).abs() <= 1e-12 * arm,
            "{speed}: {floor}"
        );
        assert_eq!(wheel, f64::NEG_INFINITY, "{speed}");
    }
}

/// A rigid-body mode has no frequency: the Campbell diagram draws no line for it (it was a
/// line along ω = 0 crossing every engine order at the origin), and marks no critical speed of
/// it.
#[test]
fn the_campbell_diagram_draws_no_rigid_body_mode() {
    use modaltol::plots::{Display, plots};
    let model = Compiled::from_str(&flywheel(1.0, 1e4, 0.0), "rigid.toml").unwrap();
    let opt = AnalyzeOptions {
        speeds: vec![0.0, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0],
        cases: model.model().tolerance_cases(&[]).unwrap(),
        quadrature: None,
        ..Default::default()
    };
    let a = analyze(&model, &opt, &|_: &str, _: usize, _: usize| {});
    for p in a.nominal.iter().flatten() {
        assert_eq!(p.modes[0].class, ModeClass::Rigid);
    }
    let (plots, critical) = plots(model.model(), &a, Display::default());
    let c = plots.iter().find(|p| p.stem == "campbell").unwrap();
    assert!(!c.svg.contains("\nmode 1"), "the rigid mode is drawn");
    assert!(c.svg.contains("\nmode 2"), "the arm's mode is not drawn");
    assert!(critical.iter().all(|cs| cs.mode != 0), "{critical:?}");
}
