//! The programs' `f64` passes compiled to native code (`tape::NativePass`) against the
//! interpreter they replace: the same numbers to the bit, everywhere a run can switch.

mod common;

use common::{EXAMPLES, example};
use modaltol::program::Linear;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The same bits, or both NaN (a NaN's payload may differ).
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}

fn numbers(l: &Linear) -> Vec<f64> {
    let mut v = l.residual.clone();
    for m in [&l.jacobian, &l.damping, &l.mass]
        .into_iter()
        .chain(&l.curvature)
    {
        v.extend(m.iter());
    }
    v.extend(&l.drive);
    v
}

#[test]
fn native_passes_give_the_interpreters_bits_at_any_state() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for name in EXAMPLES {
        let model = example(name);
        let p = model.model().nominal();
        let speed = 1.3;
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        let program = model.program(&p, speed, &q0).unwrap();
        let inst = program.at(&p, speed).unwrap();
        let m = inst.constraints();
        // States near and far from equilibrium, some where the mechanics overflows.
        let states: Vec<(Vec<f64>, Vec<f64>)> = (0..40)
            .map(|k| {
                let scale = [1e-3, 1.0, 1e3, 1e200][k % 4];
                let q = q0
                    .iter()
                    .map(|v| v + scale * rng.random_range(-1.0..1.0))
                    .collect();
                let l = (0..m)
                    .map(|_| scale * rng.random_range(-1.0..1.0))
                    .collect();
                (q, l)
            })
            .collect();
        program.native_after(None);
        let interpreted: Vec<(Vec<f64>, Vec<f64>)> = states
            .iter()
            .map(|(q, l)| (numbers(&inst.linear(q, l)), inst.residual(q, l)))
            .collect();
        assert!(!program.is_native());
        program.native_after(Some(0));
        for ((q, l), (linear, residual)) in states.iter().zip(&interpreted) {
            assert!(
                same(&numbers(&inst.linear(q, l)), linear),
                "{name}: exact evaluation at {q:?}"
            );
            assert!(
                same(&inst.residual(q, l), residual),
                "{name}: residual at {q:?}"
            );
        }
        assert!(program.is_native(), "{name}: its program is compiled");
        program.native_after(None);
        assert!(!program.is_native(), "{name}: compiled code turned off");
        // Some states are finite, some not: both kinds were compared.
        assert!(
            interpreted
                .iter()
                .any(|(l, _)| l.iter().all(|v| v.is_finite())),
            "{name}"
        );
    }
}

#[test]
fn a_sweep_that_switches_to_native_code_is_the_interpreted_sweep() {
    for name in [
        "governor.toml",
        "multi_arm_governor.toml",
        "spinning_universal_pendulum.toml",
    ] {
        let run = |after: Option<usize>| {
            let model = example(name);
            let p = model.model().nominal();
            let q0 = initial_guess(model.model(), &p, 0.5).unwrap();
            point(&model, &p, 0.5, &q0, &Options::default()).unwrap();
            let program = model.program(&p, 0.5, &q0).unwrap();
            program.native_after(after);
            let mut sweep = Sweep::new(&model, p.clone(), Options::default());
            let points: Vec<String> = (0..=120)
                .map(|i| format!("{:?}", sweep.step(0.025 * i as f64)))
                .collect();
            (points, program.is_native())
        };
        let (interpreted, native_before) = run(None);
        // Switches in the middle of the sweep.
        let (switched, native_after) = run(Some(150));
        assert!(!native_before && native_after, "{name}");
        for (a, b) in interpreted.iter().zip(&switched) {
            assert_eq!(a, b, "{name}");
        }
    }
}
