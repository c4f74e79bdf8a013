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

/// A rod hinged to the ground on a torsional spring, pulled sideways by a dead load: its mass,
/// length, damping and load made from the parameters `fields` through bounded functions
/// (`atan`), so that any finite values give a valid, underdamped rod whose one mode depends
/// smoothly on them; `parameters` the `[parameters]` table's lines.
fn derived_rod(parameters: &str, fields: [&str; 4]) -> String {
    let [m, l, c, f] = fields;
    format!(
        r#"
name = "derived rod"
gravity = [0, -9.80665, 0]
[parameters]
{parameters}
[[bodies]]
name = "rod"
mass = "2 + atan({m})"
inertia = ["(2 + atan({m}))*(0.5 + atan({l})^2)^2/12", 0, "(2 + atan({m}))*(0.5 + atan({l})^2)^2/12"]
cm = [0, "-(0.5 + atan({l})^2)/2", 0]
[[joints]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "rod"
at = [0, 0, 0]
axis = [0, 0, 1]
stiffness = 5
damping = "0.1 + 0.1*atan({c})^2"
[[loads]]
name = "pull"
type = "force"
body = "rod"
point = [0, "-(0.5 + atan({l})^2)", 0]
force = ["0.5*atan({f})", 0, 0]
"#
    )
}

/// The rod's one mode at rest: `[λ₁ + λ₂, λ₁ λ₂, ω_d]` (the pair's invariants, smooth, and
/// the damped frequency), or `None` where the point does not solve.
fn rod_mode(model: &Compiled) -> Option<[f64; 3]> {
    let p = model.model().nominal();
    let q0 = initial_guess(model.model(), &p, 0.0).ok()?;
    let pt = point(model, &p, 0.0, &q0, &Options::default()).ok()?;
    let m = pt.modes.first()?;
    let (a, b) = (m.root.lambda, m.partner.lambda);
    Some([(a + b).re, (a * b).re, m.damped_frequency])
}

/// Whether derived parameter `i` reaches itself through `uses` (the derived parameters each
/// uses).
fn on_a_cycle(i: usize, uses: &[Vec<usize>]) -> bool {
    let mut seen = vec![false; uses.len()];
    let mut stack = uses[i].clone();
    while let Some(j) = stack.pop() {
        if j == i {
            return true;
        }
        if !std::mem::replace(&mut seen[j], true) {
            stack.extend(&uses[j]);
        }
    }
    false
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(8),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Random graphs of derived parameters (DAGs and cycles, in any order of definition) over
    /// three base parameters, driving a hinged rod: a graph with a cycle is refused at a
    /// member, naming a cycle of the graph in the order each uses the next; an acyclic one
    /// validates, `--wrt` a derived parameter is refused naming it as derived, and the exact
    /// sensitivity of the rod's mode to a base parameter equals a central difference of the
    /// model re-read with that parameter set (`--set`), to a few 1e-6.
    #[test]
    fn random_derived_parameter_graphs_validate_or_refuse_and_differentiate_exactly(
        defs in prop::collection::vec((0usize..5, 0usize..9, 0usize..9), 1..7),
        fields in [0usize..9, 0usize..9, 0usize..9, 0usize..9],
        wrt in 0usize..9,
    ) {
        let base = [("a", 1.2), ("b", 0.8), ("g", 0.5)];
        let n = defs.len();
        // Names 0..3 are the base parameters, 3.. the derived ones (taken modulo the count).
        let name = |k: usize| {
            let k = k % (3 + n);
            if k < 3 { base[k].0.to_string() } else { format!("d{}", k - 3) }
        };
        let mut uses = vec![Vec::new(); n];
        let mut lines: Vec<String> = base.iter().map(|(p, v)| format!("{p} = {v}")).collect();
        for (i, &(form, x, y)) in defs.iter().enumerate() {
            for k in [x, y] {
                if k % (3 + n) >= 3 {
                    uses[i].push(k % (3 + n) - 3);
                }
            }
            let (x, y) = (name(x), name(y));
            let e = match form {
                0 => format!("{x} + {y}"),
                1 => format!("{x}*{y}"),
                2 => format!("sqrt({x}*{x} + {y})"),
                3 => format!("{x}/(1 + {y})"),
                _ => format!("0.5*{x} + 0.1 + 0*{y}"),
            };
            lines.push(format!("d{i} = \"{e}\""));
        }
        let field_names = fields.map(name);
        let text = derived_rod(&lines.join("\n"), field_names.each_ref().map(|s| s.as_str()));
        let cyclic = (0..n).any(|i| on_a_cycle(i, &uses));
        let model = match Compiled::from_str(&text, "graph.toml") {
            Ok(m) => m,
            Err(e) => {
                let e = e.to_string();
                prop_assert!(cyclic, "an acyclic graph refused: {e}\n{text}");
                // "parameter 'x': … in a cycle (x → y → x)": each member uses the next.
                let listed = e
                    .split_once("in a cycle (")
                    .and_then(|(_, r)| r.split_once(')'))
                    .map(|(c, _)| c.split(" → ").map(str::to_string).collect::<Vec<_>>());
                let Some(cycle) = listed else {
                    return Err(TestCaseError::fail(format!("a cycle refused without naming it: {e}")));
                };
                prop_assert!(e.contains(&format!("parameter '{}'", cycle[0])), "{e}");
                prop_assert!(cycle.len() >= 2 && cycle.first() == cycle.last(), "{e}");
                let index = |s: &str| s.strip_prefix('d').and_then(|k| k.parse::<usize>().ok());
                for w in cycle.windows(2) {
                    let (Some(i), Some(j)) = (index(&w[0]), index(&w[1])) else {
                        return Err(TestCaseError::fail(format!("a base parameter in a cycle: {e}")));
                    };
                    prop_assert!(uses[i].contains(&j), "{} does not use {}: {e}", w[0], w[1]);
                }
                return Ok(());
            }
        };
        prop_assert!(!cyclic, "a cyclic graph accepted:\n{text}");
        let wrt = name(wrt);
        let vars = model.model().design_variables(Some(std::slice::from_ref(&wrt)));
        if wrt.starts_with('d') {
            let e = vars.expect_err("a derived parameter is no variable");
            prop_assert!(e.contains(&format!("parameter '{wrt}' is derived")), "{e}");
            return Ok(());
        }
        let var = vars.map_err(TestCaseError::fail)?[0];
        let p = model.model().nominal();
        let q0 = initial_guess(model.model(), &p, 0.0).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let pt = point(&model, &p, 0.0, &q0, &Options::default()).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let s = modaltol::sensitivity::DesignPoint::new(&model, &p, &pt).analytic(&[var])
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        let d = &s.variables[0].modes[0];
        let exact = [d.d_sum, d.d_product, d.d_damped_frequency];
        let value = base.iter().find(|(b, _)| *b == wrt).unwrap().1;
        let h = 1e-4 * value;
        let at = |v: f64| {
            let m = Compiled::from_bytes_with(text.as_bytes(), "set.toml", &[(wrt.clone(), v)])
                .expect("a base parameter set");
            rod_mode(&m).expect("the rod solves")
        };
        let (plus, minus, nominal) = (at(value + h), at(value - h), rod_mode(&model).unwrap());
        for k in 0..3 {
            let fd = (plus[k] - minus[k]) / (2.0 * h);
            let tol = 3e-6 * exact[k].abs().max(fd.abs()) + 1e-9 * nominal[k].abs() / value;
            prop_assert!(
                (exact[k] - fd).abs() <= tol,
                "d/d{wrt} of output {k}: exact {} vs difference {fd}\n{text}",
                exact[k]
            );
        }
    }
}
