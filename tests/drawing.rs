//! The drawing and the modes as motions of bodies and ports, against second routes:
//!
//! - the joints and centres of mass drawn in the SVG's three views, read back through each
//!   view's projection, are the model's equilibrium positions (a joint from its parent's pose,
//!   where the drawing places it from its child's) to 1e-9 of the mechanism's size;
//! - a mode's displacement of every body's centre of mass and its rotation equal central
//!   differences of the poses along the mode's real and imaginary parts, and a port's equals
//!   the port's vector (the transfer function's `b`) applied to the shape;
//! - an animation frame at phase φ (the motion of every point and direction to first order,
//!   from the bodies' motions) is the mechanism posed at `q + a Re(v e^{iφ})` to `O(a²)`, and
//!   the page's data posed as its script poses it is that frame;
//! - a 150-body chain's page animates every mode in under 5 MB.

mod common;

use common::{at, example};
use modaltol::compiled::Compiled;
use modaltol::drawing::{Drawing, MOTION_BUDGET, ModeMotion, animated, html, svg};
use modaltol::mechanics::System;
use modaltol::mechanics::kinematics::poses;
use modaltol::mechanics::ports::port_vectors;
use modaltol::modal::C64;
use modaltol::rigid::Pose;
use modaltol::scene::{Posed, Scene, mode_frames, physical_shape};
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

/// A view group's projection, from its tag: scale, origin `ox`, `oy`, and its h and v
/// directions (a point `x` is drawn at `(ox + scale·h·x, oy − scale·v·x)`).
fn projection(tag: &str) -> (f64, f64, f64, [f64; 3], [f64; 3]) {
    let f = |n| attr(tag, n).unwrap().parse::<f64>().unwrap();
    (
        f("data-scale"),
        f("data-ox"),
        f("data-oy"),
        triple(attr(tag, "data-h").unwrap()),
        triple(attr(tag, "data-v").unwrap()),
    )
}

/// Every mark of class `class` in every view of `svg`: (view, name, the point's components
/// along the view's h and v directions read back from cx, cy, and those directions).
fn marks(svg: &str, class: &str) -> Vec<(String, [f64; 2], [[f64; 3]; 2])> {
    let mut out = Vec::new();
    let mut view = None;
    for tag in svg.split('<').map(|t| t.split('>').next().unwrap_or("")) {
        if tag.starts_with("g class=\"view\"") {
            view = Some(projection(tag));
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
        ("friswell_5_9_1.toml", 400.0),
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
        ("friswell_5_9_1.toml", 400.0),
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

/// The largest distance between corresponding vectors of two scenes of one mechanism.
fn farthest(a: &Scene, b: &Scene) -> f64 {
    let (mut x, mut y) = (Vec::new(), Vec::new());
    a.map(&mut |p| x.push(*p));
    b.map(&mut |p| y.push(*p));
    assert_eq!(x.len(), y.len());
    (x.iter().zip(&y))
        .map(|(p, q)| ((0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>()).sqrt())
        .fold(0.0, f64::max)
}

#[test]
fn an_animation_frame_is_the_mechanism_posed_along_the_shape_to_second_order() {
    // A drawing's frame at phase φ (what the page animates) against the exact kinematics at
    // q + a Re(v e^{iφ}) (`mode_frames`): the difference is O(a²), so a tenth of the amplitude
    // leaves about a hundredth of it; and at the drawn amplitude the largest motion is a
    // tenth of the mechanism's size.
    for (name, speed) in [
        ("rotor_on_rubber_mounts.toml", 100.0),
        ("spinning_spatial_fourbar.toml", 3.0),
        ("governor.toml", 1.6),
        ("fourbar_diagonal_spring.toml", 0.0),
        ("rotating_blade.toml", 20.0),
        ("friswell_5_9_1.toml", 400.0),
    ] {
        let m = example(name);
        let model = m.model();
        let (p, pt) = solved(&m, speed);
        let d = Drawing::new(model, &p, &pt).unwrap();
        let sys = System::new(model, &p, speed).unwrap();
        let q = &pt.equilibrium.q;
        let n = 8;
        for (mode, shape) in d.modes.iter().zip(&pt.shapes) {
            let v: Vec<C64> = shape.iter().copied().collect();
            let a = mode.amplitude;
            assert!(a > 0.0 && a.is_finite(), "{name}: {}", mode.label);
            let small = ModeMotion {
                amplitude: a / 10.0,
                motion: (mode.motion.iter())
                    .map(|m| m.map(|x| x.map(|z| z / 10.0)))
                    .collect(),
                ..mode.clone()
            };
            let at = Posed {
                model,
                sys: &sys,
                q,
                free: &pt.linear.free,
            };
            let exact = mode_frames(at, &v, a, n);
            let exact_small = mode_frames(at, &v, a / 10.0, n);
            for k in 0..n {
                let phase = std::f64::consts::TAU * k as f64 / n as f64;
                let (big, little) = (
                    farthest(&mode.frame(&d, phase), &exact[k]),
                    farthest(&small.frame(&d, phase), &exact_small[k]),
                );
                assert!(
                    little <= 0.02 * big + 1e-9 * d.size,
                    "{name}, {}, φ = {phase}: {big} at a, {little} at a/10",
                    mode.label
                );
            }
            // Along the shape's real and imaginary parts (φ = 0, π/2), no point moves more
            // than a tenth of the size.
            for phase in [0.0, std::f64::consts::FRAC_PI_2] {
                let mut moved = Vec::new();
                mode.frame(&d, phase).map(&mut |x| moved.push(*x));
                let mut still = Vec::new();
                d.scene.map(&mut |x| still.push(*x));
                for ((x, y), anchor) in moved.iter().zip(&still).zip(&d.anchors) {
                    let dist = ((0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>()).sqrt();
                    assert!(
                        anchor.direction || dist <= 0.1 * d.size * (1.0 + 1e-9),
                        "{name}: {dist} vs {}",
                        d.size
                    );
                }
            }
        }
    }
}

/// The vectors of the page's data posed at phase `phase` of its mode `m` as its script
/// (src/drawing/viewer.js) poses them.
fn page_frame(data: &serde_json::Value, m: usize, phase: f64) -> Vec<[f64; 3]> {
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let x: Vec<f64> = data["x"].as_array().unwrap().iter().map(num).collect();
    let anchor: Vec<i64> = (data["anchor"].as_array().unwrap().iter())
        .map(|v| v.as_i64().unwrap())
        .collect();
    let mode = &data["modes"][m];
    let re: Vec<f64> = mode["re"].as_array().unwrap().iter().map(num).collect();
    let im: Vec<f64> = mode["im"].as_array().unwrap().iter().map(num).collect();
    let (c, s) = (phase.cos(), phase.sin());
    let mut out: Vec<[f64; 3]> = (0..anchor.len())
        .map(|i| {
            let p = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
            if anchor[i] == 0 {
                return p;
            }
            let b = (anchor[i].unsigned_abs() - 1) as usize;
            let at = |k: usize| re[6 * b + k] * c - im[6 * b + k] * s;
            let w = [at(3), at(4), at(5)];
            let cm = data["scene"]["bodies"][b]["cm"].as_u64().unwrap() as usize;
            let r: [f64; 3] = if anchor[i] > 0 {
                [0, 1, 2].map(|k| p[k] - x[3 * cm + k])
            } else {
                p
            };
            let turned = [
                w[1] * r[2] - w[2] * r[1],
                w[2] * r[0] - w[0] * r[2],
                w[0] * r[1] - w[1] * r[0],
            ];
            let y = [0, 1, 2].map(|k| p[k] + turned[k] + if anchor[i] > 0 { at(k) } else { 0.0 });
            if anchor[i] > 0 {
                y
            } else {
                let n = dot(&y, &y).sqrt();
                y.map(|v| v / n)
            }
        })
        .collect();
    // Inside a beam's curve: the Hermite combination of its nodes' motions and its tangents'
    // turns, `H₁ δa + H₂ L (ωₐ × tₐ) + H₃ δb + H₄ L (ω_b × t_b)`.
    let index = |v: &serde_json::Value| v.as_u64().unwrap() as usize;
    for curve in data["scene"]["beams"].as_array().unwrap() {
        let points: Vec<usize> = curve["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(index)
            .collect();
        let length = num(&curve["length"]);
        let n = points.len();
        let turn = |k: usize| -> [f64; 3] {
            let Some(b) = curve["nodes"][k].as_u64().map(|b| b as usize) else {
                return [0.0; 3];
            };
            let w = [3, 4, 5].map(|j| re[6 * b + j] * c - im[6 * b + j] * s);
            let t = index(&curve["tangents"][k]);
            let u = [x[3 * t], x[3 * t + 1], x[3 * t + 2]];
            [
                w[1] * u[2] - w[2] * u[1],
                w[2] * u[0] - w[0] * u[2],
                w[0] * u[1] - w[1] * u[0],
            ]
        };
        let (ta, tb) = (turn(0), turn(1));
        let (a, b) = (points[0], points[n - 1]);
        for (k, &p) in points.iter().enumerate().take(n - 1).skip(1) {
            let xi = k as f64 / (n - 1) as f64;
            let h = [
                1.0 - 3.0 * xi * xi + 2.0 * xi.powi(3),
                xi - 2.0 * xi * xi + xi.powi(3),
                3.0 * xi * xi - 2.0 * xi.powi(3),
                xi.powi(3) - xi * xi,
            ];
            out[p] = [0, 1, 2].map(|j| {
                let (da, db) = (out[a][j] - x[3 * a + j], out[b][j] - x[3 * b + j]);
                x[3 * p + j] + h[0] * da + h[1] * length * ta[j] + h[2] * db + h[3] * length * tb[j]
            });
        }
    }
    out
}

#[test]
fn the_pages_data_poses_the_frames_of_the_drawing() {
    // The page carries the equilibrium once and each mode's body motions; posed from them as
    // its script poses them, a frame equals the drawing's (to the page's rounding, a millionth
    // of the size).
    for (name, speed) in [
        ("rotor_on_rubber_mounts.toml", 100.0),
        ("spinning_spatial_fourbar.toml", 3.0),
        ("friswell_5_9_1.toml", 400.0),
    ] {
        let m = example(name);
        let (p, pt) = solved(&m, speed);
        let d = Drawing::new(m.model(), &p, &pt).unwrap();
        let page = html(&d, None);
        let start = page
            .find(r#"<script id="data" type="application/json">"#)
            .unwrap();
        let text = &page[start..];
        let text = &text[text.find('>').unwrap() + 1..text.find("</script>").unwrap()];
        let data: serde_json::Value = serde_json::from_str(&text.replace("<\\/", "</")).unwrap();
        assert_eq!(data["modes"].as_array().unwrap().len(), d.modes.len());
        for (k, mode) in d.modes.iter().enumerate() {
            for phase in [0.0, 1.0, 2.5, 4.0] {
                let mut want = Vec::new();
                mode.frame(&d, phase).map(&mut |x| want.push(*x));
                let got = page_frame(&data, k, phase);
                assert_eq!(got.len(), want.len());
                for (g, w) in got.iter().zip(&want) {
                    for c in 0..3 {
                        assert!(
                            (g[c] - w[c]).abs() < 1e-5 * d.size.max(1.0),
                            "{name}, {}: {g:?} vs {w:?}",
                            mode.label
                        );
                    }
                }
            }
        }
    }
}

/// A chain of `n` segments (the rotating blade's family: 1 m, springs between segments,
/// flapping out of the plane of rotation), hinged to a hub spinning about z.
fn chain(n: usize) -> String {
    let h = 1.0 / n as f64;
    let mut s = format!(
        "name = \"chain {n}\"\ngravity = [0, 0, 0]\n[[bodies]]\nname = \"hub\"\nmass = 1\n\
         inertia = [0.01, 0.01, 0.01]\ncm = [0, 0, 0]\n[[joints]]\nname = \"spin\"\n\
         type = \"revolute\"\nparent = \"ground\"\nchild = \"hub\"\nat = [0, 0, 0]\n\
         axis = [0, 0, 1]\ndrive = \"speed\"\n"
    );
    for i in 0..n {
        let parent = if i == 0 {
            "hub".into()
        } else {
            format!("s{}", i - 1)
        };
        s += &format!(
            "[[bodies]]\nname = \"s{i}\"\nmass = {}\ninertia = [0, {i2}, {i2}]\n\
             cm = [{}, 0, 0]\n[[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\n\
             parent = \"{parent}\"\nchild = \"s{i}\"\nat = [{}, 0, 0]\naxis = [0, -1, 0]\n\
             stiffness = {}\n",
            2.0 * h,
            (i as f64 + 0.5) * h,
            i as f64 * h,
            50.0 / h,
            i2 = 2.0 * h * h * h / 12.0,
        );
    }
    s
}

#[test]
fn a_150_body_chains_page_is_a_few_mb_and_animates_every_mode() {
    // Its 150 modes at 24 frames each made a page of 243 MB; posed by the page from each
    // body's motion, every mode fits in under 5 MB, drawn in seconds.
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("chain.toml");
    std::fs::write(&model, chain(150)).unwrap();
    let page = dir.path().join("chain.html");
    let t = std::time::Instant::now();
    let r = common::run_with_deadline(
        &[
            "draw",
            model.to_str().unwrap(),
            "--speed",
            "5",
            "-o",
            page.to_str().unwrap(),
        ],
        std::time::Duration::from_secs(120),
    )
    .unwrap();
    let took = t.elapsed().as_secs_f64();
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let text = std::fs::read_to_string(&page).unwrap();
    assert!(text.len() < 5_000_000, "{} bytes", text.len());
    assert!(took < 30.0, "{took} s");
    assert_eq!(text.matches("<option value=").count(), 151);
    assert!(!text.contains("This page animates modes 1 to"));
}

#[test]
fn a_page_animates_the_lowest_modes_that_fit_and_the_mode_asked_for() {
    // 150 bodies: all 150 modes; 3000 bodies: the lowest 8 of 3000 (12 numbers a body and
    // mode within the budget), and mode 2000 where asked for.
    assert_eq!(animated(151, 150, None), (0..150).collect::<Vec<_>>());
    let few = animated(3001, 3000, Some(1999));
    let lowest = MOTION_BUDGET / (12 * 3001);
    assert!((1..3000).contains(&lowest));
    assert_eq!(few.len(), lowest + 1);
    assert_eq!(few[lowest], 1999);
    assert_eq!(animated(3001, 3000, Some(2)).len(), lowest);
    assert_eq!(animated(1_000_000, 5, None), vec![0]);
    assert_eq!(animated(3, 0, None), Vec::<usize>::new());
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

/// The page opens animating the first mode that oscillates (it opened still on the
/// equilibrium), `--mode K` still chooses; a rigid first mode (the flywheel's free spin about
/// its bearing) is passed over for the arm's.
#[test]
fn the_page_opens_animating_the_first_mode_that_oscillates() {
    let start = |page: &str| -> i64 {
        let i = page.find("data-start=\"").unwrap() + "data-start=\"".len();
        page[i..].split('"').next().unwrap().parse().unwrap()
    };
    let m = example("governor.toml");
    let (p, pt) = solved(&m, 1.6);
    let d = Drawing::new(m.model(), &p, &pt).unwrap();
    assert_eq!(start(&html(&d, None)), 0);
    let flywheel = "gravity = [0, -9.81, 0]\n\
        [[bodies]]\nname = \"shaft\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\ncm = [0, 0.1, 0]\n\
        [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"shaft\"\n\
        at = [0, 0, 0]\naxis = [0, 1, 0]\ndrive = \"speed\"\n\
        [[bodies]]\nname = \"wheel\"\nmass = 1\ninertia = [0.1, 0.2, 0.1]\ncm = [0, 0.3, 0]\n\
        [[joints]]\nname = \"bearing\"\ntype = \"revolute\"\nparent = \"shaft\"\nchild = \"wheel\"\n\
        at = [0, 0.3, 0]\naxis = [0, 1, 0]\n\
        [[bodies]]\nname = \"arm\"\nmass = 0.5\ninertia = [0.001, 0.001, 0.001]\ncm = [0.2, 0, 0]\n\
        [[joints]]\nname = \"hinge\"\ntype = \"revolute\"\nparent = \"shaft\"\nchild = \"arm\"\n\
        at = [0, 0, 0]\naxis = [0, 0, 1]\nstiffness = 1e4\ndamping = 0.01\n";
    let m = Compiled::from_str(flywheel, "flywheel.toml").unwrap();
    let (p, pt) = solved(&m, 5.0);
    assert_eq!(pt.modes[0].class, modaltol::modal::ModeClass::Rigid);
    let d = Drawing::new(m.model(), &p, &pt).unwrap();
    assert_eq!(start(&html(&d, None)), 1);
    assert_eq!(start(&html(&d, Some(0))), 0);
}

/// The names in the front view never print over each other and stay in their panel (boxes
/// from the font size, a glyph 0.6 em wide: the placement's own estimate, so this checks the
/// placement, not the font), on every shipped example and the tutorial's pendulum; and the
/// views are drawn with up against gravity: the front view of a z-up model is an elevation.
#[test]
fn names_do_not_collide_and_views_stand_up_against_gravity() {
    let mut names: Vec<String> = std::fs::read_dir(common::example_path(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    names.push("tutorial/pendulum.toml".into());
    for name in &names {
        let m = example(name);
        let speed = m
            .model()
            .analysis
            .speed
            .map_or(1.0, |r| r.speeds().nth(r.len() / 2).unwrap());
        let (p, pt) = solved(&m, speed);
        let d = Drawing::new(m.model(), &p, &pt).unwrap();
        let page = svg(&d, None);
        let mut boxes: Vec<[f64; 4]> = Vec::new();
        for t in page.split("<text class=\"label\" ").skip(1) {
            let num = |k: &str| -> f64 {
                let i = t.find(&format!("{k}=\"")).unwrap() + k.len() + 2;
                t[i..].split('"').next().unwrap().parse().unwrap()
            };
            let text = t.split('>').nth(1).unwrap().split('<').next().unwrap();
            let w = 0.6 * 10.0 * text.chars().count() as f64;
            let (x, y) = (num("x"), num("y"));
            let b = [x, y - 8.0, x + w, y + 2.0];
            assert!(
                b[0] >= 0.0 && b[2] <= 360.0 && b[1] >= 44.0 && b[3] <= 404.0,
                "{name}: '{text}' leaves the front view"
            );
            for o in &boxes {
                let apart = b[2] <= o[0] || o[2] <= b[0] || b[3] <= o[1] || o[3] <= b[1];
                assert!(apart, "{name}: '{text}' {b:?} prints over a name at {o:?}");
            }
            boxes.push(b);
        }
        assert!(!boxes.is_empty(), "{name}: no names");
        let g = m.model().nominal();
        let gravity = modaltol::mechanics::System::new(m.model(), &g, speed)
            .unwrap()
            .gravity;
        let front = page.split("data-view=\"0\"").nth(1).unwrap();
        let v = front
            .split("data-v=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        let v: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
        let up = v[0] * gravity.x + v[1] * gravity.y + v[2] * gravity.z;
        if gravity.norm() > 0.0 {
            assert!(
                (up + gravity.norm()).abs() <= 1e-12 * gravity.norm(),
                "{name}: the front view's up {v:?} is not against gravity {gravity:?}"
            );
        } else {
            assert_eq!(v, [0.0, 1.0, 0.0], "{name}");
        }
    }
}

/// A solid drawn in one view: its body's name, its centre and the matrix `E⁻¹` of its
/// ellipse in the view's h, v coordinates (m), and the view's h and v.
type Ellipse = (String, [f64; 2], [[f64; 2]; 2], [[f64; 3]; 2]);

/// Every solid ellipse of every view of `svg`: (name, centre and the 2×2 matrix `E⁻¹` of the
/// ellipse `uᵀE⁻¹u ≤ 1` in the view's h, v coordinates (m), the view's h and v).
fn solid_ellipses(svg: &str) -> Vec<Ellipse> {
    let mut out = Vec::new();
    let mut view = None;
    for tag in svg.split('<').map(|t| t.split('>').next().unwrap_or("")) {
        if tag.starts_with("g class=\"view\"") {
            view = Some(projection(tag));
        } else if tag.starts_with("ellipse class=\"solid\"") {
            let (s, ox, oy, h, v) = view.unwrap();
            let f = |n| attr(tag, n).unwrap().parse::<f64>().unwrap();
            let (cx, cy, rx, ry) = (f("cx"), f("cy"), f("rx"), f("ry"));
            let turn = attr(tag, "transform").unwrap();
            let angle: f64 = turn["rotate(".len()..]
                .split(' ')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            // The ellipse's axes on the screen (y down), then in h, v (v up), in metres.
            let (c, sn) = (angle.to_radians().cos(), angle.to_radians().sin());
            let axes = [[c, -sn], [-sn, -c]];
            let mut inv = [[0.0; 2]; 2];
            for (a, r) in axes.iter().zip([rx / s, ry / s]) {
                for i in 0..2 {
                    for j in 0..2 {
                        inv[i][j] += a[i] * a[j] / (r * r);
                    }
                }
            }
            out.push((
                attr(tag, "data-name").unwrap().to_string(),
                [(cx - ox) / s, (oy - cy) / s],
                inv,
                [h, v],
            ));
        }
    }
    out
}

/// The solids drawn are the bodies' equivalent ellipsoids of inertia: on the Friswell rotor
/// (two thick disks) and the rubber-mounted rotor, each body's ellipsoid built a second way
/// (principal moments from the inertia's eigendecomposition, semi-axes
/// `a_i² = 5/(2m)(I_j + I_k − I_i)` along the principal axes), its surface sampled and
/// projected, lies inside the drawn ellipse and touches it (the largest `uᵀE⁻¹u` is 1 to
/// 1e-6); the shaft is drawn at its 50 mm diameter.
#[test]
fn bodies_are_drawn_as_their_equivalent_ellipsoids_and_shafts_at_their_diameter() {
    use nalgebra::{Matrix3, SymmetricEigen, Vector3};
    for name in ["friswell_5_9_1.toml", "rotor_on_rubber_mounts.toml"] {
        let m = example(name);
        let (p, pt) = solved(&m, 100.0);
        let d = Drawing::new(m.model(), &p, &pt).unwrap();
        let page = svg(&d, None);
        let sys = System::new(m.model(), &p, 100.0).unwrap();
        let pose = poses(&sys, &pt.equilibrium.q);
        let drawn = solid_ellipses(&page);
        let mut seen = 0;
        for (b, body) in sys.bodies.iter().enumerate() {
            let bname = &m.model().bodies[b].name;
            let views: Vec<_> = drawn.iter().filter(|e| &e.0 == bname).collect();
            if body.mass == 0.0 {
                assert!(
                    views.is_empty(),
                    "{name}: massless {bname} drawn as a solid"
                );
                continue;
            }
            assert_eq!(views.len(), 3, "{name}: {bname} in each view");
            seen += 1;
            let eig = SymmetricEigen::new(body.inertia);
            let i = eig.eigenvalues;
            let semi = Vector3::from_fn(|k, _| {
                let (j, l) = ((k + 1) % 3, (k + 2) % 3);
                (2.5 / body.mass * (i[j] + i[l] - i[k])).max(0.0).sqrt()
            });
            let rot = pose[b].rot * eig.eigenvectors;
            let cm = pose[b].apply(&body.cm);
            for (_, centre, inv, [h, v]) in views {
                let (h, v) = (Vector3::from(*h), Vector3::from(*v));
                assert!(
                    (centre[0] - cm.dot(&h)).abs() < 1e-9 && (centre[1] - cm.dot(&v)).abs() < 1e-9
                );
                let mut largest = 0.0f64;
                for a in 0..48 {
                    for e in 0..25 {
                        let (th, ph) = (
                            a as f64 * std::f64::consts::PI / 24.0,
                            e as f64 * std::f64::consts::PI / 24.0,
                        );
                        let s = Vector3::new(ph.sin() * th.cos(), ph.sin() * th.sin(), ph.cos());
                        let y = rot * Matrix3::from_diagonal(&semi) * s;
                        let u = [y.dot(&h), y.dot(&v)];
                        let q = u[0] * (inv[0][0] * u[0] + inv[0][1] * u[1])
                            + u[1] * (inv[1][0] * u[0] + inv[1][1] * u[1]);
                        largest = largest.max(q);
                    }
                }
                // A disk seen edge-on is kept a pixel thick: the sampled surface is inside.
                assert!(
                    largest <= 1.0 + 1e-6,
                    "{name}: {bname} reaches beyond its ellipse ({largest})"
                );
                assert!(
                    largest >= 1.0 - 1e-2,
                    "{name}: {bname}'s ellipse is larger than it ({largest})"
                );
            }
        }
        assert!(seen >= 2, "{name}: {seen} solids");
        if name == "friswell_5_9_1.toml" {
            for tag in page.split("<polyline class=\"beam-solid\"").skip(1) {
                let width: f64 = attr(tag, "stroke-width").unwrap().parse().unwrap();
                let scale: f64 = page
                    .split("data-scale=\"")
                    .nth(1)
                    .unwrap()
                    .split('"')
                    .next()
                    .unwrap()
                    .parse()
                    .unwrap();
                assert!(
                    (width / scale - 0.05).abs() < 1e-12,
                    "{name}: the shaft drawn {} m wide",
                    width / scale
                );
            }
        }
    }
}

/// The equivalent ellipsoid of a uniform solid ellipsoid is itself, turned or not; a thin
/// uniform disk's is flat with radius `r √5/2`; a point mass has none.
#[test]
fn a_uniform_ellipsoid_is_its_own_equivalent_ellipsoid() {
    use modaltol::scene::equivalent_ellipsoid;
    use nalgebra::{Matrix3, Rotation3, Vector3};
    let (m, a) = (3.5, Vector3::new(0.4, 0.15, 0.07));
    let j = Matrix3::from_diagonal(&Vector3::new(
        a.y * a.y + a.z * a.z,
        a.x * a.x + a.z * a.z,
        a.x * a.x + a.y * a.y,
    )) * (m / 5.0);
    let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
    let s = equivalent_ellipsoid(m, &(r * j * r.transpose()));
    let want = r * Matrix3::from_diagonal(&a.component_mul(&a)) * r.transpose();
    for i in 0..3 {
        for k in 0..3 {
            assert!(
                (s[i][k] - want[(i, k)]).abs() < 1e-15,
                "{s:?} against {want}"
            );
        }
    }
    let (m, radius) = (2.0, 0.3);
    let disk = Matrix3::from_diagonal(&Vector3::new(0.5, 0.25, 0.25)) * (m * radius * radius);
    let s = equivalent_ellipsoid(m, &disk);
    assert_eq!(s[0][0], 0.0);
    assert!((s[1][1].sqrt() - radius * 5f64.sqrt() / 2.0).abs() < 1e-15);
    assert_eq!(equivalent_ellipsoid(0.0, &disk), [[0.0; 3]; 3]);
}
