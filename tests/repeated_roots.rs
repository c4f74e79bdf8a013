//! Repeated roots as clusters (issue 57, item 2): an axisymmetric rotor's double roots at rest
//! have exact first and second derivatives wherever the variables keep the symmetry (the
//! members move as one), checked against differences at re-solved points; a variable that
//! breaks the symmetry splits them, and then their rows say why instead of giving a number.
//!
//! At a perturbed point of the symmetric rotor the roots stay double, so a member's value is
//! well defined there (either member: they are equal) and its differences are an independent
//! check of the cluster's expansion (`src/modal/cluster.rs`, `src/hessian/cluster.rs`).

mod common;

use common::{example, example_text};
use modaltol::compiled::Compiled;
use modaltol::modal::{Smoothness, smoothness};
use modaltol::output::{Missing, Quantity};
use modaltol::sensitivity::{Derivatives, DesignPoint, Status};
use modaltol::sweep::{Options, Point, point};
use modaltol::tolerance::{LocalModel, match_modes, value};
use nalgebra::DMatrix;

/// The Friswell rotor's point at `speed` and its local model (gradients and Hessians) in its
/// toleranced variables.
fn local(model: &Compiled, speed: f64, hessian: bool) -> (Point, LocalModel) {
    let pt = common::at(model, speed, &Options::default());
    let p = model.model().nominal();
    let tf = model.model().analysis.transfer.as_ref();
    let lm = DesignPoint::new(model, &p, &pt)
        .with_model_transfer(tf)
        .local_model(&model.model().toleranced(), hessian)
        .expect("derivatives");
    (pt, lm)
}

/// The outputs of the modes at double roots (ω_d and ζ of each member).
fn members(pt: &Point, lm: &LocalModel) -> Vec<usize> {
    let smooth = smoothness(&pt.modes);
    let out: Vec<usize> = (lm.outputs.iter().enumerate())
        .filter(|(_, o)| {
            o.mode
                .is_some_and(|m| matches!(smooth[m], Smoothness::Repeated { .. }))
        })
        .map(|(k, _)| k)
        .collect();
    assert!(out.len() >= 8, "the rotor at rest has double roots");
    out
}

#[test]
fn a_symmetric_rotors_double_roots_have_exact_derivatives_that_match_differences() {
    let model = example("friswell_5_9_1.toml");
    let (pt, exact) = local(&model, 0.0, true);
    let (_, first) = local(&model, 0.0, false);
    let outs = members(&pt, &exact);
    let p = model.model().nominal();
    let vars = model.model().toleranced();
    let nv = vars.len();
    let tf = model.model().analysis.transfer.as_ref();
    let opt = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    // Derivatives compared as the changes they make over each variable's own size (`g_i b_i`,
    // `H_ij b_i b_j`), against the largest of them or 1e-3 (the undamped modes' ζ is rounding
    // about zero, and so are its derivatives, about 1e-12: a ζ within 1e-10 is exact here).
    let scaled = |g: &[f64]| -> Vec<f64> { g.iter().zip(&vars).map(|(x, &i)| x * p[i]).collect() };
    let scale_of = |g: &[f64]| g.iter().fold(1e-3_f64, |s, x| s.max(x.abs()));
    // Both exact routes (first-order sensitivities, the Hessians' passes) give every member a
    // gradient, and the same one.
    for &k in &outs {
        let (g, h) = (first.grad[k].as_ref(), exact.grad[k].as_ref());
        let (g, h) = (
            g.expect("first-order gradient"),
            h.expect("second-order gradient"),
        );
        let (g, h) = (scaled(g), scaled(h));
        let scale = scale_of(&g);
        for (a, b) in g.iter().zip(&h) {
            assert!(
                (a - b).abs() <= 1e-8 * scale,
                "{:?}: {a} {b}",
                exact.outputs[k]
            );
        }
        assert!(exact.hess[k].is_ok(), "{:?}", exact.outputs[k]);
    }
    // Values and gradients at the point re-solved with variable `j` moved by `step`.
    let at = |j: usize, step: f64| -> (Vec<f64>, LocalModel) {
        let mut pp = p.clone();
        pp[vars[j]] += step;
        let q = point(&model, &pp, 0.0, &pt.equilibrium.q, &opt).expect("a point");
        let q = match_modes(&pt, q);
        let tfq = tf.map(|t| modaltol::sensitivity::TransferAt::at_speed(t, 0.0));
        let values = (exact.outputs.iter())
            .map(|o| value(&q, o, tfq).unwrap_or(f64::NAN))
            .collect();
        let lm = DesignPoint::new(&model, &pp, &q)
            .with_model_transfer(tf)
            .local_model(&vars, false)
            .expect("derivatives at a perturbed point");
        (values, lm)
    };
    // Central differences at steps of 1 %, ½ % and ¼ %, extrapolated twice (truncation
    // O(h⁶)): of the values against the gradients, of the gradients against the Hessians.
    let mut grad_fd = vec![vec![0.0; nv]; exact.outputs.len()];
    let mut hess_fd = vec![DMatrix::<f64>::zeros(nv, nv); exact.outputs.len()];
    for j in 0..nv {
        let step = 1e-2 * p[vars[j]].abs();
        let central: Vec<(Vec<f64>, Vec<Vec<f64>>)> = [1.0, 0.5, 0.25]
            .iter()
            .map(|&f| {
                let ((vu, lu), (vd, ld)) = (at(j, f * step), at(j, -f * step));
                let h = 2.0 * f * step;
                let dv = vu.iter().zip(&vd).map(|(u, d)| (u - d) / h).collect();
                let dg = (0..exact.outputs.len())
                    .map(|k| match (&lu.grad[k], &ld.grad[k]) {
                        (Ok(u), Ok(d)) => u.iter().zip(d).map(|(u, d)| (u - d) / h).collect(),
                        _ => vec![f64::NAN; nv],
                    })
                    .collect();
                (dv, dg)
            })
            .collect();
        let richardson = |d0: f64, d1: f64, d2: f64| {
            let (r1, r2) = ((4.0 * d1 - d0) / 3.0, (4.0 * d2 - d1) / 3.0);
            (16.0 * r2 - r1) / 15.0
        };
        for &k in &outs {
            grad_fd[k][j] = richardson(central[0].0[k], central[1].0[k], central[2].0[k]);
            for i in 0..nv {
                hess_fd[k][(i, j)] =
                    richardson(central[0].1[k][i], central[1].1[k][i], central[2].1[k][i]);
            }
        }
    }
    for &k in &outs {
        let o = &exact.outputs[k];
        let (g, d) = (scaled(exact.grad[k].as_ref().unwrap()), scaled(&grad_fd[k]));
        let scale = scale_of(&g);
        for (a, b) in g.iter().zip(&d) {
            assert!(
                (a - b).abs() <= 1e-7 * scale,
                "{o:?}: gradient {a} against {b}"
            );
        }
        let by =
            |h: &DMatrix<f64>| DMatrix::from_fn(nv, nv, |i, j| h[(i, j)] * p[vars[i]] * p[vars[j]]);
        let h = by(exact.hess[k].as_ref().unwrap());
        let d = by(&((&hess_fd[k] + hess_fd[k].transpose()) * 0.5));
        let scale = h.amax().max(d.amax()).max(1e-3);
        assert!(
            (&h - &d).amax() <= 1e-5 * scale,
            "{o:?}: exact against differenced Hessians differ by {:e} of {:e}",
            (&h - &d).amax(),
            scale
        );
    }
}

#[test]
fn a_variable_that_breaks_the_symmetry_leaves_the_double_roots_rows_with_their_reason() {
    // The right bearing's vertical stiffness scaled by a variable of its own, `k_z` (1 at its
    // nominal value): the rotor is still axisymmetric there, the bearings' `k_bearing` moves
    // both planes alike, and `k_z` alone splits every bending pair.
    let text = example_text("friswell_5_9_1.toml")
        .replace(
            "k_thrust = 1e9",
            "k_thrust = 1e9\nk_z = { value = 1, tolerance = \"10%\" }",
        )
        .replacen(
            "stiffness = [\"k_thrust\", \"k_bearing\", \"k_bearing\", 0, 0, 0]\n\n[[ports]]",
            "stiffness = [\"k_thrust\", \"k_bearing\", \"k_bearing * k_z\", 0, 0, 0]\n\n[[ports]]",
            1,
        );
    assert!(text.contains("k_bearing * k_z"));
    let model = Compiled::from_str(&text, "anisotropic.toml").unwrap_or_else(|e| panic!("{e}"));
    let (pt, lm) = local(&model, 0.0, true);
    let outs = members(&pt, &lm);
    // Every bending pair is split, conservatively (undamped): a first-order split each, whose
    // mean motion and split match the members at re-solved points.
    let smooth = smoothness(&pt.modes);
    let pairs = smooth
        .iter()
        .filter(|s| matches!(s, Smoothness::Repeated { .. }))
        .count()
        / 2;
    assert_eq!(lm.splits.len(), pairs, "{:?}", lm.splits);
    let p = model.model().nominal();
    let vars = model.model().toleranced();
    let opt = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    // The members' ω_d at the point moved by `step` along the variables' direction `dir`.
    let members_at = |dir: &[f64], step: f64| -> Vec<[f64; 2]> {
        let mut pp = p.clone();
        for (a, &i) in vars.iter().enumerate() {
            pp[i] += step * dir[a] * p[i];
        }
        let q = match_modes(
            &pt,
            point(&model, &pp, 0.0, &pt.equilibrium.q, &opt).unwrap(),
        );
        (lm.splits.iter())
            .map(|sp| sp.modes.map(|m| q.modes[m].damped_frequency))
            .collect()
    };
    // Steps of 1 % and ½ %: the roots carry absolute rounding of about 1e-9 rad/s (the form
    // spans ω² up to 2.7e9), which smaller steps would divide into the differences.
    let h = 1e-2;
    let nv = vars.len();
    for a in 0..nv {
        for b in a..nv {
            // Along `e_a + e_b` (each variable relative to its value): the mean moves by
            // `gᵀd h`, the half split is `√(dᵀQd) h` to O(h²) (after extrapolation: O(h⁴)
            // and O(h²)).
            let dir: Vec<f64> = (0..nv)
                .map(|c| f64::from(u8::from(c == a)) + f64::from(u8::from(c == b)))
                .collect();
            let d: Vec<f64> = (0..nv).map(|c| dir[c] * p[vars[c]]).collect();
            // Central differences of the mean at `h` and `h/2`, and the half split over the
            // step at both, each Richardson-extrapolated.
            let at = |step: f64| (members_at(&dir, step), members_at(&dir, -step));
            let ((up, down), (up2, down2)) = (at(h), at(h / 2.0));
            for (k, sp) in lm.splits.iter().enumerate() {
                let mean = |m: [f64; 2]| (m[0] + m[1]) / 2.0;
                let central =
                    |u: [f64; 2], d: [f64; 2], step: f64| (mean(u) - mean(d)) / (2.0 * step);
                let dmean =
                    (4.0 * central(up2[k], down2[k], h / 2.0) - central(up[k], down[k], h)) / 3.0;
                let half = |u: [f64; 2], step: f64| (u[1] - u[0]) / (2.0 * step);
                let half = 2.0 * half(up2[k], h / 2.0) - half(up[k], h);
                let g: f64 = (0..nv).map(|c| sp.mean[c] * d[c]).sum();
                let q = (&sp.split * nalgebra::DVector::from_column_slice(&d))
                    .dot(&nalgebra::DVector::from_column_slice(&d));
                // Relative, above an absolute floor of 1e-6 rad/s a unit of relative change:
                // the differences' rounding (1e-9 rad/s over steps of 1e-2).
                let scale = g.abs().max(q.max(0.0).sqrt()).max(1.0);
                assert!(
                    (dmean - g).abs() <= 1e-6 * scale,
                    "pair {k} along {a}+{b}: mean {dmean} against {g}"
                );
                assert!(
                    (half - q.max(0.0).sqrt()).abs() <= 1e-3 * scale,
                    "pair {k} along {a}+{b}: half split {half} against {}",
                    q.max(0.0).sqrt()
                );
            }
        }
    }
    // The Taylor methods: first order fills the members' rows from the split (ω_d, and ζ,
    // which stays zero), second order keeps the reason.
    let case = modaltol::model::Case::from_parameters(model.model());
    let spread = modaltol::tolerance::Spread::new(&model, &case, &vars);
    let stats = modaltol::taylor::Taylor::at(&lm, &spread);
    for &k in &outs {
        let o = &lm.outputs[k];
        let (stat, _) = stats[k]
            .first_order
            .as_ref()
            .unwrap_or_else(|e| panic!("{o:?}: {e}"));
        assert!(stat.mean.is_finite() && stat.std.is_finite(), "{o:?}");
        assert!(stats[k].second_order.is_err(), "{o:?}");
        for (what, missing) in [
            ("gradient", lm.grad[k].as_ref().err()),
            ("Hessian", lm.hess[k].as_ref().err()),
        ] {
            assert!(
                matches!(
                    missing,
                    Some(Missing::Mode {
                        why: Smoothness::Repeated { .. },
                        ..
                    })
                ),
                "{o:?}: the {what} of a split double root says why it is missing: {missing:?}"
            );
        }
    }
    // Variable by variable: the symmetric ones move each pair as one, `k_z` splits them.
    let s = DesignPoint::new(&model, &p, &pt)
        .sensitivities(&vars, Derivatives::Exact)
        .expect("sensitivities");
    let kz = (model.model().parameters.iter())
        .position(|q| q.name == "k_z")
        .unwrap();
    for v in &s.variables {
        for (m, ms) in v.modes.iter().enumerate() {
            if matches!(smooth[m], Smoothness::Repeated { .. })
                && lm
                    .outputs
                    .iter()
                    .any(|o| o.mode == Some(m) && o.quantity == Quantity::DampedFrequency)
            {
                let expected = if v.param == kz {
                    Status::NotDifferentiable
                } else {
                    Status::Ok
                };
                assert_eq!(
                    ms.status,
                    expected,
                    "mode {} along parameter {}",
                    m + 1,
                    v.param
                );
            }
        }
    }
}
