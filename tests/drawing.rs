//! The drawing and the modes as motions of bodies and ports, against second routes:
//!
//! - the joints and centres of mass drawn in the SVG's three views, read back through each
//!   view's projection, are the model's equilibrium positions (a joint from its parent's pose,
//!   where the drawing places it from its child's) to 1e-9 of the mechanism's size;
//! - a mode's displacement of every body's centre of mass and its rotation equal central
//!   differences of the poses along the mode's real and imaginary parts, and a port's equals
//!   the port's vector (the transfer function's `b`) applied to the shape;
//! - an animation frame at phase φ is the mechanism posed at `q + a Re(v e^{iφ})`.

mod common;

use common::{at, example};
use modaltol::compiled::Compiled;
use modaltol::drawing::{Drawing, svg};
use modaltol::mechanics::System;
use modaltol::mechanics::kinematics::poses;
use modaltol::mechanics::ports::port_vectors;
use modaltol::modal::C64;
use modaltol::rigid::Pose;
use modaltol::scene::{Scene, physical_shape};
use modaltol::sweep::Options;

/// The value of attribute `name` in the tag `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    Some(&tag[i..i + tag[i..].find('"')?])
}

fn triple(s: &str) -> [f64; 3] {
    let v: Vec<f64> = s.split(',').map(|x| x.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Every mark of class `class` in every view of `svg`: (view, name, the point's components
/// along the view's h and v directions read back from cx, cy, and those directions).
fn marks(svg: &str, class: &str) -> Vec<(String, [f64; 2], [[f64; 3]; 2])> {
    let mut out = Vec::new();
    let mut view = None;
    for tag in svg.split('<').map(|t| t.split('>').next().unwrap_or("")) {
        if tag.starts_with("g class=\"view\"") {
            let f = |n| attr(tag, n).unwrap().parse::<f64>().unwrap();
            view = Some((
                f("data-scale"),
                f("data-ox"),
                f("data-oy"),
                triple(attr(tag, "data-h").unwrap()),
                triple(attr(tag, "data-v").unwrap()),
            ));
        } else if tag.starts_with(&format!("circle class=\"{class}\"")) {
            let (s, ox, oy, h, v) = view.unwrap();
            let cx: f64 = attr(tag, "cx").unwrap().parse().unwrap();
            let cy: f64 = attr(tag, "cy").unwrap().parse().unwrap();
            out.push((
                attr(tag, "data-name").unwrap().to_string(),
                [(cx - ox) / s, (oy - cy) / s],
                [h, v],
            ));
        }
    }
    out
}

fn solved(m: &Compiled, speed: f64) -> (Vec<f64>, modaltol::sweep::Point) {
    let p = m.model().nominal();
    let pt = at(m, speed, &Options::default());
    (p, pt)
}

#[test]
fn the_drawn_joints_and_centres_of_mass_are_the_equilibriums() {
    for (name, speed) in [
        ("governor.toml", 1.6),
        ("spinning_spatial_fourbar.toml", 3.0),
        ("rotor_on_rubber_mounts.toml", 100.0),
        ("conical_pendulum.toml", 7.0),
        ("rotating_blade.toml", 20.0),
    ] {
        let m = example(name);
        let model = m.model();
        let (p, pt) = solved(&m, speed);
        let d = Drawing::new(model, &p, &pt).unwrap();
        let text = svg(&d, None);
        let sys = System::new(model, &p, speed).unwrap();
        let pose = poses(&sys, &pt.equilibrium.q);
        let ground = Pose::identity();
        let tol = 1e-9 * d.size;
        let joints = marks(&text, "joint");
        assert_eq!(joints.len(), 3 * model.joints.len(), "{name}");
        for (k, j) in sys.joints.iter().enumerate() {
            let jn = &model.joints[model.order[k]].name;
            // From the parent's side (the drawing places it from the child's).
            let [uses_at, _, _] = j.kind.uses();
            // A joint that slides places its point on the child (it moves with it).
            let slides = ["prismatic", "cylindrical", "planar", "free"].contains(&j.kind.name());
            let x = if uses_at == modaltol::joints::Use::Unused || slides {
                pose[j.child].apply(&sys.bodies[j.child].cm)
            } else {
                if slides {
                    pose[j.child].apply(&j.geometry.at)
                } else {
                    j.parent.map_or(&ground, |b| &pose[b]).apply(&j.geometry.at)
                }
            };
            let x = [x.x, x.y, x.z];
            for (_, got, [h, v]) in joints.iter().filter(|(n, ..)| n == jn) {
                let want = [dot(h, &x), dot(v, &x)];
                assert!(
                    (got[0] - want[0]).abs() < tol && (got[1] - want[1]).abs() < tol,
                    "{name}: joint {jn} drawn at {got:?}, is at {want:?}"
                );
            }
        }
        let cms = marks(&text, "cm");
        assert_eq!(cms.len(), 3 * model.bodies.len());
        for (b, body) in model.bodies.iter().enumerate() {
            let x = pose[b].apply(&sys.bodies[b].cm);
            let x = [x.x, x.y, x.z];
            for (_, got, [h, v]) in cms.iter().filter(|(n, ..)| *n == body.name) {
                let want = [dot(h, &x), dot(v, &x)];
                assert!(
                    (got[0] - want[0]).abs() < tol && (got[1] - want[1]).abs() < tol,
                    "{name}: body {} drawn at {got:?}, is at {want:?}",
                    body.name
                );
            }
        }
    }
}

#[test]
fn a_modes_body_and_port_motions_are_the_kinematics_of_its_shape() {
    for (name, speed) in [
        ("rotor_on_rubber_mounts.toml", 100.0),
        ("spinning_spatial_fourbar.toml", 3.0),
        ("governor.toml", 1.6),
        ("rotating_blade.toml", 20.0),
    ] {
        let m = example(name);
        let model = m.model();
        let (p, pt) = solved(&m, speed);
        let sys = System::new(model, &p, speed).unwrap();
        let q = &pt.equilibrium.q;
        let free = &pt.linear.free;
        let b = port_vectors(&sys, q, free);
        for shape in &pt.shapes {
            let v: Vec<C64> = shape.iter().copied().collect();
            let ps = physical_shape(&sys, q, free, &v);
            let scale = v.iter().map(|z| z.norm()).fold(0.0, f64::max);
            for (part, pick) in [("re", 0), ("im", 1)] {
                let h = 1e-6 / scale;
                let at = |s: f64| {
                    let mut qs = q.clone();
                    for (&i, z) in free.iter().zip(&v) {
                        qs[i] += s * h * if pick == 0 { z.re } else { z.im };
                    }
                    poses(&sys, &qs)
                };
                let (plus, minus) = (at(1.0), at(-1.0));
                for (k, body) in model.bodies.iter().enumerate() {
                    let cm = |p: &[Pose<f64>]| p[k].apply(&sys.bodies[k].cm);
                    let fd = (cm(&plus) - cm(&minus)) / (2.0 * h);
                    // The rotation: axial((R₊ − R₋) R₀ᵀ)/(2h) to second order.
                    let r0 = pose_of(&sys, q, k);
                    let dr = (plus[k].rot - minus[k].rot) * r0.transpose() / (2.0 * h);
                    let w = [
                        0.5 * (dr[(2, 1)] - dr[(1, 2)]),
                        0.5 * (dr[(0, 2)] - dr[(2, 0)]),
                        0.5 * (dr[(1, 0)] - dr[(0, 1)]),
                    ];
                    for c in 0..3 {
                        let (d, r) = (ps.displacement[k][c], ps.rotation[k][c]);
                        let (d, r) = if pick == 0 {
                            (d.re, r.re)
                        } else {
                            (d.im, r.im)
                        };
                        assert!(
                            (d - fd[c]).abs() < 1e-6 * (1.0 + fd[c].abs()) * scale,
                            "{name}: {} displacement {c} ({part}): {d} vs {}",
                            body.name,
                            fd[c]
                        );
                        assert!(
                            (r - w[c]).abs() < 1e-6 * (1.0 + w[c].abs()) * scale,
                            "{name}: {} rotation {c} ({part}): {r} vs {}",
                            body.name,
                            w[c]
                        );
                    }
                }
            }
            for (port, bv) in ps.ports.iter().zip(&b) {
                let want: C64 = bv.iter().zip(&v).map(|(bi, z)| z * *bi).sum();
                assert!((port - want).norm() < 1e-12 * (1.0 + want.norm()) * scale);
            }
            assert_eq!(ps.ports.len(), model.ports.len());
        }
    }
}

fn pose_of(sys: &System<f64>, q: &[f64], k: usize) -> nalgebra::Matrix3<f64> {
    poses(sys, q)[k].rot
}

#[test]
fn an_animation_frame_is_the_mechanism_posed_along_the_shape() {
    let m = example("rotor_on_rubber_mounts.toml");
    let model = m.model();
    let (p, pt) = solved(&m, 100.0);
    let d = Drawing::new(model, &p, &pt).unwrap();
    let sys = System::new(model, &p, 100.0).unwrap();
    let q = &pt.equilibrium.q;
    let still = Scene::at(model, &sys, q);
    for (mode, shape) in d.modes.iter().zip(&pt.shapes) {
        let n = mode.frames.len();
        assert_eq!(n, 24);
        let v: Vec<C64> = shape.iter().copied().collect();
        let a = mode.amplitude;
        assert!(a > 0.0 && a.is_finite());
        // Every frame: the mechanism at q + a Re(v e^{iφ}).
        for (f, frame) in mode.frames.iter().enumerate() {
            let phase = C64::from_polar(1.0, std::f64::consts::TAU * f as f64 / n as f64);
            let mut qf = q.clone();
            for (&i, z) in pt.linear.free.iter().zip(&v) {
                qf[i] += a * (z * phase).re;
            }
            let want = Scene::at(model, &sys, &qf);
            for (x, y) in frame.points().zip(want.points()) {
                for c in 0..3 {
                    assert!((x[c] - y[c]).abs() < 1e-9 * d.size, "frame {f}");
                }
            }
        }
        // The largest motion is a tenth of the size (first order, so to a few per cent).
        let largest = mode
            .frames
            .iter()
            .flat_map(|fr| {
                fr.points()
                    .zip(still.points())
                    .map(|(x, y)| ((0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>()).sqrt())
                    .collect::<Vec<_>>()
            })
            .fold(0.0, f64::max);
        assert!(largest <= 0.1 * d.size * 1.05, "{largest} vs {}", d.size);
    }
}

#[test]
fn a_forward_whirl_stiffens_with_speed_and_a_backward_one_softens_whatever_the_spins_sign() {
    // The rotor's gyroscopic pair (modes 4 and 5): the mode named forward whirl rises with the
    // speed, the backward one falls (the splitting of a spinning disc), for either sense of
    // spin, where the sense of each orbit flips with the spin.
    let m = example("rotor_on_rubber_mounts.toml");
    let model = m.model();
    let p = model.nominal();
    // The gyroscopic pair: modes 4 and 5 (about 250 and 265 rad/s), one named forward, the
    // other backward, at every speed here.
    let named = |speed: f64| {
        let pt = at(&m, speed, &Options::default());
        let what = modaltol::scene::descriptions(model, &p, &pt);
        let f = |word: &str| {
            let k = [3, 4]
                .into_iter()
                .find(|&k| what[k].contains(word))
                .unwrap();
            pt.modes[k].damped_frequency
        };
        (f("forward whirl"), f("backward whirl"))
    };
    for sign in [1.0, -1.0] {
        let (f1, b1) = named(sign * 50.0);
        let (f2, b2) = named(sign * 150.0);
        assert!(
            f2 > f1 + 1.0 && b2 < b1 - 1.0,
            "{sign}: forward {f1} → {f2}, backward {b1} → {b2}"
        );
    }
    // Without spin, no whirl is named.
    let pt = at(&m, 0.0, &Options::default());
    assert!(
        modaltol::scene::descriptions(model, &p, &pt)
            .iter()
            .all(|w| !w.contains("whirl"))
    );
}

#[test]
fn the_mac_is_one_for_a_shape_at_any_scale_and_zero_across() {
    use modaltol::scene::mac;
    let a = [C64::new(1.0, 0.5), C64::new(-0.3, 2.0), C64::new(0.0, 0.1)];
    let b: Vec<C64> = a.iter().map(|z| z * C64::new(-2.0, 3.0)).collect();
    assert!((mac(&a, &b) - 1.0).abs() < 1e-14);
    let e1 = [C64::new(1.0, 0.0), C64::new(0.0, 0.0)];
    let e2 = [C64::new(0.0, 0.0), C64::new(0.0, 1.0)];
    assert!(mac(&e1, &e2).abs() < 1e-15);
    assert!(mac(&e1, &[C64::new(0.0, 0.0); 2]).abs() < 1e-15);
}

#[test]
fn the_report_draws_the_mechanism_its_modes_and_their_mac() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let model = common::example_path("rotor_on_rubber_mounts.toml");
    let r = common::run_with_deadline(
        &[
            "analyze",
            model.to_str().unwrap(),
            "--speed",
            "90:110:10",
            "--samples",
            "20",
            "--no-quadrature",
            "-o",
            out.to_str().unwrap(),
        ],
        std::time::Duration::from_secs(300),
    )
    .unwrap();
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for f in [
        "mechanism.svg",
        "mechanism.html",
        "mode_1.svg",
        "mode_2.svg",
        "mode_3.svg",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("src=\"mechanism.svg\"") && html.contains("href=\"mechanism.html\""));
    assert!(html.contains("Modal assurance criterion"));
    // The Campbell diagram names each line by its shape, whirl included.
    let campbell = std::fs::read_to_string(out.join("campbell.svg")).unwrap();
    assert!(
        campbell.contains(", FW)") && campbell.contains(", BW)"),
        "{campbell}"
    );
}
