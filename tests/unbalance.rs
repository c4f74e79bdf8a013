//! The unbalance response (issue 57, item 3): an `[[unbalances]]` entry as a transfer
//! function's input gives the steady response to the rotating force `m e Ω²` of an eccentric
//! mass, along the speed sweep, with its derivatives and its tolerance statistics.
//!
//! * A Jeffcott rotor (a disk of mass `m` on isotropic bearings `k`, `c`, its translation
//!   decoupled from its tilt) has `X = m e Ω² e^{iφ} / (k − m Ω² + i c Ω)` along `e₁` and
//!   `−i X` along `e₂ = n × e₁` (Friswell et al. 2010, §3.6): on both evaluation routes.
//! * Its exact sensitivities, the spin axis' tilt and a drive ratio (which moves the
//!   excitation frequency) included, equal central differences.
//! * Its mean and σ by first order, the quadrature and Monte Carlo against the closed form's,
//!   integrated by a fine rule (`|H|` is linear in `m e`, so a one-dimensional rule in `k`).
//! * Bad input gets a located error.

mod common;

use common::solve;
use modaltol::compiled::Compiled;
use modaltol::model::Channel;
use modaltol::sensitivity::{Derivatives, DesignPoint, TransferAt, nominal_transfer};

const M: f64 = 10.0;
const ME: f64 = 1e-4;
const K: f64 = 1e6;
const C: f64 = 200.0;
const PHASE: f64 = 0.3;

/// The Jeffcott rotor: a massless frame on a free joint held by isotropic bearings, the disk
/// spinning on it about `axis` at `drive`; probes along x and y on the frame; `extra`
/// parameters and tables.
fn jeffcott_with(axis: &str, drive: &str, extra: &str) -> String {
    // The disk's inertia axes: its spin axis is its z.
    let axes = if axis == "[0, 0, 1]" {
        String::new()
    } else {
        "x_axis = [\"cos(a)\", 0, \"-sin(a)\"]\ny_axis = [0, 1, 0]".to_string()
    };
    format!(
        r#"
name = "Jeffcott rotor"
gravity = [0, 0, 0]
[parameters]
m = {M}
me = {{ value = {ME}, tolerance = "10%" }}
k = {{ value = {K}, tolerance = "5%" }}
c = {C}
phase = {PHASE}
{extra}
[[bodies]]
name = "frame"
mass = 0
cm = [0, 0, 0]
[[bodies]]
name = "disk"
mass = "m"
inertia = [0.05, 0.05, 0.09]
{axes}
cm = [0, 0, 0]
[[joints]]
name = "float"
type = "free"
parent = "ground"
child = "frame"
at = [0, 0, 0]
[[joints]]
name = "spin"
type = "revolute"
parent = "frame"
child = "disk"
at = [0, 0, 0]
axis = {axis}
drive = "{drive}"
[[forces]]
name = "bearing"
type = "bushing"
body1 = "ground"
body2 = "frame"
point1 = [0, 0, 0]
stiffness = ["k", "k", 4e6, 2e4, 2e4, 3e3]
damping = ["c", "c", 0, 0, 0, 0]
[[ports]]
name = "probe_x"
type = "translation"
body = "frame"
point = [0, 0, 0]
direction = [1, 0, 0]
[[ports]]
name = "probe_y"
type = "translation"
body = "frame"
point = [0, 0, 0]
direction = [0, 1, 0]
[[unbalances]]
name = "u"
body = "disk"
magnitude = "me"
phase = "phase"
"#
    )
}

fn jeffcott() -> Compiled {
    Compiled::from_str(&jeffcott_with("[0, 0, 1]", "speed", ""), "jeffcott.toml").unwrap()
}

/// The closed form: the response along x at spin `w` with `k` (complex, re and im).
fn closed(w: f64, k: f64, me: f64) -> (f64, f64) {
    let (a, b) = (k - M * w * w, C * w);
    let f = me * w * w;
    // f e^{iφ} / (a + i b)
    let (fr, fi) = (f * PHASE.cos(), f * PHASE.sin());
    let d = a * a + b * b;
    ((fr * a + fi * b) / d, (fi * a - fr * b) / d)
}

fn at(model: &Compiled, input: &str, output: &str, speed: f64) -> TransferAt {
    let m = model.model();
    TransferAt {
        input: m.channel(input).unwrap(),
        output: m.channel(output).unwrap(),
        omega: speed,
    }
}

#[test]
fn the_jeffcott_rotors_unbalance_response_is_the_closed_form_on_both_routes() {
    let model = jeffcott();
    assert_eq!(
        model.model().channel("u"),
        Some(Channel::Unbalance(0)),
        "an unbalance is a channel"
    );
    let t = modaltol::model::Transfer {
        input: Channel::Unbalance(0),
        output: model.model().channel("probe_x").unwrap(),
        order: 1.0,
    };
    assert_eq!(model.model().transfer_unit(&t), "m");
    for direct in [false, true] {
        // Below, near, at and above the critical speed √(k/m) = 316.23 rad/s.
        for speed in [50.0, 250.0, 310.0, (K / M).sqrt(), 400.0, 900.0] {
            let pt = solve(&model, speed, direct);
            let (xr, xi) = closed(speed, K, ME);
            let x = nominal_transfer(&pt, &at(&model, "u", "probe_x", speed)).unwrap();
            let y = nominal_transfer(&pt, &at(&model, "u", "probe_y", speed)).unwrap();
            let scale = xr.hypot(xi);
            // y = −i x: a forward circle.
            for (got, want) in [((x.re, x.im), (xr, xi)), ((y.re, y.im), (xi, -xr))] {
                assert!(
                    (got.0 - want.0).abs() <= 1e-10 * scale
                        && (got.1 - want.1).abs() <= 1e-10 * scale,
                    "{speed} rad/s (direct {direct}): {got:?} vs {want:?}"
                );
            }
        }
        // At rest the unbalance exerts no force.
        let pt = solve(&model, 0.0, direct);
        let x = nominal_transfer(&pt, &at(&model, "u", "probe_x", 0.0)).unwrap();
        assert_eq!((x.re, x.im), (0.0, 0.0));
    }
}

#[test]
fn the_response_follows_the_spin_rate_and_sense_of_its_body() {
    // A drive at twice the speed excites at 2 × speed, whatever the transfer's speed; a
    // reversed spin turns the orbit backward (y = +i x) with the same amplitude.
    let geared = Compiled::from_str(
        &jeffcott_with("[0, 0, 1]", "2*speed", ""),
        "jeffcott_geared.toml",
    )
    .unwrap();
    let reversed = Compiled::from_str(
        &jeffcott_with("[0, 0, 1]", "-speed", ""),
        "jeffcott_reversed.toml",
    )
    .unwrap();
    for speed in [120.0, 200.0] {
        let pt = solve(&geared, speed, false);
        let x = nominal_transfer(&pt, &at(&geared, "u", "probe_x", speed)).unwrap();
        let (xr, xi) = closed(2.0 * speed, K, ME);
        assert!((x.re - xr).abs() <= 1e-10 * xr.hypot(xi), "{x:?}");
        assert!((x.im - xi).abs() <= 1e-10 * xr.hypot(xi), "{x:?}");
        let pt = solve(&reversed, speed, false);
        let x = nominal_transfer(&pt, &at(&reversed, "u", "probe_x", speed)).unwrap();
        let y = nominal_transfer(&pt, &at(&reversed, "u", "probe_y", speed)).unwrap();
        let (xr, xi) = closed(speed, K, ME);
        let scale = xr.hypot(xi);
        assert!((x.magnitude() - scale).abs() <= 1e-10 * scale, "{x:?}");
        assert!((y.magnitude() - scale).abs() <= 1e-10 * scale, "{y:?}");
        // Backward about +z: y leads x by a quarter turn.
        assert!((y.re + x.im).abs() <= 1e-10 * scale && (y.im - x.re).abs() <= 1e-10 * scale);
    }
}

#[test]
fn the_unbalance_responses_sensitivities_equal_central_differences() {
    // The spin axis tilted by `a` (the orbit's plane and the load's directions move with it),
    // the drive at `r × speed` (the excitation frequency moves with r), every input toleranced.
    let extra = r#"a = { value = 0.2, tolerance = "0.05" }
r = { value = 1.1, tolerance = "2%" }
cc = { value = 200.0, tolerance = "10%" }
mm = { value = 10.0, tolerance = "2%" }"#;
    let text = jeffcott_with("[\"sin(a)\", 0, \"cos(a)\"]", "r*speed", extra)
        .replace(
            "phase = 0.3\n",
            "phase = { value = 0.3, tolerance = \"0.1\" }\n",
        )
        .replace("damping = [\"c\", \"c\"", "damping = [\"cc\", \"cc\"")
        .replace("mass = \"m\"", "mass = \"mm\"");
    let model = Compiled::from_str(&text, "jeffcott_tilted.toml").unwrap();
    let p = model.model().nominal();
    let wrt = model.model().toleranced();
    assert_eq!(wrt.len(), 7, "{:?}", model.model().parameters);
    for direct in [false, true] {
        for speed in [150.0, 280.0, 500.0] {
            let pt = solve(&model, speed, direct);
            for probe in ["probe_x", "probe_y"] {
                let design = DesignPoint::new(&model, &p, &pt)
                    .with_transfer(Some(at(&model, "u", probe, speed)));
                let exact = design.sensitivities(&wrt, Derivatives::Exact).unwrap();
                let fd = design
                    .sensitivities(&wrt, Derivatives::FiniteDifference)
                    .unwrap();
                let h = exact.transfer_magnitude.unwrap();
                for (e, f) in exact.variables.iter().zip(&fd.variables) {
                    let name = &model.model().parameters[e.param].name;
                    let (de, df) = (
                        e.d_transfer_magnitude.unwrap(),
                        f.d_transfer_magnitude.unwrap(),
                    );
                    // Relative to |H| per unit of the parameter's own scale.
                    let scale = h / p[e.param].abs().max(0.1);
                    assert!(
                        (de - df).abs() <= 1e-5 * de.abs().max(scale),
                        "d|H|/d{name} at {speed} rad/s, {probe}, direct {direct}: exact {de}, \
                         differences {df}"
                    );
                }
            }
        }
    }
}

/// `E[g(k)^j]` for `j = 1, 2` with `k ~ N(K, σ_k)`, by Simpson's rule over ±10σ.
fn moments_in_k(w: f64, sigma_k: f64) -> (f64, f64) {
    let n = 20_000;
    let (lo, h) = (K - 10.0 * sigma_k, 20.0 * sigma_k / n as f64);
    let (mut m1, mut m2) = (0.0, 0.0);
    for i in 0..=n {
        let k = lo + i as f64 * h;
        let weight = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let z = (k - K) / sigma_k;
        let pdf = (-0.5 * z * z).exp() / (sigma_k * (2.0 * std::f64::consts::PI).sqrt());
        let (xr, xi) = closed(w, k, 1.0);
        let g = xr.hypot(xi);
        m1 += weight * pdf * g;
        m2 += weight * pdf * g * g;
    }
    (m1 * h / 3.0, m2 * h / 3.0)
}

#[test]
fn the_unbalance_responses_statistics_agree_with_the_closed_form() {
    use modaltol::analyze::{AnalyzeOptions, analyze};
    use modaltol::montecarlo::McOptions;
    use modaltol::output::Quantity;
    use modaltol::table::Method;
    let text = jeffcott_with("[0, 0, 1]", "speed", "").replace(
        "phase = \"phase\"\n",
        "phase = \"phase\"\n[analysis]\ntransfer = { input = \"u\", output = \"probe_x\" }\n",
    );
    let model = Compiled::from_str(&text, "jeffcott_statistics.toml").unwrap();
    // ±3σ tolerances: σ of m e and of k.
    let (s_me, s_k) = (0.10 * ME / 3.0, 0.05 * K / 3.0);
    // Below, on the flank of and beyond the resonance.
    let speeds = vec![200.0, 300.0, 450.0];
    let opt = AnalyzeOptions {
        speeds: speeds.clone(),
        cases: vec![modaltol::model::Case::from_parameters(model.model())],
        monte_carlo: Some(McOptions {
            samples: 20_000,
            seed: 7,
            sampling: modaltol::model::Sampling::Random,
        }),
        ..Default::default()
    };
    let rows: Vec<_> = analyze(&model, &opt, &|_, _, _| {})
        .rows
        .into_iter()
        .filter(|r| r.quantity == Quantity::TransferMagnitude)
        .collect();
    for &w in &speeds {
        // |H| = m e g(k), m e and k independent.
        let (g1, g2) = moments_in_k(w, s_k);
        let mean = ME * g1;
        let std = ((ME * ME + s_me * s_me) * g2 - mean * mean).sqrt();
        // First order: the gradient at the nominal design.
        let (xr, xi) = closed(w, K, 1.0);
        let g = xr.hypot(xi);
        let dg = -w * w * (K - M * w * w) / ((K - M * w * w).powi(2) + (C * w).powi(2)).powf(1.5);
        let first = ((g * s_me).powi(2) + (ME * dg * s_k).powi(2)).sqrt();
        let row = |m: Method| {
            (rows.iter())
                .find(|r| r.speed == w && r.method() == m)
                .unwrap_or_else(|| panic!("no {m:?} row at {w}"))
        };
        let fo = row(Method::FirstOrder);
        assert!((fo.mean - ME * g).abs() <= 1e-10 * ME * g, "{fo:?}");
        assert!(
            (fo.std - first).abs() <= 1e-8 * first,
            "{w}: {} vs {first}",
            fo.std
        );
        let quad = row(Method::Quadrature);
        assert!(
            (quad.mean - mean).abs() <= 1e-6 * mean,
            "{w}: {} vs {mean}",
            quad.mean
        );
        assert!(
            (quad.std - std).abs() <= 1e-4 * std,
            "{w}: {} vs {std}",
            quad.std
        );
        let mc = row(Method::MonteCarlo).mc().unwrap();
        assert_eq!(mc.n, 20_000);
        // Within four standard errors (the 95 % intervals' half-widths over 1.96): six checks
        // at 95 % would miss one in four runs; at 4 standard errors, one in 2500.
        let within = |x: f64, (lo, hi): (f64, f64)| {
            let se = (hi - lo) / 2.0 / 1.96;
            (x - (lo + hi) / 2.0).abs() <= 4.0 * se
        };
        assert!(within(mean, mc.mean_ci), "{w}: {mc:?} vs {mean}");
        assert!(within(std, mc.std_ci), "{w}: {mc:?} vs {std}");
    }
}

#[test]
fn bad_unbalances_get_located_errors() {
    let base = jeffcott_with("[0, 0, 1]", "speed", "");
    let refused = |from: &str, to: &str, says: &str| {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let e = Compiled::from_str(&text, "bad.toml")
            .expect_err(to)
            .to_string();
        assert!(e.contains(says), "{to}: {e}");
        assert!(e.contains("bad.toml:"), "located: {e}");
    };
    let unbalance = "[[unbalances]]\nname = \"u\"\nbody = \"disk\"";
    refused(
        unbalance,
        "[[unbalances]]\nname = \"u\"\nbody = \"ground\"",
        "the ground does not spin",
    );
    // The frame carries the disk but does not spin.
    refused(
        unbalance,
        "[[unbalances]]\nname = \"u\"\nbody = \"frame\"",
        "body 'frame' does not spin: no driven joint carries it",
    );
    refused(
        unbalance,
        "[[unbalances]]\nname = \"probe_x\"\nbody = \"disk\"",
        "duplicate name 'probe_x'",
    );
    refused(
        unbalance,
        "[[unbalances]]\nname = \"u\"\nbody = \"rotor\"",
        "unknown body 'rotor'",
    );
    refused("magnitude = \"me\"", "magnitude = \"me*e\"", "unknown");
    let with = |transfer: &str| format!("{base}\n[analysis]\ntransfer = {transfer}\n");
    for (transfer, says) in [
        (
            "{ input = \"probe_x\", output = \"u\" }",
            "'u' is an unbalance: a force in, it has no response to read",
        ),
        (
            "{ input = \"u\", output = \"probe_x\", order = 2 }",
            "`order` does not apply",
        ),
    ] {
        let e = Compiled::from_str(&with(transfer), "bad.toml")
            .expect_err(transfer)
            .to_string();
        assert!(
            e.contains(says) && e.contains("bad.toml:"),
            "{transfer}: {e}"
        );
    }
    // The same from the command line's specs.
    let model = jeffcott();
    let m = model.model();
    assert!(
        m.parse_transfer("input=probe_x,output=u")
            .unwrap_err()
            .contains("is an unbalance")
    );
    assert!(
        m.parse_transfer("input=u,output=probe_x,order=1")
            .unwrap_err()
            .contains("`order`")
    );
    assert!(
        m.parse_response("input=u,output=probe_x")
            .unwrap_err()
            .contains("no response over a range of frequencies")
    );
    assert_eq!(
        m.parse_transfer("input=u,output=probe_y").unwrap().input,
        Channel::Unbalance(0)
    );
}

#[test]
fn an_unbalance_carried_round_by_the_spin_is_refused_at_each_speed_with_its_reason() {
    // A flyball: its centre of mass orbits the drive's axis, so a "rotating force" on it is a
    // constant one in the frame the linearisation is written in. Every spinning speed fails,
    // saying why; at rest nothing spins and the response is zero.
    let text = r#"
name = "flyball"
gravity = [0, 0, 0]
[parameters]
me = 1e-4
[[bodies]]
name = "hub"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0, 0, 0]
[[bodies]]
name = "ball"
mass = 1
inertia = [0.001, 0.001, 0.001]
cm = [0.5, 0, 0]
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "hub"
at = [0, 0, 0]
axis = [0, 0, 1]
drive = "speed"
[[joints]]
name = "hinge"
type = "revolute"
parent = "hub"
child = "ball"
at = [0.5, 0, 0]
axis = [0, 0, 1]
stiffness = 100
[[unbalances]]
name = "u"
body = "ball"
magnitude = "me"
[analysis]
transfer = { input = "u", output = "hinge" }
"#;
    let model = Compiled::from_str(text, "flyball.toml").unwrap();
    let p = model.model().nominal();
    let mut sweep = modaltol::sweep::Sweep::new(&model, p, modaltol::sweep::Options::default());
    let rest = sweep.step(0.0);
    assert!(rest.is_ok(), "at rest: {:?}", rest.err());
    let e = sweep.step(10.0).expect_err("spinning").to_string();
    assert!(
        e.contains("unbalance 'u': its point is carried round by the spin at 10"),
        "{e}"
    );
}
