//! Property-based fuzzing (proptest) of expression parsing and evaluation and of model
//! validation, run in CI: arbitrary text and random byte mutations of the valid examples never
//! make the library panic, and evaluation never returns a silent NaN.
//!
//! Inputs that once broke something are kept in `tests/fuzz_corpus/` and replayed by
//! `fuzz_corpus_replays`. Longer runs: `PROPTEST_CASES=100000 cargo test --release --test fuzz`.

mod common;

use modaltol::compiled::Compiled;
use modaltol::model::Expr;
use modaltol::sweep::{Options, initial_guess, point};
use proptest::prelude::*;

fn lookup(s: &str) -> Option<usize> {
    ["a", "b", "L"].iter().position(|n| *n == s)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000),
        // Failing seeds are kept beside the corpus (replayed by proptest on the next run).
        failure_persistence: Some(Box::new(proptest::test_runner::FileFailurePersistence::Direct("tests/fuzz_corpus/proptest-regressions.txt"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn expressions_parse_or_fail_cleanly(s in "[-+*/^()a-zL0-9., eEpisqrtcoanlbx_]{0,60}") {
        if let Ok(e) = Expr::parse(&s, &lookup)
            && let Ok(v) = e.eval::<f64>(&[1.5, -2.0, 0.25], 3.0)
        {
            prop_assert!(v.is_finite(), "{s} → {v}");
        }
    }

    #[test]
    fn arbitrary_text_never_panics_the_validator(s in "\\PC{0,400}") {
        let _ = Compiled::from_str(&s, "fuzz.toml");
    }

    #[test]
    fn mutated_examples_validate_or_fail_cleanly(
        which in 0usize..5,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
    ) {
        let name = ["rotating_pendulum.toml", "governor.toml", "spinning_universal_pendulum.toml", "spinning_spatial_fourbar.toml", "rotor_on_rubber_mounts.toml"][which];
        let mut bytes = common::example_text(name).into_bytes();
        for (at, byte) in &edits {
            let i = at.index(bytes.len());
            bytes[i] = *byte;
        }
        if let Ok(model) = Compiled::from_bytes(&bytes, "mutant.toml") {
            // A mutant that validates must also solve or fail cleanly at a speed.
            let p = model.model().nominal();
            if let Ok(q0) = initial_guess(model.model(), &p, 1.0)
                && let Ok(pt) = point(&model, &p, 1.0, &q0, &Options::default())
            {
                for m in &pt.modes {
                    prop_assert!(m.damped_frequency.is_finite() && m.natural_frequency.is_finite());
                }
            }
        }
    }
}

#[test]
fn fuzz_corpus_replays() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_corpus");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let path = f.unwrap().path();
        if path.is_dir() {
            continue; // the pipeline corpus, replayed by tests/fuzz_pipeline.rs
        }
        let bytes = std::fs::read(path).unwrap();
        if let Ok(model) = Compiled::from_bytes(&bytes, "corpus.toml") {
            let p = model.model().nominal();
            if let Ok(q0) = initial_guess(model.model(), &p, 1.0) {
                let _ = point(&model, &p, 1.0, &q0, &Options::default());
            }
        }
        n += 1;
    }
    assert!(n >= 1, "the corpus is empty");
}

/// A requirement of any kind over any range, as the docs allow writing it (and some they do
/// not): its TOML.
fn requirement_text(kind: usize, mode: usize, a: f64, b: f64, from: f64, to: f64) -> String {
    let mode = if mode == 0 {
        String::new()
    } else {
        format!("mode = {mode}\n")
    };
    let body = match kind {
        0 => format!("kind = \"frequency\"\nmin = {a}\n"),
        1 => format!("kind = \"frequency\"\nmax = {b}\n"),
        2 => format!("kind = \"avoid\"\nband = [{a}, {b}]\n"),
        3 => format!("kind = \"damping\"\nmin = {}\n", a / 20.0),
        4 => "kind = \"underdamped\"\n".into(),
        5 => "kind = \"stable\"\n".into(),
        6 => "kind = \"branch\"\n".into(),
        7 => format!(
            "kind = \"separation\"\norders = [1, 2]\nmargin = \"{}%\"\n",
            a
        ),
        _ => "kind = \"separation\"\norders = [1]\nmargin = \"api684\"\n".into(),
    };
    format!("[[requirements]]\n{mode}{body}speeds = [{from}, {to}]\n")
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(24),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Random requirements (every kind, ranges on, between and off the grid) and targets on
    /// the pendulum: the model validates or is refused cleanly; an analysis (quadrature and a
    /// small Monte Carlo) never panics, every probability is in [0, 1] with its interval around
    /// it, and every value of `limits.csv` is a number or blank with a reason.
    #[test]
    fn random_requirements_give_honest_yields_and_limits(
        reqs in prop::collection::vec(
            (0usize..9, 0usize..3, 0.0f64..8.0, 0.0f64..8.0, 3.5f64..6.0, 0.0f64..1.0),
            1..4,
        ),
        target in prop::sample::select(vec![1e-300, 1e-6, 0.5, 0.9, 0.9973, 1.0 - 1e-12]),
        two in any::<bool>(),
    ) {
        let mut text = common::example_text("rotating_pendulum.toml");
        for (kind, mode, a, b, from, width) in &reqs {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            text.push_str(&requirement_text(*kind, *mode, *lo, *hi, *from, from + width));
        }
        text.push_str(&format!("[allocation]\ntarget_yield = {target}\n"));
        if two {
            text.push_str("[[analysis.cases]]\nname = \"two\"\ntolerances = { L = \"6%\", c = \"20%\" }\n");
        }
        let Ok(model) = Compiled::from_str(&text, "fuzz.toml") else { return Ok(()) };
        let m = model.model();
        let grid: Vec<f64> = (0..=5).map(|i| 3.5 + 0.5 * i as f64).collect();
        if m.check_requirement_speeds(&grid).is_err() {
            return Ok(());
        }
        let opt = modaltol::analyze::AnalyzeOptions {
            speeds: m.judged_speeds(&grid),
            cases: vec![m.analysis.cases.last().unwrap().clone()],
            monte_carlo: Some(modaltol::montecarlo::McOptions {
                samples: 16,
                seed: 3,
                sampling: modaltol::model::Sampling::Random,
            }),
            ..Default::default()
        };
        let a = modaltol::analyze::analyze(&model, &opt, &|_, _, _| {});
        for y in &a.yields {
            prop_assert!((0.0..=1.0).contains(&y.probability) || y.probability.is_nan(), "{y:?}");
            if !y.probability.is_nan() {
                prop_assert!(y.ci.0 <= y.probability + 1e-12 && y.probability <= y.ci.1 + 1e-12, "{y:?}");
            }
        }
        for l in a.yields.iter().filter_map(|y| y.limit.as_ref()) {
            if let Some([est, low, high]) = l.margin {
                prop_assert!(!(est.is_nan() || low.is_nan() || high.is_nan()), "{l:?}");
                prop_assert!(low <= est && est <= high, "{l:?}");
            }
        }
        let rows = modaltol::report::limit_rows(m, &a);
        let width = modaltol::report::LIMITS_HEADER.len();
        for r in &rows {
            prop_assert_eq!(r.len(), width);
            for cell in r {
                let l = cell.to_lowercase();
                prop_assert!(!l.contains("inf") && !l.contains("nan"), "{:?}", r);
            }
            let blank = r[11].is_empty() || r[12].is_empty() || r[13].is_empty();
            let has_unit = !r[10].is_empty();
            if has_unit && blank {
                prop_assert!(!r[width - 1].is_empty(), "a blank without a reason: {:?}", r);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(6),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Random cost tables (tiny to huge b, k up to 400, any max) and targets: `allocate`
    /// answers with finite tolerances and costs, or refuses with a reason; never a panic, an
    /// infinite cost or a NaN tolerance.
    #[test]
    fn random_costs_and_targets_allocate_or_refuse_cleanly(
        b in prop::sample::select(vec![1e-300, 1e-6, 1.0, 1e6, 1e300]),
        k in prop::sample::select(vec![0.5, 1.0, 2.0, 40.0, 400.0]),
        max in prop::sample::select(vec!["", "max = \"0.5%\", ", "max = 0.2, "]),
        target in prop::sample::select(vec![0.5, 0.9, 0.9973, 0.999999]),
    ) {
        let w = 5.0;
        let text = format!(
            "{}\n[[requirements]]\nname = \"clear\"\nkind = \"frequency\"\nmode = 1\nmin = 3.6\nspeeds = [{w}, {w}]\n\n[allocation]\ntarget_yield = {target}\ncost = {{ L = {{ {max}b = {b}, k = {k} }} }}\n",
            common::example_text("rotating_pendulum.toml")
        );
        let Ok(model) = Compiled::from_str(&text, "fuzz.toml") else { return Ok(()) };
        let case = model.model().analysis.cases[0].clone();
        let opt = modaltol::allocate::AllocateOptions {
            speeds: vec![w],
            case,
            target,
            costs: Vec::new(),
            quadrature: modaltol::quadrature::QuadOptions::default(),
            threads: Some(1),
            cancel: Default::default(),
        };
        match modaltol::allocate::allocate(&model, &opt, &|_| {}) {
            Ok(a) => {
                prop_assert!(a.cost_before.is_finite() && a.cost_after.is_finite(), "{a:?}");
                for v in &a.variables {
                    prop_assert!(v.after.is_finite() && v.after > 0.0 && v.after <= v.max * (1.0 + 1e-12), "{v:?}");
                }
                prop_assert!(a.chosen < a.rounds.len());
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }
}
