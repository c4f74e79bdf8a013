//! The recorded program (`tape`, `program`) against the direct route it is traced from: same
//! residual, Jacobian, damping and mass matrices, and the same sweeps.

mod common;

use common::example;
use modaltol::compiled::{Compiled, Route};
use modaltol::equations::Direct;
use modaltol::equations::Equations;
use modaltol::linearize::{SteadyState, choose_independent, linearize};
use modaltol::mechanics::System;
use modaltol::mechanics::dynamics::{Lifted, equilibrium_residual, evaluate_rows};
use modaltol::program::{Tier, Workspace};
use modaltol::sweep::{Options, Sweep, initial_guess};
use modaltol::tape::{Forward, Seeding, Tape, Var, record};
use nalgebra::DMatrix;
use num_dual::{Dual64, DualNum};
use num_traits::Signed;

const EXAMPLES: [&str; 4] = [
    "rotating_pendulum.toml",
    "governor.toml",
    "spinning_universal_pendulum.toml",
    "multi_arm_governor.toml",
];

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-11 * scale.max(1.0)
}

#[test]
fn a_trace_folds_constants_shares_operations_and_differentiates() {
    // f(x, y) = x·y + sin(x)·1 + 0·y + x·y, g = (x·y)/y + c: x·y is recorded once, 0·y and ·1
    // vanish.
    let f = |v: &[Var]| {
        let (x, y) = (v[0], v[1]);
        let one = Var::from(1.0);
        let zero = Var::from(0.0);
        Some(vec![
            x * y + x.sin() * one + zero * y + x * y,
            (x * y) / y + Var::from(2.5),
        ])
    };
    let tape = record(&[0.7, 1.3], f).expect("no branch");
    // Inputs 2, x·y, sin x, two additions, the division and the constant addition.
    assert_eq!(tape.len(), 8, "{tape:?}");
    let at = [1.1, -0.4];
    let mut work = Vec::new();
    let y = tape.eval(&[], &at, &mut work);
    let (x0, y0) = (at[0], at[1]);
    assert_eq!(y[0], x0 * y0 + x0.sin() + x0 * y0);
    assert_eq!(y[1], (x0 * y0) / y0 + 2.5);
    // Forward lanes against dual numbers.
    let seeding = tape.seeding(&[(0, 0), (1, 1)], 2, 2);
    let (v, d) = tape.forward(&[], &at, &seeding, &mut Forward::default());
    assert_eq!(v, y);
    for lane in 0..2 {
        let xd = Dual64::new(x0, if lane == 0 { 1.0 } else { 0.0 });
        let yd = Dual64::new(y0, if lane == 1 { 1.0 } else { 0.0 });
        let f0 = xd * yd + xd.sin() + xd * yd;
        let f1 = (xd * yd) / yd + 2.5;
        assert!((d[lane] - f0.eps).abs() < 1e-15);
        assert!((d[2 + lane] - f1.eps).abs() < 1e-15);
    }
    // Over dual numbers the program gives the same derivatives (second route).
    let xd = [Dual64::new(x0, 1.0), Dual64::from_re(y0)];
    let yd = tape.eval(&[], &xd, &mut Vec::new());
    assert!((yd[0].eps - d[0]).abs() < 1e-15);
    // At three values of x in one pass, as three evaluations (y does not move).
    let vary_x = tape.seeding(&[(0, 0)], 1, 2);
    let xs = [0.3, -1.7, 2.0];
    let batch = tape.eval_varied(&[], &at, &vary_x, xs, &mut Vec::new());
    for (l, &xv) in xs.iter().enumerate() {
        let one = tape.eval(&[], &[xv, at[1]], &mut Vec::new());
        for (o, b) in one.iter().zip(&batch) {
            assert_eq!(*o, b[l], "x = {xv}");
        }
    }
    // Derivatives of the first output only: both values, the first's derivatives unchanged.
    let first = tape.seeding(&[(0, 0), (1, 1)], 2, 1);
    let (v1, d1) = tape.forward(&[], &at, &first, &mut Forward::default());
    assert_eq!(v1, y);
    assert_eq!(d1, d[..2]);
}

/// The first two outputs of `f(x, y, z)` traced at `(0.7, 1.3, 0)`: replayed with `z = 0` made
/// a constant, and recorded with `z = 0` from the start (both finished), and the whole trace.
fn replayed_and_recorded(f: impl Fn(Var, Var, Var) -> Vec<Var>) -> (Tape, Tape, Tape) {
    let at = [0.7, 1.3, 0.0];
    let all = record(&at, |v| Some(f(v[0], v[1], v[2]))).unwrap();
    let direct = record(&at, |v| Some(f(v[0], v[1], Var::from(0.0))[..2].to_vec()))
        .unwrap()
        .finish(&[0, 1]);
    let replayed = all
        .specialise(&at, &[(2, 0.0)], &[0, 1])
        .unwrap()
        .finish(&[0, 1]);
    (replayed, direct, all)
}

#[test]
fn a_trace_specialised_to_constant_inputs_is_the_trace_recorded_with_them() {
    // One trace with z as an input, replayed with z = 0 (and one output dropped), against the
    // trace recorded with z = 0 from the start: the same operations fold, the same values.
    let f = |x: Var, y: Var, z: Var| {
        vec![
            x * y + z * x.sin() + (y + z) * (x - z),
            (x * z).exp() * y + y * y,
            z * z + x,
        ]
    };
    let (replayed, direct, all) = replayed_and_recorded(f);
    assert_eq!(replayed.len(), direct.len(), "{replayed:?}\n{direct:?}");
    assert!(replayed.len() < all.finish(&[0, 1]).len());
    for x in [[1.1, -0.4, 9.0], [-2.0, 0.3, -1.0]] {
        let a = replayed.eval(&[], &x, &mut Vec::new());
        let b = direct.eval(&[], &x, &mut Vec::new());
        assert_eq!(a, b);
        assert_eq!(a[1], x[1] + x[1] * x[1]);
    }
}

#[test]
fn a_replay_that_folds_two_operations_into_one_keeps_both_and_their_values() {
    // With z = 0, `(x + z·y)·x` folds to `x·x`, an operation the trace already has: the replay
    // appends without hash-consing, so it keeps the duplicate (one operation more than the
    // trace recorded with z = 0), and both outputs stay exact.
    let f = |x: Var, y: Var, z: Var| vec![(x + z * y) * x, x * x + y];
    let (replayed, direct, _) = replayed_and_recorded(f);
    assert!(
        replayed.len() <= direct.len() + 1,
        "{replayed:?}\n{direct:?}"
    );
    for x in [[1.1, -0.4, 9.0], [-2.0, 0.3, -1.0]] {
        let a = replayed.eval(&[], &x, &mut Vec::new());
        assert_eq!(a, [x[0] * x[0], x[0] * x[0] + x[1]]);
        assert_eq!(a, direct.eval(&[], &x, &mut Vec::new()));
    }
}

#[test]
fn a_finished_and_split_program_is_the_trace_fused_and_reordered() {
    // Products used once by a sum or a difference (fused), a product used twice and one that
    // is an output (not fused), a sum of two products (one of them fused), a product shared
    // with an output left out (fused: pruned first), and parts that depend on the fixed input
    // 0 alone (placed first).
    let f = |v: &[Var], all: bool| {
        let (p, x, y) = (v[0], v[1], v[2]);
        let pp = p * p + p.sin();
        let shared = x * y;
        let out = y * pp;
        let mut outputs = vec![
            x * pp + y,
            shared + shared * x - out,
            (y * y + x * x) + (pp - x.cos() * pp),
            out,
        ];
        if all {
            outputs.push((shared + y * y).exp());
        }
        Some(outputs)
    };
    let at = [0.3, 0.7, 1.3];
    let raw = record(&at, |v| f(v, true)).expect("no branch");
    let keep = [0, 1, 2, 3];
    let needed = record(&at, |v| f(v, false)).unwrap().len();
    let finished = raw.finish(&keep);
    let split = raw.finish_split(&keep, &[0]);
    // p·p, x·pp, shared·x, one of y·y and x·x, cos x·pp.
    assert_eq!(finished.len(), needed - 5, "{finished:?}");
    assert_eq!(split.len(), finished.len());
    // Input 0, sin p and p·p + sin p.
    assert_eq!(split.eval_static(&at).len(), 3, "{split:?}");
    for point in [[0.3, -1.1, 0.4], [-0.8, 2.5, -0.9]] {
        let all = raw.eval(&[], &point, &mut Vec::new());
        let want: Vec<f64> = keep.iter().map(|&k| all[k]).collect();
        assert_eq!(finished.eval(&[], &point, &mut Vec::new()), want);
        let fixed = split.eval_static(&point);
        assert_eq!(split.eval(&fixed, &point, &mut Vec::new()), want);
        // Split again by another input: the same values.
        let again = split.split(&[1]);
        let fixed = again.eval_static(&point);
        assert_eq!(again.eval(&fixed, &point, &mut Vec::new()), want);
    }
}

/// A recurrence along 300 inputs: output k depends on inputs 0..=k.
fn recurrence<T: modaltol::real::Real>(x: &[T]) -> Vec<T> {
    let mut c = x[0];
    let mut out = vec![c];
    for k in 1..x.len() {
        c = c * T::from(0.5) + x[k].sin() * x[k - 1] + c * x[k];
        out.push(c);
    }
    out
}

/// The derivatives `d` (outputs × lanes, lane k along input k) of [`recurrence`] at `at`
/// along `lanes`, against dual numbers through the function itself, to 1e-13.
fn assert_recurrence_lanes(at: &[f64], d: &[f64], lanes: &[usize]) {
    let n = at.len();
    for &lane in lanes {
        let xd: Vec<Dual64> = (0..n)
            .map(|k| Dual64::new(at[k], if k == lane { 1.0 } else { 0.0 }))
            .collect();
        for (r, y) in recurrence(&xd).iter().enumerate() {
            let got = d[r * n + lane];
            assert!(
                (got - y.eps).abs() <= 1e-13 * y.eps.abs().max(1.0),
                "∂y{r}/∂x{lane}: {got} vs {}",
                y.eps
            );
        }
    }
}

/// The recurrence of `n` inputs recorded at a fixed point, with a lane per input.
fn recurrence_program(n: usize) -> (Vec<f64>, Tape, Seeding) {
    let at: Vec<f64> = (0..n).map(|k| 0.3 + 0.4 * (k as f64 * 0.7).sin()).collect();
    let tape = record(&at, |v| Some(recurrence(v)))
        .unwrap()
        .finish(&(0..n).collect::<Vec<_>>());
    let seeds: Vec<(usize, usize)> = (0..n).map(|k| (k, k)).collect();
    let seeding = tape.seeding(&seeds, n, n);
    (at, tape, seeding)
}

#[test]
fn a_forward_pass_over_more_lanes_than_a_block_runs_block_by_block_and_is_exact() {
    let n = 300;
    assert!(n > modaltol::tape::BLOCK);
    let (at, tape, seeding) = recurrence_program(n);
    let (v, d) = tape.forward(&[], &at, &seeding, &mut Forward::default());
    assert_eq!(v, recurrence(&at));
    // Columns in the first block, on both sides of the boundary and in the last.
    assert_recurrence_lanes(&at, &d, &[0, 1, 255, 256, 257, 299]);
}

#[test]
fn a_forward_pass_whose_operations_share_rows_is_exact() {
    // Big enough that the tangent rows are shared between operations alive at different
    // times (the loop of big models, with its raw reads and writes).
    let n = 1000;
    let (at, tape, seeding) = recurrence_program(n);
    assert!(seeding.shares_rows());
    let mut work = Forward::default();
    let (v, d) = tape.forward(&[], &at, &seeding, &mut work);
    assert_eq!(v, recurrence(&at));
    // A second pass over the same buffer (rows written by the first) gives the same bits.
    assert_eq!(tape.forward(&[], &at, &seeding, &mut work).1, d);
    assert_recurrence_lanes(&at, &d, &[0, 1, 2, 3, 4, 255, 256, 511, 600, 997, 999]);
}

#[test]
fn a_trace_that_branches_on_a_value_is_refused() {
    let branching = |v: &[Var]| Some(vec![if v[0] > Var::from(0.0) { v[0] } else { -v[0] }]);
    assert!(record(&[1.0], branching).is_none());
    // |x| recorded as an operation is fine, and right on both sides.
    let tape = record(&[1.0], |v| Some(vec![v[0].abs()])).unwrap();
    assert_eq!(tape.eval(&[], &[-3.0], &mut Vec::new())[0], 3.0);
    // A failing function gives no program and leaves no recording behind.
    assert!(record(&[1.0], |_| None).is_none());
    let v = Var::from(2.0) * Var::from(3.0);
    assert_eq!(v.value(), 6.0);
}

/// Parameters, speed, coordinates and multipliers.
type State = (Vec<f64>, f64, Vec<f64>, Vec<f64>);

/// States to compare at: the nominal equilibrium's neighbourhood at a few speeds and
/// parameter values off nominal.
fn states(name: &str) -> Vec<State> {
    let model = example(name);
    let p0 = model.model().nominal();
    let mut out = Vec::new();
    for (k, speed) in [0.3, 1.7, 4.2].into_iter().enumerate() {
        let p: Vec<f64> = p0
            .iter()
            .enumerate()
            .map(|(i, v)| v * (1.0 + 0.02 * ((i + k) % 3) as f64 - 0.02))
            .collect();
        let q: Vec<f64> = initial_guess(model.model(), &p, speed)
            .unwrap()
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.05 * ((i * 7 + k) % 5) as f64 - 0.1)
            .collect();
        let lambda = (0..model.model().n_constraints())
            .map(|j| 3.0 - 1.3 * j as f64 + k as f64)
            .collect();
        out.push((p, speed, q, lambda));
    }
    out
}

#[test]
fn a_residual_is_the_same_to_the_bit_before_and_after_its_own_program_is_made() {
    for name in EXAMPLES {
        let model = example(name);
        let p0 = model.model().nominal();
        let q0 = initial_guess(model.model(), &p0, 1.0).unwrap();
        let program = model.program().unwrap();
        // The model's states, and the reference configuration at rest (exact zeros).
        let mut at = states(name);
        at.push((
            p0.clone(),
            0.0,
            vec![0.0; q0.len()],
            vec![0.0; model.model().n_constraints()],
        ));
        let residuals = || {
            at.iter()
                .map(|(p, speed, q, lambda)| {
                    (program
                        .at(p, *speed, Tier::Few, &Workspace::default())
                        .unwrap())
                    .residual(q, lambda)
                })
                .collect::<Vec<_>>()
        };
        // A few residuals run through the program with the rates (the recording's check among
        // them); once a sweep's tier has made the program of `F` alone, through that.
        let before = residuals();
        assert!(program.residual_program().is_none(), "{name}");
        let workspace = Workspace::default();
        let inst = program.at(&p0, 1.0, Tier::Many, &workspace).unwrap();
        let lambda = vec![0.5; model.model().n_constraints()];
        inst.residual(&q0, &lambda);
        assert!(program.residual_program().is_some(), "{name}");
        let after = residuals();
        for (b, a) in before.iter().zip(&after) {
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(b), bits(a), "{name}");
        }
    }
}

/// The steady-state check's probe ([`Equations::probe_linearisation`]): on the recorded route
/// one forward pass along three fixed directions, on the direct route the linearisation's
/// full matrices times those directions. The same `F`, `K v`, `C w`, `M u` and `Φ_R`, on the
/// examples (a loop's constraints on the spatial four-bar, a meshed rotor's beams), and
/// directions of unit size that depend on nothing but the number of coordinates.
#[test]
fn the_probed_linearisation_is_the_linearisation_along_its_directions_on_both_routes() {
    use modaltol::equations::probe_directions;
    let [v, w, u] = probe_directions(5);
    assert_eq!(probe_directions(5), [v.clone(), w.clone(), u.clone()]);
    assert!(
        [&v, &w, &u]
            .iter()
            .all(|d| d.iter().all(|x| (0.5..=1.0).contains(&x.abs())))
    );
    assert!(v != w && w != u && v.iter().any(|x| *x < 0.0) && v.iter().any(|x| *x > 0.0));
    let mut names: Vec<&str> = EXAMPLES.to_vec();
    names.extend(["spinning_spatial_fourbar.toml", "friswell_5_9_1.toml"]);
    for name in names {
        let recorded = example(name);
        let direct = recorded.clone().with_route(Route::Direct);
        let workspace = Workspace::default();
        let p = recorded.model().nominal();
        for speed in [0.0, 1.7, 40.0] {
            let guess = initial_guess(recorded.model(), &p, speed).unwrap();
            let q: Vec<f64> = (guess.iter().enumerate())
                .map(|(i, v)| v + 1e-3 * ((i * 7) % 5) as f64)
                .collect();
            let lambda: Vec<f64> = (0..recorded.model().n_constraints())
                .map(|j| 3.0 - 1.3 * j as f64)
                .collect();
            let a = recorded.at(&p, speed, (Tier::Few, &workspace)).unwrap();
            let d = direct.at(&p, speed, (Tier::Few, &workspace)).unwrap();
            let free = recorded.model().free();
            let independent = if lambda.is_empty() {
                free.clone()
            } else {
                choose_independent(&d.constraint_jacobian(&q), &free, None).unwrap()
            };
            let pa = a.probe_linearisation(&q, &lambda, &independent).unwrap();
            let pd = d.probe_linearisation(&q, &lambda, &independent).unwrap();
            let same = |what: &str, x: &[f64], y: &[f64]| {
                let scale = y.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                assert_eq!(x.len(), y.len(), "{name} at {speed}: {what}");
                for (x, y) in x.iter().zip(y) {
                    assert!(close(*x, *y, scale), "{name} at {speed}: {what} {x} vs {y}");
                }
            };
            same("F", &pa.residual, &pd.residual);
            for (k, what) in ["K v", "C w", "M u"].into_iter().enumerate() {
                same(what, &pa.products[k], &pd.products[k]);
            }
            assert_eq!(pa.phi.shape(), (lambda.len(), free.len()));
            same("Φ_R", pa.phi.as_slice(), pd.phi.as_slice());
        }
    }
}

#[test]
fn the_program_reproduces_the_direct_route_on_every_example() {
    for name in EXAMPLES {
        let model = example(name);
        let program = model
            .program()
            .unwrap_or_else(|| panic!("{name}: the recording was refused"));
        let free = model.model().free();
        let nf = free.len();
        for (p, speed, q, lambda) in states(name) {
            let sys = System::new(model.model(), &p, speed).unwrap();
            let direct = Direct::new(sys.clone(), free.clone());
            let workspace = Workspace::default();
            let inst = program.at(&p, speed, Tier::Many, &workspace).unwrap();
            // ∂F/∂p in one pass against one dual-number residual per parameter: along all the
            // parameters, and along some of them in another order.
            let np = p.len();
            let all: Vec<usize> = (0..np).collect();
            let some: Vec<usize> = (0..np).rev().step_by(2).collect();
            let (dp, dsome) = (
                program.parameter_derivatives(&p, speed, (&q, &lambda), &all, &workspace),
                program.parameter_derivatives(&p, speed, (&q, &lambda), &some, &workspace),
            );
            for b in 0..np {
                let pd: Vec<Dual64> = p
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| Dual64::new(v, if i == b { 1.0 } else { 0.0 }))
                    .collect();
                let lift = |v: &[f64]| v.iter().map(|&x| Dual64::from_re(x)).collect::<Vec<_>>();
                let f =
                    program.residual_over(&pd, Dual64::from_re(speed), &lift(&q), &lift(&lambda));
                let fs = f.iter().fold(0.0f64, |s, v| s.max(v.eps.abs()));
                for (r, v) in f.iter().enumerate() {
                    let a = dp[r * np + b];
                    assert!(
                        close(a, v.eps, fs),
                        "{name}: ∂F_{r}/∂p_{b} {a} vs {}",
                        v.eps
                    );
                    if let Some(c) = some.iter().position(|&k| k == b) {
                        let a = dsome[r * some.len() + c];
                        assert!(close(a, v.eps, fs), "{name}: ∂F_{r}/∂p_{b} {a} (some)");
                    }
                }
            }
            let qd = sys.steady_speeds();
            let f = equilibrium_residual(&Lifted::new(sys.clone()), &free, &q, &qd, &lambda);
            let scale = f.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for (a, b) in inst.residual(&q, &lambda).iter().zip(&f) {
                assert!(close(*a, *b, scale), "{name}: residual {a} vs {b}");
            }
            let (_, j_direct) = direct.residual_and_jacobian(&q, &lambda);
            let (_, j_tape) = inst.residual_and_jacobian(&q, &lambda);
            let lin = inst.linear(&q, &lambda);
            let js = j_direct.amax();
            for (a, b) in j_tape.iter().zip(j_direct.iter()) {
                assert!(close(*a, *b, js), "{name}: Jacobian {a} vs {b}");
            }
            for (a, b) in lin.jacobian.iter().zip(j_direct.iter()) {
                assert!(close(*a, *b, js), "{name}: Jacobian (full pass) {a} vs {b}");
            }
            // The pass at other multipliers, shifted to these (F and the Jacobian are affine
            // in λ through Φ_R and the constraints' curvature).
            let other: Vec<f64> = lambda.iter().map(|l| 0.3 - 2.0 * l).collect();
            let mut shifted = inst.linear(&q, &other);
            assert_eq!(lin.drive.len(), model.model().driven().len());
            let delta: Vec<f64> = lambda.iter().zip(&other).map(|(a, b)| a - b).collect();
            shifted.shift_multipliers(&delta);
            for (a, b) in shifted.residual.iter().zip(&f) {
                assert!(close(*a, *b, scale), "{name}: shifted residual {a} vs {b}");
            }
            for (a, b) in shifted.jacobian.iter().zip(j_direct.iter()) {
                assert!(close(*a, *b, js), "{name}: shifted Jacobian {a} vs {b}");
            }
            // The drive rows (values only in the pass), shifted too, against the direct route.
            let driven = model.model().driven();
            let zero = vec![0.0; q.len()];
            let g = evaluate_rows(&Lifted::new(sys.clone()), &q, &qd, &zero, &driven)
                .with_multipliers(&lambda);
            assert_eq!(shifted.drive.len(), driven.len());
            let ds = g
                .iter()
                .fold(0.0f64, |s, v| if v.is_nan() { s } else { s.max(v.abs()) });
            for (a, &i) in shifted.drive.iter().zip(&driven) {
                assert!(close(*a, g[i], ds), "{name}: drive row {a} vs {}", g[i]);
            }
            for (k, h) in shifted.curvature.iter().enumerate() {
                let asym = (h - h.transpose()).amax();
                assert!(
                    asym <= 1e-12 * h.amax().max(1.0),
                    "{name}: ∂²Φ_{k} not symmetric"
                );
            }
            // C and M against the direct linearisation.
            let m = model.model().n_constraints();
            let phi_r = DMatrix::from_fn(m, nf, |k, j| j_direct[(j, nf + k)]);
            let independent = if m == 0 {
                free.clone()
            } else {
                choose_independent(&phi_r, &free, None).unwrap()
            };
            let at = SteadyState {
                q: &q,
                qd: &qd,
                lambda: &lambda,
            };
            let l = linearize(direct.dual(), &free, at, &independent, None).unwrap();
            for (a, b) in lin.damping.iter().zip(l.c_full.iter()) {
                assert!(close(*a, *b, l.c_full.amax()), "{name}: C {a} vs {b}");
            }
            for (a, b) in lin.mass.iter().zip(l.m_full.iter()) {
                assert!(close(*a, *b, l.m_full.amax()), "{name}: M {a} vs {b}");
            }
            for (a, b) in lin
                .jacobian
                .view((0, 0), (nf, nf))
                .iter()
                .zip(l.k_full.iter())
            {
                assert!(close(*a, *b, l.k_full.amax()), "{name}: K {a} vs {b}");
            }
        }
    }
}

#[test]
fn sweeps_agree_with_and_without_the_program() {
    for name in EXAMPLES {
        let model = example(name);
        let p = model.model().nominal();
        let run = |direct: bool| {
            let route = if direct {
                Route::Direct
            } else {
                Route::Recorded
            };
            let model = model.clone().with_route(route);
            let mut s = Sweep::new(&model, p.clone(), Options::default());
            (0..=40)
                .map(|i| s.step(0.125 * i as f64))
                .collect::<Vec<_>>()
        };
        for (a, b) in run(false).iter().zip(run(true)) {
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    for (x, y) in a.equilibrium.q.iter().zip(&b.equilibrium.q) {
                        assert!((x - y).abs() < 1e-10, "{name}: q {x} vs {y}");
                    }
                    assert_eq!(a.modes.len(), b.modes.len());
                    for (x, y) in a.modes.iter().zip(&b.modes) {
                        let d = (x.root.lambda - y.root.lambda).norm();
                        assert!(d < 1e-8 * (1.0 + y.root.lambda.norm()), "{name}: {d}");
                    }
                    for (x, y) in a
                        .equilibrium
                        .drive_force
                        .iter()
                        .zip(&b.equilibrium.drive_force)
                    {
                        assert!((x - y).abs() < 1e-8 * (1.0 + y.abs()), "{name}: drive");
                    }
                }
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (a, b) => panic!("{name}: {:?} vs {:?}", a.is_ok(), b.is_ok()),
            }
        }
    }
}

/// Every point of a fine sweep (where the chord steps run on extrapolated Jacobians and stop
/// without a last residual) is certified by the direct route: its Jacobian is the exact one
/// at the returned state, and the Newton step from there is below the step tolerance.
#[test]
fn every_swept_point_is_certified_by_an_exact_newton_step() {
    for name in EXAMPLES {
        let model = example(name);
        let p = model.model().nominal();
        let free = model.model().free();
        let nf = free.len();
        let options = Options::default();
        let tol = options.newton.step_tolerance;
        let mut sweep = Sweep::new(&model, p.clone(), options);
        let mut checked = 0;
        for i in 0..=300 {
            let speed = 0.02 * i as f64;
            let Ok(pt) = sweep.step(speed) else { continue };
            let eq = &pt.equilibrium;
            let sys = System::new(model.model(), &p, speed).unwrap();
            let direct = Direct::new(sys, free.clone());
            let (f, j) = direct.residual_and_jacobian(&eq.q, &eq.lambda);
            for (a, b) in eq.jacobian.iter().zip(j.iter()) {
                assert!(
                    close(*a, *b, j.amax()),
                    "{name} at {speed}: Jacobian {a} vs {b}"
                );
            }
            let step = j.lu().solve(&nalgebra::DVector::from_vec(f)).unwrap();
            let q_scale = 1.0 + free.iter().fold(0.0f64, |s, &i| s.max(eq.q[i].abs()));
            let l_scale = 1.0 + eq.lambda.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let dq = step.rows(0, nf).amax() / q_scale;
            let dl = step.rows(nf, step.len() - nf).amax() / (1e3 * l_scale);
            assert!(dq.max(dl) <= tol, "{name} at {speed}: step {dq:e}, {dl:e}");
            checked += 1;
        }
        assert!(checked > 250, "{name}: {checked}");
    }
}

/// The governor with a stiffness term `(100 (attach − 0.08))^1.5` that vanishes at the nominal
/// attachment: the expression takes its special case for a zero base there, so a recording
/// made at nominal would hold a constant where the direct route has a function of `attach`.
/// `set` replaces parameters' nominal values.
fn governor_with_a_kinked_spring(set: &[(String, f64)]) -> Compiled {
    let text = common::example_text("governor.toml").replace(
        "stiffness = \"spring_k\"",
        "stiffness = \"spring_k * (1 + (100*(attach - 0.08))^1.5)\"",
    );
    Compiled::from_bytes_with(text.as_bytes(), "kinked.toml", set).unwrap()
}

#[test]
fn a_recording_that_misses_a_value_dependent_case_is_refused_and_the_direct_route_serves() {
    use modaltol::sensitivity::DesignPoint;
    let model = governor_with_a_kinked_spring(&[]);
    let p = model.model().nominal();
    assert!(model.program().is_none());
    // Everything still runs, directly: the sweep and the sensitivities (off the kink, where the
    // finite differences are meaningful).
    let mut p1 = p.clone();
    let attach = model
        .model()
        .parameters
        .iter()
        .position(|x| x.name == "attach")
        .unwrap();
    p1[attach] *= 1.05;
    // Recorded off the kink (its nominal attachment moved there), the same model is traced
    // fine (so the refusal above is the check against the direct route at a perturbed point,
    // not a failure to record).
    let off = [("attach".to_string(), p1[attach])];
    assert!(governor_with_a_kinked_spring(&off).program().is_some());
    let mut sweep = Sweep::new(&model, p1.clone(), Options::default());
    let pt = (1..=16)
        .map(|i| sweep.step(0.125 * i as f64).unwrap())
        .next_back()
        .unwrap();
    let wrt = model.model().toleranced();
    let a = DesignPoint::new(&model, &p1, &pt).analytic(&wrt).unwrap();
    let f = DesignPoint::new(&model, &p1, &pt)
        .finite_difference(&wrt)
        .unwrap();
    for (x, y) in a.variables.iter().zip(&f.variables) {
        let (dx, dy) = (x.modes[0].d_damped_frequency, y.modes[0].d_damped_frequency);
        assert!((dx - dy).abs() < 1e-4 * (1.0 + dy.abs()), "{dx} vs {dy}");
    }
}

#[test]
fn a_field_that_fails_at_some_speeds_is_named_there_on_the_recorded_route() {
    // The spring rate needs Ω ≥ 0.5 rad/s; the model's speeds start below that, so the program
    // is recorded at the middle of their range (the next of the model's reference points), and
    // the sweep meets speeds where the field does not evaluate. Both routes give the same
    // results and the same errors (a soft spring also locks the links at some speeds).
    let text = common::example_text("governor.toml").replace(
        "stiffness = \"spring_k\"",
        "stiffness = \"spring_k * sqrt(speed - 0.5)\"",
    );
    let model = Compiled::from_str(&text, "sqrt_speed.toml").unwrap();
    let run = |direct: bool| {
        let route = if direct {
            Route::Direct
        } else {
            Route::Recorded
        };
        let model = model.clone().with_route(route);
        let mut s = Sweep::new(&model, model.model().nominal(), Options::default());
        [2.0, 1.5, 1.0, 0.4, 0.3, 0.75, 1.25]
            .into_iter()
            .map(|w| s.step(w).map_err(|e| e.to_string()))
            .collect::<Vec<_>>()
    };
    let (recorded, direct) = (run(false), run(true));
    assert!(model.program().is_some());
    for (a, b) in recorded.iter().zip(&direct) {
        match (a, b) {
            (Ok(a), Ok(b)) => {
                let (x, y) = (a.modes[0].root.lambda, b.modes[0].root.lambda);
                assert!((x - y).norm() < 1e-8 * (1.0 + y.norm()));
            }
            // The same reason; how many iterations a Newton solve wanders at a locked
            // mechanism before it gives up depends on rounding, which the routes do in
            // different orders.
            (Err(a), Err(b)) => assert_eq!(without_counts(a), without_counts(b)),
            (a, b) => panic!("{a:?} vs {b:?}"),
        }
    }
    for k in [3, 4] {
        let e = recorded[k].as_ref().unwrap_err();
        assert!(e.contains("sqrt_speed.toml") && e.contains("sqrt"), "{e}");
    }
}

/// An error message with its iteration counts taken out.
fn without_counts(e: &str) -> String {
    e.split(' ')
        .map(|w| if w.parse::<u64>().is_ok() { "N" } else { w })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Every method of the one equations interface gives the same numbers on both routes, over
/// dual numbers seeded in a parameter (the scalar of the sensitivities): the residual, Newton's
/// Jacobian, the rates, the fitted multipliers, the drive rows, the constraint Jacobian and the
/// steady-state probe, values and derivatives alike.
#[test]
fn both_routes_answer_every_method_of_the_equations_alike_over_dual_numbers() {
    type D = Dual64;
    let re = |v: &[D]| v.iter().map(|x| x.re).collect::<Vec<f64>>();
    let eps = |v: &[D]| v.iter().map(|x| x.eps).collect::<Vec<f64>>();
    let same = |name: &str, what: &str, a: &[f64], b: &[f64]| {
        assert_eq!(a.len(), b.len(), "{name}: {what} lengths");
        let scale = b.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!(close(*x, *y, scale), "{name}: {what} {x} vs {y}");
        }
    };
    // The multipliers fitted as Newton fits them, here on the values only (the fit itself is
    // the caller's; what is compared is what the routes hand it and do with its answer).
    let fit = |a: DMatrix<D>, b: nalgebra::DVector<D>| -> Vec<D> {
        let l = modaltol::linalg::least_squares(a.map(|v| v.re), b.map(|v| v.re));
        l.into_iter().map(D::from_re).collect()
    };
    for name in EXAMPLES {
        let recorded = example(name);
        let direct = recorded.clone().with_route(Route::Direct);
        let workspace = Workspace::default();
        for (p, speed, q, lambda) in states(name) {
            let b = p.len() / 2;
            let pd: Vec<D> = (p.iter().enumerate())
                .map(|(i, &v)| D::new(v, if i == b { 1.0 } else { 0.0 }))
                .collect();
            let lift = |v: &[f64]| v.iter().map(|&x| D::from_re(x)).collect::<Vec<_>>();
            let (ql, ll) = (lift(&q), lift(&lambda));
            let a = (recorded.at(&pd, D::from_re(speed), (Tier::Few, &workspace))).unwrap();
            let d = (direct.at(&pd, D::from_re(speed), (Tier::Few, &workspace))).unwrap();
            assert_eq!(a.free(), d.free());
            assert_eq!(a.constraints(), d.constraints());
            let (fa, fd) = (a.residual(&ql, &ll), d.residual(&ql, &ll));
            same(name, "residual", &re(&fa), &re(&fd));
            same(name, "∂residual/∂p", &eps(&fa), &eps(&fd));
            let (ea, ed) = (a.evaluate(&ql, &ll, true), d.evaluate(&ql, &ll, true));
            same(name, "evaluated residual", &re(&ea.residual), &re(&fd));
            let (ja, jd) = (ea.jacobian.as_slice(), ed.jacobian.as_slice());
            same(name, "Jacobian", &re(ja), &re(jd));
            same(name, "∂Jacobian/∂p", &eps(ja), &eps(jd));
            // The recorded route has the rates and the drive rows from the same pass.
            let rates = ea.rates.expect("the recorded route gives the rates");
            let lin = d
                .linearize(&ql, &ll, &recorded.model().free(), None)
                .expect("linearisable");
            same(
                name,
                "mass",
                &re(rates.mass.as_slice()),
                &re(lin.m.as_slice()),
            );
            let driven = recorded.model().driven();
            let rows = d.drive_rows(&ql, &ll, &driven);
            same(name, "drive rows", &re(&ea.drive.unwrap()), &re(&rows));
            same(
                name,
                "drive rows (own)",
                &re(&a.drive_rows(&ql, &ll, &driven)),
                &re(&rows),
            );
            let (la, fa) = a.evaluate_fitted(&ql, false, &fit);
            let (ld, fd) = d.evaluate_fitted(&ql, false, &fit);
            same(name, "fitted multipliers", &re(&la), &re(&ld));
            same(
                name,
                "fitted residual",
                &re(&fa.residual),
                &re(&fd.residual),
            );
            let (ca, cd) = (a.constraint_jacobian(&ql), d.constraint_jacobian(&ql));
            same(name, "Φ_R", &re(ca.as_slice()), &re(cd.as_slice()));
            same(name, "∂Φ_R/∂p", &eps(ca.as_slice()), &eps(cd.as_slice()));
            let offsets = [0.5, 1.5, -2.0];
            for (k, &c) in driven.iter().enumerate() {
                let alone = [(k, c, 1.0)];
                let (oa, od) = (
                    a.residual_at_drive_offsets(&ql, &ll, &alone, offsets),
                    d.residual_at_drive_offsets(&ql, &ll, &alone, offsets),
                );
                same(name, "steady-state probe", &oa, &od);
            }
            // All of them turning together, at unequal rates.
            let together: Vec<(usize, usize, f64)> = (driven.iter().enumerate())
                .map(|(k, &c)| (k, c, 1.0 / (k + 1) as f64))
                .collect();
            let (oa, od) = (
                a.residual_at_drive_offsets(&ql, &ll, &together, offsets),
                d.residual_at_drive_offsets(&ql, &ll, &together, offsets),
            );
            same(name, "steady-state probe, drives together", &oa, &od);
        }
    }
}
