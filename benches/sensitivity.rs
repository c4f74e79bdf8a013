//! Sensitivities of all modes and of |H| with respect to all toleranced design variables at one
//! speed, against one modal point. Run with `cargo bench --bench sensitivity`.

use criterion::{Criterion, criterion_group, criterion_main};
use modaltol::compiled::Compiled;
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::{Options, initial_guess, point};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    for (file, speed) in [
        ("rotating_pendulum.toml", 5.0),
        ("governor.toml", 1.595),
        ("spinning_universal_pendulum.toml", 3.0),
    ] {
        let model = Compiled::from_file(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("examples")
                .join(file),
        )
        .unwrap();
        let p = model.model().nominal();
        let wrt = model.model().toleranced();
        let tf = Some(TransferAt::at_speed(
            &model.model().analysis.transfer.unwrap(),
            speed,
        ));
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        let pt = point(&model, &p, speed, &q0, &Options::default()).unwrap();
        let q = pt.equilibrium.q.clone();
        // The point interpreted (a sweep's tier, `Options::default()`), as the ratio the goal
        // is about has it.
        let name = file.trim_end_matches(".toml");
        c.bench_function(&format!("{name}/modal_point"), |b| {
            b.iter(|| point(&model, &p, black_box(speed), &q, &Options::default()).unwrap())
        });
        c.bench_function(&format!("{name}/sensitivities_all_variables"), |b| {
            b.iter(|| {
                DesignPoint::new(&model, &p, &pt)
                    .with_transfer(tf)
                    .analytic(black_box(&wrt))
                    .unwrap()
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
