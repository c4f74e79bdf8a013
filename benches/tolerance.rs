//! Figures on the governor: the Taylor methods over 501 speeds × the three spring cases, the
//! quadrature of the same cases and of the three-variable case, and Monte Carlo with 100
//! samples × 501 speeds for one case (extrapolate ×30 for the paper's 3000 samples). Run with
//! `cargo bench --bench tolerance`. The CLI's timers give the quadrature against the 3000-sample
//! Monte Carlo in one run (`summary.json`, `ratio_monte_carlo_to_quadrature`).

use criterion::{Criterion, criterion_group, criterion_main};
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::Sampling;
use modaltol::montecarlo::McOptions;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let model = Compiled::from_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/governor.toml"),
    )
    .unwrap();
    let speeds: Vec<f64> = (0..501).map(|i| i as f64 * 0.01).collect();
    let springs: Vec<_> = model
        .model()
        .analysis
        .cases
        .iter()
        .filter(|c| c.name.starts_with('k'))
        .cloned()
        .collect();
    let mut g = c.benchmark_group("governor");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    let analytic = AnalyzeOptions {
        speeds: speeds.clone(),
        cases: springs.clone(),
        quadrature: None,
        monte_carlo: None,
        ..Default::default()
    };
    g.bench_function("analytic_501_speeds_3_cases", |b| {
        b.iter(|| analyze(&model, &analytic, &|_, _, _| {}))
    });
    for (name, cases) in [
        ("quadrature_501_speeds_3_spring_cases", springs.clone()),
        (
            "quadrature_501_speeds_all3",
            model
                .model()
                .analysis
                .cases
                .iter()
                .filter(|c| c.name == "all3")
                .cloned()
                .collect(),
        ),
    ] {
        let quad = AnalyzeOptions {
            speeds: speeds.clone(),
            cases,
            monte_carlo: None,
            ..Default::default()
        };
        g.bench_function(name, |b| b.iter(|| analyze(&model, &quad, &|_, _, _| {})));
    }
    let mc = AnalyzeOptions {
        speeds,
        cases: springs[..1].to_vec(),
        quadrature: None,
        monte_carlo: Some(McOptions {
            samples: 100,
            seed: 1,
            sampling: Sampling::Random,
        }),
        ..Default::default()
    };
    g.bench_function(
        "analytic_and_monte_carlo_100_samples_501_speeds_1_case",
        |b| b.iter(|| analyze(&model, &mc, &|_, _, _| {})),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
