//! The Taylor methods (first order, second order, invariant) fill every row they can on
//! multi-mode models, whatever the model's scale, and a row they cannot fill says why.
//!
//! Scaling every mass, inertia, spring, damper and preload of a model by the same factor leaves
//! its modes unchanged (the equations of motion are multiplied by it) and divides its
//! transfer functions by it: the derivatives of ω_d and ζ are unchanged, those of |H| divided
//! by the factor. The simple-root test of the expansions used to compare a determinant with an
//! absolute threshold, which emptied 228 of the blade's 240 first-order rows and every row of a
//! model scaled by 1e9, silently.

mod common;

use common::{example, example_text};
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::modal::{Smoothness, smoothness};
use modaltol::output::{Missing, Quantity};
use modaltol::sensitivity::DesignPoint;
use modaltol::sweep::{Options, Point, Sweep};
use modaltol::table::Method;
use modaltol::tolerance::{LocalModel, match_modes};
use nalgebra::DMatrix;

/// The model text with every mass, inertia, spring, damper and preload multiplied by `factor`
/// (numbers multiplied, expressions wrapped), the rest untouched.
fn scaled(text: &str, factor: f64) -> String {
    fn scale(v: &mut toml::Value, f: f64) {
        match v {
            toml::Value::Float(x) => *x *= f,
            toml::Value::Integer(i) => *v = toml::Value::Float(*i as f64 * f),
            toml::Value::String(e) => *e = format!("({e})*{f:e}"),
            toml::Value::Array(a) => a.iter_mut().for_each(|x| scale(x, f)),
            _ => panic!("unexpected field {v:?}"),
        }
    }
    let mut doc: toml::Table = text.parse().expect("TOML");
    for (table, keys) in [
        ("bodies", &["mass", "inertia"][..]),
        ("joints", &["stiffness", "damping"][..]),
        ("forces", &["stiffness", "damping", "preload"][..]),
    ] {
        let Some(toml::Value::Array(items)) = doc.get_mut(table) else {
            continue;
        };
        for item in items {
            for key in keys {
                if let Some(v) = item.get_mut(*key) {
                    scale(v, factor);
                }
            }
        }
    }
    toml::to_string(&doc).expect("TOML")
}

/// Local models (gradients and Hessians of every output) along a sweep of `model` at
/// `speeds`, modes matched to `reference`'s where given; the variables are the toleranced
/// parameters in the order of `names` where given.
fn local_models(
    model: &Compiled,
    speeds: &[f64],
    reference: Option<(&[Point], &[String])>,
) -> Vec<(Point, LocalModel)> {
    let p = model.model().nominal();
    let vars: Vec<usize> = match reference {
        Some((_, names)) => names
            .iter()
            .map(|n| {
                model
                    .model()
                    .parameters
                    .iter()
                    .position(|q| &q.name == n)
                    .expect("a parameter")
            })
            .collect(),
        None => model.model().toleranced(),
    };
    let tf = model.model().analysis.transfer.as_ref();
    let mut sweep = Sweep::new(model, p.clone(), Options::default());
    speeds
        .iter()
        .enumerate()
        .map(|(i, &w)| {
            let mut pt = sweep.step(w).unwrap_or_else(|e| panic!("Ω = {w}: {e}"));
            if let Some((r, _)) = reference {
                pt = match_modes(&r[i], pt);
            }
            let lm = DesignPoint::new(model, &p, &pt)
                .with_model_transfer(tf)
                .local_model(&vars, true)
                .expect("derivatives");
            (pt, lm)
        })
        .collect()
}

/// `a` and `b` agree to `tol` relative to the larger of them (entry by entry against the
/// largest entry).
fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    let scale = a
        .iter()
        .chain(b)
        .fold(f64::MIN_POSITIVE, |s, x| s.max(x.abs()));
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
}

/// The multi-mode examples at speeds inside their ranges.
fn multi_mode_examples() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("rotating_blade.toml", vec![0.0, 10.0, 20.0]),
        (
            "rotor_on_rubber_mounts.toml",
            vec![0.0, 100.0, 200.0, 300.0],
        ),
        ("spinning_spatial_fourbar.toml", vec![0.0, 3.0, 6.0]),
        ("spinning_universal_pendulum.toml", vec![0.5, 3.0, 6.0]),
        // One mode, but 2 closed loops: the equilibrium's multipliers scale with the model.
        ("governor.toml", vec![0.5, 1.595, 3.0]),
        ("multi_arm_governor.toml", vec![1.0, 3.0]),
    ]
}

#[test]
fn every_taylor_row_of_the_multi_mode_examples_is_filled_whatever_their_scale() {
    for (file, speeds) in multi_mode_examples() {
        let text = example_text(file);
        let model = example(file);
        let base = local_models(&model, &speeds, None);
        let points: Vec<Point> = base.iter().map(|(pt, _)| pt.clone()).collect();
        let names: Vec<String> = (model.model().toleranced().iter())
            .map(|&b| model.model().parameters[b].name.clone())
            .collect();
        for (pt, lm) in &base {
            // These speeds are away from any class change or repeated root: every mode is
            // simple, and every gradient and Hessian exists.
            assert!(
                smoothness(&pt.modes)
                    .iter()
                    .all(|s| *s == Smoothness::Simple),
                "{file} Ω = {}: {:?}",
                pt.speed,
                smoothness(&pt.modes)
            );
            for (k, o) in lm.outputs.iter().enumerate() {
                assert!(
                    lm.grad[k].is_ok(),
                    "{file} Ω = {} {o:?}: {:?}",
                    pt.speed,
                    lm.grad[k]
                );
                assert!(
                    lm.hess[k].is_ok(),
                    "{file} Ω = {} {o:?}: {:?}",
                    pt.speed,
                    lm.hess[k]
                );
            }
            assert!(lm.disc.iter().all(|d| d.1.is_ok() && d.2.is_ok()), "{file}");
        }
        for factor in [1e-9, 1e-3, 1e3, 1e9] {
            let model = Compiled::from_str(&scaled(&text, factor), file)
                .unwrap_or_else(|e| panic!("{file} ×{factor}: {e}"));
            let scaled_models = local_models(&model, &speeds, Some((&points, &names)));
            for ((_, a), (pt, b)) in base.iter().zip(&scaled_models) {
                let what = format!("{file} ×{factor:e} Ω = {}", pt.speed);
                for (k, o) in a.outputs.iter().enumerate() {
                    // |H| is in response per unit force: divided by the factor.
                    let unit = if o.quantity == Quantity::TransferMagnitude {
                        1.0 / factor
                    } else {
                        1.0
                    };
                    let (va, vb) = (a.value[k] * unit, b.value[k]);
                    assert!(
                        (va - vb).abs() <= 1e-8 * va.abs().max(vb.abs()),
                        "{what} {o:?}: {va} vs {vb}"
                    );
                    let ga: Vec<f64> = a.grad[k]
                        .as_ref()
                        .unwrap()
                        .iter()
                        .map(|g| g * unit)
                        .collect();
                    let gb = b.grad[k]
                        .as_ref()
                        .unwrap_or_else(|e| panic!("{what} {o:?}: {e}"));
                    assert!(close(&ga, gb, 1e-7), "{what} {o:?}: {ga:?} vs {gb:?}");
                    let ha = a.hess[k].as_ref().unwrap() * unit;
                    let hb = b.hess[k]
                        .as_ref()
                        .unwrap_or_else(|e| panic!("{what} {o:?}: {e}"));
                    assert!(
                        close(ha.as_slice(), hb.as_slice(), 1e-6),
                        "{what} {o:?}: {ha} vs {hb}"
                    );
                }
            }
        }
    }
}

/// A chain of `n` segments whose segments each carry their own toleranced mass per length and
/// bending stiffness (`2n` design variables), with joint dampers.
fn toleranced_chain(n: usize) -> String {
    let h = 1.0 / n as f64;
    let mut s =
        format!("name = \"chain {n}\"\ngravity = [0, 0, 0]\n[parameters]\nh = {h}\nc = 0.02\n");
    for i in 0..n {
        s += &format!(
            "mu{i} = {{ value = {}, tolerance = \"2%\" }}\nEI{i} = {{ value = {}, tolerance = \"5%\" }}\n",
            2.0 + 0.05 * i as f64,
            50.0 - 1.5 * i as f64
        );
    }
    s += "[[bodies]]\nname = \"hub\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\ncm = [0, 0, 0]\n\
          [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"hub\"\n\
          at = [0, 0, 0]\naxis = [0, 0, 1]\ndrive = \"speed\"\n";
    for i in 0..n {
        let parent = if i == 0 {
            "hub".into()
        } else {
            format!("s{}", i - 1)
        };
        let k = if i == 0 {
            format!("2*EI{i}/h")
        } else {
            format!("EI{i}/h")
        };
        s += &format!(
            "[[bodies]]\nname = \"s{i}\"\nmass = \"mu{i}*h\"\n\
             inertia = [0, \"mu{i}*h^3/12\", \"mu{i}*h^3/12\"]\ncm = [\"{}*h\", 0, 0]\n\
             [[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\nparent = \"{parent}\"\n\
             child = \"s{i}\"\nat = [\"{i}*h\", 0, 0]\naxis = [0, -1, 0]\nstiffness = \"{k}\"\n\
             damping = \"c\"\n",
            i as f64 + 0.5
        );
    }
    s += &format!(
        "[analysis]\n[[analysis.cases]]\nname = \"all\"\ntolerances = {{ {} }}\n",
        (0..n)
            .map(|i| format!("mu{i} = \"2%\", EI{i} = \"5%\""))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s
}

/// Hessians of every output of the chain against central differences of the exact gradients
/// at re-solved points (Richardson-extrapolated, symmetrised): the two agree on all 24
/// variables and 12 modes.
#[test]
fn a_chain_with_two_dozen_toleranced_variables_has_every_derivative_and_each_matches_differences() {
    let n = 12;
    let model =
        Compiled::from_str(&toleranced_chain(n), "chain.toml").unwrap_or_else(|e| panic!("{e}"));
    let p = model.model().nominal();
    let vars = model.model().toleranced();
    assert_eq!(vars.len(), 2 * n);
    let opt = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    let (pt, exact) = local_models(&model, &[15.0], None).remove(0);
    assert_eq!(pt.modes.len(), n);
    let nv = vars.len();
    let outs = exact.outputs.len();
    // Column j of every output's Hessian by the gradients at b_j ± step.
    let column = |j: usize, step: f64| -> Vec<Vec<f64>> {
        let b = vars[j];
        let side = |s: f64| {
            let mut pp = p.clone();
            pp[b] += s * step;
            let q = modaltol::sweep::point(&model, &pp, pt.speed, &pt.equilibrium.q, &opt).unwrap();
            DesignPoint::new(&model, &pp, &match_modes(&pt, q))
                .local_model(&vars, false)
                .unwrap()
        };
        let (up, down) = (side(1.0), side(-1.0));
        (0..outs)
            .map(|k| {
                let (u, d) = (up.grad[k].as_ref().unwrap(), down.grad[k].as_ref().unwrap());
                (0..nv).map(|i| (u[i] - d[i]) / (2.0 * step)).collect()
            })
            .collect()
    };
    // The exact gradients of the highest modes carry about 1e-9 of rounding (the two exact
    // routes, first-order sensitivities and the Hessians' passes, agree to 3e-9 there), which
    // central differences divide by the step: steps h, h/2, h/4 of 5 % extrapolated twice
    // (Richardson, truncation O(h⁶)) agree with the exact Hessians to 1e-6, where steps of
    // 0.1 % did to 1.4e-5.
    let mut differenced = vec![DMatrix::<f64>::zeros(nv, nv); outs];
    for j in 0..nv {
        let step = 5e-2 * p[vars[j]].abs();
        let d = [
            column(j, step),
            column(j, 0.5 * step),
            column(j, 0.25 * step),
        ];
        for (k, h) in differenced.iter_mut().enumerate() {
            for i in 0..nv {
                let r1 = (4.0 * d[1][k][i] - d[0][k][i]) / 3.0;
                let r2 = (4.0 * d[2][k][i] - d[1][k][i]) / 3.0;
                h[(i, j)] = (16.0 * r2 - r1) / 15.0;
            }
        }
    }
    for (k, o) in exact.outputs.iter().enumerate() {
        let h = exact.hess[k]
            .as_ref()
            .unwrap_or_else(|e| panic!("{o:?}: {e}"));
        let d = (&differenced[k] + differenced[k].transpose()) * 0.5;
        assert!(
            (h - &d).amax() <= 1e-5 * h.amax().max(d.amax()),
            "{o:?}: exact vs differenced Hessians differ by {:e} of {:e}",
            (h - &d).amax(),
            h.amax()
        );
    }
}

/// The README's blade, analysed by every Taylor method: every row has a value, `summary.json`
/// lists no row without one, and the report prints no NaN.
#[test]
fn the_blades_analysis_has_every_taylor_row_and_no_nan_in_its_report() {
    let model = example("rotating_blade.toml");
    let opt = AnalyzeOptions {
        speeds: vec![0.0, 10.0, 20.0],
        cases: model.model().analysis.cases.clone(),
        quadrature: None,
        ..Default::default()
    };
    let a = analyze(&model, &opt, &|_, _, _| {});
    assert!(a.failures.is_empty(), "{:?}", a.failures);
    let taylor = [
        Method::FirstOrder,
        Method::SecondOrder,
        Method::Invariant,
        Method::Analytic,
    ];
    let rows: Vec<_> = a
        .rows
        .iter()
        .filter(|r| taylor.contains(&r.method()))
        .collect();
    // Per case and speed: 40 outputs by first order, second order and analytic, 20 by the
    // invariant method.
    assert_eq!(
        rows.len(),
        2 * 3 * (40 * 3 + 20),
        "rows per case, speed, method"
    );
    for r in &rows {
        assert!(
            r.mean.is_finite() && r.std.is_finite() && r.missing.is_none(),
            "{r:?}"
        );
    }
    let summary = modaltol::report::summary_json(model.model(), &a, None, 1);
    assert_eq!(summary["unfilled"], serde_json::json!([]));
    let html = modaltol::report::report_html(model.model(), &a, &[], &[], Default::default());
    assert!(!html.contains("NaN"), "the report prints NaN");
}

/// A mass on a slider with a spring `k` and a damper `c` (1 DOF), toleranced mass.
fn slider(k: f64, c: f64) -> Compiled {
    let text = format!(
        "[parameters]\nm = {{ value = 1.0, tolerance = \"3%\" }}\n\
         [[bodies]]\nname = \"b\"\nmass = \"m\"\ncm = [0, 0, 0]\n\
         [[joints]]\nname = \"x\"\ntype = \"prismatic\"\nparent = \"ground\"\nchild = \"b\"\n\
         axis = [1, 0, 0]\nstiffness = {k}\ndamping = {c}\n"
    );
    Compiled::from_str(&text, "slider.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// Where a row cannot be filled it says why: critical damping (the mode's two roots coincide)
/// leaves ω_d without a derivative (its kink) but not ζ, which is smooth there; a free slider
/// with a damper is a rigid-body mode whose ζ is undefined.
#[test]
fn a_row_without_a_value_carries_its_reason() {
    let at_rest = |model: &Compiled| {
        let p = model.model().nominal();
        let pt = Sweep::new(model, p.clone(), Options::default())
            .step(0.0)
            .unwrap();
        let lm = DesignPoint::new(model, &p, &pt)
            .local_model(&model.model().toleranced(), true)
            .unwrap();
        (pt, lm)
    };
    // m = k = 1, c = 2: λ = −1 twice, ζ = c/(2√(km)) = 1, dζ/dm = −ζ/(2m).
    let (pt, lm) = at_rest(&slider(1.0, 2.0));
    assert_eq!(smoothness(&pt.modes), vec![Smoothness::Coalescing]);
    let kink = Missing::Mode {
        mode: 0,
        why: Smoothness::Coalescing,
    };
    assert_eq!(lm.grad[0], Err(kink.clone()));
    assert!(kink.to_string().contains("two roots coincide"), "{kink}");
    let dzeta = lm.grad[1]
        .as_ref()
        .expect("ζ is smooth at critical damping");
    assert!((dzeta[0] + 0.5).abs() < 1e-12, "{dzeta:?}");
    // No spring: a rigid-body mode, λ = 0 and −c/m.
    let (pt, lm) = at_rest(&slider(0.0, 2.0));
    assert_eq!(smoothness(&pt.modes), vec![Smoothness::Rigid]);
    assert_eq!(lm.grad[1], Err(Missing::RigidDamping { mode: 0 }));
    assert!(lm.value[1].is_nan() && lm.value[0] == 0.0);
}
