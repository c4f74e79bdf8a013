//! Inertia given in a body's own axes (`x_axis`, `y_axis`) equals the same inertia turned into
//! global axes by hand, `I = R diag(J) Rᵀ` with R from Rodrigues' formula here: same roots on
//! both routes, with y given off-orthogonal (it is made orthogonal to x).

mod common;

use common::{roots, same_roots, solve};
use modaltol::compiled::Compiled;

/// The spinning arm of the other tests with a tip body (inertia in its own axes) on a second
/// hinge; `inertia` is the arm's inertia entry.
fn arm_text(inertia: &str) -> String {
    common::spinning_arm(
        inertia,
        "stiffness = 4\ndamping = 0.05",
        r#"
[[joints]]
name = "twist"
type = "revolute"
parent = "arm"
child = "tip"
at = [0.3, -0.2, 0.05]
axis = [1, -0.4, 0.3]
stiffness = 0.5
[[bodies]]
name = "tip"
mass = 0.2
inertia = [0.001, 0.002, 0.003]
x_axis = [0, 1, 1]
y_axis = [0, -1, 1]
cm = [0.35, -0.25, 0.05]
"#,
    )
}

fn arm(inertia: &str) -> Compiled {
    Compiled::from_str(&arm_text(inertia), "arm.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// Rotation by `angle` about the unit vector `n` (Rodrigues).
fn rotation(n: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let k = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let kk: f64 = (0..3).map(|l| k[i][l] * k[l][j]).sum();
            f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - c) * kk
        })
    })
}

#[test]
fn inertia_in_body_axes_equals_the_same_inertia_turned_by_hand() {
    let norm = (0.3f64 * 0.3 + 0.8 * 0.8 + 0.5 * 0.5).sqrt();
    let r = rotation([0.3 / norm, -0.8 / norm, 0.5 / norm], 0.9);
    let j = [0.004, 0.006, 0.009];
    let global: [[f64; 3]; 3] = std::array::from_fn(|a| {
        std::array::from_fn(|b| (0..3).map(|k| r[a][k] * j[k] * r[b][k]).sum())
    });
    let column = |k: usize| [r[0][k], r[1][k], r[2][k]];
    let (x, y) = (column(0), column(1));
    let y_skewed: [f64; 3] = std::array::from_fn(|i| 2.0 * y[i] + 0.7 * x[i]);
    let by_hand = arm(&format!("inertia = {global:?}"));
    let in_axes = arm(&format!(
        "inertia = {j:?}\nx_axis = {:?}\ny_axis = {y_skewed:?}",
        x.map(|v| 3.0 * v)
    ));
    for w in [0.0, 3.0] {
        for direct in [false, true] {
            same_roots(
                &roots(&solve(&in_axes, w, direct)),
                &roots(&solve(&by_hand, w, direct)),
                1e-10,
            );
        }
    }
    // A body frame that is not one is refused.
    let text = arm_text("inertia = [1, 2, 3]\nx_axis = [1, 1, 0]\ny_axis = [2, 2, 0]");
    let e = Compiled::from_str(&text, "arm.toml").unwrap_err();
    assert!(e.message.contains("x_axis and y_axis are parallel"), "{e}");
    let text = arm_text("inertia = [1, 2, 3]\nx_axis = [1, 1, 0]");
    let e = Compiled::from_str(&text, "arm.toml").unwrap_err();
    assert!(e.message.contains("give both 'x_axis' and 'y_axis'"), "{e}");
}
