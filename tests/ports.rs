//! Transfer functions between physical points ([[ports]]).
//!
//! * A port's vector `b` (force in, displacement out) against central differences of the
//!   point's position over the kinematics, for every coordinate; a rotation port's against
//!   differences of the body's orientation.
//! * The governor: a translation port at the collar along the spindle axis is the collar's
//!   slide coordinate, and a rotation port on a ball about its hinge axis is the arm angle, so
//!   their transfer functions and the analytic derivatives of |H| agree with the coordinates'
//!   (to 1e-12 and 1e-9 relative).

mod common;

use common::{example_text, solve};
use modaltol::compiled::Compiled;
use modaltol::mechanics::System;
use modaltol::mechanics::kinematics::poses;
use modaltol::mechanics::ports::port_vectors;
use modaltol::model::Channel;
use modaltol::sensitivity::{DesignPoint, TransferAt, nominal_transfer};

fn governor_with_ports() -> Compiled {
    Compiled::from_str(&governor_text(), "governor_ports.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn governor_text() -> String {
    example_text("governor.toml").replace(
        "[analysis]",
        r#"[[ports]]
name = "collar_y"
type = "translation"
body = "collar"
point = [0, "collar_y", 0]
direction = [0, 2, 0]

[[ports]]
name = "ball1_swing"
type = "rotation"
body = "ball1"
direction = [0, 0, 1]

[[ports]]
name = "ball1_off"
type = "translation"
body = "ball1"
point = [0.15, 0.05, 0.02]
direction = [0.3, -1, 0.5]

[[ports]]
name = "ball2_tilted"
type = "rotation"
body = "ball2"
direction = [0.2, 0.4, -1]

[analysis]"#,
    )
}

#[test]
fn port_vectors_are_the_derivatives_of_the_points_motion() {
    let model = governor_with_ports();
    let pt = solve(&model, 3.0, false);
    let p = model.model().nominal();
    let sys = System::new(model.model(), &p, 3.0).unwrap();
    let q = pt.equilibrium.q.clone();
    let all: Vec<usize> = (0..q.len()).collect();
    let b = port_vectors(&sys, &q, &all);
    let h = 1e-6;
    let at = |i: usize, s: f64| {
        let mut qq = q.clone();
        qq[i] += s * h;
        poses(&sys, &qq)
    };
    let here = poses(&sys, &q);
    for (k, port) in sys.ports.iter().enumerate() {
        let rot = here[port.body].rot;
        let u = rot * port.direction;
        for (i, &bi) in b[k].iter().enumerate() {
            let (plus, minus) = (at(i, 1.0), at(i, -1.0));
            let (a, c) = (&plus[port.body], &minus[port.body]);
            let fd = if port.rotation {
                // ω δt = axial(Ṙ Rᵀ) δt.
                let dr = (a.rot - c.rot) / (2.0 * h) * rot.transpose();
                let w = nalgebra::Vector3::new(
                    dr[(2, 1)] - dr[(1, 2)],
                    dr[(0, 2)] - dr[(2, 0)],
                    dr[(1, 0)] - dr[(0, 1)],
                ) * 0.5;
                u.dot(&w)
            } else {
                u.dot(&((a.apply(&port.point) - c.apply(&port.point)) / (2.0 * h)))
            };
            assert!(
                (bi - fd).abs() <= 1e-8,
                "port {k}, coordinate {i}: {bi} vs {fd}"
            );
        }
    }
}

/// |H|, arg H and the analytic d|H|/dp of two transfer functions agree.
fn same_transfer(model: &Compiled, a: (Channel, Channel), b: (Channel, Channel)) {
    let p = model.model().nominal();
    let wrt = model.model().toleranced();
    for speed in [1.0, 2.5, 4.0] {
        for direct in [false, true] {
            let pt = solve(model, speed, direct);
            for omega in [0.7 * speed, speed, 13.0] {
                let ta = TransferAt {
                    input: a.0,
                    output: a.1,
                    omega,
                };
                let tb = TransferAt {
                    input: b.0,
                    output: b.1,
                    omega,
                };
                let (ha, hb) = (
                    nominal_transfer(&pt, &ta).unwrap(),
                    nominal_transfer(&pt, &tb).unwrap(),
                );
                let scale = ha.magnitude();
                assert!(
                    (ha.re - hb.re).abs() <= 1e-12 * scale
                        && (ha.im - hb.im).abs() <= 1e-12 * scale,
                    "{ha:?} vs {hb:?} at {speed} rad/s, ω = {omega}"
                );
                let (sa, sb) = (
                    DesignPoint::new(model, &p, &pt)
                        .with_transfer(Some(ta))
                        .analytic(&wrt)
                        .unwrap(),
                    DesignPoint::new(model, &p, &pt)
                        .with_transfer(Some(tb))
                        .analytic(&wrt)
                        .unwrap(),
                );
                for (x, y) in sa.variables.iter().zip(&sb.variables) {
                    let (dx, dy) = (
                        x.d_transfer_magnitude.unwrap(),
                        y.d_transfer_magnitude.unwrap(),
                    );
                    assert!(
                        (dx - dy).abs() <= 1e-9 * dx.abs().max(1e-300),
                        "d|H|/d{}: {dx} vs {dy}",
                        model.model().parameters[x.param].name
                    );
                }
            }
        }
    }
}

#[test]
fn a_port_at_the_collar_along_the_spindle_is_the_collar_coordinate() {
    let model = governor_with_ports();
    let slide = model.model().channel("slide").unwrap();
    let port = model.model().channel("collar_y").unwrap();
    assert_eq!(port, Channel::Port(0));
    same_transfer(&model, (slide, slide), (port, port));
    // Mixed ends: a force at the collar port, the collar coordinate's response.
    same_transfer(&model, (slide, slide), (port, slide));
}

#[test]
fn a_rotation_port_about_a_hinge_axis_is_the_hinge_coordinate() {
    let model = governor_with_ports();
    let arm = model.model().channel("arm1").unwrap();
    let swing = model.model().channel("ball1_swing").unwrap();
    let slide = model.model().channel("slide").unwrap();
    same_transfer(&model, (arm, slide), (swing, slide));
    same_transfer(&model, (arm, arm), (swing, swing));
}

#[test]
fn reciprocity_holds_between_any_two_ports_at_rest() {
    // Without spin (no gyroscopic or circulatory terms) the receptance is symmetric:
    // H(a → b) = H(b → a), for ports at arbitrary points and directions.
    let model = governor_with_ports();
    let pt = solve(&model, 0.0, false);
    let (a, b) = (
        model.model().channel("ball1_off").unwrap(),
        model.model().channel("ball2_tilted").unwrap(),
    );
    for omega in [0.5, 5.0, 40.0] {
        let ab = nominal_transfer(
            &pt,
            &TransferAt {
                input: a,
                output: b,
                omega,
            },
        )
        .unwrap();
        let ba = nominal_transfer(
            &pt,
            &TransferAt {
                input: b,
                output: a,
                omega,
            },
        )
        .unwrap();
        let scale = ab.magnitude();
        assert!(scale > 0.0);
        assert!(
            (ab.re - ba.re).abs() <= 1e-12 * scale && (ab.im - ba.im).abs() <= 1e-12 * scale,
            "{ab:?} vs {ba:?}"
        );
    }
}

#[test]
fn the_tolerance_analysis_of_a_port_transfer_equals_the_coordinates() {
    // Every method's mean and σ of |H| (the Taylor methods through the Hessians of the port
    // vectors, the quadrature through their values) for the collar port as for the collar's
    // coordinate; and the unit of |H| follows the ends.
    use modaltol::analyze::{AnalyzeOptions, analyze};
    use modaltol::output::Quantity;
    let by_port = Compiled::from_str(
        &governor_text().replace(
            "transfer = { input = \"slide\", output = \"slide\", order = 1 }",
            "transfer = { input = \"collar_y\", output = \"collar_y\", order = 1 }",
        ),
        "governor_ports.toml",
    )
    .unwrap();
    let by_coordinate = governor_with_ports();
    assert_eq!(
        by_port.model().analysis.transfer.unwrap().input,
        by_port.model().channel("collar_y").unwrap()
    );
    let t = by_coordinate.model().analysis.transfer.unwrap();
    assert_eq!(by_coordinate.model().transfer_unit(&t), "m/N");
    let rotation = by_coordinate.model().channel("ball1_swing").unwrap();
    let mixed = modaltol::model::Transfer {
        input: rotation,
        output: t.output,
        order: 1.0,
    };
    assert_eq!(by_coordinate.model().transfer_unit(&mixed), "m/(N·m)");
    let run = |m: &Compiled| {
        let case = m
            .model()
            .analysis
            .cases
            .iter()
            .find(|c| c.name == "all3")
            .unwrap();
        let opt = AnalyzeOptions {
            speeds: vec![1.0, 2.5, 4.0],
            cases: vec![case.clone()],
            ..Default::default()
        };
        analyze(m, &opt, &|_, _, _| {})
            .rows
            .into_iter()
            .filter(|r| r.quantity == Quantity::TransferMagnitude)
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(&by_port), run(&by_coordinate));
    assert_eq!(a.len(), b.len());
    assert!(a.len() >= 9, "{}", a.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((x.speed, x.method()), (y.speed, y.method()));
        assert!(
            (x.mean - y.mean).abs() <= 1e-9 * y.mean.abs(),
            "{x:?} vs {y:?}"
        );
        assert!(
            (x.std - y.std).abs() <= 1e-9 * y.std.abs(),
            "{x:?} vs {y:?}"
        );
    }
}
