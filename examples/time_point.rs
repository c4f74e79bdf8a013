//! Timing for A/B comparisons on a noisy machine: the best of 15 rounds (not criterion's
//! mean) for the exact evaluation with drive rows, the residual, a cold modal point of a model
//! at 1.595 rad/s and all its sensitivities there, in µs (the last two in the same rounds'
//! conditions, so their ratio is not skewed by the machine's phases), then the gradients and
//! Hessians of every output along the toleranced parameters (best of 15 rounds of 100).
//! The same with the program's passes compiled to native code (`Tier::Native`).
//! `cargo run --release --example time_point -- [examples/governor.toml]`.
use modaltol::compiled::Compiled;
use modaltol::equilibrium::Start;
use modaltol::output::outputs;
use modaltol::program::{Tier, Workspace};
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::{Options, Solver, initial_guess, point};
use std::hint::black_box;
use std::time::Instant;

/// Best time per call of `f` over 15 rounds of `n` calls (s).
fn best(n: usize, mut f: impl FnMut()) -> f64 {
    (0..15)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..n {
                f();
            }
            t.elapsed().as_secs_f64() / n as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let file = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "examples/governor.toml".into());
    let model = Compiled::from_file(std::path::Path::new(&file)).unwrap();
    let p = model.model().nominal();
    let speed = 1.595;
    let q0 = initial_guess(model.model(), &p, speed).unwrap();
    let pt = point(&model, &p, speed, &q0, &Options::default()).unwrap();
    let (q, l) = (pt.equilibrium.q.clone(), pt.equilibrium.lambda.clone());
    let program = model.program().unwrap();
    // Exact evaluation, residual and a cold modal point (s), at a sweep's tier or compiled, in
    // one working memory as a sweep or an analysis keeps it.
    let workspace = Workspace::default();
    let passes = |tier: Tier| {
        let inst = program.at(&p, speed, tier, &workspace).unwrap();
        let options = Options {
            tier,
            ..Options::default()
        };
        [
            best(20000, || {
                black_box(inst.linear(black_box(&q), &l));
            }),
            best(20000, || {
                black_box(inst.residual(black_box(&q), &l));
            }),
            best(5000, || {
                let start = Start::default();
                let solver = Solver {
                    model: &model,
                    p: &p,
                    opt: &options,
                    workspace: &workspace,
                };
                let pt = solver.point_from(speed, black_box(&q), start);
                black_box(pt.unwrap());
            }),
        ]
    };
    let [linear, residual, cold] = passes(Tier::Many);
    let tf = model
        .model()
        .analysis
        .transfer
        .map(|t| TransferAt::at_speed(&t, speed));
    let wrt = model.model().toleranced();
    let at = DesignPoint::new(&model, &p, &pt)
        .with_transfer(tf)
        .with_workspace(&workspace);
    let sens = best(2000, || {
        black_box(at.analytic(&wrt).unwrap());
    });
    println!(
        "exact evaluation {:.2} µs, residual {:.2} µs, modal point {:.2} µs, sensitivities \
         ({} variables) {:.2} µs = {:.2} points",
        linear * 1e6,
        residual * 1e6,
        cold * 1e6,
        wrt.len(),
        sens * 1e6,
        sens / cold
    );
    // Gradients and Hessians of every output (the second-order method's passes).
    let outs = outputs(pt.modes.len(), tf.is_some());
    let second = best(100, || {
        black_box(at.hessians(&wrt, &outs).unwrap());
    });
    println!(
        "gradients and Hessians ({} variables) {:.2} µs",
        wrt.len(),
        second * 1e6
    );
    // `point` on its own: the working memory made afresh at each call (what one `modal` does).
    let fresh = best(5000, || {
        black_box(point(&model, &p, speed, black_box(&q), &Options::default()).unwrap());
    });
    println!(
        "modal point with fresh working memory {:.2} µs",
        fresh * 1e6
    );
    let t = Instant::now();
    (program.at(&p, speed, Tier::Native, &Workspace::default()))
        .unwrap()
        .linear(&q, &l);
    let compile = t.elapsed().as_secs_f64();
    let [native_linear, native_residual, native_cold] = passes(Tier::Native);
    println!(
        "native code (compiled in {:.1} ms): exact evaluation {:.2} µs, residual {:.2} µs, \
         modal point {:.2} µs",
        compile * 1e3,
        native_linear * 1e6,
        native_residual * 1e6,
        native_cold * 1e6
    );
}
