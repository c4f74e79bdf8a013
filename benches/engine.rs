//! One modal point (equilibrium + linearisation + modes), the recorded program's passes there
//! and a 501-point sweep of each example, interpreted and with the program compiled to native
//! code (`Tier::Native`; the same results, a long run's speed).
//! Run with `cargo bench --bench engine`.

use criterion::{Criterion, criterion_group, criterion_main};
use modaltol::compiled::Compiled;
use modaltol::program::{Tier, Workspace};
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use std::hint::black_box;

fn example(name: &str) -> Compiled {
    Compiled::from_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples")
            .join(name),
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    for (file, speed, to) in [
        ("rotating_pendulum.toml", 5.0, 6.0),
        ("governor.toml", 1.595, 5.0),
        ("spinning_universal_pendulum.toml", 3.0, 6.0),
        ("multi_arm_governor.toml", 1.595, 5.0),
    ] {
        let model = example(file);
        let p = model.model().nominal();
        let name = file.trim_end_matches(".toml");
        // A point started from the previous speed's solution, as in a sweep.
        let q0 = point(
            &model,
            &p,
            speed,
            &initial_guess(model.model(), &p, speed).unwrap(),
            &Options::default(),
        )
        .unwrap()
        .equilibrium
        .q;
        for tier in [Tier::Many, Tier::Native] {
            let name = if tier == Tier::Native {
                format!("{name}/native")
            } else {
                name.to_string()
            };
            passes(c, &model, &name, speed, to, &q0, tier);
        }
    }
}

/// The passes, a point and a sweep of one model at `tier`, under `name`.
fn passes(
    c: &mut Criterion,
    model: &Compiled,
    name: &str,
    speed: f64,
    to: f64,
    q0: &[f64],
    tier: Tier,
) {
    let p = model.model().nominal();
    let options = Options {
        tier,
        ..Options::default()
    };
    // The recorded program's passes at that point: the residual, Newton's Jacobian, and
    // the exact evaluation (Jacobian, C and M in one pass).
    let workspace = Workspace::default();
    if let Some(inst) = model
        .program()
        .and_then(|program| program.at(&p, speed, tier, &workspace))
    {
        let lambda = point(model, &p, speed, q0, &Options::default())
            .unwrap()
            .equilibrium
            .lambda;
        c.bench_function(&format!("{name}/pass/residual"), |b| {
            b.iter(|| inst.residual(black_box(q0), &lambda))
        });
        c.bench_function(&format!("{name}/pass/jacobian"), |b| {
            b.iter(|| inst.residual_and_jacobian(black_box(q0), &lambda))
        });
        c.bench_function(&format!("{name}/pass/linear"), |b| {
            b.iter(|| inst.linear(black_box(q0), &lambda))
        });
    }
    c.bench_function(&format!("{name}/modal_point"), |b| {
        b.iter(|| point(model, &p, black_box(speed), q0, &options).unwrap())
    });
    let mut g = c.benchmark_group(format!("{name}/sweep_501"));
    g.sample_size(10);
    g.bench_function("sweep", |b| {
        b.iter(|| {
            let mut s = Sweep::new(model, p.clone(), options.clone());
            for i in 0..501 {
                let _ = black_box(s.step(to * i as f64 / 500.0));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
