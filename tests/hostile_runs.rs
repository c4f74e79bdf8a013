//! The real binary against hostile input, one test per defect class of the issue "Nothing
//! crashes, hangs, lies or gets lost": extreme finite values (no panic, no hang), silent NaN,
//! physically impossible Monte Carlo samples, corrupted shards, interrupted writes, resource
//! bounds, exit codes and messages. Every run is under a deadline: a hang fails the test.

mod common;

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::Run;

/// Runs the binary with `args`; a run still going after `limit` fails the test (a hang).
fn run_limited(args: &[&str], limit: Duration) -> Run {
    common::run_with_deadline(args, limit).unwrap_or_else(|e| panic!("{e}"))
}

fn run(args: &[&str]) -> Run {
    run_limited(args, Duration::from_secs(60))
}

/// An example with `from` replaced by `to` (which must occur), written to `dir/name`.
fn variant(dir: &Path, example: &str, name: &str, edits: &[(&str, &str)]) -> String {
    let mut text = common::example_text(example);
    for (from, to) in edits {
        assert!(text.contains(from), "{example} has no '{from}'");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// Every numeric cell of a sweep CSV is finite unless the row's status is `failed`. A cell is
/// a number where it parses as one (`NaN` and `inf` do); the message's prose ("|H| is
/// infinite …", which a sweep with the model's transfer function writes at a resonance) is
/// not.
fn assert_finite_or_failed(csv: &str, what: &str) {
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let status = header.iter().position(|h| *h == "status").unwrap();
    for line in rows {
        let cells: Vec<&str> = line.split(',').collect();
        if cells[status] == "failed" {
            continue;
        }
        for c in &cells {
            assert!(
                !c.trim().parse::<f64>().is_ok_and(|v| !v.is_finite()),
                "{what}: non-finite number in a row that did not fail: {line}"
            );
        }
    }
}

#[test]
fn extreme_finite_values_fail_speeds_with_a_reason_never_panic_or_hang() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let models = [
        variant(
            d,
            "spinning_universal_pendulum.toml",
            "c.toml",
            &[("c = 0.05", "c = 1e308")],
        ),
        variant(
            d,
            "spinning_universal_pendulum.toml",
            "k.toml",
            &[("stiffness = \"kx\"", "stiffness = 1e308")],
        ),
        variant(
            d,
            "governor.toml",
            "len.toml",
            &[("link_length = 0.10922", "link_length = -1e308")],
        ),
        variant(
            d,
            "rotating_pendulum.toml",
            "hinge_c.toml",
            &[("c = 3.0", "c = 1e308")],
        ),
        variant(
            d,
            "rotating_pendulum.toml",
            "exp.toml",
            &[("damping = \"c\"", "damping = \"exp(speed*1000)\"")],
        ),
        variant(
            d,
            "rotating_pendulum.toml",
            "tiny_g.toml",
            &[("gravity = [0, -9.80665, 0]", "gravity = [0, 5e-324, 0]")],
        ),
        variant(
            d,
            "multi_arm_governor.toml",
            "far.toml",
            &[(
                "point1 = [0, \"hinge_y\", 0]",
                "point1 = [1e308, \"hinge_y\", 0]",
            )],
        ),
    ];
    for m in &models {
        let o = run_limited(&["sweep", m, "--speed", "0:6:1"], Duration::from_secs(30));
        assert!(!o.stderr.contains("panicked"), "{m}: {}", o.stderr);
        assert!(
            matches!(o.code, Some(0 | 1)),
            "{m}: exit {:?} {}",
            o.code,
            o.stderr
        );
        assert_finite_or_failed(&o.stdout, m);
        // Failed rows say why.
        for line in o.stdout.lines().filter(|l| l.contains(",failed,")) {
            assert!(
                !line.ends_with(','),
                "{m}: a failed row without a reason: {line}"
            );
        }
        let o = run_limited(&["modal", m, "--speed", "1"], Duration::from_secs(30));
        assert!(!o.stderr.contains("panicked"), "{m}: {}", o.stderr);
        assert!(matches!(o.code, Some(0 | 1)), "{m}: exit {:?}", o.code);
        assert!(
            !o.stdout.to_lowercase().contains("nan") && !o.stdout.contains("inf "),
            "{m}: {}",
            o.stdout
        );
    }
}

#[test]
fn a_huge_axis_gives_the_same_numbers_as_its_direction() {
    let dir = tempfile::tempdir().unwrap();
    let huge = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "huge.toml",
        &[("axis = [0, 0, 1]", "axis = [1e200, 1e200, 0]")],
    );
    let unit = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "unit.toml",
        &[("axis = [0, 0, 1]", "axis = [1, 1, 0]")],
    );
    let a = run(&["sweep", &huge, "--speed", "0:6:0.5"]);
    let b = run(&["sweep", &unit, "--speed", "0:6:0.5"]);
    assert_eq!(a.code, Some(0), "{}", a.stderr);
    assert_eq!(a.stdout, b.stdout);
}

#[test]
fn non_finite_constants_are_refused_at_load_with_their_place() {
    let dir = tempfile::tempdir().unwrap();
    let m = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "g.toml",
        &[(
            "gravity = [0, -9.80665, 0]",
            "gravity = [0, \"0*exp(1000)\", 0]",
        )],
    );
    let o = run(&["check", &m]);
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.contains("g.toml:9:"), "{}", o.stderr);
}

#[test]
fn impossible_monte_carlo_samples_count_as_failed_with_their_reason() {
    let dir = tempfile::tempdir().unwrap();
    // Rod mass m·(L − 0.9): with L = 1 ± 60 %, a sixth of the normal samples have L < 0.9.
    let m = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "mass.toml",
        &[
            ("mass = \"m\"", "mass = \"m*(L-0.9)\""),
            (
                "tolerances = { L = \"3%\" }",
                "tolerances = { L = \"60%\" }",
            ),
        ],
    );
    let o = run(&["check", &m]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        o.stdout.contains("warning: case 'L3'") && o.stdout.contains("negative mass"),
        "{}",
        o.stdout
    );
    let out = dir.path().join("out");
    let o = run(&[
        "analyze",
        &m,
        "-o",
        out.to_str().unwrap(),
        "--speed",
        "0:2:1",
        "--samples",
        "600",
        "--case",
        "L3",
        "--no-quadrature",
    ]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        o.stderr.contains("not physically admissible"),
        "{}",
        o.stderr
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let bad = &s["monte_carlo"]["inadmissible_samples"][0];
    let n = bad["samples"].as_u64().unwrap();
    // P(L < 0.9) = Φ(−0.1/0.2) = 0.3085 for σ = 0.6/3: 185 of 600, 99.9 % band ± 37.
    assert!((148..=222).contains(&n), "{n} inadmissible samples");
    assert!(
        bad["reasons"][0]["reason"]
            .as_str()
            .unwrap()
            .contains("negative mass")
    );
    // They are failures in the Monte Carlo rows, never values.
    let text = std::fs::read_to_string(out.join("tolerance.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (method, failed, samples) = (col("method"), col("failed"), col("samples"));
    let mut rows = 0;
    for rec in r.records() {
        let rec = rec.unwrap();
        if &rec[method] == "monte_carlo" {
            let f: u64 = rec[failed].parse().unwrap();
            let k: u64 = rec[samples].parse().unwrap();
            assert!(f >= n && f + k == 600, "failed {f}, values {k}");
            rows += 1;
        }
    }
    assert!(rows > 0);
}

/// The settings of the shard runs below.
const SHARD_RUN: [&str; 6] = ["--speed", "0:3:1", "--samples", "300", "--case", "L3"];

/// Runs `analyze --shard K/3` of `model` with `extra` options into `dir`, returns its path.
fn shard(dir: &Path, model: &str, k: usize, extra: &[&str]) -> String {
    let out = dir.to_str().unwrap();
    let spec = format!("{k}/3");
    let mut args = vec!["analyze", model, "-o", out, "--shard", &spec];
    args.extend(SHARD_RUN);
    args.extend(extra);
    let o = run(&args);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    dir.join(format!("shard-{k}-of-3.json"))
        .display()
        .to_string()
}

/// Runs `analyze --shard K/3` for K = 1..3 into `dir` and returns the shard paths.
fn shards(dir: &Path, model: &str) -> Vec<String> {
    (1..=3).map(|k| shard(dir, model, k, &[])).collect()
}

/// `merge --model MODEL -o DIR/merged --case L3 SHARDS…`.
fn merge(dir: &Path, model: &str, shards: &[String]) -> Run {
    let out = dir.join("merged");
    let mut args = vec!["merge", "--model", model, "-o", out.to_str().unwrap()];
    args.extend(["--case", "L3"]);
    args.extend(shards.iter().map(String::as_str));
    run(&args)
}

#[test]
fn a_shard_of_another_model_or_run_is_refused_naming_what_differs() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let good = shards(dir.path(), m);
    // One shard each from a model whose gravity, geometry, an expression or a parameter
    // differs, or from a run with other options: refused, naming the file and what differs.
    let elsewhere = dir.path().join("other");
    std::fs::create_dir(&elsewhere).unwrap();
    let gravity = variant(
        &elsewhere,
        "rotating_pendulum.toml",
        "g.toml",
        &[("-9.80665", "-7")],
    );
    let damping = variant(
        &elsewhere,
        "rotating_pendulum.toml",
        "c.toml",
        &[("damping = \"c\"", "damping = \"c*1.1\"")],
    );
    for (k, model, extra, what) in [
        (2, gravity.as_str(), &[][..], "gravity"),
        (3, damping.as_str(), &[][..], "joints"),
        (1, m, &["--set", "L=1.1"][..], "parameters"),
        (2, m, &["--no-quadrature"][..], "quadrature"),
        (3, m, &["--sampling", "sobol"][..], "sampling"),
    ] {
        let odd = shard(&elsewhere, model, k, extra);
        let mut set = good.clone();
        set[k - 1] = odd;
        let o = merge(dir.path(), m, &set);
        assert_eq!(o.code, Some(2), "{what}: merged; {}", o.stderr);
        assert!(
            o.stderr.contains(&format!("other/shard-{k}-of-3.json")) && o.stderr.contains(what),
            "{what}: {}",
            o.stderr
        );
    }
    assert_eq!(merge(dir.path(), m, &good).code, Some(0));
}

#[test]
fn merged_shards_run_the_quadrature_their_run_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let whole = dir.path().join("whole");
    let mut args = vec![
        "analyze",
        m,
        "-o",
        whole.to_str().unwrap(),
        "--no-quadrature",
    ];
    args.extend(SHARD_RUN);
    assert_eq!(run(&args).code, Some(0));
    let set: Vec<String> = (1..=3)
        .map(|k| shard(dir.path(), m, k, &["--no-quadrature"]))
        .collect();
    let o = merge(dir.path(), m, &set);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    // The same rows and numbers, but the Monte Carlo quantiles (which need every sample's
    // value, and which a merge leaves empty); and no quadrature rows.
    let rows = |d: &Path| -> Vec<Vec<String>> {
        let mut r = csv::Reader::from_path(d.join("tolerance.csv")).unwrap();
        let h = r.headers().unwrap().clone();
        let method = h.iter().position(|c| c == "method").unwrap();
        let q = h.iter().position(|c| c == "q05").unwrap();
        r.records()
            .map(|x| {
                let mut v: Vec<String> = x.unwrap().iter().map(String::from).collect();
                assert_ne!(v[method], "quadrature");
                if v[method] == "monte_carlo" {
                    v[q..q + 3].iter_mut().for_each(String::clear);
                }
                v
            })
            .collect()
    };
    assert!(rows(&whole) == rows(&dir.path().join("merged")));
}

#[test]
fn merge_refuses_every_corrupted_or_relabelled_shard() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let paths = shards(dir.path(), m);
    let merge = |files: &[String]| {
        let out = dir.path().join("merged");
        let mut args = vec![
            "merge",
            "--model",
            m,
            "-o",
            out.to_str().unwrap(),
            "--case",
            "L3",
        ];
        args.extend(files.iter().map(String::as_str));
        run(&args)
    };
    let ok = merge(&paths);
    assert_eq!(ok.code, Some(0), "{}", ok.stderr);
    let original = std::fs::read_to_string(&paths[0]).unwrap();
    let json: serde_json::Value = serde_json::from_str(&original).unwrap();
    let resealed = |v: &serde_json::Value| {
        // The same edit with a recomputed digest (what a careful forger would do).
        let mut f: modaltol::shard::ShardFile = serde_json::from_value(v.clone()).unwrap();
        f.digest.clear();
        f.to_json()
    };
    let mut edits: Vec<(String, String)> = Vec::new();
    // Plain edits (digest not recomputed) of a mean, and a cut file.
    let at = original.find("\"mean\":").unwrap() + "\"mean\":".len();
    let end = at + original[at..].find(',').unwrap();
    edits.push((
        "a mean edited".into(),
        format!("{}0.123{}", &original[..at], &original[end..]),
    ));
    edits.push((
        "truncated".into(),
        original[..original.len() / 2].to_string(),
    ));
    // Edits with a recomputed digest: counts that cannot be, a negative m2, a relabelled shard.
    for (what, field, value) in [
        ("n too large", "n", serde_json::json!(10_000)),
        ("failed too large", "failed", serde_json::json!(10_000)),
        ("negative m2", "m2", serde_json::json!(-5.0)),
    ] {
        let mut v = json.clone();
        v["cases"][0][0]["moments"][1][0][field] = value;
        edits.push((what.into(), resealed(&v)));
    }
    let second: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&paths[1]).unwrap()).unwrap();
    let mut relabelled = second.clone();
    relabelled["shard"] = serde_json::json!(1);
    edits.push(("shard 2 relabelled as 1".into(), resealed(&relabelled)));
    edits.push((
        "shard 2 relabelled as 1, digest kept".into(),
        serde_json::to_string(&relabelled).unwrap(),
    ));
    for (what, text) in edits {
        let bad = dir.path().join("shard-1-of-3.json");
        std::fs::write(&bad, &text).unwrap();
        let o = merge(&paths);
        assert_eq!(o.code, Some(2), "{what}: accepted; {}", o.stderr);
        assert!(
            o.stderr.contains("shard-1-of-3.json"),
            "{what}: the message does not name the file: {}",
            o.stderr
        );
    }
    std::fs::write(&paths[0], original).unwrap();
    assert_eq!(merge(&paths).code, Some(0));
}

#[test]
fn bounded_inputs_are_refused_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let t = Duration::from_secs(10);
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let out = dir.path().join("o");
    let o = run_limited(
        &[
            "analyze",
            m,
            "-o",
            out.to_str().unwrap(),
            "--samples",
            "1000000000000",
        ],
        t,
    );
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    // 10⁹ speeds of an analysis (all held in memory): refused before they are made.
    let o = run_limited(
        &[
            "analyze",
            m,
            "-o",
            out.to_str().unwrap(),
            "--speed",
            "0:999999999:1",
        ],
        t,
    );
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    assert!(o.stderr.contains("1000000000 speeds"), "{}", o.stderr);
    let big = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "big.toml",
        &[("samples = 3000", "samples = 1000000000000")],
    );
    let o = run_limited(&["check", &big], t);
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    assert!(o.stderr.contains("big.toml:"), "{}", o.stderr);
    let o = run_limited(&["check", "/dev/zero"], t);
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    let long = "x".repeat(100_000);
    let name = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "name.toml",
        &[(
            "name = \"rotating pendulum\"",
            &format!("name = \"{long}\""),
        )],
    );
    let o = run_limited(&["check", &name], t);
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.len() < 1500, "{} bytes of message", o.stderr.len());
    let case = variant(
        dir.path(),
        "rotating_pendulum.toml",
        "case.toml",
        &[("name = \"L6\"", &format!("name = \"{}\"", "y".repeat(300)))],
    );
    let o = run_limited(&["check", &case], t);
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.contains("case.toml:"), "{}", o.stderr);
    // A key of 5 000 dotted parts: refused with a place.
    let dotted = dir.path().join("dotted.toml");
    std::fs::write(
        &dotted,
        format!("a{} = 1\n", ".b".repeat(5000)) + &common::example_text("rotating_pendulum.toml"),
    )
    .unwrap();
    let o = run_limited(&["check", dotted.to_str().unwrap()], t);
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.contains("dotted.toml:1:"), "{}", o.stderr);
}

/// Runs the binary with `args` under `ulimit -v KB` (the address space a container or a batch
/// job may grant).
fn run_with_address_space(kb: usize, args: &[&str]) -> Run {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {kb} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_modaltol"))
        .args(args);
    common::command_with_deadline(cmd, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn more_shards_than_samples_are_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let out = dir.path().join("o");
    for (spec, ok) in [("1/20", true), ("1/21", false), ("21/99999999999", false)] {
        let args = [
            "analyze",
            m.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--speed",
            "0:1:1",
            "--samples",
            "20",
            "--shard",
            spec,
        ];
        let o = run_limited(&args, Duration::from_secs(30));
        if ok {
            assert_eq!(o.code, Some(0), "--shard {spec}: {}", o.stderr);
        } else {
            assert_eq!(o.code, Some(2), "--shard {spec}: {}", o.stderr);
            assert!(
                o.stderr.contains("without a"),
                "--shard {spec}: {}",
                o.stderr
            );
        }
    }
}

#[test]
fn thread_counts_are_bounded_and_a_refusal_of_the_system_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let out = dir.path().join("o");
    let o = out.to_str().unwrap();
    let analyze = |threads: &'static str| {
        vec![
            "analyze",
            m,
            "-o",
            o,
            "--speed",
            "0:1:1",
            "--samples",
            "20",
            "--threads",
            threads,
        ]
    };
    for (threads, why) in [("0", "at least 1"), ("3000", "more than the 1024")] {
        let o = run_limited(&analyze(threads), Duration::from_secs(10));
        assert_eq!(o.code, Some(2), "--threads {threads}: {}", o.stderr);
        assert!(o.stderr.contains(why), "--threads {threads}: {}", o.stderr);
    }
    // Within the bound but more than 1.5 GB of address space holds (their stacks): the
    // system's refusal, reported before anything is computed; never a panic.
    let o = run_with_address_space(1_500_000, &analyze("1000"));
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(
        o.stderr.contains("cannot start 1000 worker threads") && !o.stderr.contains("panicked"),
        "{}",
        o.stderr
    );
    assert!(!out.exists(), "a result was written");
}

#[test]
fn a_failed_modal_point_gives_its_reason_in_every_format() {
    for name in common::EXAMPLES {
        let m = common::example_path(name);
        let m = m.to_str().unwrap();
        let model = common::example(name);
        let mut reasons = Vec::new();
        for format in ["table", "json", "csv"] {
            let o = run(&["modal", m, "--speed", "1e308", "--format", format]);
            assert_eq!(o.code, Some(1), "{name} {format}: {}", o.stderr);
            let reason = o
                .stderr
                .split("failed: ")
                .nth(1)
                .unwrap()
                .trim()
                .to_string();
            assert!(
                o.stdout.to_lowercase().contains("failed") && o.stdout.contains(&reason),
                "{name} {format}: {}",
                o.stdout
            );
            reasons.push(reason);
            if format == "csv" {
                let mut r = csv::Reader::from_reader(o.stdout.as_bytes());
                let header = r.headers().unwrap().clone();
                let message = header.iter().position(|h| h == "message").unwrap();
                let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
                assert_eq!(rows.len(), model.model().dof().max(1), "{name}");
                for row in rows {
                    assert_eq!(&row[2], "failed");
                    assert_eq!(row[message], reasons[0], "{name}");
                }
            }
        }
        assert!(
            reasons.iter().all(|r| r == &reasons[0] && !r.is_empty()),
            "{reasons:?}"
        );
    }
}

#[test]
fn exit_codes_and_messages_name_what_went_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    // A failed point is not a success.
    let o = run(&["modal", m, "--speed", "1e308"]);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("failed"), "{}", o.stderr);
    // A negative speed range is a value, not a flag.
    let o = run(&["sweep", m, "--speed", "-1:0:0.5"]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert_eq!(o.stdout.lines().count(), 4);
    // I/O errors name the path.
    for args in [
        vec!["analyze", m, "-o", "/proc/modaltol/out", "--no-monte-carlo"],
        vec!["sweep", m, "--speed", "0:1:1", "-o", "/proc/modaltol/x.csv"],
    ] {
        let o = run(&args);
        assert!(matches!(o.code, Some(1 | 2)), "{:?}", o.code);
        assert!(o.stderr.contains("/proc/modaltol"), "{}", o.stderr);
    }
    // A spring between coincident points is refused naming the spring.
    let text = common::example_text("rotating_pendulum.toml")
        + "\n[[forces]]\nname = \"tie\"\ntype = \"spring_damper\"\nbody1 = \"rod\"\npoint1 = [0, 0, 0]\nbody2 = \"ground\"\npoint2 = [0, 0, 0]\nstiffness = 10\n";
    let f = dir.path().join("tie.toml");
    std::fs::write(&f, text).unwrap();
    let o = run(&["check", f.to_str().unwrap()]);
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.contains("'tie'"), "{}", o.stderr);
}

#[test]
fn a_closed_pipe_ends_the_run_quietly() {
    let m = common::example_path("governor.toml");
    let mut child = Command::new(env!("CARGO_BIN_EXE_modaltol"))
        .args(["sweep", m.to_str().unwrap(), "--speed", "0:100:0.01"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut first = [0u8; 64];
    out.read_exact(&mut first).unwrap();
    drop(out);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    // Nothing but the progress lines a log gets (stderr is not a terminal here).
    assert!(
        err.lines().all(|l| l.starts_with("sweep speeds: ")),
        "{err}"
    );
}

/// Kills `analyze` at random moments over a directory holding a complete earlier run: each
/// time the directory holds the earlier run or the new one, whole (its manifest's files, with
/// their digests, and nothing else), never a mix.
#[test]
fn a_killed_analyze_leaves_the_old_result_or_the_new_one() {
    use modaltol::files::Manifest;
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    let target = dir.path().join("results");
    let t = target.to_str().unwrap();
    let args = |seed: &str| {
        vec![
            "analyze".to_string(),
            m.into(),
            "-o".into(),
            t.into(),
            "--speed".into(),
            "0:6:0.5".into(),
            "--samples".into(),
            "200".into(),
            "--case".into(),
            "L3".into(),
            "--seed".into(),
            seed.into(),
        ]
    };
    let first = run(&args("1").iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(first.code, Some(0), "{}", first.stderr);
    let old = std::fs::read(target.join("tolerance.csv")).unwrap();
    let reference = dir.path().join("reference");
    let mut new_args = args("2");
    new_args[3] = reference.to_str().unwrap().into();
    let o = run(&new_args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.code, Some(0));
    let new = std::fs::read(reference.join("tolerance.csv")).unwrap();
    assert_ne!(old, new);
    // How long a whole run takes, to spread the kills over it.
    let t0 = Instant::now();
    let o = run(&args("1").iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.code, Some(0));
    let whole = t0.elapsed();
    let (mut saw_old, mut saw_new) = (0, 0);
    let rounds = 40;
    for i in 0..rounds {
        let seed = if i % 2 == 0 { "2" } else { "1" };
        let mut child = Command::new(env!("CARGO_BIN_EXE_modaltol"))
            .args(args(seed))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // Deterministic, spread over the run and a little beyond.
        let at = whole.mul_f64(((i * 7919) % rounds) as f64 / rounds as f64 * 1.1);
        std::thread::sleep(at);
        let _ = child.kill();
        let _ = child.wait();
        let manifest = Manifest::read(&target).expect("no complete manifest after a kill");
        manifest
            .verify(&target)
            .unwrap_or_else(|e| panic!("round {i}: a mix of runs: {e}"));
        let mut listed: Vec<String> = manifest.files.iter().map(|f| f.file.clone()).collect();
        listed.push("manifest.json".into());
        listed.sort();
        let mut present: Vec<String> = std::fs::read_dir(&target)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        present.sort();
        assert_eq!(listed, present, "round {i}: files beside the run");
        let csv = std::fs::read(target.join("tolerance.csv")).unwrap();
        if csv == old {
            saw_old += 1;
        } else if csv == new {
            saw_new += 1;
        } else {
            panic!("round {i}: tolerance.csv is neither the old nor the new result");
        }
    }
    assert!(saw_old + saw_new == rounds);
}
