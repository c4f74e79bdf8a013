//! Profiling driver for the issue-4 figures on one thread: the governor's analytic propagation
//! over 501 speeds × the three spring cases (ten times), or with `mc` Monte Carlo with 100
//! samples × 501 speeds for one case. Prints the wall time; run under `perf record`.
//! `cargo run --release --example profile_analyze -- [mc]`.
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::Sampling;
use modaltol::montecarlo::McOptions;

fn main() {
    let mc = std::env::args().nth(1).is_some_and(|s| s == "mc");
    let model = Compiled::from_file(std::path::Path::new("examples/governor.toml")).unwrap();
    let springs: Vec<_> = model
        .model()
        .analysis
        .cases
        .iter()
        .filter(|c| c.name.starts_with('k'))
        .cloned()
        .collect();
    let opts = AnalyzeOptions {
        speeds: (0..501).map(|i| i as f64 * 0.01).collect(),
        cases: if mc { springs[..1].to_vec() } else { springs },
        monte_carlo: mc.then_some(McOptions {
            samples: 100,
            seed: 1,
            sampling: Sampling::Random,
        }),
        threads: Some(1),
        ..Default::default()
    };
    let runs = if mc { 1 } else { 10 };
    let t = std::time::Instant::now();
    for _ in 0..runs {
        let _ = analyze(&model, &opts, &|_, _, _| {});
    }
    println!("{:?} per run", t.elapsed() / runs);
}
