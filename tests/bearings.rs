//! The `bearing` force element and force elements' stiffness and damping matrices (issue 57,
//! item 1), against closed forms, against the bushing, and their sensitivities against
//! finite differences, on the recorded and the direct route.
//!
//! * A journal (a rigid body on a free joint, held in tilt by a bushing) in a bearing with
//!   isotropic stiffness `k`, damping `c` and the cross-coupling `kxy = q = −kyx` has the whirl
//!   roots of `m s² + c s + k ± i q = 0` in closed form (Friswell et al. 2010, §5.5; the
//!   destabilising cross-coupled stiffness of a journal bearing or a seal), unstable exactly
//!   when `q > c √(k/m)`.
//! * With every coefficient different and non-symmetric, each of the four lateral roots makes
//!   `det(m s² I + C s + K)` vanish, the determinant written out independently.
//! * A bearing along a shaft's axis equals the bushing whose components it resolves (the
//!   default `x` and a given `axis2`), on a journal whose tilt couples to its translation.
//! * The analytic sensitivities to every coefficient, cross terms included, equal central
//!   finite differences.

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;
use modaltol::model::Channel;
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::{BranchKind, Options, Sweep};

fn model(text: &str) -> Compiled {
    Compiled::from_str(text, "bearings.toml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A journal of mass `m` (inertia `[jx, jy, jz]`, centre of mass `cm`) on a free joint at the
/// origin, held in tilt by a bushing of rotational stiffness `kr` at the origin, with `extra`
/// (the bearing under test, parameters and any analysis tables).
fn journal(cm: [f64; 3], extra: &str) -> Compiled {
    model(&format!(
        r#"
name = "journal"
[parameters]
m = 3.0
kr = 5e4
[[bodies]]
name = "journal"
mass = "m"
inertia = [0.02, 0.03, 0.05]
cm = {cm:?}
[[joints]]
name = "float"
type = "free"
parent = "ground"
child = "journal"
at = [0, 0, 0]
[[forces]]
name = "tilt"
type = "bushing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
stiffness = [0, 0, 0, "kr", "kr", "kr"]
{extra}
"#
    ))
}

/// The roots of `m s² + c s + κ = 0` for a complex `κ`.
fn quadratic(m: f64, c: f64, kappa: C64) -> [C64; 2] {
    let d = (C64::new(c * c, 0.0) - 4.0 * m * kappa).sqrt();
    [(-c + d) / (2.0 * m), (-c - d) / (2.0 * m)]
}

#[test]
fn cross_coupled_stiffness_whirls_as_the_closed_form_and_destabilises_above_c_omega() {
    let (m, k, c, kz): (f64, f64, f64, f64) = (3.0, 2e6, 40.0, 5e6);
    let (jx, jy, jz, kr) = (0.02, 0.03, 0.05, 5e4);
    let onset = c * (k / m).sqrt();
    for q in [0.5 * onset, 2.0 * onset] {
        let bearing = format!(
            r#"
[[forces]]
name = "bearing"
type = "bearing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
axis = [0, 0, 1]
stiffness = [[{k}, {q}, 0], [{mq}, {k}, 0], [0, 0, {kz}]]
damping = [[{c}, 0, 0], [0, {c}, 0], [0, 0, 0]]
"#,
            mq = -q
        );
        let j = journal([0.0; 3], &bearing);
        let mut exact = Vec::new();
        for kappa in [C64::new(k, q), C64::new(k, -q)] {
            exact.extend(quadratic(m, c, kappa));
        }
        exact.extend(quadratic(m, 0.0, C64::new(kz, 0.0)));
        for jj in [jx, jy, jz] {
            exact.extend(quadratic(jj, 0.0, C64::new(kr, 0.0)));
        }
        for direct in [false, true] {
            let pt = solve(&j, 0.0, direct);
            same_roots(&roots(&pt), &exact, 1e-10);
            // (The undamped axial and tilting roots sit on the axis to rounding.)
            let unstable = roots(&pt).iter().any(|r| r.re > 1e-9 * r.norm());
            assert_eq!(unstable, q > onset, "q = {q}, onset {onset}");
        }
    }
}

#[test]
fn non_symmetric_coefficients_give_the_roots_of_the_written_out_determinant() {
    let (m, kz) = (3.0, 5e6);
    let kk = [[2e6, 3e5], [-7e5, 1.4e6]];
    let cc = [[40.0, 15.0], [-25.0, 90.0]];
    let bearing = format!(
        r#"
[[forces]]
name = "bearing"
type = "bearing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
axis = [0, 0, 1]
stiffness = [[{}, {}, 0], [{}, {}, 0], [0, 0, {kz}]]
damping = [[{}, {}, 0], [{}, {}, 0], [0, 0, 0]]
"#,
        kk[0][0], kk[0][1], kk[1][0], kk[1][1], cc[0][0], cc[0][1], cc[1][0], cc[1][1]
    );
    let j = journal([0.0; 3], &bearing);
    // det(m s² I + C s + K), written out for the 2 × 2 lateral block.
    let det = |s: C64| {
        let e = |i: usize, l: usize| {
            let diag = if i == l {
                m * s * s
            } else {
                C64::new(0.0, 0.0)
            };
            diag + cc[i][l] * s + kk[i][l]
        };
        e(0, 0) * e(1, 1) - e(0, 1) * e(1, 0)
    };
    for direct in [false, true] {
        let pt = solve(&j, 0.0, direct);
        let lateral: Vec<C64> = roots(&pt)
            .into_iter()
            .filter(|s| {
                // The lateral roots: neither axial (kz/m) nor tilting (kr/J).
                let w2 = s.norm_sqr();
                (w2 - kz / m).abs() > 1e-3 * kz / m
                    && ![0.02, 0.03, 0.05]
                        .iter()
                        .any(|jj| (w2 - 5e4 / jj).abs() < 1e-3 * 5e4 / jj)
            })
            .collect();
        assert_eq!(lateral.len(), 4, "{lateral:?}");
        for s in lateral {
            // Each term of the determinant is of size (m|s|² + |C||s| + |K|)²; its value at
            // a root is rounding.
            let scale = (m * s.norm_sqr() + 100.0 * s.norm() + 2e6).powi(2);
            assert!(det(s).norm() <= 1e-11 * scale, "det({s}) = {}", det(s));
        }
    }
}

/// A bearing along `axis` with `axis2` (if any) resolves the displacement as the bushing with
/// the matching components, on a journal whose tilt couples to its translation.
#[test]
fn a_bearing_resolves_along_its_own_directions_as_the_bushing() {
    let cm = [0.3, 0.1, -0.05];
    let bushing = journal(
        cm,
        r#"
[[forces]]
name = "b"
type = "bushing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
stiffness = [3e6, 1e6, 2e6, 0, 0, 0]
damping = [30, 10, 20, 0, 0, 0]
"#,
    );
    for (axis2, stiffness, damping) in [
        // x along global y by default (the coordinate axis least aligned with the axis).
        ("", "[1e6, 2e6, 3e6]", "[10, 20, 30]"),
        // x along global z, so y = x̂ × ẑ = −ŷ.
        ("axis2 = [0, 0, 1]", "[2e6, 1e6, 3e6]", "[20, 10, 30]"),
    ] {
        let bearing = journal(
            cm,
            &format!(
                r#"
[[forces]]
name = "b"
type = "bearing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
axis = [1, 0, 0]
{axis2}
stiffness = {stiffness}
damping = {damping}
"#
            ),
        );
        for direct in [false, true] {
            same_roots(
                &roots(&solve(&bearing, 0.0, direct)),
                &roots(&solve(&bushing, 0.0, direct)),
                1e-10,
            );
        }
    }
    // A matrix whose off-diagonal entries are zero is the diagonal it holds.
    let matrix = journal(
        cm,
        r#"
[[forces]]
name = "b"
type = "bushing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
stiffness = [[3e6, 0, 0, 0, 0, 0], [0, 1e6, 0, 0, 0, 0], [0, 0, 2e6, 0, 0, 0],
             [0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]]
damping = [30, 10, 20, 0, 0, 0]
"#,
    );
    assert!(matrix.model().forces.iter().all(|f| f.cross.is_empty()));
    same_roots(
        &roots(&solve(&matrix, 0.0, false)),
        &roots(&solve(&bushing, 0.0, false)),
        0.0,
    );
}

fn agree(a: f64, b: f64, floor: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + floor
}

#[test]
fn sensitivities_to_every_coefficient_equal_finite_differences() {
    let j = journal(
        [0.2, 0.0, 0.0],
        r#"
[parameters.kxx]
value = 2e6
tolerance = "5%"
[parameters.kxy]
value = 3e5
tolerance = "20%"
[parameters.kyx]
value = -4e5
tolerance = "20%"
[parameters.kyy]
value = 1.5e6
tolerance = "5%"
[parameters.cxx]
value = 60
tolerance = "10%"
[parameters.cxy]
value = 12
tolerance = "30%"
[parameters.cyx]
value = -20
tolerance = "30%"
[parameters.cyy]
value = 80
tolerance = "10%"

[[forces]]
name = "bearing"
type = "bearing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
axis = [0, 0, 1]
stiffness = [["kxx", "kxy", 0], ["kyx", "kyy", 0], [0, 0, 5e6]]
damping = [["cxx", "cxy", 0], ["cyx", "cyy", 0], [0, 0, 0]]
"#,
    );
    let wrt = j.model().toleranced();
    assert_eq!(wrt.len(), 8);
    let p = j.model().nominal();
    let pt = Sweep::new(&j, p.clone(), Options::default())
        .step(0.0)
        .unwrap();
    let a = DesignPoint::new(&j, &p, &pt).analytic(&wrt).unwrap();
    let f = DesignPoint::new(&j, &p, &pt)
        .finite_difference(&wrt)
        .unwrap();
    let mut compared = 0;
    for (va, vf) in a.variables.iter().zip(&f.variables) {
        let b = p[va.param].abs();
        let name = &j.model().parameters[va.param].name;
        for (k, (ma, mf)) in va.modes.iter().zip(&vf.modes).enumerate() {
            let wn = pt.modes[k].natural_frequency;
            for (what, x, y, floor) in [
                (
                    "dω_d",
                    ma.d_damped_frequency,
                    mf.d_damped_frequency,
                    1e-9 * wn / b,
                ),
                ("dζ", ma.d_damping_ratio, mf.d_damping_ratio, 1e-9 / b),
                ("dRe λ", ma.d_eigen_re, mf.d_eigen_re, 1e-9 * wn / b),
            ] {
                assert!(
                    agree(x, y, floor),
                    "mode {} {what}/d{name}: AD {x} FD {y}",
                    k + 1
                );
            }
            compared += 1;
        }
        // Every coefficient moves the lateral modes.
        assert!(
            va.modes
                .iter()
                .any(|m| m.d_damped_frequency.abs() > 1e-6 * 1e3 / b),
            "d/d{name} is zero everywhere"
        );
    }
    assert_eq!(compared, 8 * pt.modes.len());
}

/// The journal in a bearing whose `kxx` is `kxx` (an expression), the table `table` given.
fn tabled(kxx: &str, table: &str) -> Compiled {
    journal(
        [0.2, 0.0, 0.0],
        &format!(
            r#"
[parameters.scale]
value = 1.0
tolerance = "5%"
[parameters.gear]
value = 1.0
tolerance = "5%"

{table}

[[forces]]
name = "bearing"
type = "bearing"
body1 = "ground"
body2 = "journal"
point1 = [0, 0, 0]
axis = [0, 0, 1]
stiffness = [["{kxx}", 2e5, 0], [-3e5, 1.5e6, 0], [0, 0, 5e6]]
damping = 50
"#
        ),
    )
}

#[test]
fn a_table_and_an_expression_of_speed_agree_where_they_are_the_same_function() {
    // A table of the line k = 1e6 (1 + speed/200) is that line, inside the table and beyond
    // it (where the table continues by its end slope).
    let line = tabled(
        "scale*kxx(gear*speed)",
        "[[tables]]\nname = \"kxx\"\nx = [0, 100, 250, 300]\ny = [1e6, 1.5e6, 2.25e6, 2.5e6]",
    );
    let expression = tabled("scale*1e6*(1 + gear*speed/200)", "");
    // A curved table is, at each speed, the bearing with the interpolated number written in.
    let curve_table =
        "[[tables]]\nname = \"kxx\"\nx = [0, 100, 250, 300]\ny = [1e6, 1.8e6, 2.0e6, 3.5e6]";
    let curved = tabled("scale*kxx(gear*speed)", curve_table);
    let table = modaltol::model::table::Table::new(
        "kxx",
        vec![0.0, 100.0, 250.0, 300.0],
        vec![1e6, 1.8e6, 2.0e6, 3.5e6],
    )
    .unwrap();
    for w in [0.0, 37.5, 100.0, 180.0, 300.0, 420.0] {
        for direct in [false, true] {
            same_roots(
                &roots(&solve(&line, w, direct)),
                &roots(&solve(&expression, w, direct)),
                1e-12,
            );
            let written = tabled(&format!("{:e}", table.eval(w)), "");
            same_roots(
                &roots(&solve(&curved, w, direct)),
                &roots(&solve(&written, 0.0, direct)),
                1e-12,
            );
        }
    }
}

#[test]
fn sensitivities_through_a_table_equal_finite_differences() {
    let m = tabled(
        "scale*kxx(gear*speed)",
        "[[tables]]\nname = \"kxx\"\nx = [0, 100, 250, 300]\ny = [1e6, 1.8e6, 2.0e6, 3.5e6]",
    );
    let wrt = m.model().toleranced();
    let p = m.model().nominal();
    let mut sweep = Sweep::new(&m, p.clone(), Options::default());
    for w in [60.0, 180.0, 350.0] {
        let pt = sweep.step(w).unwrap();
        let a = DesignPoint::new(&m, &p, &pt).analytic(&wrt).unwrap();
        let f = DesignPoint::new(&m, &p, &pt)
            .finite_difference(&wrt)
            .unwrap();
        for (va, vf) in a.variables.iter().zip(&f.variables) {
            let name = &m.model().parameters[va.param].name;
            let mut moved = false;
            for (k, (ma, mf)) in va.modes.iter().zip(&vf.modes).enumerate() {
                let wn = pt.modes[k].natural_frequency;
                let (x, y) = (ma.d_damped_frequency, mf.d_damped_frequency);
                assert!(
                    agree(x, y, 1e-9 * wn),
                    "Ω = {w} mode {} dω_d/d{name}: AD {x} FD {y}",
                    k + 1
                );
                let (x, y) = (ma.d_damping_ratio, mf.d_damping_ratio);
                assert!(
                    agree(x, y, 1e-9),
                    "Ω = {w} mode {} dζ/d{name}: AD {x} FD {y}",
                    k + 1
                );
                moved |= x.abs() > 1e-9;
            }
            assert!(moved, "Ω = {w}: nothing moves with {name}");
        }
    }
}

/// The shipped example on speed-tabulated, cross-coupled bearings: both routes alike, the
/// first forward mode destabilised by the cross-coupling between 340 and 350 rad/s (its
/// requirement's range ends below; flutter, so no stable branch is looked for), and every
/// variable's sensitivities against finite differences at an operating speed.
#[test]
fn the_friswell_bearings_example_solves_alike_and_differentiates_exactly() {
    let m = common::example("friswell_bearings.toml");
    for w in [150.0, 340.0, 350.0] {
        let (a, b) = (solve(&m, w, false), solve(&m, w, true));
        same_roots(&roots(&a), &roots(&b), 1e-10);
        let unstable = roots(&a).iter().any(|r| r.re > 1e-9 * r.norm());
        assert_eq!(unstable, w > 345.0, "Ω = {w}");
        // Past it the instability is flutter: the stiffness stays positive definite, no other
        // equilibrium branches off the axis, and none is looked for.
        assert_eq!(
            matches!(
                a.branch.kind,
                BranchKind::Unstable {
                    searched: false,
                    flutter_only: true,
                    ..
                }
            ),
            unstable,
            "Ω = {w}: {}",
            a.branch
        );
    }
    let wrt = m.model().toleranced();
    let p = m.model().nominal();
    let pt = solve(&m, 150.0, false);
    // The unbalance response at disk 1 too.
    let unbalance = m
        .model()
        .analysis
        .transfer
        .map(|t| TransferAt::at_speed(&t, 150.0));
    assert!(matches!(unbalance.unwrap().input, Channel::Unbalance(_)));
    let design = DesignPoint::new(&m, &p, &pt).with_transfer(unbalance);
    let a = design.analytic(&wrt).unwrap();
    let f = design.finite_difference(&wrt).unwrap();
    let h = a.transfer_magnitude.unwrap();
    assert!(h > 1e-7 && h < 1e-4, "|X| = {h} m");
    for (va, vf) in a.variables.iter().zip(&f.variables) {
        let name = &m.model().parameters[va.param].name;
        let b = p[va.param].abs();
        let (x, y) = (
            va.d_transfer_magnitude.unwrap(),
            vf.d_transfer_magnitude.unwrap(),
        );
        assert!(agree(x, y, 1e-8 * h / b), "d|X|/d{name}: AD {x} FD {y}");
        // The lateral modes below 1000 rad/s.
        for (k, (ma, mf)) in va.modes.iter().zip(&vf.modes).enumerate() {
            let mode = &pt.modes[k];
            if mode.damped_frequency > 1000.0 || mode.damping_ratio.abs() < 1e-6 {
                continue;
            }
            let wn = mode.natural_frequency;
            let (x, y) = (ma.d_damped_frequency, mf.d_damped_frequency);
            assert!(
                agree(x, y, 1e-8 * wn / b),
                "mode {} dω_d/d{name}: AD {x} FD {y}",
                k + 1
            );
            let (x, y) = (ma.d_damping_ratio, mf.d_damping_ratio);
            assert!(
                agree(x, y, 1e-8 / b),
                "mode {} dζ/d{name}: AD {x} FD {y}",
                k + 1
            );
        }
    }
}
