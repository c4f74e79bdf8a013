//! `[[shafts]]`: a shaft meshed from stations is the same model as its bodies, joints and beams
//! written out by hand, on both evaluation routes:
//!
//! * the shipped Friswell 5.9.1 rotor (one shaft table, disks `fixed` to nodes, the twist held
//!   by the shaft's coupling) against the same rotor written node by node (disks as the nodes'
//!   own mass, the twist held by a joint stiffness): every root at rest and at 4000 rpm;
//! * Friswell Example 5.9.2 (anisotropic bearings) at the book's frequencies;
//! * the same rotor seen from the ground (spinning nodes) and from a frame turning with it
//!   (nodes on a driven carrier): every root the same, shifted by the speed where it whirls
//!   (the frame-consistency test that catches spurious spin softening);
//! * a tapered station against the stepped stations of its elements' midpoint diameters;
//! * a blade meshed from a hub body (`start_body`) at the published rotating-cantilever
//!   frequencies;
//! * the rigid-segment blade (`examples/rotating_blade.toml`'s chain) converging, at second
//!   order in the segment length, to the beam blade of `examples/rotating_blade_beams.toml`;
//! * the governor on a flexible spindle (`examples/governor_on_flexible_spindle.toml`): its
//!   collar mode is the rigid governor's, its spindle's modes above it;
//! * a cantilever of 60 elements (a 360-coordinate pencil whose reduced matrix spans eight
//!   decades) at the closed-form matrices' frequencies, both planes' roots together;
//! * bad shafts refused at the field they come from.

#[path = "../examples/common/chain.rs"]
#[allow(dead_code)]
mod chain;
mod common;

use common::solve;
use common::timoshenko::{Plane, plane, whirl};
use modaltol::compiled::Compiled;
use nalgebra::DMatrix;
use std::f64::consts::PI;

fn model(text: &str) -> Compiled {
    Compiled::from_str(text, "shaft.toml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The roots `λ` (upper half plane, by imaginary part) at `speed`.
fn roots(m: &Compiled, speed: f64, direct: bool) -> Vec<(f64, f64)> {
    let pt = solve(m, speed, direct);
    let mut out: Vec<(f64, f64)> = (pt.modes.iter())
        .map(|m| (m.root.lambda.re, m.root.lambda.im))
        .collect();
    out.sort_by(|a, b| a.1.total_cmp(&b.1));
    out
}

/// Every root of `a` within `tol` (relative to the largest) of the root of `b` in its place.
fn same_roots(a: &[(f64, f64)], b: &[(f64, f64)], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: number of roots");
    let scale = a.iter().map(|r| r.0.hypot(r.1)).fold(0.0, f64::max);
    for (x, y) in a.iter().zip(b) {
        let d = (x.0 - y.0).hypot(x.1 - y.1);
        assert!(d <= tol * scale, "{what}: {x:?} vs {y:?}");
    }
}

/// Friswell 5.9.1 written node by node: each node a massless frame on a free joint and a
/// spinning node on a driven revolute, the disks the nodes' own mass, the twist held by node
/// 0's free joint.
fn friswell_by_hand() -> String {
    let disk = |m: &str, d: &str| {
        format!(
            "mass = \"{m}\"\ninertia = [\"{m}*({d}^2 + bore^2)/8\", \
             \"{m}*({d}^2 + bore^2)/16 + {m}*width^2/12\", \"{m}*({d}^2 + bore^2)/16 + {m}*width^2/12\"]\n"
        )
    };
    let text = common::example_text("friswell_5_9_1.toml");
    let mut out = text[..text.find("\n[[shafts]]").unwrap()].to_string();
    for k in 0..=6 {
        let x = 0.25 * k as f64;
        let mass = match k {
            2 => disk("disk1", "D1"),
            4 => disk("disk2", "D2"),
            _ => "mass = 0\n".into(),
        };
        let stiffness = match k {
            0 => "stiffness = [0, 0, 0, \"k_coupling\", 0, 0]\n",
            _ => "",
        };
        out += &format!(
            "[[bodies]]\nname = \"t{k}\"\nmass = 0\ncm = [{x}, 0, 0]\n\
             [[bodies]]\nname = \"n{k}\"\n{mass}cm = [{x}, 0, 0]\n\
             [[joints]]\nname = \"f{k}\"\ntype = \"free\"\nparent = \"ground\"\nchild = \"t{k}\"\n\
             at = [{x}, 0, 0]\n{stiffness}\
             [[joints]]\nname = \"s{k}\"\ntype = \"revolute\"\nparent = \"t{k}\"\nchild = \"n{k}\"\n\
             at = [{x}, 0, 0]\naxis = [1, 0, 0]\ndrive = \"speed\"\n"
        );
    }
    for k in 0..6 {
        out += &format!(
            "[[beams]]\nname = \"e{k}\"\nbody1 = \"n{k}\"\npoint1 = [{}, 0, 0]\nbody2 = \"n{}\"\n\
             point2 = [{}, 0, 0]\nreference = [0, 1, 0]\nouter_diameter = \"d\"\nE = \"E\"\n\
             G = \"G\"\ndensity = \"rho\"\n",
            0.25 * k as f64,
            k + 1,
            0.25 * (k + 1) as f64
        );
    }
    for k in [0, 6] {
        out += &format!(
            "[[forces]]\nname = \"bearing{k}\"\ntype = \"bushing\"\nbody1 = \"ground\"\n\
             body2 = \"n{k}\"\npoint1 = [{}, 0, 0]\n\
             stiffness = [\"k_thrust\", \"k_bearing\", \"k_bearing\", 0, 0, 0]\n",
            0.25 * k as f64
        );
    }
    out
}

#[test]
fn a_meshed_rotor_is_the_rotor_written_node_by_node() {
    let meshed = common::example("friswell_5_9_1.toml");
    let by_hand = model(&friswell_by_hand());
    for speed in [0.0, 4000.0 * PI / 30.0] {
        for direct in [false, true] {
            same_roots(
                &roots(&meshed, speed, direct),
                &roots(&by_hand, speed, direct),
                1e-12,
                &format!("{speed} rad/s, direct {direct}"),
            );
        }
    }
}

#[test]
fn friswell_example_5_9_2_anisotropic_bearings_at_the_book_frequencies() {
    // kyy = 0.8 kxx: the bending pairs split at rest (Friswell et al. 2010, Example 5.9.2;
    // 650.41 rad/s is the free-free torsion, untouched).
    let text = common::example_text("friswell_5_9_1.toml").replace(
        "stiffness = [\"k_thrust\", \"k_bearing\", \"k_bearing\", 0, 0, 0]",
        "stiffness = [\"k_thrust\", \"k_bearing\", \"0.8*k_bearing\", 0, 0, 0]",
    );
    assert_eq!(text.matches("0.8*k_bearing").count(), 2, "test setup");
    let m = model(&text);
    for direct in [false, true] {
        let w: Vec<f64> = roots(&m, 0.0, direct).iter().map(|r| r.1).collect();
        for x in [82.65, 86.66, 254.52, 274.31, 650.41, 679.49] {
            let off = w.iter().map(|y| (y - x).abs() / x).fold(1.0, f64::min);
            assert!(off <= 1e-4, "direct {direct}: {x} is {off:e} from {w:?}");
        }
    }
}

/// Friswell's rotor with its nodes on a carrier driven at the speed: the spin a drive of the
/// frame the nodes' translations and tilts are measured in, the twist held to the carrier by
/// the same coupling.
fn turning_friswell() -> String {
    let text = common::example_text("friswell_5_9_1.toml")
        .replace(
            "spin = \"speed\"\ncoupling = \"k_coupling\"\n",
            "parent = \"carrier\"\n",
        )
        .replacen(
            "\n[[shafts]]\n",
            "\n[[bodies]]\nname = \"carrier\"\nmass = 0\ncm = [0, 0, 0]\n\
             [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\n\
             child = \"carrier\"\nat = [0, 0, 0]\naxis = [1, 0, 0]\ndrive = \"speed\"\n\
             [[forces]]\nname = \"twist\"\ntype = \"rotational_spring_damper\"\n\
             body1 = \"carrier\"\nbody2 = \"shaft_0\"\naxis = [1, 0, 0]\n\
             stiffness = \"k_coupling\"\n[[shafts]]\n",
            1,
        );
    assert!(text.contains("parent = \"carrier\""), "test setup");
    text
}

#[test]
fn a_rotor_seen_from_the_ground_and_from_its_turning_frame_has_the_same_roots() {
    // In the frame turning at Ω an axisymmetric rotor's whirl at ω is seen at |ω ∓ Ω| (forward
    // and backward), its axial and torsional modes at ω. Built both ways from the same file:
    // the example's spinning nodes, and its nodes on a carrier driven at the speed (the spin
    // then a drive of the frame, the twist held to the carrier by the same coupling:
    // [`turning_friswell`]).
    let fixed = common::example("friswell_5_9_1.toml");
    let turning = model(&turning_friswell());
    for speed in [100.0, 4000.0 * PI / 30.0] {
        for direct in [false, true] {
            let a: Vec<f64> = roots(&fixed, speed, direct).iter().map(|r| r.1).collect();
            let b: Vec<f64> = roots(&turning, speed, direct).iter().map(|r| r.1).collect();
            assert_eq!(a.len(), b.len());
            for w in &b {
                let off = (a.iter())
                    .flat_map(|x| [(x - speed).abs(), x + speed, *x])
                    .map(|x| (x - w).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    off <= 1e-9 * w.max(1.0),
                    "{speed} rad/s, direct {direct}: {w} seen turning is {off:e} from every \
                     root seen from the ground shifted by the speed"
                );
            }
        }
    }
}

/// The frame each mode's frequency is said to be seen from is the one its roots are in (the
/// test above: the carrier's roots are the ground's shifted by the speed): every mode of the
/// example is `fixed`, every mode on the carrier `rotating` with its drive, in `modal`'s JSON.
#[test]
fn the_frame_a_mode_is_said_to_be_seen_from_is_the_frame_its_roots_are_in() {
    let fixed = common::example("friswell_5_9_1.toml");
    let turning = model(&turning_friswell());
    for (m, expected) in [(&fixed, "fixed"), (&turning, "rotating")] {
        let p = m.model().nominal();
        let pt = solve(m, 300.0, false);
        let json = modaltol::report::modal_json(m.model(), &p, 300.0, &Ok(pt));
        let modes = json["modes"].as_array().unwrap();
        assert_eq!(modes.len(), 42);
        for md in modes {
            assert_eq!(md["frame"], expected, "{}", md["mode"]);
            let by = if expected == "fixed" {
                serde_json::Value::Null
            } else {
                "spin".into()
            };
            assert_eq!(md["frame_turned_by"], by);
        }
    }
}

/// A tube cantilever along z from ground of `stations` (each `length, elements, diameter`).
fn cantilever(stations: &str) -> String {
    format!(
        "name = \"cantilever\"\ngravity = [0, 0, 0]\n\
         [[shafts]]\nname = \"c\"\nstart = [0, 0, 0]\naxis = [0, 0, 2]\nstart_body = \"ground\"\n\
         E = 2e11\nnu = 0.3\ndensity = 7800\nstations = [{stations}]\n"
    )
}

#[test]
fn a_tapered_station_is_the_stepped_shaft_of_its_midpoints() {
    let tapered = model(&cantilever(
        "{ length = 0.8, elements = 4, outer_diameter = [0.06, 0.04], inner_diameter = [0.02, 0.01] }",
    ));
    let stepped = (0..4)
        .map(|k| {
            let f = (k as f64 + 0.5) / 4.0;
            format!(
                "{{ length = 0.2, outer_diameter = {}, inner_diameter = {} }}",
                0.06 + (0.04 - 0.06) * f,
                0.02 + (0.01 - 0.02) * f
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let stepped = model(&cantilever(&stepped));
    for direct in [false, true] {
        same_roots(
            &roots(&tapered, 0.0, direct),
            &roots(&stepped, 0.0, direct),
            1e-12,
            "taper",
        );
    }
    // A uniform "taper" is the uniform shaft, and the taper moves the frequencies.
    let uniform = model(&cantilever(
        "{ length = 0.8, elements = 4, outer_diameter = 0.05, inner_diameter = 0.015 }",
    ));
    let flat = model(&cantilever(
        "{ length = 0.8, elements = 4, outer_diameter = [0.05, 0.05], inner_diameter = [0.015, 0.015] }",
    ));
    same_roots(
        &roots(&uniform, 0.0, false),
        &roots(&flat, 0.0, false),
        1e-12,
        "flat",
    );
    assert!(roots(&tapered, 0.0, false)[0].1 > 1.05 * roots(&uniform, 0.0, false)[0].1);
}

#[test]
fn a_blade_meshed_from_its_hub_flaps_at_the_published_frequencies() {
    // The uniform cantilever of `tests/beams.rs` (ρA = 1, EI = 1 flapwise, L = 1) on a hub
    // spinning about z, now one shaft table from the hub: its first two flap frequencies at
    // the nondimensional speeds 0 and 4 (Wright et al. 1982; Hodges & Rutkowski 1981).
    let m = model(
        "name = \"blade\"\ngravity = [0, 0, 0]\n\
         [[bodies]]\nname = \"hub\"\nmass = 0\ncm = [0, 0, 0]\n\
         [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"hub\"\n\
         at = [0, 0, 0]\naxis = [0, 0, 1]\ndrive = \"speed\"\n\
         [[shafts]]\nname = \"blade\"\nstart = [0, 0, 0]\naxis = [1, 0, 0]\nreference = [0, 0, 1]\n\
         parent = \"hub\"\nstart_body = \"hub\"\n\
         stations = [{ length = 1, elements = 12, EA = 1e7, GJ = 100, EI = [4, 1], rhoA = 1, \
         rhoI = [1e-4, 0, 0] }]\n",
    );
    for (speed, published) in [(0.0, [3.5160, 22.0346]), (4.0, [5.5850, 24.2735])] {
        for direct in [false, true] {
            let w: Vec<f64> = roots(&m, speed, direct).iter().map(|r| r.1).collect();
            for x in published {
                let off = w.iter().map(|y| (y - x).abs() / x).fold(1.0, f64::min);
                assert!(off <= 1e-3, "λ = {speed}: {x} is {off:e} from {w:?}");
            }
        }
    }
}

#[test]
fn a_finely_meshed_cantilever_keeps_its_repeated_roots() {
    // Before the symmetric eigensolver's pairs were checked by their residuals, faer's
    // decomposition gave this cantilever at 60 elements a first pair 100.82 / 101.47 rad/s and
    // at 80 a diverging root; the closed form's first roots are 101.4656 twice.
    let n = 60;
    let m = model(&cantilever(&format!(
        "{{ length = 1.5, elements = {n}, outer_diameter = 0.05 }}"
    )));
    let (d, e, g, rho) = (0.05, 2e11, 2e11 / 2.6, 7800.0);
    let (a, i) = (PI * d * d / 4.0, PI * d.powi(4) / 64.0);
    let nu: f64 = 0.3;
    let kappa = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);
    let section = Plane {
        ei: e * i,
        ga: kappa * g * a,
        rho_a: rho * a,
        rho_i: rho * i,
    };
    let l = 1.5 / n as f64;
    let one = plane(section, l, true);
    let mut mats = [0, 1, 2].map(|_| DMatrix::zeros(2 * n, 2 * n));
    for el in 0..n {
        for (whole, part) in mats.iter_mut().zip(&one) {
            // Node 0 is clamped: element `el` spans dofs 2el−2 .. 2el+1.
            for r in 0..4 {
                for c in 0..4 {
                    let (gr, gc) = (2 * el + r, 2 * el + c);
                    if gr >= 2 && gc >= 2 {
                        whole[(gr - 2, gc - 2)] += part[(r, c)];
                    }
                }
            }
        }
    }
    let mut reference = whirl(&mats, 0.0);
    reference.sort_by(f64::total_cmp);
    for direct in [false, true] {
        let w: Vec<f64> = roots(&m, 0.0, direct).iter().map(|r| r.1).collect();
        for k in 0..6 {
            let x = reference[k / 2];
            // The reduced matrix's rounding, ε ‖L⁻¹K̂L⁻ᵀ‖ / ω² ≈ 2e-16 · 1e12 / 1e4: a few 1e-9.
            assert!(
                ((w[k] - x) / x).abs() <= 2e-8,
                "direct {direct}: root {k} is {} against {x}",
                w[k]
            );
        }
    }
}

#[test]
fn the_rigid_segment_blade_converges_to_the_beam_blade() {
    // Hencky's chain of n rigid segments (springs EI/h) is a second-order finite-difference
    // model of the Euler–Bernoulli blade: its first two flap frequencies approach the beam
    // elements' (whose own error at 12 elements is below 1e-6) with errors falling about
    // fourfold as n doubles, at rest and spinning.
    let beam = common::example("rotating_blade_beams.toml");
    for speed in [0.0, 10.0, 20.0] {
        let reference = common::flapwise(&beam, speed, false);
        let errors: Vec<[f64; 2]> = [10, 20, 40, 80]
            .iter()
            .map(|&n| {
                let w: Vec<f64> = roots(&model(&chain::chain(n)), speed, false)
                    .iter()
                    .map(|r| r.1)
                    .collect();
                [0, 1].map(|k| ((w[k] - reference[k]) / reference[k]).abs())
            })
            .collect();
        for k in 0..2 {
            for pair in errors.windows(2) {
                let ratio = pair[0][k] / pair[1][k];
                assert!(
                    (3.0..5.0).contains(&ratio),
                    "{speed} rad/s, flap mode {}: errors {errors:?}",
                    k + 1
                );
            }
            assert!(errors[3][k] < 2e-3, "{speed} rad/s: {errors:?}");
        }
    }
}

#[test]
fn the_governor_on_its_flexible_spindle_keeps_the_rigid_governors_collar_mode() {
    // The governor's arms hinged on a spindle node and its collar sliding on another, the
    // nodes riding on the turning carrier: the collar mode is the rigid governor's (whose
    // spindle is driven, so its mass does not enter), moved only by the spindle's compliance
    // (its gravity sag, its tilt under the arms' reactions); and the spindle's own bending
    // modes lie above it.
    let rigid = common::example("governor.toml");
    let flexible = common::example("governor_on_flexible_spindle.toml");
    for speed in [1.0, 3.0] {
        let want = roots(&rigid, speed, false)[0];
        for direct in [false, true] {
            let got = roots(&flexible, speed, direct);
            let gap = (got[0].0 - want.0).hypot(got[0].1 - want.1) / want.0.hypot(want.1);
            assert!(gap < 1e-5, "{speed} rad/s: {:?} vs {want:?}", got[0]);
            assert!(got[1].1 > 100.0, "{speed} rad/s: {got:?}");
        }
    }
}

/// A cantilever of one station, for the bad-input cases.
const ONE: &str = r#"name = "one"
[[shafts]]
name = "s"
start = [0, 0, 0]
axis = [1, 0, 0]
E = 2e11
nu = 0.3
density = 7800
start_body = "ground"

[[shafts.stations]]
length = 0.5
elements = 3
outer_diameter = 0.05
inner_diameter = 0.02
"#;

#[test]
fn bad_shafts_are_refused_at_their_field() {
    assert!(Compiled::from_str(ONE, "ok.toml").is_ok());
    let cases: [(&str, &str, &str, &str); 12] = [
        ("length = 0.5", "length = 0", "length", "must be positive"),
        (
            "length = 0.5",
            "length = \"speed\"",
            "length",
            "must not depend on the speed",
        ),
        ("elements = 3", "elements = 0", "elements", "whole number"),
        (
            "elements = 3",
            "elements = 20000",
            "elements",
            "whole number",
        ),
        (
            "axis = [1, 0, 0]",
            "axis = [0, 0, 0]",
            "axis",
            "axis is zero",
        ),
        (
            "axis = [1, 0, 0]",
            "axis = [1, 0]",
            "axis",
            "expected 3 components",
        ),
        (
            "outer_diameter = 0.05",
            "outer_diameter = [0.05, 0.04, 0.03]",
            "outer_diameter",
            "not 3 values",
        ),
        (
            "inner_diameter = 0.02",
            "inner_diameter = 0.05",
            "inner_diameter",
            "not below the outer",
        ),
        (
            "density = 7800",
            "density = 7800\ncoupling = 1",
            "coupling",
            "spinning shaft",
        ),
        (
            "start_body = \"ground\"",
            "start_body = \"hub\"",
            "start_body",
            "unknown body 'hub'",
        ),
        (
            "inner_diameter = 0.02",
            "inner_diameter = 0.02\nEA = 1e8",
            "[[shafts.stations]]",
            "both as a tube",
        ),
        (
            "name = \"s\"",
            "name = \"s s\"",
            "name = \"s s\"",
            "letters, digits",
        ),
    ];
    for (from, to, at, message) in cases {
        assert!(ONE.contains(from), "test setup: {from}");
        let text = ONE.replacen(from, to, 1);
        let e = Compiled::from_str(&text, "bad.toml").expect_err(&format!("{to}: refused"));
        let want = text[..text.find(at).unwrap()].matches('\n').count() + 1;
        assert_eq!(e.line, Some(want), "{to}: {e}");
        assert!(e.message.contains(message), "{to}: {e}");
    }
    // What a shaft's parts cannot say together.
    for (from, to, at, message) in [
        (
            "density = 7800",
            "density = 7800\nspin = \"speed\"\ncoupling = 1",
            "coupling = 1",
            "`start_body` 'ground' is the first node",
        ),
        (
            "density = 7800",
            "density = 7800\nspin = \"speed\"",
            "start_body",
            "the ground does not",
        ),
        (
            "outer_diameter = 0.05",
            "outer_diameter = [0.05, -0.01]",
            "outer_diameter",
            "outer diameter -0.01 at the station's end",
        ),
        (
            "inner_diameter = 0.02",
            "inner_diameter = [0.02, 0.06]",
            "inner_diameter",
            "inner diameter 0.06 at the station's end",
        ),
        ("elements = 3", "elements = 1", "end_body", "to itself"),
    ] {
        let base = ONE.replacen(
            "start_body = \"ground\"",
            "start_body = \"ground\"\nend_body = \"ground\"",
            usize::from(message == "to itself"),
        );
        let text = base.replacen(from, to, 1);
        let e = Compiled::from_str(&text, "bad.toml").expect_err(&format!("{to}: refused"));
        let want = text[..text.find(at).unwrap()].matches('\n').count() + 1;
        assert_eq!(e.line, Some(want), "{to}: {e}");
        assert!(e.message.contains(message), "{to}: {e}");
    }
    // Too many elements is refused before any is generated (a 6 KB file once took 9 GB).
    let many = ONE.replacen("elements = 3", "elements = 10000", 1)
        + "[[shafts.stations]]\nlength = 0.5\nelements = 10000\nouter_diameter = 0.05\n";
    let e = Compiled::from_str(&many, "bad.toml").expect_err("too many");
    assert!(e.message.contains("more than 10000 elements"), "{e}");
    // A station's own ν replaces the shaft's G (they say one thing).
    let own = ONE.replacen(
        "inner_diameter = 0.02",
        "inner_diameter = 0.02\nnu = 0.25",
        1,
    );
    assert!(Compiled::from_str(&own, "ok.toml").is_ok());
    // A length toleranced through zero turns its element end for end: inadmissible.
    let toleranced = ONE.replacen("length = 0.5", "length = \"l\"", 1).replacen(
        "name = \"one\"\n",
        "name = \"one\"\n[parameters]\nl = { value = 0.5, tolerance = \"300%\" }\n",
        1,
    );
    let m = Compiled::from_str(&toleranced, "l.toml").unwrap();
    let mut p = m.model().nominal();
    assert!(m.model().admissible(&p).is_ok());
    p[0] = -0.2;
    let d = m.model().admissible(&p).expect_err("reversed");
    assert!(d.reason.contains("meet or cross"), "{}", d.reason);
    // No stations at all.
    let text = ONE[..ONE.find("[[shafts.stations]]").unwrap()].to_string() + "stations = []\n";
    let e = Compiled::from_str(&text, "bad.toml").expect_err("no stations");
    assert!(e.message.contains("no stations"), "{e}");
}
