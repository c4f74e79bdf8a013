//! Couplers between joint coordinates (`[[couplers]]`, `a q₁ + b q₂ = c`) against the closed
//! form of a gear pair: gear 1 (inertia J₁ on a torsional spring k) meshing with gear 2 (J₂, a
//! viscous bearing c₂), radii r₁, r₂: `r₁ q₁ + r₂ q₂ = 0`, so q₂ = −(r₁/r₂) q₁ and the reflected
//! inertia and damping give `(J₁ + n² J₂) s² + n² c₂ s + k = 0`, `n = r₁/r₂`. Both routes.

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;
use modaltol::modal::C64;

fn gears(extra: &str) -> String {
    format!(
        r#"
name = "gear pair"
gravity = [0, 0, 0]

[parameters]
J1 = 0.02
J2 = 0.05
k = 40.0
c2 = 0.03
r1 = 0.04
r2 = 0.1

[[bodies]]
name = "gear1"
mass = 1
inertia = [0.01, 0.01, "J1"]
cm = [0, 0, 0]

[[bodies]]
name = "gear2"
mass = 2
inertia = [0.02, 0.02, "J2"]
cm = ["r1 + r2", 0, 0]

[[joints]]
name = "shaft1"
type = "revolute"
parent = "ground"
child = "gear1"
at = [0, 0, 0]
axis = [0, 0, 1]
stiffness = "k"

[[joints]]
name = "shaft2"
type = "revolute"
parent = "ground"
child = "gear2"
at = ["r1 + r2", 0, 0]
axis = [0, 0, 1]
damping = "c2"
{extra}"#
    )
}

const MESH: &str = r#"
[[couplers]]
name = "mesh"
coordinates = ["shaft1", "shaft2"]
coefficients = ["r1", "r2"]
"#;

#[test]
fn a_gear_pair_has_the_reflected_inertia_and_damping() {
    let m = Compiled::from_str(&gears(MESH), "gears.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.model().dof(), 1);
    let (j1, j2, k, c2, n) = (0.02, 0.05, 40.0, 0.03, 0.04 / 0.1);
    let (jj, cc) = (j1 + n * n * j2, n * n * c2);
    let disc = C64::new(cc * cc - 4.0 * jj * k, 0.0).sqrt();
    let exact = [(-cc + disc) / (2.0 * jj), (-cc - disc) / (2.0 * jj)];
    for direct in [false, true] {
        let pt = solve(&m, 0.0, direct);
        same_roots(&roots(&pt), &exact, 1e-12);
    }
}

#[test]
fn bad_couplers_are_refused_at_their_place() {
    for (extra, expect) in [
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\"]\ncoefficients = [1, 1]",
            "lists two joint coordinates",
        ),
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"nope\"]\ncoefficients = [1, 1]",
            "no joint coordinate 'nope'",
        ),
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"shaft1\"]\ncoefficients = [1, 1]",
            "the same",
        ),
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [0, 0]",
            "both coefficients are zero",
        ),
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [1]",
            "[a, b]",
        ),
        // The same mesh twice: the second is a combination of the first.
        (
            "[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [\"r1\", \"r2\"]\n[[couplers]]\nname = \"m2\"\ncoordinates = [\"shaft2\", \"shaft1\"]\ncoefficients = [\"2*r2\", \"2*r1\"]",
            "a combination of the cut joints' and the other couplers'",
        ),
        // A parallelogram (cranks of 0.04 m, a rod closing them as a distance cut) already has
        // q₁ = q₂ from its loop: the coupler repeating it is refused, though its coefficients
        // are larger than the cut's row (0.14 × 0.04).
        (
            "[[constraints]]\nname = \"rod\"\ntype = \"distance\"\nbody1 = \"gear1\"\npoint1 = [0, 0.04, 0]\nbody2 = \"gear2\"\npoint2 = [\"r1 + r2\", 0.04, 0]\n[[couplers]]\nname = \"m\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [1, -1]",
            "coupler 'm': its equation is a combination of the cut joints'",
        ),
        // Cranks of 0.04 and 0.1 m: the loop's tangent at the drawing is r₁q₁ = r₂q₂, which
        // the coupler imposes exactly; the two lock the mechanism, so it is refused (not
        // counted as one degree of freedom with the cut's equation dropped).
        (
            "[[constraints]]\nname = \"rod\"\ntype = \"distance\"\nbody1 = \"gear1\"\npoint1 = [0, \"r1\", 0]\nbody2 = \"gear2\"\npoint2 = [\"r1 + r2\", \"r2\", 0]\n[[couplers]]\nname = \"belt\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [\"r1\", \"-r2\"]",
            "only tangent to it there (then the two lock the mechanism)",
        ),
        // Couplers share the joints' names.
        (
            "[[couplers]]\nname = \"shaft1\"\ncoordinates = [\"shaft1\", \"shaft2\"]\ncoefficients = [\"r1\", \"r2\"]",
            "duplicate name 'shaft1': a joint has it",
        ),
    ] {
        let e = match Compiled::from_str(&gears(extra), "bad.toml") {
            Ok(_) => panic!("accepted: {extra}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("bad.toml:"), "located: {e}");
        assert!(e.contains(expect), "{extra}: {e}");
    }
}

/// A solve that fails where the couplers' equations are redundant (a coefficient `−1e300` at
/// speed 1, the gravity overflowing) is reported naming the coupler, as a cut joint would be:
/// the equations' owners include the couplers (found by the pipeline fuzzer: a panic, the
/// owners listing the cut joints only).
#[test]
fn a_failed_solve_names_a_redundant_coupler() {
    let text = gears(MESH).replace("gravity = [0, 0, 0]", "gravity = [0, \"1e308*speed\", 0]")
        + r#"
[[bodies]]
name = "rack"
mass = 0.5
inertia = [0.001, 0.001, 0.001]
cm = ["r1 + r2", "-r2", 0]

[[joints]]
name = "slide"
type = "prismatic"
parent = "ground"
child = "rack"
axis = [1, 0, 0]
stiffness = 100

[[couplers]]
name = "pinion"
coordinates = ["shaft2", "slide"]
coefficients = ["r2", "-speed*1e300"]
"#;
    let m = Compiled::from_str(&text, "gears.toml").unwrap_or_else(|e| panic!("{e}"));
    let p = m.model().nominal();
    let e = modaltol::sweep::point_at(&m, &p, 1.0, &Default::default())
        .expect_err("the gravity overflows")
        .to_string();
    assert!(
        e.contains("redundant cut joints or couplers: mesh duplicate"),
        "{e}"
    );
}
