//! Sensitivities: closed forms for the pendulum, AD against finite differences of the whole
//! pipeline for every example, the governor's transfer peak, and why the left eigenvector matters.

mod common;

use common::pendulum::G;

use common::example;
use modaltol::sensitivity::{
    DesignPoint, Status, TransferAt, eigenvalue_derivative, nominal_transfer,
};
use modaltol::sweep::{Options, Sweep, point};
use num_dual::Dual64;

/// The pendulum's known answer (`tests/common/pendulum.rs`) differentiated in L by dual numbers:
/// (ω_d, |H(jΩ)|, discriminant 4IK − c²).
fn pendulum_closed_form(l: Dual64, w: f64) -> (Dual64, Dual64, f64) {
    let known = common::pendulum::pendulum(l, w);
    (
        known.damped_frequency,
        known.transfer,
        known.discriminant.re,
    )
}

#[test]
fn pendulum_sensitivities_match_closed_form() {
    let model = example("rotating_pendulum.toml");
    let tf = model.model().analysis.transfer.unwrap();
    let l = model.model().parameter("L").unwrap();
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    let critical = (1.5 * G).sqrt();
    let resonance = (0.75 * G).sqrt();
    let mut checked = 0;
    for s in 0..=600 {
        let w = s as f64 * 0.01;
        let pt = sweep.step(w).unwrap();
        let sens = DesignPoint::new(&model, &model.model().nominal(), &pt)
            .with_transfer(Some(TransferAt::at_speed(&tf, w)))
            .analytic(&[l])
            .unwrap();
        let (wd, h, disc) = pendulum_closed_form(Dual64::new(1.0, 1.0), w);
        let v = &sens.variables[0];
        let mode = &v.modes[0];
        let mag = sens.transfer_magnitude.unwrap();
        assert!(
            (mag - h.re).abs() <= 1e-10 * h.re,
            "Ω = {w}: |H| = {mag} vs {}",
            h.re
        );
        let dh = v.d_transfer_magnitude.unwrap();
        // d|H|/dL: relative 1e-8, with a floor at the rounding level of the terms it cancels.
        assert!(
            (dh - h.eps).abs() <= 1e-8 * h.eps.abs() + 1e-12 * h.re,
            "Ω = {w}: d|H|/dL = {dh} vs {}",
            h.eps
        );
        if disc.abs() < 0.05 || (w - critical).abs() < 0.01 {
            continue; // class change: ω_d = √max(0, D) is not differentiable there
        }
        assert_eq!(mode.status, Status::Ok, "Ω = {w}");
        assert!(
            (mode.d_damped_frequency - wd.eps).abs() <= 1e-8 * wd.eps.abs() + 1e-12,
            "Ω = {w}: dω_d/dL = {} vs {}",
            mode.d_damped_frequency,
            wd.eps
        );
        checked += 1;
    }
    assert!(checked > 500);
    // The paper's observation: the length tolerance does not move |H| at the undamped
    // synchronous resonance √(3g/4L), nor anywhere on the swung-out branch.
    for w in [resonance, 4.2, 5.0, 6.0] {
        let pt = common::at(&model, w, &Options::default());
        let sens = DesignPoint::new(&model, &model.model().nominal(), &pt)
            .with_transfer(Some(TransferAt::at_speed(&tf, w)))
            .analytic(&[l])
            .unwrap();
        let dh = sens.variables[0].d_transfer_magnitude.unwrap();
        assert!(dh.abs() < 1e-12, "Ω = {w}: d|H|/dL = {dh}");
    }
}

#[test]
fn overdamped_roots_coalescing_are_flagged_not_differentiated() {
    let model = example("rotating_pendulum.toml");
    let l = model.model().parameter("L").unwrap();
    // Critical damping on the hanging branch: Ω² = 3g/2L − c²/(4I²).
    let w = (1.5 * G - 2.25f64).sqrt();
    let pt = common::at(&model, w, &Options::default());
    let sens = DesignPoint::new(&model, &model.model().nominal(), &pt)
        .analytic(&[l])
        .unwrap();
    assert_eq!(sens.variables[0].modes[0].status, Status::NotDifferentiable);
}

/// |a − b| within 1e-6 relative, with an absolute floor for quantities that vanish.
fn agree(a: f64, b: f64, floor: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + floor
}

#[test]
fn automatic_and_finite_differences_agree_for_every_example() {
    for (file, from, to) in [
        ("rotating_pendulum.toml", 0.1, 6.0),
        ("governor.toml", 0.2, 12.0),
        ("spinning_universal_pendulum.toml", 0.0, 6.0),
    ] {
        let model = example(file);
        let tf = model.model().analysis.transfer.unwrap();
        let wrt = model.model().toleranced();
        let p = model.model().nominal();
        let mut sweep = Sweep::new(&model, p.clone(), Options::default());
        let mut compared = 0;
        for s in 0..20 {
            let w = from + (to - from) * s as f64 / 19.0;
            let pt = sweep.step(w).unwrap();
            let t = Some(TransferAt::at_speed(&tf, w));
            let a = DesignPoint::new(&model, &p, &pt)
                .with_transfer(t)
                .analytic(&wrt)
                .unwrap();
            let f = DesignPoint::new(&model, &p, &pt)
                .with_transfer(t)
                .finite_difference(&wrt)
                .unwrap();
            let hmag = a.transfer_magnitude.unwrap();
            for (va, vf) in a.variables.iter().zip(&f.variables) {
                let b = p[va.param].abs();
                let name = &model.model().parameters[va.param].name;
                match (va.d_transfer_magnitude, vf.d_transfer_magnitude) {
                    (Some(ha), Some(hf)) => assert!(
                        agree(ha, hf, 1e-9 * hmag / b + 1e-15),
                        "{file} Ω = {w} d|H|/d{name}: AD {ha} FD {hf}"
                    ),
                    (None, _) => assert!(
                        hmag < 1e-12,
                        "{file} Ω = {w}: d|H|/d{name} missing though |H| = {hmag}"
                    ),
                    (Some(ha), None) => {
                        panic!("{file} Ω = {w}: FD has no d|H|/d{name}, AD says {ha}")
                    }
                }
                for (k, (ma, mf)) in va.modes.iter().zip(&vf.modes).enumerate() {
                    if ma.status != Status::Ok || mf.status != Status::Ok {
                        continue;
                    }
                    let wn = pt.modes[k].natural_frequency;
                    for (what, x, y, floor) in [
                        (
                            "dω_d",
                            ma.d_damped_frequency,
                            mf.d_damped_frequency,
                            1e-9 * wn / b,
                        ),
                        (
                            "dω_n",
                            ma.d_natural_frequency,
                            mf.d_natural_frequency,
                            1e-9 * wn / b,
                        ),
                        ("dζ", ma.d_damping_ratio, mf.d_damping_ratio, 1e-9 / b),
                        ("dRe λ", ma.d_eigen_re, mf.d_eigen_re, 1e-9 * wn / b),
                        ("d(λ₁+λ₂)", ma.d_sum, mf.d_sum, 1e-9 * wn / b),
                        ("d(λ₁λ₂)", ma.d_product, mf.d_product, 1e-9 * wn * wn / b),
                    ] {
                        assert!(
                            agree(x, y, floor),
                            "{file} Ω = {w} mode {} {what}/d{name}: AD {x} FD {y}",
                            k + 1
                        );
                    }
                    compared += 1;
                }
            }
        }
        assert!(
            compared >= 20 * model.model().toleranced().len() / 2,
            "{file}: only {compared} comparisons"
        );
    }
}

#[test]
fn governor_transfer_peaks_at_1_595() {
    let model = example("governor.toml");
    let tf = model.model().analysis.transfer.unwrap();
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    let mut best = (0.0, 0.0);
    for i in 0..=600 {
        let w = 1.3 + i as f64 * 0.001;
        let pt = sweep.step(w).unwrap();
        let h = nominal_transfer(&pt, &TransferAt::at_speed(&tf, w))
            .unwrap()
            .magnitude();
        if h > best.1 {
            best = (w, h);
        }
    }
    assert!((best.0 - 1.595).abs() <= 0.002, "peak at {} rad/s", best.0);
}

#[test]
fn gyroscopic_example_needs_the_left_eigenvector() {
    let model = example("spinning_universal_pendulum.toml");
    let p = model.model().nominal();
    let wrt = model.model().toleranced();
    let pt = common::at(&model, 4.0, &Options::default());
    let f = DesignPoint::new(&model, &p, &pt)
        .finite_difference(&wrt)
        .unwrap();
    let a = DesignPoint::new(&model, &p, &pt).analytic(&wrt).unwrap();
    let mut worst_symmetric = 0.0f64;
    for (k, &b) in wrt.iter().enumerate() {
        // Re-derive M̂', Ĉ', K̂' by central differences to feed both formulas.
        let h = 1e-6 * p[b].abs();
        let lin = |s: f64| {
            let mut pp = p.clone();
            pp[b] += s * h;
            let o = Options {
                independent: Some(pt.linear.independent.clone()),
                no_branch_switch: true,
                ..Default::default()
            };
            point(&model, &pp, 4.0, &pt.equilibrium.q, &o)
                .unwrap()
                .linear
        };
        let (lp, lm) = (lin(1.0), lin(-1.0));
        let d = |x: &nalgebra::DMatrix<f64>, y: &nalgebra::DMatrix<f64>| (x - y) / (2.0 * h);
        let (dm, dc, dk) = (d(&lp.m, &lm.m), d(&lp.c, &lm.c), d(&lp.k, &lm.k));
        for (j, mode) in pt.modes.iter().enumerate() {
            let r = &mode.root;
            let proper = eigenvalue_derivative(
                r.lambda,
                &r.right,
                &r.left,
                (&pt.linear.m, &pt.linear.c),
                (&dm, &dc, &dk),
            );
            let symmetric = eigenvalue_derivative(
                r.lambda,
                &r.right,
                &r.right,
                (&pt.linear.m, &pt.linear.c),
                (&dm, &dc, &dk),
            );
            let fd = f.variables[k].modes[j].d_damped_frequency;
            assert!(
                agree(a.variables[k].modes[j].d_damped_frequency, fd, 1e-9),
                "AD vs FD"
            );
            assert!(
                (proper.im - fd).abs() <= 1e-5 * fd.abs().max(1e-3),
                "left-vector formula {} vs FD {fd}",
                proper.im
            );
            worst_symmetric = worst_symmetric.max((symmetric.im - fd).abs() / fd.abs().max(1e-3));
        }
    }
    assert!(
        worst_symmetric > 1e-2,
        "the symmetric formula φᵀ(…)φ should be visibly wrong here, off by only {worst_symmetric}"
    );
}

/// Three or four variables share one pass over `Dual4`: each variable's derivatives are bit for
/// bit those of a pass of its own over `Dual64` (all the parameters of three examples in groups
/// of four, the governor's three toleranced ones in one group of three).
#[test]
fn variables_sharing_a_pass_get_the_bits_of_passes_of_their_own() {
    for file in [
        "governor.toml",
        "spinning_universal_pendulum.toml",
        "multi_arm_governor_13_variables.toml",
    ] {
        let model = example(file);
        let p = model.model().nominal();
        let pt = common::at(&model, 1.3, &Options::default());
        let all: Vec<usize> = (0..p.len()).rev().collect();
        for wrt in [all, model.model().toleranced()] {
            let together = DesignPoint::new(&model, &p, &pt)
                .dual_linearizations(&wrt)
                .unwrap();
            assert_eq!(together.len(), wrt.len());
            for (shared, &b) in together.iter().zip(&wrt) {
                let alone = DesignPoint::new(&model, &p, &pt)
                    .dual_linearizations(&[b])
                    .unwrap()
                    .remove(0);
                assert_eq!(shared.param, b);
                // The `Debug` text tells every bit apart, `-0.0` from `0.0` included.
                assert_eq!(
                    format!("{:?} {:?}", shared.linear, shared.d_equilibrium),
                    format!("{:?} {:?}", alone.linear, alone.d_equilibrium),
                    "{file}: parameter {b}"
                );
            }
        }
    }
}
