//! The programs' `f64` passes compiled to native code (`tape::NativePass`) against the
//! interpreter they replace: the same numbers to the bit, everywhere a run can switch.

mod common;

use common::{EXAMPLES, example};
use modaltol::program::{Linear, Tier, Workspace};
use modaltol::sweep::{Options, Sweep, initial_guess};
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
        let program = model.program().unwrap();
        let (w1, w2) = (Workspace::default(), Workspace::default());
        let inst = program.at(&p, speed, Tier::Many, &w1).unwrap();
        let native = program.at(&p, speed, Tier::Native, &w2).unwrap();
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
        let interpreted: Vec<(Vec<f64>, Vec<f64>)> = states
            .iter()
            .map(|(q, l)| (numbers(&inst.linear(q, l)), inst.residual(q, l)))
            .collect();
        assert!(
            !program.is_native(),
            "{name}: compiled only when a caller asks"
        );
        for ((q, l), (linear, residual)) in states.iter().zip(&interpreted) {
            assert!(
                same(&numbers(&native.linear(q, l)), linear),
                "{name}: exact evaluation at {q:?}"
            );
            assert!(
                same(&native.residual(q, l), residual),
                "{name}: residual at {q:?}"
            );
        }
        assert!(program.is_native(), "{name}: its program is compiled");
        // The interpreted instance stays interpreted, with the same numbers.
        let (q, l) = &states[0];
        assert!(same(&inst.residual(q, l), &interpreted[0].1), "{name}");
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
fn a_sweep_gives_the_same_points_at_every_tier() {
    for name in [
        "governor.toml",
        "multi_arm_governor.toml",
        "spinning_universal_pendulum.toml",
    ] {
        let run = |tier: Tier| {
            let model = example(name);
            let p = model.model().nominal();
            let options = Options {
                tier,
                ..Options::default()
            };
            let mut sweep = Sweep::new(&model, p.clone(), options);
            let points: Vec<String> = (0..=120)
                .map(|i| format!("{:?}", sweep.step(0.025 * i as f64)))
                .collect();
            let program = model.program().unwrap();
            (
                points,
                program.is_native(),
                program.residual_program().is_some(),
            )
        };
        let (few, native_few, _) = run(Tier::Few);
        let (many, native_many, specialised_many) = run(Tier::Many);
        let (native, native_native, _) = run(Tier::Native);
        assert!(!native_few && !native_many && native_native, "{name}");
        assert!(specialised_many, "{name}");
        for ((a, b), c) in few.iter().zip(&many).zip(&native) {
            assert_eq!(a, b, "{name}");
            assert_eq!(a, c, "{name}");
        }
    }
}
