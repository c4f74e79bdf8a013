//! The equations of motion's inertial terms, from the bodies' velocities and accelerations
//! composed joint by joint from the root (`mechanics::dynamics`), against a second route: every
//! body's pose differentiated twice in time as a whole (second-order dual numbers through the
//! tree's poses) and Kane's sum `r_i = Σ_b J_v,iᵀ m (ẍ − g) + J_ω,iᵀ (I_w α + ω × I_w ω)`, at
//! states with every coordinate moving and accelerating, on a tree with every joint type.

use modaltol::compiled::Compiled;
use modaltol::mechanics::System;
use modaltol::mechanics::dynamics::{Lifted, evaluate, partials};
use modaltol::mechanics::kinematics::poses;
use modaltol::real::{M3, V3, axial, mul3, mul3_t, mulv};
use num_dual::{Dual2, Dual64};

/// A tree of eight bodies, one per joint type, with tilted axes, off-axis centres of mass and
/// inertia given in tilted axes, under gravity, without force elements.
const TREE: &str = r#"
name = "every joint"
gravity = [0.3, -9.81, 0.5]

[[bodies]]
name = "b1"
mass = 1.3
inertia = [0.02, 0.03, 0.04]
x_axis = [1, 0.2, 0]
y_axis = [0, 1, 0.3]
cm = [0.2, 0.1, -0.05]

[[bodies]]
name = "b2"
mass = 0.7
inertia = [0.01, 0.015, 0.012]
cm = [0.35, 0.2, 0.1]

[[bodies]]
name = "b3"
mass = 0.9
inertia = [0.011, 0.02, 0.017]
x_axis = [0.3, 1, 0.1]
y_axis = [1, -0.2, 0.4]
cm = [0.5, 0.1, 0.25]

[[bodies]]
name = "b4"
mass = 0.5
inertia = [0.004, 0.006, 0.005]
cm = [0.6, -0.1, 0.3]

[[bodies]]
name = "b5"
mass = 0.8
inertia = [0.007, 0.003, 0.009]
cm = [0.75, 0.05, 0.2]

[[bodies]]
name = "b6"
mass = 0.6
inertia = [0.002, 0.004, 0.003]
x_axis = [1, 1, 0]
y_axis = [0, 0.5, 1]
cm = [0.9, 0.2, 0.15]

[[bodies]]
name = "b7"
mass = 0.4
inertia = [0.001, 0.002, 0.0015]
cm = [1.0, 0.3, 0.1]

[[bodies]]
name = "b8"
mass = 0.3
inertia = [0.001, 0.001, 0.002]
cm = [0.3, 0.4, -0.2]

[[joints]]
name = "j1"
type = "revolute"
parent = "ground"
child = "b1"
at = [0.05, 0, 0.02]
axis = [0.3, 0.2, 1]

[[joints]]
name = "j2"
type = "spherical"
parent = "b1"
child = "b2"
at = [0.3, 0.15, 0]

[[joints]]
name = "j3"
type = "universal"
parent = "b2"
child = "b3"
at = [0.45, 0.15, 0.2]
axis = [1, 0.1, 0]
axis2 = [0, 0.2, 1]

[[joints]]
name = "j4"
type = "cylindrical"
parent = "b3"
child = "b4"
at = [0.55, 0, 0.3]
axis = [0.2, 1, 0.3]

[[joints]]
name = "j5"
type = "planar"
parent = "b4"
child = "b5"
at = [0.7, 0, 0.25]
axis = [0.1, 0.3, 1]

[[joints]]
name = "j6"
type = "free"
parent = "b5"
child = "b6"
at = [0.85, 0.1, 0.2]

[[joints]]
name = "j7"
type = "prismatic"
parent = "b6"
child = "b7"
axis = [1, 0.4, -0.2]

[[joints]]
name = "j8"
type = "fixed"
parent = "b2"
child = "b8"
"#;

/// Kane's sum over the poses differentiated in time (the second route).
fn kane(sys: &System<f64>, q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
    let qt: Vec<Dual2<f64>> = (0..q.len())
        .map(|i| Dual2::new(q[i], qd[i], qdd[i]))
        .collect();
    let pt = poses(&sys.map(Dual2::from_re), &qt);
    let j = partials(&sys.map(Dual64::from_re), q);
    (0..q.len())
        .map(|i| {
            (sys.bodies.iter().enumerate())
                .map(|(b, body)| {
                    let acc = pt[b].apply(&body.cm.map(Dual2::from_re)).map(|c| c.v2);
                    let a: M3<f64> = pt[b].rot.map(|c| c.re);
                    let omega = axial(&mul3_t(&pt[b].rot.map(|c| c.v1), &a));
                    let alpha = axial(&mul3_t(&pt[b].rot.map(|c| c.v2), &a));
                    let iw = mul3_t(&mul3(&a, &body.inertia), &a);
                    let moment: V3<f64> = mulv(&iw, &alpha) + omega.cross(&mulv(&iw, &omega));
                    j.body.jv(sys, i, b).dot(&((acc - sys.gravity) * body.mass))
                        + j.body.jw(sys, i, b).dot(&moment)
                })
                .sum()
        })
        .collect()
}

#[test]
fn the_recursive_motions_give_kanes_inertial_forces_on_every_joint_type() {
    let model = Compiled::from_str(TREE, "tree.toml").unwrap();
    let sys = System::new(model.model(), &model.model().nominal(), 0.0).unwrap();
    let lifted = Lifted::new(sys.clone());
    let n = sys.n;
    assert_eq!(n, 1 + 3 + 2 + 2 + 3 + 6 + 1, "every joint's coordinates");
    for k in 0..4 {
        // Deterministic states away from the reference configuration.
        let at = |scale: f64, phase: usize| -> Vec<f64> {
            (0..n)
                .map(|i| scale * (((i * 7 + k * 3 + phase) % 11) as f64 / 5.0 - 1.0))
                .collect()
        };
        let (q, qd, qdd) = (at(0.6, 0), at(2.0, 4), at(5.0, 9));
        let r = evaluate(&lifted, &q, &qd, &qdd).r;
        let second = kane(&sys, &q, &qd, &qdd);
        let scale = second.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        for (i, (a, b)) in r.iter().zip(&second).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "state {k}, coordinate {i}: {a} against {b}"
            );
        }
        // The velocity terms alone (zero accelerations) are not zero: the check sees them.
        let still = evaluate(&lifted, &q, &qd, &vec![0.0; n]).r;
        let gravity_only = evaluate(&lifted, &q, &vec![0.0; n], &vec![0.0; n]).r;
        assert!(
            (still.iter().zip(&gravity_only)).any(|(a, b)| (a - b).abs() > 1e-3 * scale),
            "state {k}"
        );
    }
}
