//! Everything downstream of the modes on flexible models (issue 56): every propagation method
//! on the Friswell rotor, and requirements, yield, allocation and Sobol indices on a meshed
//! Jeffcott rotor, each against the Monte Carlo.
//!
//! The Monte Carlo runs are random samples with a fixed seed; agreement is asked within about
//! four of its standard errors (σ's relative standard error is `1/√(2N)` for a near-normal
//! output), so a method that is off by more than the sampling noise fails.

mod common;

use common::example;
use modaltol::allocate::{AllocateOptions, allocate};
use modaltol::analyze::{Analysis, AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::{Case, Sampling};
use modaltol::montecarlo::McOptions;
use modaltol::output::Quantity;
use modaltol::quadrature::QuadOptions;
use modaltol::sobol::SobolOptions;
use modaltol::table::{Method, Row, Target};

/// The row of `method` for output (`quantity`, `mode`) at `speed` in case 0.
fn row(a: &Analysis, method: Method, quantity: Quantity, mode: Option<usize>, speed: f64) -> &Row {
    a.rows
        .iter()
        .find(|r| {
            r.case == 0
                && r.method() == method
                && r.quantity == quantity
                && r.mode == mode
                && r.speed == speed
        })
        .unwrap_or_else(|| panic!("no {method:?} row of {quantity:?} {mode:?} at {speed}"))
}

/// `r`'s mean and σ against the Monte Carlo row `mc` of `n` samples: within four standard
/// errors of the mean and of σ (plus rounding).
fn agrees(r: &Row, mc: &Row, n: usize, what: &str) {
    let se = mc.std / (n as f64).sqrt();
    let floor = 1e-12 * mc.mean.abs();
    assert!(
        (r.mean - mc.mean).abs() <= 4.0 * se + floor,
        "{what}: mean {} against the Monte Carlo's {} ± {se}",
        r.mean,
        mc.mean
    );
    let rel = 4.0 / (2.0 * n as f64).sqrt();
    assert!(
        (r.std - mc.std).abs() <= rel * mc.std + floor,
        "{what}: σ {} against the Monte Carlo's {} (±{:.1} %)",
        r.std,
        mc.std,
        100.0 * rel
    );
}

#[test]
fn every_method_fills_the_friswell_rotors_rows_and_agrees_with_the_monte_carlo() {
    let model = example("friswell_5_9_1.toml");
    let rpm = std::f64::consts::PI / 30.0;
    // At rest the bending modes are double roots; at 2000 and 4000 rpm the gyroscopic
    // moments split every pair.
    let speeds = vec![0.0, 2000.0 * rpm, 4000.0 * rpm];
    let samples = 1200;
    let opt = AnalyzeOptions {
        speeds: speeds.clone(),
        cases: vec![Case::from_parameters(model.model())],
        quadrature: Some(QuadOptions::default()),
        monte_carlo: Some(McOptions {
            samples,
            seed: 11,
            sampling: Sampling::Random,
        }),
        ..Default::default()
    };
    let a = analyze(&model, &opt, &|_, _, _| {});
    assert!(a.failures.is_empty(), "{:?}", a.failures);
    let methods = [
        Method::FirstOrder,
        Method::SecondOrder,
        Method::Quadrature,
        Method::MonteCarlo,
    ];
    // Every row has a value: at rest the double roots of the bending modes as clusters that
    // the (axisymmetric) tolerances move as one (issue 57).
    for r in a.rows.iter().filter(|r| methods.contains(&r.method())) {
        let what = format!(
            "{:?} {:?} mode {:?} at {} rad/s",
            r.method(),
            r.quantity,
            r.mode,
            r.speed
        );
        if let Some(m) = &r.missing {
            panic!("{what}: no value ({m})");
        }
        assert!(r.mean.is_finite() && r.std.is_finite(), "{what}");
        // The quadrature meets its request on every mode (the ζ of these undamped modes is
        // rounding about zero at every node: it used to be refined to the budget and
        // flagged), at rest too.
        if r.method() == Method::Quadrature && r.quantity != Quantity::TransferMagnitude {
            assert_eq!(r.within_request(), Some(true), "{what}: {:?}", r.errors());
        }
    }
    // Each ω_d by second order and by the quadrature against the Monte Carlo, and the
    // transfer magnitude by the quadrature, at rest (double roots) and spinning.
    let modes = a
        .outputs
        .iter()
        .filter(|o| o.quantity == Quantity::DampedFrequency)
        .count();
    for &w in &speeds {
        for m in 0..modes {
            let mc = row(
                &a,
                Method::MonteCarlo,
                Quantity::DampedFrequency,
                Some(m),
                w,
            );
            assert_eq!(mc.mc().unwrap().n, samples, "every sample has a value");
            for method in [Method::SecondOrder, Method::Quadrature] {
                let r = row(&a, method, Quantity::DampedFrequency, Some(m), w);
                agrees(
                    r,
                    mc,
                    samples,
                    &format!("{method:?} ω_d mode {} at {w}", m + 1),
                );
            }
        }
        let mc = row(&a, Method::MonteCarlo, Quantity::TransferMagnitude, None, w);
        let r = row(&a, Method::Quadrature, Quantity::TransferMagnitude, None, w);
        agrees(r, mc, samples, &format!("quadrature |H| at {w}"));
    }
}

/// A Jeffcott rotor meshed as a shaft of two elements (disk on the middle node, bearings at the
/// ends), its diameter, bearing stiffness and disk mass toleranced, required to keep its
/// forward whirl 20.5 % clear of the running speed (1×) below its critical speed.
fn jeffcott() -> Compiled {
    Compiled::from_str(
        r#"
name = "meshed Jeffcott rotor"
gravity = [0, 0, 0]

[parameters]
d = { value = 0.03, tolerance = "1%" }
k = { value = 2e6, tolerance = "10%" }
m = { value = 20, tolerance = "3%" }

[[shafts]]
name = "shaft"
start = [0, 0, 0]
axis = [1, 0, 0]
spin = "speed"
coupling = 1
E = 2.1e11
nu = 0.3
density = 7800
stations = [{ length = 0.8, elements = 2, outer_diameter = "d" }]

[[bodies]]
name = "disk"
mass = "m"
inertia = ["m*0.15^2/2", "m*0.15^2/4", "m*0.15^2/4"]
cm = [0.4, 0, 0]

[[joints]]
name = "disk_on_shaft"
type = "fixed"
parent = "shaft_1"
child = "disk"
at = [0.4, 0, 0]

[[forces]]
name = "bearing0"
type = "bushing"
body1 = "ground"
body2 = "shaft_0"
point1 = [0, 0, 0]
stiffness = [1e9, "k", "k", 0, 0, 0]

[[forces]]
name = "bearing2"
type = "bushing"
body1 = "ground"
body2 = "shaft_2"
point1 = [0.8, 0, 0]
stiffness = [1e9, "k", "k", 0, 0, 0]

[[requirements]]
name = "clear_of_1x"
kind = "separation"
mode = 3
orders = [1]
margin = "20.5%"
speeds = [140, 140]

[allocation]
target_yield = 0.99
cost = { d = { b = 1e-5 }, k = { b = 2e4 }, m = { b = 0.1 } }
"#,
        "jeffcott.toml",
    )
    .unwrap()
}

#[test]
fn a_meshed_rotors_yield_allocation_and_sobol_indices_agree_with_the_monte_carlo() {
    let model = jeffcott();
    let speeds = vec![140.0];
    let case = Case::from_parameters(model.model());
    let samples = 4000;
    let opt = AnalyzeOptions {
        speeds: speeds.clone(),
        cases: vec![case.clone()],
        quadrature: Some(QuadOptions::default()),
        monte_carlo: Some(McOptions {
            samples,
            seed: 5,
            sampling: Sampling::Random,
        }),
        sobol: Some(SobolOptions {
            samples: 2000,
            seed: 5,
        }),
        ..Default::default()
    };
    let a = analyze(&model, &opt, &|_, _, _| {});
    assert!(a.failures.is_empty(), "{:?}", a.failures);
    // The requirement's yield: neither certain nor hopeless, by the quadrature within the
    // Monte Carlo's interval widened by the quadrature's own error estimate.
    let range = |method: Method| {
        a.yields
            .iter()
            .find(|y| y.method == method && y.requirement == Some(0) && y.speed.is_none())
            .unwrap_or_else(|| panic!("no {method:?} yield"))
    };
    let (quad, mc) = (range(Method::Quadrature), range(Method::MonteCarlo));
    assert!(
        mc.probability > 0.5 && mc.probability < 0.995,
        "a requirement worth allocating: {}",
        mc.probability
    );
    assert!(
        quad.ci.1 >= mc.ci.0 && quad.ci.0 <= mc.ci.1,
        "quadrature yield {} [{}, {}] against the Monte Carlo's {} [{}, {}]",
        quad.probability,
        quad.ci.0,
        quad.ci.1,
        mc.probability,
        mc.ci.0,
        mc.ci.1
    );
    // Sobol indices of the whirl frequency: the bearing stiffness dominates, and the first-order
    // indices match the first-order variance shares within their intervals.
    let whirl = a
        .outputs
        .iter()
        .position(|o| o.quantity == Quantity::DampedFrequency && o.mode == Some(2))
        .unwrap();
    let first_order = row(
        &a,
        Method::FirstOrder,
        Quantity::DampedFrequency,
        Some(2),
        140.0,
    );
    let shares = first_order.shares().expect("first-order shares");
    let indices: Vec<_> = a
        .sobol
        .iter()
        .filter(|(c, s)| *c == 0 && s.target == Target::Output(0, whirl))
        .map(|(_, s)| s)
        .collect();
    assert_eq!(indices.len(), 3, "{:?}", a.sobol_refused);
    for s in &indices {
        let share = shares[s.variable];
        let width = (s.first_ci.1 - s.first_ci.0).max(0.02);
        assert!(
            (s.first - share).abs() <= 2.0 * width,
            "variable {}: first-order index {} [{}, {}] against the share {share}",
            s.variable,
            s.first,
            s.first_ci.0,
            s.first_ci.1
        );
    }
    // Allocation: the cheapest tolerances verified by the quadrature to meet 99 %.
    let alloc = allocate(
        &model,
        &AllocateOptions {
            speeds,
            case,
            target: model.model().allocation.target_yield,
            costs: Vec::new(),
            quadrature: QuadOptions::default(),
            threads: None,
            cancel: Default::default(),
        },
        &|_| {},
    )
    .unwrap();
    assert!(alloc.met, "{alloc:?}");
    let chosen = &alloc.rounds[alloc.chosen];
    assert!(
        chosen.verified.0 - chosen.verified.1 >= 0.99,
        "{:?}",
        chosen.verified
    );
    assert!(alloc.cost_gap.is_some_and(|g| g < 0.05), "{alloc:?}");
}
