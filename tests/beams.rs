//! The beam element (issue 56) against the closed-form Timoshenko matrices of
//! `common::timoshenko`, on both evaluation routes:
//!
//! * a clamped, inclined two-element beam with unequal bending planes linearises to the
//!   assembled closed-form stiffness and consistent mass, turned to global axes;
//! * a shaft spinning about its own axis (each node on a free joint and a driven revolute,
//!   Nelson's fixed-frame model) has `Ĉ = Ω G` and no spin softening in `K̂`;
//! * under an axial load the stiffness gains exactly the consistent geometric stiffness of
//!   the solved axial force, not the string term alone;
//! * Friswell et al. (2010) Example 5.9.1 whirls at ROSS's published frequencies;
//! * material damping `β` gives `Ĉ = β K̂` and `ζ = βω/2` at rest, and on a spinning rotor the
//!   internal-damping instability from exactly the speed where it meets its forward whirl.

mod common;

use common::solve;
use common::timoshenko::{Beam3, Plane, assemble, element};
use modaltol::compiled::Compiled;
use nalgebra::{DMatrix, Matrix3};
use std::f64::consts::PI;

fn model(text: &str) -> Compiled {
    if let Ok(dir) = std::env::var("DUMP") {
        let name = text.lines().next().unwrap().split('"').nth(1).unwrap();
        std::fs::write(format!("{dir}/{name}.toml"), text).unwrap();
    }
    Compiled::from_str(text, "beams.toml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// How each node of a line of beams is held.
#[derive(Clone, Copy, PartialEq)]
enum Nodes {
    /// A free joint from ground: three translations and three rotations in global axes.
    Free,
    /// A free joint from ground to a massless frame, then a revolute about the beam's axis
    /// driven at the speed: the node spins, its translations and tilts are in ground axes.
    Spinning,
}

/// `n` beams in a row from `start` along the unit `dir` (total `length`), node 0 on ground
/// when `clamped` (a spinning clamp for spinning nodes; else a node like the others).
struct Line {
    n: usize,
    start: [f64; 3],
    dir: [f64; 3],
    length: f64,
    reference: [f64; 3],
    nodes: Nodes,
    clamped: bool,
}

/// The model text of `line`, its beams' section fields `section`.
fn line(line: Line, section: &str) -> String {
    let Line {
        n,
        start,
        dir,
        length,
        reference,
        nodes,
        clamped,
    } = line;
    let at = |k: usize| {
        let s = length * k as f64 / n as f64;
        format!(
            "[{}, {}, {}]",
            start[0] + s * dir[0],
            start[1] + s * dir[1],
            start[2] + s * dir[2]
        )
    };
    let mut out = String::new();
    let first = usize::from(clamped && nodes == Nodes::Free);
    for k in first..=n {
        if k == 0 && clamped {
            // A spinning clamp: node 0 turns with the drive and nothing else.
            out += &format!(
                "[[bodies]]\nname = \"n0\"\nmass = 0\ncm = {p}\n\
                 [[joints]]\nname = \"s0\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"n0\"\n\
                 at = {p}\naxis = [{}, {}, {}]\ndrive = \"speed\"\n",
                dir[0],
                dir[1],
                dir[2],
                p = at(0)
            );
            continue;
        }
        let p = at(k);
        match nodes {
            Nodes::Free => {
                out += &format!(
                    "[[bodies]]\nname = \"n{k}\"\nmass = 0\ncm = {p}\n\
                 [[joints]]\nname = \"j{k}\"\ntype = \"free\"\nparent = \"ground\"\nchild = \"n{k}\"\nat = {p}\n"
                )
            }
            Nodes::Spinning => {
                out += &format!(
                    "[[bodies]]\nname = \"t{k}\"\nmass = 0\ncm = {p}\n\
                 [[bodies]]\nname = \"n{k}\"\nmass = 0\ncm = {p}\n\
                 [[joints]]\nname = \"j{k}\"\ntype = \"free\"\nparent = \"ground\"\nchild = \"t{k}\"\nat = {p}\n\
                 [[joints]]\nname = \"s{k}\"\ntype = \"revolute\"\nparent = \"t{k}\"\nchild = \"n{k}\"\nat = {p}\n\
                 axis = [{}, {}, {}]\ndrive = \"speed\"\n",
                    dir[0], dir[1], dir[2]
                )
            }
        }
    }
    for k in 0..n {
        let a = if k == 0 && clamped && nodes == Nodes::Free {
            "ground".to_string()
        } else {
            format!("n{k}")
        };
        out += &format!(
            "[[beams]]\nname = \"e{k}\"\nbody1 = \"{a}\"\npoint1 = {}\nbody2 = \"n{}\"\npoint2 = {}\n\
             reference = [{}, {}, {}]\n{section}\n",
            at(k),
            k + 1,
            at(k + 1),
            reference[0],
            reference[1],
            reference[2],
        );
    }
    out
}

/// `M` turned from the element's axes `e` (columns) to global ones, per 3-vector block.
fn to_global(m: &DMatrix<f64>, e: &Matrix3<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    let mut t = DMatrix::zeros(n, n);
    for b in 0..n / 3 {
        t.view_mut((3 * b, 3 * b), (3, 3)).copy_from(e);
    }
    &t * m * t.transpose()
}

/// `|a − b| ≤ tol · max|b|`, entry by entry.
fn same(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}");
    let scale = b.amax();
    let worst = (a - b).amax();
    assert!(
        worst <= tol * scale,
        "{what}: differs by {worst:e} (largest entry {scale:e})\n{a}\n{b}"
    );
}

/// The properties section of the first test: unequal planes, shear flexible, and its
/// closed-form counterpart.
const PROPERTIES: &str = "EA = 4.0e8\nGJ = 3.0e5\nEI = [2.0e5, 5.0e5]\nkGA = [6.0e7, 9.0e7]\n\
                          rhoA = 15.0\nrhoI = [0.02, 0.006, 0.014]";

fn properties() -> Beam3 {
    Beam3 {
        ea: 4.0e8,
        gj: 3.0e5,
        rho_a: 15.0,
        rho_j: 0.02,
        // About e₂ the deflection is along e₃ and shears with κGA₃; about e₃ with κGA₂.
        about2: Plane {
            ei: 2.0e5,
            ga: 9.0e7,
            rho_a: 15.0,
            rho_i: 0.006,
        },
        about3: Plane {
            ei: 5.0e5,
            ga: 6.0e7,
            rho_a: 15.0,
            rho_i: 0.014,
        },
    }
}

/// The element's axes for the unit `dir` and a reference direction.
fn axes(dir: [f64; 3], reference: [f64; 3]) -> Matrix3<f64> {
    let e1 = nalgebra::Vector3::from(dir).normalize();
    let r = nalgebra::Vector3::from(reference);
    let e2 = (r - e1 * r.dot(&e1)).normalize();
    Matrix3::from_columns(&[e1, e2, e1.cross(&e2)])
}

/// The inclined clamped beam against the closed forms, undamped and with stiffness-proportional
/// material damping `β`: `K̂` and `M̂` the assembled closed forms, `Ĉ = β K̂` on both routes (0
/// without `β`), and every mode damped at `ζ = β ω_n / 2` (proportional damping: the undamped
/// modes decouple `Ĉ` too).
#[test]
fn an_inclined_clamped_beam_linearises_to_the_closed_form_matrices() {
    let n = 2;
    let length = 1.3;
    let d = nalgebra::Vector3::new(0.3, -0.5, 0.8).normalize();
    let dir = [d.x, d.y, d.z];
    let reference = [0.2, 0.9, 0.1];
    let e = axes(dir, reference);
    let whole = assemble(&element(&properties(), length / n as f64), n, true);
    let k = to_global(&whole[0], &e);
    for beta in [0.0, 2.0e-4] {
        let section = match beta {
            0.0 => PROPERTIES.to_string(),
            b => format!("{PROPERTIES}\nbeta = {b}"),
        };
        let text = format!(
            "name = \"inclined\"\ngravity = [0, 0, 0]\n{}",
            line(
                Line {
                    n,
                    start: [0.1, 0.2, -0.3],
                    dir,
                    length,
                    reference,
                    nodes: Nodes::Free,
                    clamped: true
                },
                &section
            )
        );
        let m = model(&text);
        for direct in [false, true] {
            let pt = solve(&m, 0.0, direct);
            let lin = &pt.linear;
            same(&lin.k, &k, 1e-11, "K");
            same(&lin.m, &to_global(&whole[1], &e), 1e-11, "M");
            if beta == 0.0 {
                assert!(lin.c.amax() == 0.0, "C at rest");
                continue;
            }
            same(&lin.c, &(&k * beta), 1e-11, "C");
            for mode in &pt.modes {
                let (wn, zeta) = (mode.natural_frequency, mode.damping_ratio);
                assert!(
                    (zeta - beta * wn / 2.0).abs() <= 1e-9 * zeta,
                    "ω_n {wn}: ζ {zeta} against βω_n/2 = {}",
                    beta * wn / 2.0
                );
            }
        }
    }
}

/// Internal damping destabilises a rotor above its first forward critical speed: damping that
/// turns with the shaft resists the rate of its deformation seen from the shaft, which for a
/// forward circular whirl at ω is proportional to ω − Ω. On the Friswell rotor (axisymmetric,
/// isotropic undamped bearings) with `β` on the shaft, the least-damped root near the first
/// critical crosses into the right half-plane exactly where the speed equals its own frequency
/// (Ω = ω_fw(Ω), the first forward critical speed: the shape is then frozen in the shaft and
/// nothing damps it), found here by bisection on both routes; below it every root is damped.
#[test]
fn internal_damping_destabilises_the_rotor_from_its_first_forward_critical_speed() {
    let text = common::example_text("friswell_5_9_1.toml").replacen(
        "density = \"rho\"\n",
        "density = \"rho\"\nbeta = 2e-4\n",
        1,
    );
    assert!(text.contains("beta = 2e-4"), "the shaft is damped");
    let m = model(&text);
    // The root near the first critical with the largest real part `(Re λ, Im λ)`, and the
    // largest real part of all the others.
    let roots = |w: f64, direct: bool| {
        let pt = solve(&m, w, direct);
        let near = |r: &modaltol::modal::Mode| (r.root.lambda.im - 87.0).abs() < 20.0;
        let worst = |f: &dyn Fn(&modaltol::modal::Mode) -> bool| {
            pt.modes
                .iter()
                .filter(|r| f(r))
                .map(|r| (r.root.lambda.re, r.root.lambda.im))
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .unwrap()
        };
        (worst(&near), worst(&|r| !near(r)).0)
    };
    // (The torsional mode on the soft coupling twists no element: undamped, Re λ is rounding
    // about zero.)
    let (below, others) = roots(60.0, false);
    assert!(below.0 < 0.0 && others <= 1e-9, "{below:?} {others}");
    // The onset on the recorded route by regula falsi with the Illinois modification (Re λ is
    // smooth in Ω).
    let (mut a, mut b) = ((60.0, below.0), (120.0, roots(120.0, false).0.0));
    assert!(b.1 > 0.0, "unstable above the critical speed");
    let mut side = 0;
    let onset = loop {
        let x = (a.0 * b.1 - b.0 * a.1) / (b.1 - a.1);
        let (((re, w), _), width) = (roots(x, false), b.0 - a.0);
        if re.abs() <= 1e-12 * w || width <= 1e-10 * x {
            break x;
        }
        if re > 0.0 {
            b = (x, re);
            if side == 1 {
                a.1 *= 0.5;
            }
            side = 1;
        } else {
            a = (x, re);
            if side == -1 {
                b.1 *= 0.5;
            }
            side = -1;
        }
    };
    // There, on both routes: the whirl at the speed, and neutrally stable.
    for direct in [false, true] {
        let ((re, w), _) = roots(onset, direct);
        assert!(
            (w - onset).abs() <= 1e-7 * onset && re.abs() <= 1e-9 * w,
            "onset at Ω = {onset} rad/s: root {re} + {w}i (direct: {direct})"
        );
    }
}

/// A steel tube of outer and inner diameter `d`, `di` as the closed forms read it: Cowper's
/// shear coefficient from `ν = E/2G − 1`.
fn tube(d: f64, di: f64, e: f64, g: f64, rho: f64) -> Beam3 {
    let nu = e / (2.0 * g) - 1.0;
    let a = PI * (d * d - di * di) / 4.0;
    let i = PI * (d.powi(4) - di.powi(4)) / 64.0;
    let m2 = (di / d).powi(2);
    let kappa = 6.0 * (1.0 + nu) * (1.0 + m2).powi(2)
        / ((7.0 + 6.0 * nu) * (1.0 + m2).powi(2) + (20.0 + 12.0 * nu) * m2);
    let plane = Plane {
        ei: e * i,
        ga: kappa * g * a,
        rho_a: rho * a,
        rho_i: rho * i,
    };
    Beam3 {
        ea: e * a,
        gj: g * 2.0 * i,
        rho_a: rho * a,
        rho_j: rho * 2.0 * i,
        about2: plane,
        about3: plane,
    }
}

#[test]
fn a_shaft_spinning_about_its_axis_has_the_gyroscopic_matrix_and_no_spin_softening() {
    // Three elements from a spinning clamp, each node a free joint then a driven revolute:
    // the stationary-frame (Nelson) model, K̂ independent of Ω and Ĉ = Ω G, with G in the
    // closed form of a spin about e₁.
    let (n, length) = (3, 0.9);
    let d = nalgebra::Vector3::new(0.6, 0.0, -0.8);
    let dir = [d.x, d.y, d.z];
    let reference = [0.0, 1.0, 0.0];
    let section =
        "outer_diameter = 0.06\ninner_diameter = 0.02\nE = 2.1e11\nG = 8.1e10\ndensity = 7800";
    let text = format!(
        "name = \"spinning\"\ngravity = [0, 0, 0]\n{}",
        line(
            Line {
                n,
                start: [0.0, 0.0, 0.0],
                dir,
                length,
                reference,
                nodes: Nodes::Spinning,
                clamped: true
            },
            section
        )
    );
    let m = model(&text);
    let e = axes(dir, reference);
    let parts = element(&tube(0.06, 0.02, 2.1e11, 8.1e10, 7800.0), length / n as f64);
    let whole = assemble(&parts, n, true);
    for direct in [false, true] {
        for spin in [0.0, 400.0, 3000.0] {
            let pt = solve(&m, spin, direct);
            let lin = &pt.linear;
            same(&lin.k, &to_global(&whole[0], &e), 1e-10, "K");
            same(&lin.m, &to_global(&whole[1], &e), 1e-11, "M");
            if spin > 0.0 {
                same(&lin.c, &(to_global(&whole[2], &e) * spin), 1e-10, "C");
            }
        }
    }
}

#[test]
fn an_axial_load_adds_the_consistent_geometric_stiffness_of_the_solved_force() {
    // A clamped, shear-flexible beam along x pulled at its tip by P. Each element stretches to
    // ℓ = h(1 + P/EA) and carries N = P, so its exact tangent is the closed form with the
    // lateral translations read against ℓ (the chord angle is v/ℓ): `S (K₀ + P K_σ) S` with
    // `S = h/ℓ` on them, and the string term at ℓ rather than h. That is the assembled
    // Engesser-type K_σ, not the string term P/ℓ alone (which differs in the translations
    // by a tenth here, φ = 0.36).
    let (n, length, pull) = (4, 2.0, 2.0e3);
    let plane = Plane {
        ei: 3.0e5,
        ga: 4.0e7,
        rho_a: 15.0,
        rho_i: 0.004,
    };
    let ea = 4.0e8;
    let beam = Beam3 {
        ea,
        gj: 2.4e5,
        rho_a: 15.0,
        rho_j: 0.008,
        about2: plane,
        about3: plane,
    };
    let section = "EA = 4.0e8\nGJ = 2.4e5\nEI = 3.0e5\nkGA = 4.0e7\nrhoA = 15.0\nrhoI = [0.008, 0.004, 0.004]";
    let text = format!(
        "name = \"pulled\"\ngravity = [0, 0, 0]\n{}\n[[loads]]\nname = \"pull\"\ntype = \"force\"\n\
         body = \"n{n}\"\npoint = [{length}, 0, 0]\nforce = [{pull}, 0, 0]\n",
        line(
            Line {
                n,
                start: [0.0; 3],
                dir: [1.0, 0.0, 0.0],
                length,
                reference: [0.0, 1.0, 0.0],
                nodes: Nodes::Free,
                clamped: true
            },
            section
        )
    );
    let m = model(&text);
    let h = length / n as f64;
    let stretched = h * (1.0 + pull / ea);
    let [k0, _, _, sigma] = element(&beam, h);
    // The string term per unit N/ℓ: on the lateral translations of the two nodes.
    let mut string = DMatrix::zeros(12, 12);
    for (i, j, v) in [(1, 1, 1.0), (1, 7, -1.0), (7, 1, -1.0), (7, 7, 1.0)] {
        for off in [0, 1] {
            string[(i + off, j + off)] = v;
        }
    }
    let mut scale = DMatrix::identity(12, 12);
    for i in [1, 2, 7, 8] {
        scale[(i, i)] = h / stretched;
    }
    let exact = |sigma: &DMatrix<f64>| {
        let whole = &scale * (&k0 + sigma * pull) * &scale
            + &string * (pull / stretched - pull * h / (stretched * stretched));
        assemble(&[whole], n, true).remove(0)
    };
    // With the string term alone in place of K_σ: what a co-rotational element without the
    // shallow-arch term gives.
    let alone = exact(&(&string / h));
    let exact = exact(&sigma);
    for direct in [false, true] {
        let k = solve(&m, 0.0, direct).linear.k;
        same(&k, &exact, 1e-12, "K");
        assert!((&k - &alone).amax() > 0.05 * (&sigma * pull).amax());
    }
}

#[test]
fn friswell_example_5_9_1_whirls_at_the_published_frequencies() {
    // Friswell et al. (2010) Example 5.9.1 as ROSS builds it (`rotor_example1`): a 1.5 m steel
    // shaft of 50 mm in six elements, disks on nodes 2 (Ø 280 mm) and 4 (Ø 350 mm), both
    // 70 mm wide on a 50 mm bore, bearings of 1 MN/m at the ends. ROSS's lateral frequencies
    // (rad/s; its 650.41 is torsional and depends on how the shaft is held about its axis,
    // here by a soft coupling): 0 rpm 86.66, 274.31, 716.78 (each twice); 4000 rpm
    // backward 85.39, 251.78, 600.18, forward 87.80, 294.71.
    let (e, g, rho) = (211.0e9, 81.2e9, 7810.0);
    let section = format!("outer_diameter = 0.05\nE = {e}\nG = {g}\ndensity = {rho}");
    let mut text = format!(
        "name = \"friswell_5_9_1\"\ngravity = [0, 0, 0]\n{}",
        line(
            Line {
                n: 6,
                start: [0.0; 3],
                dir: [1.0, 0.0, 0.0],
                length: 1.5,
                reference: [0.0, 1.0, 0.0],
                nodes: Nodes::Spinning,
                clamped: false
            },
            &section
        )
    );
    // The disks on their nodes; the node bodies are massless otherwise.
    let disk = |outer: f64| {
        let (w, inner) = (0.07, 0.05);
        let mass = rho * PI * w * (outer * outer - inner * inner) / 4.0;
        let polar = mass * (outer * outer + inner * inner) / 8.0;
        (mass, polar, polar / 2.0 + mass * w * w / 12.0)
    };
    for (node, outer) in [(2, 0.28), (4, 0.35)] {
        let (mass, polar, diametral) = disk(outer);
        let x = 0.25 * node as f64;
        text = text.replace(
            &format!("name = \"n{node}\"\nmass = 0\ncm = [{x}, 0, 0]\n"),
            &format!(
                "name = \"n{node}\"\nmass = {mass}\ncm = [{x}, 0, 0]\ninertia = [{polar}, {diametral}, {diametral}]\n"
            ),
        );
    }
    for node in [0, 6] {
        text += &format!(
            "[[forces]]\nname = \"bearing{node}\"\ntype = \"bushing\"\nbody1 = \"ground\"\nbody2 = \"n{node}\"\n\
             point1 = [{}, 0, 0]\nstiffness = [1e9, 1e6, 1e6, 0, 0, 0]\n",
            0.25 * node as f64
        );
    }
    // Torsion held by a soft coupling on node 0's twist (its free joint's rx).
    text = text.replace(
        "name = \"j0\"\ntype = \"free\"\nparent = \"ground\"\nchild = \"t0\"\nat = [0, 0, 0]\n",
        "name = \"j0\"\ntype = \"free\"\nparent = \"ground\"\nchild = \"t0\"\nat = [0, 0, 0]\n\
         stiffness = [0, 0, 0, 1, 0, 0]\n",
    );
    let m = model(&text);
    // The independent reference: the closed-form matrices of one plane and the disks.
    let beam = tube(0.05, 0.0, e, g, rho);
    let plane = common::timoshenko::plane(beam.about3, 0.25, true);
    let mut mats = [0, 1, 2].map(|_| DMatrix::zeros(14, 14));
    for el in 0..6 {
        for (whole, part) in mats.iter_mut().zip(&plane) {
            let mut block = whole.view_mut((2 * el, 2 * el), (4, 4));
            block += part;
        }
    }
    for (node, outer) in [(2, 0.28), (4, 0.35)] {
        let (mass, polar, diametral) = disk(outer);
        mats[1][(2 * node, 2 * node)] += mass;
        mats[1][(2 * node + 1, 2 * node + 1)] += diametral;
        mats[2][(2 * node + 1, 2 * node + 1)] += polar;
    }
    for node in [0, 6] {
        mats[0][(2 * node, 2 * node)] += 1.0e6;
    }
    let published: [(f64, &[f64]); 2] = [
        (0.0, &[86.66, 274.31, 716.78]),
        (4000.0 * PI / 30.0, &[85.39, 251.78, 600.18, 87.80, 294.71]),
    ];
    for (spin, ross) in published {
        let mut reference = common::timoshenko::whirl(&mats, spin);
        reference.extend(common::timoshenko::whirl(&mats, -spin));
        for direct in [false, true] {
            let pt = solve(&m, spin, direct);
            let w: Vec<f64> = pt.modes.iter().map(|m| m.root.lambda.im.abs()).collect();
            let nearest = |x: f64| {
                w.iter()
                    .map(|y| (y - x).abs() / x)
                    .fold(f64::INFINITY, f64::min)
            };
            for &x in ross {
                assert!(
                    nearest(x) <= 1e-4,
                    "{spin} rad/s: ROSS's {x} is {:e} from {w:?}",
                    nearest(x)
                );
            }
            // To rounding, spinning too: before the first-order form was balanced and its
            // roots refined on the pencil, this stiff system's low whirl roots (the roots span
            // 1 to 6e4 rad/s) were 1.5e-8 off.
            for &x in reference.iter().filter(|&&x| x < 1000.0) {
                assert!(
                    nearest(x) <= 5e-8,
                    "{spin} rad/s: the closed form's {x} is {:e} away",
                    nearest(x)
                );
            }
        }
    }
}

/// A uniform Euler–Bernoulli blade of `n` elements on a hub spinning about z at the speed,
/// clamped at the axis: `ρA = 1`, `EI = 1` flapwise (about e₃ = −y, deflection along z) and 4
/// in the plane of rotation (about e₂ = z), `L = 1`, nearly inextensible, so the nondimensional speed
/// `λ = Ω√(ρAL⁴/EI)` is the speed and `ω̄` the frequency. Each node is on a free joint
/// carried by the hub (the rotating frame).
fn blade(n: usize) -> Compiled {
    let mut text = String::from(
        "name = \"blade\"\ngravity = [0, 0, 0]\n\
         [[bodies]]\nname = \"hub\"\nmass = 0\ncm = [0, 0, 0]\n\
         [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"hub\"\n\
         at = [0, 0, 0]\naxis = [0, 0, 1]\ndrive = \"speed\"\n",
    );
    let at = |k: usize| format!("[{}, 0, 0]", k as f64 / n as f64);
    for k in 1..=n {
        text += &format!(
            "[[bodies]]\nname = \"n{k}\"\nmass = 0\ncm = {p}\n\
             [[joints]]\nname = \"j{k}\"\ntype = \"free\"\nparent = \"hub\"\nchild = \"n{k}\"\nat = {p}\n",
            p = at(k)
        );
    }
    for k in 0..n {
        let a = if k == 0 {
            "hub".to_string()
        } else {
            format!("n{k}")
        };
        text += &format!(
            "[[beams]]\nname = \"e{k}\"\nbody1 = \"{a}\"\npoint1 = {}\nbody2 = \"n{}\"\npoint2 = {}\n\
             reference = [0, 0, 1]\nEA = 1e7\nGJ = 100\nEI = [4, 1]\nrhoA = 1\nrhoI = [1e-4, 0, 0]\n",
            at(k),
            k + 1,
            at(k + 1)
        );
    }
    model(&text)
}

#[test]
fn a_rotating_blade_flaps_at_the_published_frequencies() {
    // Uniform cantilever on a hub of zero radius, flapwise, nondimensional (Wright, Smith,
    // Thresher & Wang 1982, J. Appl. Mech. 49:197; Hodges & Rutkowski 1981, AIAA J. 19:1459;
    // the values as tabulated by Banerjee 2000, J. Sound Vib. 233:857, Table 1, and re-derived
    // here independently by Hermite elements with the exact centrifugal tension to ±1e-4).
    let table: [(f64, [f64; 2]); 6] = [
        (0.0, [3.5160, 22.0346]),
        (1.0, [3.6816, 22.1811]),
        (2.0, [4.1373, 22.6150]),
        (4.0, [5.5850, 24.2735]),
        (8.0, [9.2569, 29.9955]),
        (12.0, [13.1702, 37.6034]),
    ];
    for n in [8, 16] {
        let m = blade(n);
        for (speed, published) in table {
            for direct in [false, true] {
                let w = common::flapwise(&m, speed, direct);
                for (k, x) in published.iter().enumerate() {
                    assert!(
                        ((w[k] - x) / x).abs() <= 1e-3,
                        "{n} elements, λ = {speed}, flap mode {}: {} vs {x}",
                        k + 1,
                        w[k]
                    );
                }
            }
        }
    }
    // Southwell's coefficients, ω² = ω₀² + S Ω² for small Ω: 1.1933 and 6.4782.
    let m = blade(16);
    let (w0, w) = (
        common::flapwise(&m, 0.0, false),
        common::flapwise(&m, 0.05, false),
    );
    for (k, s) in [1.1933, 6.4782].into_iter().enumerate() {
        let measured = (w[k] * w[k] - w0[k] * w0[k]) / (0.05 * 0.05);
        assert!(
            ((measured - s) / s).abs() <= 2e-3,
            "Southwell {}: {measured} vs {s}",
            k + 1
        );
    }
}

/// One tube beam from ground to a free node, for the bad-input cases.
const ONE: &str = r#"name = "one"
[[bodies]]
name = "n1"
mass = 0
cm = [1, 0, 0]

[[joints]]
name = "j1"
type = "free"
parent = "ground"
child = "n1"
at = [1, 0, 0]

[[beams]]
name = "e0"
body1 = "ground"
point1 = [0, 0, 0]
body2 = "n1"
point2 = [1, 0, 0]
outer_diameter = 0.05
inner_diameter = 0.02
E = 2.1e11
G = 8.1e10
density = 7800
"#;

/// The error of `ONE` with `from` replaced by `to`: its line and column (1-based) and message.
fn refused(from: &str, to: &str) -> (usize, usize, String) {
    assert!(ONE.contains(from), "test setup: {from}");
    let text = ONE.replacen(from, to, 1);
    let e = Compiled::from_str(&text, "bad.toml").expect_err(&format!("{to}: refused"));
    (e.line.unwrap(), e.column.unwrap(), e.message)
}

#[test]
fn bad_beams_are_refused_with_their_place() {
    let cases: [(&str, &str, &str, &str); 10] = [
        (
            "outer_diameter = 0.05",
            "outer_diameter = 0",
            "outer_diameter",
            "must be positive",
        ),
        ("E = 2.1e11", "E = -2.1e11", "E =", "must be positive"),
        (
            "density = 7800",
            "density = 0",
            "density",
            "must be positive",
        ),
        (
            "inner_diameter = 0.02",
            "inner_diameter = 0.05",
            "inner_diameter",
            "not below the outer",
        ),
        ("body2 = \"n1\"", "body2 = \"ground\"", "body2", "same body"),
        (
            "point2 = [1, 0, 0]",
            "point2 = [0, 0, 0]",
            "point2",
            "zero length",
        ),
        ("G = 8.1e10", "G = 8.1e10\nnu = 0.3", "G =", "not both"),
        ("G = 8.1e10", "nu = 0.7", "nu = ", "Poisson's ratio"),
        (
            "density = 7800",
            "density = 7800\nEA = 1e8",
            "[[beams]]",
            "both as a tube",
        ),
        (
            "density = 7800",
            "density = 7800\nbeta = -1e-4",
            "beta",
            "must be zero or positive",
        ),
    ];
    for (from, to, at, message) in cases {
        let (l, c, m) = refused(from, to);
        let text = ONE.replacen(from, to, 1);
        let want = text[..text.find(at).unwrap()].matches('\n').count() + 1;
        assert_eq!(l, want, "{to}: {m}");
        assert!(c >= 1, "{to}");
        assert!(m.contains(message), "{to}: {m}");
        assert!(m.contains("beam 'e0'"), "{to}: {m}");
    }
    // Section properties: each stiffness positive, a rotary inertia zero or positive.
    let props = "EA = 1e8\nGJ = 1e4\nEI = [1e4, 2e4]\nrhoA = 5\nrhoI = [0.01, 0.005, 0.005]";
    let tube =
        "outer_diameter = 0.05\ninner_diameter = 0.02\nE = 2.1e11\nG = 8.1e10\ndensity = 7800";
    for (from, to, message) in [
        ("EI = [1e4, 2e4]", "EI = [1e4, 0]", "EI[1] is 0"),
        ("rhoA = 5", "rhoA = -5", "rhoA is -5"),
        (
            "rhoI = [0.01, 0.005, 0.005]",
            "rhoI = [0.01, -0.005, 0]",
            "rhoI[1] is -0.005",
        ),
        (
            "rhoI = [0.01, 0.005, 0.005]",
            "rhoI = [0.01, 0.005]",
            "expected 3 value(s)",
        ),
    ] {
        let text = ONE.replacen(tube, &props.replacen(from, to, 1), 1);
        let e = Compiled::from_str(&text, "bad.toml").expect_err(to);
        assert!(e.message.contains(message), "{to}: {}", e.message);
        let want = text[..text.find(to).unwrap()].matches('\n').count() + 1;
        assert_eq!(e.line, Some(want), "{to}: {e}");
    }
    // A rotary inertia of zero is a modelling choice, not an error.
    let zero = ONE.replacen(
        tube,
        &props.replacen("rhoI = [0.01, 0.005, 0.005]", "rhoI = [0.01, 0, 0]", 1),
        1,
    );
    assert!(Compiled::from_str(&zero, "ok.toml").is_ok());
}

#[test]
fn friswell_rotor_frequency_derivatives_match_central_differences() {
    // The shipped example at 4000 rpm (every whirl root simple): dω/dp for the shaft
    // diameter, its modulus and density, a disk's mass and the bearing stiffness, through the
    // move of the equilibrium, against central differences of the whole solve.
    use modaltol::sensitivity::{DesignPoint, Status};
    use modaltol::sweep::{Options, initial_guess, point};
    let m = common::example("friswell_5_9_1.toml");
    let speed = 4000.0 * PI / 30.0;
    let nominal = m.model().nominal();
    let solve_at = |p: &[f64]| {
        let q0 = initial_guess(m.model(), p, speed).unwrap();
        point(&m, p, speed, &q0, &Options::default()).unwrap()
    };
    let pt = solve_at(&nominal);
    let names = ["d", "E", "rho", "disk2", "k_bearing"];
    let wrt: Vec<usize> = names
        .iter()
        .map(|n| m.model().parameter(n).unwrap())
        .collect();
    let exact = DesignPoint::new(&m, &nominal, &pt).analytic(&wrt).unwrap();
    for (v, &i) in exact.variables.iter().zip(&wrt) {
        let h = 1e-5 * nominal[i];
        let mut p = nominal.clone();
        p[i] = nominal[i] + h;
        let up = solve_at(&p);
        p[i] = nominal[i] - h;
        let down = solve_at(&p);
        // The six lowest whirl roots above the torsional coupling's.
        for k in 1..7 {
            let mode = &v.modes[k];
            assert_eq!(
                mode.status,
                Status::Ok,
                "{}: mode {k}",
                m.model().parameters[i].name
            );
            let fd = (up.modes[k].damped_frequency - down.modes[k].damped_frequency) / (2.0 * h);
            assert!(
                (mode.d_damped_frequency - fd).abs()
                    <= 1e-6
                        * fd.abs()
                            .max(1e-3 * pt.modes[k].damped_frequency / nominal[i]),
                "{}: mode {k}: {} vs {fd}",
                m.model().parameters[i].name,
                mode.d_damped_frequency
            );
        }
    }
}
