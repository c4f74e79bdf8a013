//! Cost of size: a generated family of chains of n rigid segments with joint springs on a hub
//! spinning about z (the rotating blade of `examples/rotating_blade.toml`, any n), measured per
//! n in a fresh process each: one cold modal point (recording included), one swept point (the
//! mean over a 20-speed sweep after its first point), the sensitivities to the two parameters at
//! one point, and the process's peak resident memory (`VmHWM`, Linux) after the cold points
//! and at the end. Then the growth exponents fitted by least squares on the log–log points.
//! Times are the best of 3 runs.
//!
//! `cargo run --release --example scale_chain -- [n …]` (default: 10 20 40 80 160; 320 runs in
//! about two minutes); `… -- damped n`: one cold modal point of the chain with joint dampers,
//! most of its modes overdamped; `… -- record n` (or a model file instead of n): the cold point
//! split into recording the program and the point after it (from the initial guess), and the
//! same point on the direct route, best of 20 (of 300 for models under 20 kB) in this process;
//! `… -- hessians n`: the gradients and Hessians along the chain's parameters at one point;
//! `… -- tolerances n [--monte-carlo] [--no-quadrature] k …` (issue 38's family): the analysis
//! of the n-segment chain (default 40) whose first k segments carry their own toleranced `mu`
//! and `EI` (2k independent variables), 13 speeds over 0–60 rad/s, two threads: the time of
//! the first-order stage (the nominal sweep and the gradients), of the second-order stage (the
//! Hessians), of all the Taylor methods, of the quadrature (and its nodes) and of a
//! 3000-sample Monte Carlo, the rows each method filled, the peak memory so far, and the
//! growth exponents of the times in the number of variables; `… -- local n k`: the gradients
//! alone, and with the Hessians, at one point of that chain (`--fastest-only`: without the
//! pass-per-pair route beside it); `… -- governor [--monte-carlo] [--no-quadrature]
//! [--without-transfer]`: the same for the 12-arm governor with 13 and with 37 toleranced
//! variables (without its transfer function: ω_d and ζ only); `… -- accuracy n k samples
//! [--reference FILE] [--family F] [--seed S] [--detail]`: the quadrature's, second order's and first order's mean and σ against a Monte
//! Carlo of that many samples (inside its 99 % intervals; `--detail`: each row outside), or
//! against the Monte Carlo rows of a `tolerance.csv` written once by `modaltol analyze`
//! (`… -- model n k` prints the model file). Judge the share of rows inside on two seeds or
//! more: every row reads the same samples, so one sample set moves many rows together.
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::{Compiled, Route};
use modaltol::hessian::MixedRoute;
use modaltol::modal::ModeClass;
use modaltol::model::Sampling;
use modaltol::montecarlo::McOptions;
use modaltol::output::Quantity;
use modaltol::output::outputs;
use modaltol::program::{Tier, Workspace};
use modaltol::quadrature::QuadOptions;
use modaltol::sensitivity::DesignPoint;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use modaltol::table::Method;
use modaltol::table::Row;
use modaltol::table::{Detail, McStat};
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{exponent, peak_mb};

#[path = "common/chain.rs"]
mod common_chain;
use common_chain::{Coupling, chain, chain_family, chain_toleranced, with_joint_dampers};

/// The family `--family neighbours|global|moving` names (issue 55's), if any.
fn coupling(args: &[String]) -> Option<Coupling> {
    let at = args.iter().position(|a| a == "--family")?;
    Some(match args.get(at + 1).map(String::as_str) {
        Some("neighbours") => Coupling::Neighbours,
        Some("global") => Coupling::Global,
        Some("moving") => Coupling::Moving,
        other => panic!("--family neighbours|global|moving, not {other:?}"),
    })
}

/// The numbers among `args` (the flags and `--family`'s value left out).
fn numbers(args: &[String]) -> Vec<usize> {
    args.iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && (*i == 0 || args[i - 1] != "--family"))
        .map(|(_, a)| a.parse().unwrap())
        .collect()
}

/// The `n`-segment chain with `k` toleranced segments: issue 38's family (each parameter in
/// one element) or the `--family` asked for.
fn toleranced(n: usize, k: usize, args: &[String]) -> String {
    match coupling(args) {
        Some(c) => chain_family(n, k, c),
        None => chain_toleranced(n, k),
    }
}

/// Measures one n in this process: `cold swept sensitivities` (s) and the peak memory after
/// the cold points and at the end (MB).
fn measure(n: usize) -> [f64; 5] {
    let text = chain(n);
    let best = |f: &mut dyn FnMut() -> f64| (0..3).map(|_| f()).fold(f64::INFINITY, f64::min);
    let speed = 5.0;
    let cold = best(&mut || {
        // A fresh model each time: the recording is part of a cold point.
        let model = Compiled::from_str(&text, "chain.toml").unwrap();
        let p = model.model().nominal();
        let t = Instant::now();
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        // As `modal` solves it.
        point(&model, &p, speed, &q0, &Options::single()).unwrap();
        t.elapsed().as_secs_f64()
    });
    let cold_peak = peak_mb();
    let model = Compiled::from_str(&text, "chain.toml").unwrap();
    let p = model.model().nominal();
    let swept = best(&mut || {
        let mut sweep = Sweep::new(&model, p.clone(), Options::default());
        sweep.step(0.0).unwrap();
        let t = Instant::now();
        for k in 1..20 {
            sweep.step(0.5 * k as f64).unwrap();
        }
        t.elapsed().as_secs_f64() / 19.0
    });
    let q0 = initial_guess(model.model(), &p, speed).unwrap();
    let pt = point(&model, &p, speed, &q0, &Options::default()).unwrap();
    let wrt = model.model().toleranced();
    let sens = best(&mut || {
        let t = Instant::now();
        DesignPoint::new(&model, &p, &pt).analytic(&wrt).unwrap();
        t.elapsed().as_secs_f64()
    });
    [cold, swept, sens, cold_peak, peak_mb()]
}

/// `tolerances n [--monte-carlo] [--no-quadrature] k …` (see the module documentation).
fn tolerances(args: &[String]) {
    let nums = numbers(args);
    let n = nums.first().copied().unwrap_or(40);
    let ks = if nums.len() > 1 {
        nums[1..].to_vec()
    } else {
        vec![5, 10, 20]
    };
    let models = ks.iter().map(|&k| toleranced(n, k, args)).collect();
    let speeds = (0..13).map(|i| 5.0 * i as f64).collect();
    family(&format!("{n}-segment chain"), models, speeds, args);
}

/// `governor [--monte-carlo] [--no-quadrature] [--without-transfer]`: the 12-arm governor with
/// 13 toleranced variables (`examples/multi_arm_governor_13_variables.toml`: the spring and
/// each arm's link attachment) and with 37 (each arm's ball mass and link length too), 13
/// speeds over 0.5–3.5 rad/s; with its transfer function (|H| rows) unless
/// `--without-transfer`.
fn governor(args: &[String]) {
    let mut thirteen = include_str!("multi_arm_governor_13_variables.toml").to_string();
    if args.iter().any(|a| a == "--without-transfer") {
        let line = "transfer = { input = \"slide\", output = \"slide\", order = 1 }\n";
        assert!(thirteen.contains(line));
        thirteen = thirteen.replace(line, "");
    }
    let mut more = thirteen.clone();
    let mut own = String::new();
    let mut tolerances = String::new();
    for arm in 1..=12 {
        more = more
            .replacen(
                "mass = \"2*ball_mass/arms\"",
                &format!("mass = \"2*ball_mass_{arm}/arms\""),
                1,
            )
            .replacen(
                "length = \"link_length\"",
                &format!("length = \"link_length_{arm}\""),
                1,
            );
        own += &format!(
            "ball_mass_{arm} = {{ value = 1.0, tolerance = \"3%\" }}\n\
             link_length_{arm} = {{ value = 0.10922, tolerance = \"0.5%\" }}\n"
        );
        tolerances += &format!(", ball_mass_{arm} = \"3%\", link_length_{arm} = \"0.5%\"");
    }
    assert!(!more.contains("\"2*ball_mass/arms\"") && !more.contains("\"link_length\""));
    let more = more
        .replacen("arms = 12.0", &format!("{own}arms = 12.0"), 1)
        .replacen(
            "attach12 = \"3%\" }",
            &format!("attach12 = \"3%\"{tolerances} }}"),
            1,
        );
    let speeds = (0..13).map(|i| 0.5 + 0.25 * i as f64).collect();
    family("12-arm governor", vec![thirteen, more], speeds, args);
}

/// The analysis of each of `models` (one tolerance case each, more variables from one to the
/// next) over `speeds` on two threads: per method the time, the quadrature's nodes and the
/// rows filled, and the growth exponents of the times in the number of variables.
fn family(what: &str, models: Vec<String>, speeds: Vec<f64>, args: &[String]) {
    let monte_carlo = args.iter().any(|a| a == "--monte-carlo");
    let quadrature = !args.iter().any(|a| a == "--no-quadrature");
    println!(
        "{what}, {} speeds: variables | first order s | second order s | Taylor s \
         | quadrature s (nodes) | Monte Carlo s | rows filled: first order, second order, \
         quadrature | peak MB",
        speeds.len()
    );
    let mut rows = Vec::new();
    for text in models {
        let model = Compiled::from_str(&text, "model.toml").unwrap();
        let cases = model.model().tolerance_cases(&[]).unwrap();
        let options = AnalyzeOptions {
            speeds: speeds.clone(),
            cases,
            quadrature: quadrature.then(QuadOptions::default),
            monte_carlo: monte_carlo.then_some(McOptions {
                samples: 3000,
                seed: 1,
                sampling: Sampling::Random,
            }),
            threads: Some(2),
            ..AnalyzeOptions::default()
        };
        let a = analyze(&model, &options, &|_: &str, _: usize, _: usize| {});
        let filled = |m: Method| {
            let of: Vec<&Row> = a.rows.iter().filter(|r| r.method() == m).collect();
            let done = of.iter().filter(|r| r.std.is_finite()).count();
            format!("{done}/{}", of.len())
        };
        let nodes: usize = a.quadrature_rules.iter().map(|r| r.1).sum();
        let (taylor, quad) = (a.analytic_seconds, a.quadrature_seconds.unwrap_or(f64::NAN));
        let mc = a.monte_carlo_seconds.unwrap_or(f64::NAN);
        let (first, second) = (a.first_order_seconds, a.second_order_seconds);
        println!(
            "{:9} | {first:8.3} | {second:8.3} | {taylor:8.3} | {quad:8.3} ({nodes}) | {mc:8.3} \
             | {}, {}, {} | {:.0}",
            a.vars.len(),
            filled(Method::FirstOrder),
            filled(Method::SecondOrder),
            filled(Method::Quadrature),
            peak_mb()
        );
        rows.push([a.vars.len() as f64, first, second, taylor, quad]);
    }
    if rows.len() >= 2 {
        let x: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let fit = |j: usize| exponent(&x, &rows.iter().map(|r| r[j]).collect::<Vec<_>>());
        println!(
            "growth in the variables p: first order p^{:.2}, second order p^{:.2}, Taylor \
             p^{:.2}, quadrature p^{:.2}",
            fit(1),
            fit(2),
            fit(3),
            fit(4)
        );
    }
}

/// `accuracy n k samples`: the n-segment chain with 2k toleranced variables, 13 speeds, by the
/// quadrature, second order, first order and a Monte Carlo of `samples` random samples (seed
/// `--seed`, default 1): per method, the share of rows whose mean and σ lie inside the Monte Carlo's 99 %
/// intervals (its 95 % ones widened by 2.576/1.960) and the largest relative deviation of σ;
/// for the quadrature also the share of rows whose error estimate covers its distance from the
/// Monte Carlo beyond that interval.
fn accuracy(args: &[String]) {
    let n: usize = args[0].parse().unwrap();
    let k: usize = args[1].parse().unwrap();
    let samples: usize = args[2].parse().unwrap();
    let reference = args
        .iter()
        .position(|a| a == "--reference")
        .map(|i| reference_rows(&args[i + 1]));
    let model = Compiled::from_str(&toleranced(n, k, args), "chain.toml").unwrap();
    let options = AnalyzeOptions {
        speeds: (0..13).map(|i| 5.0 * i as f64).collect(),
        cases: model.model().tolerance_cases(&[]).unwrap(),
        monte_carlo: reference.is_none().then_some(McOptions {
            samples,
            seed: args
                .iter()
                .position(|a| a == "--seed")
                .map_or(1, |i| args[i + 1].parse().unwrap()),
            sampling: Sampling::Random,
        }),
        threads: Some(2),
        ..AnalyzeOptions::default()
    };
    let detail = args.iter().any(|a| a == "--detail");
    let mut a = analyze(&model, &options, &|_: &str, _: usize, _: usize| {});
    if let Some(rows) = reference {
        a.rows.extend(rows);
    }
    let widen = 2.5758 / 1.95996;
    println!(
        "{n}-segment chain, {} variables, Monte Carlo {samples} samples ({:.0} s), quadrature \
         {:.1} s: method | rows | mean inside 99 % | σ inside 99 % | largest |σ/σ_MC − 1| \
         | error estimate covers",
        a.vars.len(),
        a.monte_carlo_seconds.unwrap_or(f64::NAN),
        a.quadrature_seconds.unwrap_or(f64::NAN)
    );
    for method in [Method::Quadrature, Method::SecondOrder, Method::FirstOrder] {
        let (mut rows, mut mean_in, mut std_in, mut covered, mut worst) = (0, 0, 0, 0, 0.0f64);
        for r in a
            .rows
            .iter()
            .filter(|r| r.method() == method && r.std.is_finite())
        {
            let Some(mc) = a
                .rows
                .iter()
                .find(|m| {
                    m.method() == Method::MonteCarlo
                        && m.speed.to_bits() == r.speed.to_bits()
                        && m.quantity == r.quantity
                        && m.mode == r.mode
                })
                .and_then(|m| m.mc())
            else {
                continue;
            };
            if mc.std.is_nan() || mc.std <= 0.0 {
                continue;
            }
            rows += 1;
            let half = |(lo, hi): (f64, f64)| 0.5 * (hi - lo) * widen;
            let (dm, ds) = ((r.mean - mc.mean).abs(), (r.std - mc.std).abs());
            let (hm, hs) = (half(mc.mean_ci), half(mc.std_ci));
            mean_in += usize::from(dm <= hm);
            std_in += usize::from(ds <= hs);
            if detail && ds > hs {
                println!(
                    "  {} speed {} mode {:?} {:?}: σ {:.6e} against {:.6e} ({:.6e}..{:.6e}), \
                     error estimate {:.1e}",
                    method.as_str(),
                    r.speed,
                    r.mode,
                    r.quantity,
                    r.std,
                    mc.std,
                    mc.std_ci.0,
                    mc.std_ci.1,
                    r.errors().map_or(f64::NAN, |e| e.1)
                );
            }
            worst = worst.max((r.std / mc.std - 1.0).abs());
            if let Some((em, es)) = r.errors() {
                covered += usize::from(dm <= hm + em && ds <= hs + es);
            }
        }
        let pct = |x: usize| 100.0 * x as f64 / rows.max(1) as f64;
        println!(
            "{} | {rows} | {:.1} % | {:.1} % | {:.2} % | {}",
            method.as_str(),
            pct(mean_in),
            pct(std_in),
            100.0 * worst,
            if method == Method::Quadrature {
                format!("{:.1} %", pct(covered))
            } else {
                "–".into()
            }
        );
    }
}

/// The Monte Carlo rows of a `tolerance.csv` written by `modaltol analyze` (a reference run
/// once, for `accuracy … --reference FILE`).
fn reference_rows(path: &str) -> Vec<Row> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let head = reader.headers().unwrap().clone();
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let num = |r: &csv::StringRecord, name: &str| r[col(name)].parse::<f64>().unwrap_or(f64::NAN);
    reader
        .records()
        .map(Result::unwrap)
        .filter(|r| &r[col("method")] == "monte_carlo" && !r[col("std")].is_empty())
        .map(|r| {
            let quantity = [
                Quantity::DampedFrequency,
                Quantity::DampingRatio,
                Quantity::TransferMagnitude,
            ]
            .into_iter()
            .find(|q| q.as_str() == &r[col("quantity")])
            .unwrap();
            let (mean, std) = (num(&r, "mean"), num(&r, "std"));
            Row {
                speed: num(&r, "speed"),
                quantity,
                mode: r[col("mode")].parse::<usize>().ok().map(|m| m - 1),
                case: 0,
                mean,
                std,
                detail: Detail::MonteCarlo(McStat {
                    n: num(&r, "samples") as usize,
                    mean,
                    std,
                    mean_ci: (num(&r, "mean_ci_low"), num(&r, "mean_ci_high")),
                    std_ci: (num(&r, "std_ci_low"), num(&r, "std_ci_high")),
                    failed: 0,
                    class_changed: 0,
                    overdamped: 0,
                    unstable: 0,
                    other_branch: 0,
                    quantiles: None,
                }),
                missing: None,
            }
        })
        .collect()
}

/// `model n k`: the n-segment chain with 2k toleranced variables, as a model file.
fn print_model(args: &[String]) {
    let nums = numbers(args);
    print!("{}", toleranced(nums[0], nums[1], args));
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("model") {
        print_model(&args[1..]);
        return;
    }
    if args.first().map(String::as_str) == Some("accuracy") {
        accuracy(&args[1..]);
        return;
    }
    if args.first().map(String::as_str) == Some("governor") {
        governor(&args[1..]);
        return;
    }
    if args.first().map(String::as_str) == Some("tolerances") {
        tolerances(&args[1..]);
        return;
    }
    if args.first().map(String::as_str) == Some("cold") {
        // Profiling driver: `cold n reps [direct]` repeats the cold point (for `perf record`;
        // `direct` without the recorded program).
        let n = args[1].parse().unwrap();
        let text = chain(n);
        let route = if args.get(3).is_some_and(|a| a == "direct") {
            Route::Direct
        } else {
            Route::Recorded
        };
        for _ in 0..args[2].parse().unwrap() {
            let model = Compiled::from_str(&text, "chain.toml")
                .unwrap()
                .with_route(route);
            let p = model.model().nominal();
            let q0 = initial_guess(model.model(), &p, 5.0).unwrap();
            point(&model, &p, 5.0, &q0, &Options::default()).unwrap();
        }
        return;
    }
    if args.first().map(String::as_str) == Some("damped") {
        // `damped n`: one cold modal point of the chain with a damper 10⁻³ k beside each
        // spring, where most modes are overdamped (hundreds of real roots to pair at 480).
        let n = args[1].parse().unwrap();
        let text = with_joint_dampers(&chain(n), 1e-3);
        let model = Compiled::from_str(&text, "chain.toml").unwrap();
        let p = model.model().nominal();
        let t = Instant::now();
        let q0 = initial_guess(model.model(), &p, 5.0).unwrap();
        let pt = point(&model, &p, 5.0, &q0, &Options::default()).unwrap();
        let overdamped = pt
            .modes
            .iter()
            .filter(|m| m.class == ModeClass::Overdamped)
            .count();
        println!(
            "{n} segments with joint dampers: cold modal point {:.3} s, {overdamped} of {} \
             modes overdamped, peak {:.1} MB",
            t.elapsed().as_secs_f64(),
            pt.modes.len(),
            peak_mb()
        );
        return;
    }
    if args.first().map(String::as_str) == Some("record") {
        let text = match args[1].parse() {
            Ok(n) => chain(n),
            Err(_) => std::fs::read_to_string(&args[1]).unwrap(),
        };
        let rounds = if text.len() < 20_000 { 300 } else { 20 };
        let time = |f: &mut dyn FnMut()| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        };
        let [mut record, mut after, mut direct] = [f64::INFINITY; 3];
        // One point, as `modal` solves it.
        let single = Options {
            tier: Tier::Few,
            ..Options::default()
        };
        for _ in 0..rounds {
            // A fresh model each round: `problem` records its program.
            let model = Compiled::from_str(&text, "model.toml").unwrap();
            let p = model.model().nominal();
            let q0 = initial_guess(model.model(), &p, 5.0).unwrap();
            record = record.min(time(&mut || {
                model
                    .problem(&p, 5.0, (Tier::Few, &Workspace::default()))
                    .unwrap();
            }));
            after = after.min(time(&mut || {
                point(&model, &p, 5.0, &q0, &single).unwrap();
            }));
            let reference = model.clone().with_route(Route::Direct);
            direct = direct.min(time(&mut || {
                point(&reference, &p, 5.0, &q0, &single).unwrap();
            }));
        }
        println!(
            "recording {record:.3} ms, point after it {after:.3} ms (cold point {:.3} ms), \
             direct point {direct:.3} ms",
            record + after
        );
        return;
    }
    if args.first().map(String::as_str) == Some("hessians") {
        // `hessians n`: the gradients and Hessians of every output along the chain's
        // parameters at one point (the second-order method's passes), best of 3.
        let n = args[1].parse().unwrap();
        let model = Compiled::from_str(&chain(n), "chain.toml").unwrap();
        let p = model.model().nominal();
        let q0 = initial_guess(model.model(), &p, 5.0).unwrap();
        let pt = point(&model, &p, 5.0, &q0, &Options::default()).unwrap();
        let wrt: Vec<usize> = (0..p.len()).collect();
        let outs = outputs(pt.modes.len(), false);
        let best = (0..3)
            .map(|_| {
                let t = Instant::now();
                DesignPoint::new(&model, &p, &pt)
                    .hessians(&wrt, &outs)
                    .unwrap();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        println!(
            "{n} segments: gradients and Hessians along {} parameters {:.2} ms",
            wrt.len(),
            best * 1e3
        );
        return;
    }
    if args.first().map(String::as_str) == Some("local") {
        // `local n k`: at one point (5 rad/s) of the n-segment chain with 2k toleranced
        // variables, the gradients of every output (first order) and the gradients and
        // Hessians (second order), best of 3.
        let nums = numbers(&args[1..]);
        let (n, k) = (nums[0], nums[1]);
        let model = Compiled::from_str(&toleranced(n, k, &args[1..]), "chain.toml").unwrap();
        let p = model.model().nominal();
        let q0 = initial_guess(model.model(), &p, 5.0).unwrap();
        let pt = point(&model, &p, 5.0, &q0, &Options::default()).unwrap();
        let wrt: Vec<usize> = model.model().tolerance_cases(&[]).unwrap()[0]
            .tolerances
            .iter()
            .map(|t| t.0)
            .collect();
        let outs = outputs(pt.modes.len(), false);
        let ws = Workspace::default();
        let best = |f: &mut dyn FnMut()| {
            (0..3)
                .map(|_| {
                    let t = Instant::now();
                    f();
                    t.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let g = best(&mut || {
            DesignPoint::new(&model, &p, &pt)
                .with_workspace(&ws)
                .analytic(&wrt)
                .unwrap();
        });
        let by = |route| {
            DesignPoint::new(&model, &p, &pt)
                .with_workspace(&ws)
                .hessians_by(&wrt, &outs, route)
                .unwrap()
        };
        let h = best(&mut || {
            by(MixedRoute::Fastest);
        });
        if args.iter().any(|a| a == "--fastest-only") {
            println!(
                "{n} segments, {} variables: gradients {:.2} ms, gradients and Hessians {:.2} ms",
                wrt.len(),
                g * 1e3,
                h * 1e3
            );
            return;
        }
        let passes = best(&mut || {
            by(MixedRoute::Passes);
        });
        // The two routes' Hessians entry by entry, relative to each Hessian's largest entry.
        let (fast, reference) = (by(MixedRoute::Fastest), by(MixedRoute::Passes));
        let deviation = fast
            .outputs
            .iter()
            .zip(&reference.outputs)
            .filter_map(|(a, b)| Some((a.as_ref().ok()?, b.as_ref().ok()?)))
            .map(|(a, b)| (a - b).amax() / b.amax().max(f64::MIN_POSITIVE))
            .fold(0.0, f64::max);
        println!(
            "{n} segments, {} variables: gradients {:.2} ms, gradients and Hessians {:.2} ms \
             (a pass per pair {:.2} ms; largest relative difference {deviation:.1e})",
            wrt.len(),
            g * 1e3,
            h * 1e3,
            passes * 1e3
        );
        return;
    }
    if args.first().map(String::as_str) == Some("one") {
        let n = args[1].parse().unwrap();
        let [cold, swept, sens, cold_mb, mb] = measure(n);
        println!("{cold} {swept} {sens} {cold_mb} {mb}");
        return;
    }
    let ns: Vec<usize> = if args.is_empty() {
        vec![10, 20, 40, 80, 160]
    } else {
        args.iter().map(|a| a.parse().unwrap()).collect()
    };
    let exe = std::env::current_exe().unwrap();
    println!(
        "bodies n | cold modal point | per swept speed | sensitivities (2) | peak: cold point, all"
    );
    let mut rows = Vec::new();
    for &n in &ns {
        let out = std::process::Command::new(&exe)
            .args(["one", &n.to_string()])
            .output()
            .unwrap();
        let v: Vec<f64> = String::from_utf8_lossy(&out.stdout)
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        println!(
            "{n:8} | {:13.3} ms | {:12.3} ms | {:14.3} ms | {:7.1} MB, {:6.1} MB",
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * 1e3,
            v[3],
            v[4]
        );
        rows.push((n as f64, v));
    }
    if rows.len() >= 2 {
        let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
        let fit = |k: usize| exponent(&x, &rows.iter().map(|r| r.1[k]).collect::<Vec<_>>());
        println!(
            "growth exponents: cold point n^{:.2}, swept point n^{:.2}, sensitivities n^{:.2}, \
             memory (cold point) n^{:.2}, (all) n^{:.2}",
            fit(0),
            fit(1),
            fit(2),
            fit(3),
            fit(4)
        );
    }
}
