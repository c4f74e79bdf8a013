//! The peaks of a response along the speed (issue 57, item 3): located between the swept
//! speeds, with the exact derivatives of the peak and of its speed.
//!
//! * A damped Jeffcott rotor: the unbalance response `|X| = m e Ω² / |k − MΩ² + icΩ|` peaks
//!   at `Ω*² = 2k² / (2kM − c²)`, and the force response `1 / |k − MΩ² + icΩ|` at
//!   `Ω*² = k/M − c²/(2M²)` (excited at `order × Ω`): peak and speed against the closed form,
//!   their derivatives against the closed form's (differentiated by dual numbers, exactly).
//! * Undamped, the response is unbounded at `Ω_r = √(k/M) / order`: a resonance with its
//!   speed and `dΩ_r/dp`, never a number; the backward crossing that unbalance does not
//!   excite is no resonance.
//! * The Friswell rotor without damping: each forward critical speed of its unbalance response
//!   is where a mode's ω_d equals the spin, and its derivatives equal central differences of
//!   the whole search.
//! * The first-order σ of the peak and of its speed against a Monte Carlo of the closed form.

mod common;

use common::{example, example_text};
use modaltol::compiled::Compiled;
use modaltol::model::{Channel, Transfer};
use modaltol::peaks::{Peak, PeakKind, peaks};
use modaltol::sweep::{Options, Point, Sweep};
use num_dual::{Dual64, DualNum};

type D = Dual64;

const M: f64 = 10.0;
const ME: f64 = 1e-4;
const K: f64 = 1e6;
const C: f64 = 200.0;

/// A Jeffcott rotor (a disk of mass `m` on a massless frame held by isotropic bearings `k`,
/// `c`), its unbalance `me`, and a port on the frame along x (a force in, a displacement out).
fn jeffcott(c: f64) -> Compiled {
    let text = format!(
        r#"
name = "Jeffcott rotor"
gravity = [0, 0, 0]
[parameters]
m = {{ value = {M}, tolerance = "2%" }}
me = {{ value = {ME}, tolerance = "10%" }}
k = {{ value = {K}, tolerance = "5%" }}
c = {{ value = {c}, tolerance = "10%" }}
[[bodies]]
name = "frame"
mass = 0
cm = [0, 0, 0]
[[bodies]]
name = "disk"
mass = "m"
inertia = [0.05, 0.05, 0.09]
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
axis = [0, 0, 1]
drive = "speed"
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
[[unbalances]]
name = "u"
body = "disk"
magnitude = "me"
"#
    );
    Compiled::from_str(&text, "jeffcott.toml").unwrap()
}

/// The design's points at `speeds`, continued (on one branch: a rotor's equilibrium is its
/// axis, and above the stability threshold of its bearings no other branch is looked for).
fn swept(model: &Compiled, p: &[f64], speeds: &[f64]) -> Vec<Option<Point>> {
    let options = Options {
        no_branch_switch: true,
        ..Options::default()
    };
    let mut sweep = Sweep::new(model, p.to_vec(), options);
    speeds.iter().map(|&s| sweep.step(s).ok()).collect()
}

fn grid(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|i| from + step * i as f64).collect()
}

/// The design variables in the model's order: m, me, k, c.
fn vars(model: &Compiled) -> Vec<usize> {
    ["m", "me", "k", "c"]
        .iter()
        .map(|n| model.model().parameter(n).unwrap())
        .collect()
}

/// The unbalance response's peak `(Ω*, |X|*)` in closed form, over dual numbers.
fn unbalance_peak(m: D, me: D, k: D, c: D) -> (D, D) {
    let u = k * k * 2.0 / (k * m * 2.0 - c * c);
    let x = me * u / ((k - m * u).powi(2) + c * c * u).sqrt();
    (u.sqrt(), x)
}

/// The unbalance response's amplification factor `Ω*/(Ω₂ − Ω₁)` at `[m, me, k, c]`: the
/// half-power speeds, where `|X| = |X|*/√2`, by bisection on the closed form.
fn unbalance_amplification([m, me, k, c]: [f64; 4]) -> f64 {
    let x = |w: f64| me * w * w / ((k - m * w * w).powi(2) + (c * w).powi(2)).sqrt();
    let (s, g) = unbalance_peak(D::from(m), D::from(me), D::from(k), D::from(c));
    let half = g.re / std::f64::consts::SQRT_2;
    let bisect = |(mut lo, mut hi): (f64, f64), rising: bool| {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if (x(mid) < half) == rising {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let (w1, w2) = (bisect((1.0, s.re), true), bisect((s.re, 1e4), false));
    s.re / (w2 - w1)
}

/// The force response's peak `(Ω*, |H|*)` at `order × Ω`, over dual numbers.
fn force_peak(m: D, k: D, c: D, order: f64) -> (D, D) {
    let w2 = k / m - c * c / (m * m * 2.0);
    let h = ((k - m * w2).powi(2) + c * c * w2).sqrt().recip();
    (w2.sqrt() / order, h)
}

/// The closed form's derivatives along each of (m, me, k, c) at nominal.
fn closed_derivatives(f: impl Fn([Dual64; 4]) -> (Dual64, Dual64)) -> (Vec<f64>, Vec<f64>) {
    let nominal = [M, ME, K, C];
    let (mut ds, mut dg) = (Vec::new(), Vec::new());
    for a in 0..4 {
        let x = std::array::from_fn(|i| Dual64::new(nominal[i], f64::from(u8::from(i == a))));
        let (s, g) = f(x);
        ds.push(s.eps);
        dg.push(g.eps);
    }
    (ds, dg)
}

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol * want.abs().max(1e-300),
        "{what}: {got} vs {want} ({:.2e} relative)",
        (got - want).abs() / want.abs()
    );
}

fn only(found: Vec<Result<Peak, modaltol::peaks::PeakFailure>>) -> Peak {
    let ok: Vec<Peak> = found
        .into_iter()
        .map(|r| r.unwrap_or_else(|f| panic!("near {}: {}", f.near, f.why)))
        .collect();
    assert_eq!(ok.len(), 1, "one peak: {ok:?}");
    ok.into_iter().next().unwrap()
}

#[test]
fn the_damped_jeffcott_rotors_peaks_and_their_speeds_are_the_closed_forms() {
    let model = jeffcott(C);
    let p = model.model().nominal();
    let wrt = vars(&model);
    let channel = |n: &str| model.model().channel(n).unwrap();
    // The unbalance response, swept coarsely across the critical speed (316 rad/s).
    let points = swept(&model, &p, &grid(100.0, 500.0, 40.0));
    let unbalance = Transfer {
        input: Channel::Unbalance(0),
        output: channel("probe_x"),
        order: 1.0,
    };
    let peak = only(peaks(&model, &p, &points, &unbalance, &wrt));
    assert_eq!(peak.kind, PeakKind::Maximum);
    let (s, g) = unbalance_peak(D::from(M), D::from(ME), D::from(K), D::from(C));
    let (s, g) = (s.re, g.re);
    close(peak.speed, s, 1e-12, "unbalance: speed of the peak");
    close(peak.magnitude.unwrap(), g, 1e-10, "unbalance: peak");
    let (ds, dg) = closed_derivatives(|[m, me, k, c]| unbalance_peak(m, me, k, c));
    let nominal = [M, ME, K, C];
    for a in 0..4 {
        // Relative to the largest change of Ω* per relative change of a variable (Ω* does
        // not depend on me: its derivative is rounding).
        let scale = (0..4)
            .map(|b| (ds[b] * nominal[b]).abs())
            .fold(0.0, f64::max);
        let got = peak.d_speed.as_ref().unwrap()[a];
        assert!(
            (got - ds[a]).abs() * nominal[a] <= 1e-8 * scale,
            "unbalance: dΩ*/dp[{a}] {got} vs {}",
            ds[a]
        );
        close(
            peak.d_magnitude.as_ref().unwrap()[a],
            dg[a],
            1e-8,
            "unbalance: d|X|*/dp",
        );
    }
    // The amplification factor Ω*/(Ω₂ − Ω₁) (half-power speeds, |X| = |X|*/√2), against
    // the closed form's by bisection, and its derivatives against central differences of it.
    let (af, d_af) = peak.amplification.as_ref().unwrap();
    close(
        *af,
        unbalance_amplification(nominal),
        1e-10,
        "amplification factor",
    );
    assert!(
        (af * 2.0 * C / (2.0 * (K * M).sqrt()) - 1.0).abs() < 0.01,
        "about 1/(2ζ)"
    );
    for a in 0..4 {
        let at = |sign: f64| {
            let mut v = nominal;
            v[a] *= 1.0 + sign * 1e-6;
            unbalance_amplification(v)
        };
        let fd = (at(1.0) - at(-1.0)) / (2e-6 * nominal[a]);
        assert!(
            (d_af[a] - fd).abs() * nominal[a] <= 1e-6 * af,
            "dAF/dp[{a}]: {} vs central differences {fd}",
            d_af[a]
        );
    }
    // The force response at orders 1 and 2.
    for order in [1.0, 2.0] {
        let speeds = grid(100.0 / order, 500.0 / order, 40.0 / order);
        let points = swept(&model, &p, &speeds);
        let force = Transfer {
            input: channel("probe_x"),
            output: channel("probe_x"),
            order,
        };
        let peak = only(peaks(&model, &p, &points, &force, &wrt));
        let (s, g) = force_peak(D::from(M), D::from(K), D::from(C), order);
        let (s, g) = (s.re, g.re);
        close(peak.speed, s, 1e-12, "force: speed of the peak");
        close(peak.magnitude.unwrap(), g, 1e-10, "force: peak");
        let (ds, dg) = closed_derivatives(|[m, _, k, c]| force_peak(m, k, c, order));
        for a in 0..4 {
            let (got_s, got_g) = (
                peak.d_speed.as_ref().unwrap()[a],
                peak.d_magnitude.as_ref().unwrap()[a],
            );
            // me does not enter the force response.
            if a == 1 {
                assert_eq!((got_s, got_g), (0.0, 0.0));
                continue;
            }
            close(got_s, ds[a], 1e-8, "force: dΩ*/dp");
            close(got_g, dg[a], 1e-8, "force: d|H|*/dp");
        }
    }
}

#[test]
fn the_undamped_response_is_a_resonance_at_its_speed_never_a_number() {
    let model = jeffcott(0.0);
    let p = model.model().nominal();
    let wrt = vars(&model);
    let channel = |n: &str| model.model().channel(n).unwrap();
    let critical = (K / M).sqrt();
    for (input, order) in [(Channel::Unbalance(0), 1.0), (channel("probe_x"), 2.0)] {
        let speeds = grid(100.0 / order, 500.0 / order, 40.0 / order);
        let points = swept(&model, &p, &speeds);
        let t = Transfer {
            input,
            output: channel("probe_x"),
            order,
        };
        let peak = only(peaks(&model, &p, &points, &t, &wrt));
        assert_eq!(peak.kind, PeakKind::Resonance, "{input:?}");
        assert!(peak.magnitude.is_none() && peak.d_magnitude.is_err());
        close(peak.speed, critical / order, 1e-12, "resonance speed");
        // Ω_r = √(k/m)/order: dΩ_r/dm = −Ω_r/(2m), dΩ_r/dk = Ω_r/(2k), nothing else.
        let d = peak.d_speed.as_ref().unwrap();
        let r = critical / order;
        close(d[0], -r / (2.0 * M), 1e-9, "dΩ_r/dm");
        close(d[2], r / (2.0 * K), 1e-9, "dΩ_r/dk");
        assert!(d[1].abs() <= 1e-12 * r / ME && d[3].abs() <= 1e-12, "{d:?}");
    }
}

/// The peaks of `model`'s `[analysis] transfer` at parameters `p` over `speeds`.
fn peaks_at(model: &Compiled, p: &[f64], speeds: &[f64], wrt: &[usize]) -> Vec<Peak> {
    let t = model.model().analysis.transfer.unwrap();
    peaks(model, p, &swept(model, p, speeds), &t, wrt)
        .into_iter()
        .map(|r| r.unwrap_or_else(|f| panic!("near {}: {}", f.near, f.why)))
        .collect()
}

/// Each peak's derivatives with respect to the parameters `names` against central differences
/// of the whole search (sweep and peaks) at `p ± h p`: the speed's, and the magnitude's of a
/// maximum, within `tol` of the largest change per relative change of a variable.
fn against_central_differences(model: &Compiled, speeds: &[f64], names: &[&str], tol: f64) {
    let p = model.model().nominal();
    let wrt: Vec<usize> = (names.iter())
        .map(|n| model.model().parameter(n).unwrap())
        .collect();
    let found = peaks_at(model, &p, speeds, &wrt);
    assert!(!found.is_empty());
    let h = 1e-5;
    let mut fd_speed = vec![vec![0.0; wrt.len()]; found.len()];
    let mut fd_magnitude = vec![vec![0.0; wrt.len()]; found.len()];
    let mut fd_amplification = vec![vec![0.0; wrt.len()]; found.len()];
    for (a, &b) in wrt.iter().enumerate() {
        let at = |sign: f64| {
            let mut q = p.clone();
            q[b] *= 1.0 + sign * h;
            peaks_at(model, &q, speeds, &[])
        };
        let (up, down) = (at(1.0), at(-1.0));
        assert_eq!((up.len(), down.len()), (found.len(), found.len()));
        for i in 0..found.len() {
            let step = 2.0 * h * p[b];
            fd_speed[i][a] = (up[i].speed - down[i].speed) / step;
            if let (Some(u), Some(d)) = (up[i].magnitude, down[i].magnitude) {
                fd_magnitude[i][a] = (u - d) / step;
            }
            if let (Ok(u), Ok(d)) = (&up[i].amplification, &down[i].amplification) {
                fd_amplification[i][a] = (u.0 - d.0) / step;
            }
        }
    }
    for (i, peak) in found.iter().enumerate() {
        let checks = [
            ("speed", peak.d_speed.as_ref().ok(), &fd_speed[i]),
            (
                "magnitude",
                peak.d_magnitude.as_ref().ok(),
                &fd_magnitude[i],
            ),
            (
                "amplification factor",
                peak.amplification.as_ref().ok().map(|a| &a.1),
                &fd_amplification[i],
            ),
        ];
        for (what, exact, fd) in checks {
            let Some(exact) = exact else {
                assert_ne!(what, "speed", "{peak:?}");
                assert_eq!(peak.kind, PeakKind::Resonance, "{what}: {peak:?}");
                continue;
            };
            let scale = (0..wrt.len())
                .map(|a| (fd[a] * p[wrt[a]]).abs())
                .fold(0.0, f64::max);
            for a in 0..wrt.len() {
                assert!(
                    (exact[a] - fd[a]).abs() * p[wrt[a]] <= tol * scale,
                    "peak at {} rad/s, d({what})/d({}): exact {} vs central differences {}",
                    peak.speed,
                    names[a],
                    exact[a],
                    fd[a]
                );
            }
        }
    }
}

/// The Friswell rotor of Example 5.9.1 (undamped bearings) with an unbalance on disk 1 and its
/// response at disk 1 as the transfer function.
fn undamped_friswell() -> Compiled {
    let text = example_text("friswell_5_9_1.toml").replace(
        "transfer = { input = \"disk2_y\", output = \"disk1_y\", order = 1 }",
        "transfer = { input = \"u\", output = \"disk1_y\" }",
    ) + "\n[[unbalances]]\nname = \"u\"\nbody = \"disk1\"\nmagnitude = \"disk1*8e-6\"\n";
    Compiled::from_str(&text, "friswell_unbalance.toml").unwrap()
}

#[test]
fn the_undamped_friswell_rotors_resonances_are_its_forward_critical_speeds() {
    let model = undamped_friswell();
    let p = model.model().nominal();
    let speeds = grid(0.0, 400.0, 20.0);
    let found = peaks_at(&model, &p, &speeds, &[]);
    // The unbalance excites the forward whirl only: one resonance per forward crossing of the
    // spin in the range (the backward ones, and the other modes' crossings, leave H finite).
    assert!(found.len() >= 2, "{found:?}");
    for peak in &found {
        assert_eq!(peak.kind, PeakKind::Resonance, "{peak:?}");
        assert!(peak.magnitude.is_none());
        // An independent modal point at that speed has a mode there, whirling forward.
        let pt = common::at(&model, peak.speed, &Options::default());
        let mode = (pt.modes.iter())
            .position(|m| (m.damped_frequency - peak.speed).abs() <= 1e-9 * peak.speed)
            .unwrap_or_else(|| panic!("a mode at {} rad/s", peak.speed));
        let whirl = modaltol::whirl::of_point(model.model(), &p, &pt).unwrap();
        assert_eq!(
            whirl[mode],
            Some(modaltol::whirl::Whirl::Forward),
            "{}",
            peak.speed
        );
    }
    against_central_differences(
        &model,
        &speeds,
        &["d", "E", "rho", "disk1", "disk2", "k_bearing"],
        1e-5,
    );
}

#[test]
fn the_damped_friswell_rotors_peaks_are_maxima_and_differentiate_like_central_differences() {
    let model = example("friswell_bearings.toml");
    let p = model.model().nominal();
    let speeds = grid(0.0, 400.0, 40.0);
    let found = peaks_at(&model, &p, &speeds, &[]);
    assert_eq!(found.len(), 2, "{found:?}");
    let t = model.model().analysis.transfer.unwrap();
    let magnitude = |speed: f64| {
        let pt = common::at(&model, speed, &Options::default());
        let at = modaltol::sensitivity::TransferAt::at_speed(&t, speed);
        modaltol::sensitivity::nominal_transfer(&pt, &at)
            .unwrap()
            .magnitude()
    };
    for peak in &found {
        assert_eq!(peak.kind, PeakKind::Maximum);
        // The vertex of the parabola through independent points at Ω* and Ω* ± δ.
        let (s, delta) = (peak.speed, 1e-5 * peak.speed);
        let (gm, g0, gp) = (magnitude(s - delta), magnitude(s), magnitude(s + delta));
        close(g0, peak.magnitude.unwrap(), 1e-12, "|H| at the peak");
        assert!(g0 > gm && g0 > gp, "a maximum at {s}");
        let vertex = s + delta * (gm - gp) / (2.0 * (gm - 2.0 * g0 + gp));
        assert!((vertex - s).abs() <= 1e-8 * s, "{vertex} vs {s}");
    }
    against_central_differences(
        &model,
        &speeds,
        &[
            "d",
            "E",
            "rho",
            "disk1",
            "disk2",
            "k_scale",
            "c_scale",
            "eccentricity",
        ],
        1e-5,
    );
}

#[test]
fn the_first_order_sigma_of_the_peak_and_its_speed_is_the_exact_ones_to_first_order() {
    // The damped Jeffcott rotor's peak and its speed under its tolerances (m 2 %, me 10 %,
    // k 5 %, c 10 %, each ±3σ of a normal): the exact mean and σ of the closed form by a
    // tensor rule in the four variables, against first order from the exact gradients. They
    // differ by the curvature only (relatively the square of the variables' spread, here
    // under 1 %); a wrong gradient or spread would differ by its own size.
    let model = jeffcott(C);
    let p = model.model().nominal();
    let wrt = vars(&model);
    let points = swept(&model, &p, &grid(100.0, 500.0, 40.0));
    let t = Transfer {
        input: Channel::Unbalance(0),
        output: model.model().channel("probe_x").unwrap(),
        order: 1.0,
    };
    let peak = only(peaks(&model, &p, &points, &t, &wrt));
    let case = modaltol::model::Case::from_parameters(model.model());
    let spread = modaltol::tolerance::Spread::new(&model, &case, &wrt);
    let first = peak.first_order(&spread);
    let (speed, magnitude) = (first.speed.unwrap(), first.magnitude.unwrap());
    let nominal = [M, ME, K, C];
    let relative = [0.02 / 3.0, 0.1 / 3.0, 0.05 / 3.0, 0.1 / 3.0];
    let rule = common::normal_rule(14, 7.0);
    let mut moments = [[0.0; 3]; 2];
    for &(z0, w0) in &rule {
        for &(z1, w1) in &rule {
            for &(z2, w2) in &rule {
                for &(z3, w3) in &rule {
                    let v: [f64; 4] = std::array::from_fn(|i| {
                        nominal[i] * (1.0 + relative[i] * [z0, z1, z2, z3][i])
                    });
                    let (s, g) =
                        unbalance_peak(D::from(v[0]), D::from(v[1]), D::from(v[2]), D::from(v[3]));
                    let w = w0 * w1 * w2 * w3;
                    for (m, x) in moments.iter_mut().zip([s.re, g.re]) {
                        m[0] += w;
                        m[1] += w * x;
                        m[2] += w * x * x;
                    }
                }
            }
        }
    }
    for (what, m, stat) in [
        ("speed", moments[0], speed),
        ("peak", moments[1], magnitude),
    ] {
        let mean = m[1] / m[0];
        let sigma = (m[2] / m[0] - mean * mean).sqrt();
        assert!((m[0] - 1.0).abs() < 1e-10, "the rule's weights");
        // The peak goes as 1/c: its mean moves by about (σ_c/c)² = 1.1e-3 above nominal.
        close(stat.mean, mean, 3e-3, what);
        close(stat.std, sigma, 1e-2, what);
        // The curvature's share is seen: first order is not the exact answer by accident.
        assert!((stat.std - sigma).abs() > 1e-6 * sigma, "{what}");
    }
}
