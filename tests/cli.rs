//! The real binary on real files: exit codes, CSV columns, JSON shape, failed rows.

mod common;

use common::example_path as example;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_modaltol"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn check_summarises_the_governor() {
    let o = run(&["check", example("governor.toml").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    assert!(s.contains("degrees of freedom: 1"), "{s}");
    assert!(s.contains("constraints: 2 (2 equations)"), "{s}");
    for name in [
        "spindle",
        "ball1",
        "ball2",
        "collar",
        "link1",
        "link2",
        "spring_k",
        "attach",
        "ball_mass",
    ] {
        assert!(s.contains(name), "{name} missing from\n{s}");
    }
}

#[test]
fn sweep_writes_one_row_per_speed_and_mode() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.csv");
    let o = run(&[
        "sweep",
        example("spinning_universal_pendulum.toml")
            .to_str()
            .unwrap(),
        "--speed",
        "0:2:0.5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = csv::Reader::from_path(&out).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    for c in [
        "speed",
        "mode",
        "status",
        "damped_frequency",
        "natural_frequency",
        "damping_ratio",
        "eigen_re",
        "eigen_im",
        "q:spin",
        "q:tilt_x",
        "q:tilt_z",
        "drive:spin",
    ] {
        assert!(
            header.contains(&c.to_string()),
            "{c} missing from {header:?}"
        );
    }
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 5 * 2);
    for row in &rows {
        let wd: f64 = row[3].parse().unwrap();
        assert!(wd.is_finite() && wd > 0.0);
        assert_eq!(&row[2], "underdamped");
    }
}

#[test]
fn sweep_to_stdout_and_from_the_model_range() {
    let o = run(&[
        "sweep",
        example("rotating_pendulum.toml").to_str().unwrap(),
        "--speed",
        "0:1:0.5",
    ]);
    assert!(o.status.success());
    let s = stdout(&o);
    assert!(s.starts_with("speed,mode,status,"));
    assert_eq!(s.lines().count(), 4);
}

#[test]
fn modal_json_has_matrices_and_modes() {
    let o = run(&[
        "modal",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "1.595",
        "--format",
        "json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["speed"], 1.595);
    assert_eq!(v["modes"].as_array().unwrap().len(), 1);
    assert!(v["M"][0][0].as_f64().unwrap() > 0.0);
    assert_eq!(v["equilibrium"]["coordinates"].as_array().unwrap().len(), 4);
    assert_eq!(v["units"]["frequency"], "rad/s");
}

#[test]
fn modal_table_with_chosen_independent_coordinate() {
    let o = run(&[
        "modal",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "2",
        "--independent",
        "slide",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("independent coordinates [slide]"));
    let o = run(&[
        "modal",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "2",
        "--independent",
        "spin",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a free joint coordinate"));
}

#[test]
fn bad_model_exits_2_with_location() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("m.toml");
    let text =
        common::example_text("rotating_pendulum.toml").replace("mass = \"m\"", "mass = \"m +\"");
    std::fs::write(&f, text).unwrap();
    let o = run(&["check", f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("m.toml:23:"), "{e}");
    assert!(e.contains("bad expression"), "{e}");
    assert!(!e.contains("panicked"));
}

#[test]
fn missing_file_and_bad_speed_range_are_input_errors() {
    let o = run(&["check", "/nonexistent/model.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("cannot read the model file"));
    let o = run(&[
        "sweep",
        example("rotating_pendulum.toml").to_str().unwrap(),
        "--speed",
        "3:1:0.1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("TO is below FROM"));
}

#[test]
fn failed_speeds_are_rows_and_the_sweep_goes_on() {
    // Division by zero at speed 0 only: that row fails, the others are solved.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("m.toml");
    let text = common::example_text("rotating_pendulum.toml")
        .replace("damping = \"c\"", "damping = \"c * speed / speed\"");
    std::fs::write(&f, text).unwrap();
    let o = run(&["sweep", f.to_str().unwrap(), "--speed", "0:1:0.5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(lines.len(), 4);
    assert!(lines[1].starts_with("0,1,failed,"), "{}", lines[1]);
    assert!(
        lines[1].contains("division by zero") && lines[1].contains("joint 'hinge' damping"),
        "{}",
        lines[1]
    );
    assert!(lines[2].contains("underdamped") && lines[3].contains("underdamped"));
    assert!(stderr(&o).contains("1 of 3 speeds failed"));
}

#[test]
fn sweep_with_transfer_and_sensitivity_columns() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.csv");
    let o = run(&[
        "sweep",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "1:2:0.5",
        "--sensitivity",
        "--transfer",
        "input=slide,output=slide",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = csv::Reader::from_path(&out).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    for p in ["ball_mass", "spring_k", "attach"] {
        for q in ["damped_frequency", "damping_ratio", "transfer_magnitude"] {
            assert!(
                header.contains(&format!("d({q})/d({p})")),
                "d({q})/d({p}) missing"
            );
        }
    }
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 3);
    for row in &rows {
        let h: f64 = row[col("transfer_magnitude")].parse().unwrap();
        assert!(h > 0.0 && h < 1.0);
        assert_eq!(&row[col("sensitivity_status")], "ok");
        assert!(
            row[col("d(damped_frequency)/d(spring_k)")]
                .parse::<f64>()
                .unwrap()
                > 0.0
        );
    }
}

/// `sweep` reads the model's `[analysis] transfer` where `--transfer` is not given, as
/// `sensitivity` does: the same |H| by both at a speed; `--transfer none` leaves it out.
#[test]
fn sweep_takes_the_model_s_transfer_as_sensitivity_does() {
    let model = example("rotating_pendulum.toml");
    let model = model.to_str().unwrap();
    let o = run(&["sweep", model, "--speed", "3.2:3.2:1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let col = header
        .iter()
        .position(|h| h == "transfer_magnitude")
        .unwrap();
    let swept: f64 = r.records().next().unwrap().unwrap()[col].parse().unwrap();
    let o = run(&["sensitivity", model, "--speed", "3.2", "--format", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let at = json["transfer_magnitude"].as_f64().unwrap();
    assert!((swept - at).abs() <= 1e-12 * at, "{swept} vs {at}");
    let o = run(&["sweep", model, "--speed", "3.2:3.2:1", "--transfer", "none"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stdout(&o)
            .lines()
            .next()
            .unwrap()
            .contains("transfer_magnitude")
    );
}

/// `draw` without `--speed` draws the middle of the model's [analysis] speeds (as the report
/// does), where the governor spins; it drew the first, 0 rad/s, the mechanism at rest.
#[test]
fn draw_defaults_to_the_middle_of_the_analysed_speeds() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.svg");
    let o = run(&[
        "draw",
        example("governor.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = modaltol::compiled::Compiled::from_file(&example("governor.toml")).unwrap();
    let speeds: Vec<f64> = m.model().analysis.speed.unwrap().speeds().collect();
    let middle = speeds[speeds.len() / 2];
    assert!(middle > 0.0);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(
        svg.contains(&format!("governor at {middle} rad/s")),
        "not at {middle}"
    );
}

/// `modal --frequency-unit hz` (or rpm) gives the table's frequencies as f = ω/2π (per minute
/// for rpm), named f_d, f_n; the default stays rad/s.
#[test]
fn modal_table_in_hz_and_rpm() {
    let model = example("governor.toml");
    let row = |unit: &str| -> (String, f64) {
        let o = run(&[
            "modal",
            model.to_str().unwrap(),
            "--speed",
            "1.6",
            "--frequency-unit",
            unit,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = stdout(&o);
        let header = text
            .lines()
            .find(|l| l.contains("status"))
            .unwrap()
            .to_string();
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with("1  "))
            .unwrap();
        (
            header,
            line.split_whitespace().nth(2).unwrap().parse().unwrap(),
        )
    };
    let (h, w) = row("rad/s");
    assert!(h.contains("ω_d"), "{h}");
    let (h, f) = row("hz");
    assert!(h.contains("f_d") && !h.contains("ω_d"), "{h}");
    assert!((f - w / std::f64::consts::TAU).abs() < 1e-7, "{f} vs {w}");
    let (_, n) = row("rpm");
    assert!(
        (n - w * 60.0 / std::f64::consts::TAU).abs() < 1e-6,
        "{n} vs {w}"
    );
}

#[test]
fn sensitivity_json_ad_and_fd_agree() {
    let get = |how: &str| {
        let o = run(&[
            "sensitivity",
            example("governor.toml").to_str().unwrap(),
            "--speed",
            "1.595",
            "--format",
            "json",
            "--derivatives",
            how,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_str::<serde_json::Value>(&stdout(&o)).unwrap()
    };
    let (ad, fd) = (get("ad"), get("fd"));
    assert_eq!(ad["derivatives"], "ad");
    let vars = ad["variables"].as_array().unwrap();
    assert_eq!(vars.len(), 3);
    for (a, f) in vars.iter().zip(fd["variables"].as_array().unwrap()) {
        let x = a["modes"][0]["d_damped_frequency"].as_f64().unwrap();
        let y = f["modes"][0]["d_damped_frequency"].as_f64().unwrap();
        assert!(
            (x - y).abs() <= 1e-6 * x.abs(),
            "{} {x} vs {y}",
            a["parameter"]
        );
    }
}

#[test]
fn frf_columns_and_unknown_joint() {
    let o = run(&[
        "frf",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "1.595",
        "--input",
        "slide",
        "--output",
        "slide",
        "--freq",
        "0.5:5:0.5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let header = s.lines().next().unwrap();
    assert!(header.starts_with("frequency,magnitude,phase"), "{header}");
    assert!(header.contains("d(magnitude)/d(spring_k)"));
    assert_eq!(s.lines().count(), 11);
    let o = run(&[
        "frf",
        example("governor.toml").to_str().unwrap(),
        "--speed",
        "1",
        "--input",
        "nope",
        "--output",
        "slide",
        "--freq",
        "1:2:1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("'nope' is neither a free joint coordinate, a port nor an unbalance")
    );
}

#[test]
fn analyze_writes_tables_plots_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a");
    let o = run(&[
        "analyze",
        example("rotating_pendulum.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--speed",
        "1:4:0.5",
        "--samples",
        "40",
        "--seed",
        "3",
        "--threads",
        "2",
        "--sampling",
        "sobol",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = csv::Reader::from_path(out.join("tolerance.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    for c in [
        "speed",
        "quantity",
        "mode",
        "case",
        "method",
        "mean",
        "std",
        "mean_ci_low",
        "std_ci_high",
        "failed",
        "class_changed",
        "basis",
        "share:L",
    ] {
        assert!(header.contains(&c.to_string()), "{c} missing");
    }
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    let methods: std::collections::BTreeSet<&str> =
        rows.iter().map(|r| r.get(4).unwrap()).collect();
    assert_eq!(
        methods.into_iter().collect::<Vec<_>>(),
        [
            "analytic",
            "first_order",
            "invariant",
            "monte_carlo",
            "quadrature",
            "second_order"
        ]
    );
    // 7 speeds × 3 cases × (ω_d: 6 methods, ζ: 5, |H|: 5).
    assert_eq!(rows.len(), 7 * 3 * 16);
    // Quadrature and Monte Carlo rows carry quantiles, the quadrature error estimates, and the
    // analytic rows take the quadrature.
    let col = |c: &str| header.iter().position(|h| h == c).unwrap();
    for r in &rows {
        let has = |c: &str| !r.get(col(c)).unwrap().is_empty();
        match r.get(4).unwrap() {
            "quadrature" | "analytic" => {
                assert!(has("q05") && has("q95") && has("mean_error") && has("std_error"));
            }
            "monte_carlo" => assert!(has("q50") && !has("mean_error")),
            _ => assert!(!has("q50") && !has("std_error")),
        }
        if r.get(4) == Some("analytic") {
            assert_eq!(r.get(col("basis")), Some("quadrature"));
        }
    }
    let mut p = csv::Reader::from_path(out.join("probabilities.csv")).unwrap();
    assert_eq!(
        p.headers().unwrap().iter().collect::<Vec<_>>(),
        [
            "speed",
            "case",
            "method",
            "event",
            "mode",
            "probability",
            "ci_low",
            "ci_high"
        ]
    );
    let events: std::collections::BTreeSet<(String, String)> = p
        .records()
        .map(|x| {
            let x = x.unwrap();
            let (lo, prob, hi): (f64, f64, f64) = (
                x[6].parse().unwrap(),
                x[5].parse().unwrap(),
                x[7].parse().unwrap(),
            );
            assert!((0.0..=1.0).contains(&prob) && lo <= prob && prob <= hi);
            (x[2].to_string(), x[3].to_string())
        })
        .collect();
    for m in ["quadrature", "monte_carlo"] {
        for e in ["overdamped", "unstable", "other_branch"] {
            assert!(events.contains(&(m.to_string(), e.to_string())), "{m} {e}");
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["monte_carlo"]["samples"], 40);
    assert!(summary["analytic_seconds"].as_f64().unwrap() > 0.0);
    assert!(summary["quadrature_seconds"].as_f64().unwrap() > 0.0);
    assert!(
        summary["probabilities"]
            .as_array()
            .is_some_and(|a| !a.is_empty())
    );
    // The paper's timings, for its own example only.
    assert_eq!(summary["paper"]["example"], "pendulum");
    assert_eq!(summary["paper"]["ratio"].as_f64(), Some(638.0));
    // Every image the report shows exists, as SVG and PNG.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let imgs: Vec<&str> = html
        .split("<img src=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert!(imgs.len() >= 13, "{} plots", imgs.len());
    for img in imgs {
        assert!(out.join(img).exists(), "{img}");
        let png = out.join(img.replace(".svg", ".png"));
        assert!(
            std::fs::read(&png).unwrap().starts_with(b"\x89PNG"),
            "{}",
            png.display()
        );
    }
    assert!(html.contains("448.281") && html.contains("Reading guide"));
    let svg = std::fs::read_to_string(out.join("campbell.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
}

#[test]
fn analyze_without_a_model_runs_the_built_in_governor() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g");
    let o = run(&[
        "analyze",
        "-o",
        out.to_str().unwrap(),
        "--no-monte-carlo",
        "--speed",
        "1:2:0.5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("tolerance.csv")).unwrap();
    for case in ["k3", "k6", "k12", "mass3", "attach3"] {
        assert!(text.contains(&format!(",{case},")), "{case}");
    }
    // An unknown --case is an input error naming the cases there are.
    let o = run(&[
        "analyze",
        "-o",
        out.to_str().unwrap(),
        "--no-monte-carlo",
        "--case",
        "k4",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("k3, k6, k12"), "{}", stderr(&o));
}

/// `--campbell-case` chooses the case the Campbell diagram's bands and "In short" are about
/// (default: the one with the most toleranced variables, the governor's `all3`); a case not
/// analysed is an input error naming those that are.
#[test]
fn analyze_campbell_case_chooses_the_case_the_report_is_about() {
    let dir = tempfile::tempdir().unwrap();
    let report = |case: Option<&str>| {
        let out = dir.path().join(case.unwrap_or("default"));
        let mut args = vec![
            "analyze",
            "-o",
            out.to_str().unwrap(),
            "--no-monte-carlo",
            "--speed",
            "1:2:0.5",
        ];
        if let Some(c) = case {
            args.extend(["--campbell-case", c]);
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read_to_string(out.join("report.html")).unwrap()
    };
    assert!(report(None).contains("In short</h2><p>Case <b>all3</b>"));
    assert!(report(Some("k6")).contains("In short</h2><p>Case <b>k6</b> (1 toleranced"));
    let out = dir.path().join("bad");
    let o = run(&[
        "analyze",
        "-o",
        out.to_str().unwrap(),
        "--no-monte-carlo",
        "--case",
        "k3",
        "--case",
        "k6",
        "--campbell-case",
        "all3",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(
            "--campbell-case: no tolerance case 'all3' among the cases analysed (k3, k6)"
        ),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists(), "nothing written for a refused run");
}

#[test]
fn interrupted_monte_carlo_leaves_a_flagged_partial_result() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p");
    let child = bin()
        .args([
            "analyze",
            "-o",
            out.to_str().unwrap(),
            "--speed",
            "1:1.5:0.5",
            "--samples",
            "1000000",
            "--threads",
            "2",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("partial result"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["partial"], true);
    let done = summary["monte_carlo"]["samples_done"].as_array().unwrap();
    assert!(
        done[0].as_u64().unwrap() >= 64 && done[0].as_u64().unwrap() < 1_000_000,
        "{done:?}"
    );
    let csv = std::fs::read_to_string(out.join("tolerance.csv")).unwrap();
    assert!(
        csv.contains(",monte_carlo,"),
        "the samples done are in the table"
    );
    assert!(
        std::fs::read_to_string(out.join("report.html"))
            .unwrap()
            .contains("Partial result")
    );
}

#[test]
fn merged_shards_equal_one_run_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let d = |s: &str| dir.path().join(s).to_str().unwrap().to_string();
    let model = example("rotating_pendulum.toml");
    let m = model.to_str().unwrap();
    let common = [
        "--speed",
        "1:4:0.5",
        "--samples",
        "200",
        "--seed",
        "11",
        "--sampling",
        "lhs",
        "--case",
        "L3",
        "--case",
        "L12",
    ];
    let whole = run(&[&["analyze", m, "-o", &d("whole")][..], &common].concat());
    assert!(whole.status.success(), "{}", stderr(&whole));
    for k in 1..=3 {
        let o = run(&[
            &[
                "analyze",
                m,
                "-o",
                &d(&format!("s{k}")),
                "--shard",
                &format!("{k}/3"),
                "--threads",
                "1",
            ][..],
            &common,
        ]
        .concat());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let shards: Vec<String> = [3, 1, 2]
        .iter()
        .map(|k| d(&format!("s{k}/shard-{k}-of-3.json")))
        .collect();
    let shard_args: Vec<&str> = shards.iter().map(String::as_str).collect();
    let o = run(&[
        &[
            "merge",
            "--model",
            m,
            "-o",
            &d("merged"),
            "--case",
            "L3",
            "--case",
            "L12",
        ][..],
        &shard_args[..],
    ]
    .concat());
    assert!(o.status.success(), "{}", stderr(&o));
    // Only the chosen cases were run.
    let text = std::fs::read_to_string(dir.path().join("whole/tolerance.csv")).unwrap();
    assert!(text.contains(",L3,") && text.contains(",L12,") && !text.contains(",L6,"));
    // The shards name their cases: merged without `--case`, the same files. Merging them as
    // if other cases had been run is refused.
    let o = run(&[
        &["merge", "--model", m, "-o", &d("named")][..],
        &shard_args[..],
    ]
    .concat());
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["tolerance.csv", "probabilities.csv"] {
        let a = std::fs::read(dir.path().join("merged").join(name)).unwrap();
        let b = std::fs::read(dir.path().join("named").join(name)).unwrap();
        assert!(a == b, "{name} merged without --case differs");
    }
    let o = run(&[
        &["merge", "--model", m, "-o", &d("bad0"), "--case", "L6"][..],
        &shard_args[..],
    ]
    .concat());
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("other tolerance cases"),
        "{}",
        stderr(&o)
    );
    // The same files, bit for bit, the Monte Carlo quantiles included (the shards carry their
    // samples' values).
    for name in ["tolerance.csv", "limits.csv", "yield.csv"] {
        let a = std::fs::read(dir.path().join("whole").join(name));
        let b = std::fs::read(dir.path().join("merged").join(name));
        assert!(a.is_ok() == b.is_ok(), "{name}");
        if let (Ok(a), Ok(b)) = (a, b) {
            assert!(a == b, "merged {name} differs from one run");
        }
    }
    let mut r = csv::Reader::from_path(dir.path().join("merged/tolerance.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let (method, q) = (
        h.iter().position(|c| c == "method").unwrap(),
        h.iter().position(|c| c == "q05").unwrap(),
    );
    assert!(
        r.records()
            .map(Result::unwrap)
            .any(|x| &x[method] == "monte_carlo" && !x[q].is_empty()),
        "the merge has the Monte Carlo quantiles"
    );
    let a = std::fs::read(dir.path().join("whole/probabilities.csv")).unwrap();
    let b = std::fs::read(dir.path().join("merged/probabilities.csv")).unwrap();
    assert!(a == b, "merged probabilities differ from one run");
    // A missing shard, or a shard of another model, is refused.
    let o = run(&[
        "merge",
        "--model",
        m,
        "-o",
        &d("bad"),
        "--case",
        "L3",
        "--case",
        "L12",
        &shards[0],
        &shards[1],
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(
            "needs shards 1 to 3 of 3, once each; got shards 1, 3; missing shard-2-of-3.json"
        ),
        "{}",
        stderr(&o)
    );
    let o = run(&[
        "merge",
        "-o",
        &d("bad2"),
        &shards[0],
        &shards[1],
        &shards[2],
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("another model"), "{}", stderr(&o));
}

#[test]
fn quadrature_tolerance_must_be_a_relative_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q");
    let m = common::example_path("rotating_pendulum.toml");
    for bad in ["0", "nan", "2", "-1e-3", "inf"] {
        let o = run(&[
            "analyze",
            m.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--no-monte-carlo",
            &format!("--quadrature-tolerance={bad}"),
        ]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("--quadrature-tolerance"),
            "{}",
            stderr(&o)
        );
    }
}

/// `--quadrature-nodes` caps the designs the quadrature sweeps per case (never below the
/// rule's first stage, which the summary then names), and refuses what is not a count.
#[test]
fn quadrature_nodes_cap_the_quadrature() {
    let dir = tempfile::tempdir().unwrap();
    let m = common::example_path("multi_arm_governor_13_variables.toml");
    let m = m.to_str().unwrap();
    for bad in ["0", "-3", "1.5", "many"] {
        let out = dir.path().join("bad");
        let o = run(&[
            "analyze",
            m,
            "-o",
            out.to_str().unwrap(),
            "--no-monte-carlo",
            &format!("--quadrature-nodes={bad}"),
        ]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        assert!(stderr(&o).contains("--quadrature-nodes"), "{}", stderr(&o));
    }
    // A tolerance no rule meets: the refinement runs to its budget.
    let swept = |nodes: Option<&str>| {
        let out = dir.path().join(format!("q{}", nodes.unwrap_or("default")));
        let mut args = vec![
            "analyze",
            m,
            "-o",
            out.to_str().unwrap(),
            "--no-monte-carlo",
            "--speed",
            "1:2:0.5",
            "--quadrature-tolerance",
            "1e-9",
        ];
        let flag = nodes.map(|n| format!("--quadrature-nodes={n}"));
        args.extend(flag.as_deref());
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let case = summary["quadrature"]["cases"][0].clone();
        (
            case["nodes_swept"].as_u64().unwrap(),
            case["rule"].as_str().unwrap().to_string(),
        )
    };
    let (default, _) = swept(None);
    let (capped, _) = swept(Some("150"));
    let (least, rule) = swept(Some("10"));
    assert!(default > 150 && default <= 300, "{default}");
    assert!(capped <= 150 && capped > 80, "{capped}");
    // Below the first stage (16 lines of 5 nodes), the first stage is swept and said so.
    assert_eq!(least, 80);
    assert!(
        rule.contains("first stage needs 80 nodes, more than the 10 asked for"),
        "{rule}"
    );
}

#[test]
fn frf_takes_the_transfer_like_sweep_and_output_is_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("frf.csv");
    let gov = example("governor.toml");
    let gov = gov.to_str().unwrap();
    let common = ["frf", gov, "--speed", "1.595", "--freq", "0.5:5:0.5"];
    let new = run(&[
        &common[..],
        &[
            "--transfer",
            "input=slide,output=slide",
            "-o",
            file.to_str().unwrap(),
        ],
    ]
    .concat());
    assert!(new.status.success(), "{}", stderr(&new));
    assert!(stdout(&new).is_empty());
    // The older spelling still works: --input/--output name the pair, the CSV on stdout.
    let old = run(&[&common[..], &["--input", "slide", "--output", "slide"]].concat());
    assert!(old.status.success(), "{}", stderr(&old));
    assert!(stderr(&old).contains("older spelling"), "{}", stderr(&old));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), stdout(&old));
    // The model's own transfer function is the default (the pendulum has one).
    let pend = example("rotating_pendulum.toml");
    let o = run(&[
        "frf",
        pend.to_str().unwrap(),
        "--speed",
        "1",
        "--freq",
        "1:2:1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o).lines().count(), 3);
    // Both spellings at once, or an order (meaningless for a response over --freq), are refused.
    let both = run(&[
        &common[..],
        &["--transfer", "input=slide,output=slide", "--input", "slide"],
    ]
    .concat());
    assert_eq!(both.status.code(), Some(2), "{}", stderr(&both));
    let order = run(&[
        &common[..],
        &["--transfer", "input=slide,output=slide,order=2"],
    ]
    .concat());
    assert_eq!(order.status.code(), Some(2), "{}", stderr(&order));
    assert!(stderr(&order).contains("order"), "{}", stderr(&order));
}

#[test]
fn set_replaces_a_parameter_as_the_edited_file_does() {
    let text = std::fs::read_to_string(example("rotating_pendulum.toml")).unwrap();
    let edited = text.replacen("L = { value = 1.0", "L = { value = 1.07", 1);
    assert_ne!(
        edited, text,
        "the example's L line changed: update this test"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("edited.toml");
    std::fs::write(&path, edited).unwrap();
    let args = ["--speed", "0:6:0.5", "--transfer", "model", "--sensitivity"];
    let from_file = run(&[&["sweep", path.to_str().unwrap()][..], &args[..]].concat());
    let pend = example("rotating_pendulum.toml");
    let pend = pend.to_str().unwrap();
    let set = run(&[&["--set", "L=1.07", "sweep", pend][..], &args[..]].concat());
    let nominal = run(&[&["sweep", pend][..], &args[..]].concat());
    assert!(set.status.success(), "{}", stderr(&set));
    assert_eq!(stdout(&set), stdout(&from_file));
    assert_ne!(stdout(&set), stdout(&nominal));
    let unknown = run(&["check", pend, "--set", "Lx=1"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(
        stderr(&unknown).contains("override 'Lx'"),
        "{}",
        stderr(&unknown)
    );
    let nan = run(&["check", pend, "--set", "L=nan"]);
    assert_eq!(nan.status.code(), Some(2));
}

#[test]
fn negative_counts_are_explained_not_mistaken_for_flags() {
    let o = run(&["analyze", "-o", "unused", "--samples", "-5"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("expected a whole number"), "{e}");
    assert!(!e.contains("-- -5"), "{e}");
}

#[test]
fn progress_goes_to_a_log_one_line_per_tenth() {
    // stderr is a pipe here, not a terminal: a batch job's log.
    let dir = tempfile::tempdir().unwrap();
    let o = run(&[
        "analyze",
        example("rotating_pendulum.toml").to_str().unwrap(),
        "-o",
        dir.path().join("a").to_str().unwrap(),
        "--speed",
        "3:4:0.1",
        "--samples",
        "640",
        "--case",
        "L3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(!e.contains('\r'), "{e}");
    let mc: Vec<&str> = e
        .lines()
        .filter(|l| l.starts_with("monte carlo L3: "))
        .collect();
    assert!((2..=11).contains(&mc.len()), "{e}");
    assert_eq!(mc.last(), Some(&"monte carlo L3: 640/640"), "{e}");
    assert!(e.lines().any(|l| l.starts_with("quadrature L3: ")), "{e}");
}

#[test]
fn check_columns_stay_aligned_for_long_names() {
    let text = std::fs::read_to_string(example("rotating_pendulum.toml")).unwrap();
    let long = "a_hinge_with_a_rather_long_name";
    let edited = text.replace("\"hinge\"", &format!("\"{long}\""));
    assert_ne!(edited, text);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.toml");
    std::fs::write(&path, edited).unwrap();
    let o = run(&["check", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let joints: Vec<&str> = s
        .lines()
        .skip_while(|l| !l.starts_with("  joints"))
        .skip(1)
        .take(2)
        .collect();
    // The type column starts at the same place on every joint line.
    let at = |l: &str, w: &str| l.find(w).unwrap_or_else(|| panic!("{w} in {l}"));
    assert_eq!(at(joints[0], "revolute"), at(joints[1], "revolute"), "{s}");
}

#[test]
fn modal_and_sensitivity_as_csv_name_the_shapes_and_give_elasticities() {
    let gov = example("governor.toml");
    let gov = gov.to_str().unwrap();
    let o = run(&["modal", gov, "--speed", "1.595", "--format", "csv"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let header: Vec<&str> = s.lines().next().unwrap().split(',').collect();
    for c in ["arm1", "arm2", "slide"] {
        assert!(header.contains(&format!("shape_re:{c}").as_str()), "{s}");
    }
    // The largest shape component is 1; the governor's equilibrium is the stable one reached.
    let cells: Vec<&str> = s.lines().nth(1).unwrap().split(',').collect();
    let row: Vec<f64> = (header.iter().zip(&cells))
        .filter(|(h, _)| h.starts_with("shape_"))
        .map(|(_, x)| x.parse().unwrap())
        .collect();
    assert_eq!(header[header.len() - 2..], ["branch", "message"]);
    assert_eq!(cells[cells.len() - 2..], ["stable", ""]);
    let largest = row.chunks(2).map(|z| z[0].hypot(z[1])).fold(0.0, f64::max);
    assert!((largest - 1.0).abs() < 1e-12, "{s}");
    let o = run(&["sensitivity", gov, "--speed", "1.595", "--format", "csv"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let header: Vec<&str> = s.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    for line in s.lines().skip(1) {
        let r: Vec<&str> = line.split(',').collect();
        let f = |n: &str| r[col(n)].parse::<f64>().unwrap();
        let e = f("value") / f("damped_frequency") * f("d_damped_frequency");
        assert!(
            (f("elasticity_damped_frequency") - e).abs() <= 1e-12 * e.abs(),
            "{line}"
        );
    }
    assert_eq!(s.lines().count(), 4, "{s}"); // one mode × three toleranced parameters
}

#[test]
fn sweep_gives_the_tuning_order_of_every_mode() {
    let o = run(&[
        "sweep",
        example("spinning_universal_pendulum.toml")
            .to_str()
            .unwrap(),
        "--speed",
        "0:2:0.5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    let header: Vec<&str> = s.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    for line in s.lines().skip(1) {
        let r: Vec<&str> = line.split(',').collect();
        let speed: f64 = r[col("speed")].parse().unwrap();
        let order = r[col("tuning_order")];
        if speed == 0.0 {
            assert!(order.is_empty(), "{line}");
        } else {
            let wd: f64 = r[col("damped_frequency")].parse().unwrap();
            assert_eq!(order.parse::<f64>().unwrap(), wd / speed, "{line}");
        }
    }
}

#[test]
fn a_requirement_range_beyond_the_speeds_is_refused_by_analyze_and_allocate() {
    // A range written in rpm by mistake: no analysed speed can judge it.
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("rpm.toml");
    let text = std::fs::read_to_string(common::example_path("rotating_pendulum.toml")).unwrap();
    std::fs::write(
        &model,
        format!("{text}\n[[requirements]]\nname = \"in_rpm\"\nkind = \"damping\"\nmode = 1\nmin = 0.1\nspeeds = [1000, 3000]\n"),
    )
    .unwrap();
    let out = dir.path().join("o");
    for args in [
        vec!["analyze", "--no-monte-carlo", "--speed", "0:6:0.5"],
        vec!["allocate", "--speed", "0:6:0.5"],
    ] {
        let mut a = args.clone();
        a.extend([model.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("--speed") && e.contains("'in_rpm'") && e.contains("1000–3000"),
            "{e}"
        );
        assert!(!out.exists(), "nothing written");
    }
}

/// The pendulum example with a requirement "ω_d ≥ 2 over 4–5 rad/s" appended, in `dir`.
fn pendulum_with_requirement(dir: &std::path::Path) -> std::path::PathBuf {
    let model = dir.join("req.toml");
    let text = std::fs::read_to_string(common::example_path("rotating_pendulum.toml")).unwrap();
    std::fs::write(
        &model,
        format!("{text}\n[[requirements]]\nname = \"clear\"\nkind = \"frequency\"\nmode = 1\nmin = 2.0\nspeeds = [4, 5]\n"),
    )
    .unwrap();
    model
}

/// `path`'s header and rows.
fn table(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (h, rows)
}

#[test]
fn limits_are_numbers_or_blank_with_a_reason_at_any_target_yield() {
    // Targets that no sample count resolves (10⁻³⁰⁰, 1 − 10⁻¹²) and a few samples: every
    // unbounded end is blank and says why; nothing is ±inf or NaN; the note is on stderr.
    let dir = tempfile::tempdir().unwrap();
    let model = pendulum_with_requirement(dir.path());
    for (i, target) in ["1e-300", "0.999999999999", "0.9"].into_iter().enumerate() {
        let out = dir.path().join(format!("o{i}"));
        let o = run(&[
            "analyze",
            model.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--speed",
            "4:5:0.5",
            "--samples",
            "64",
            "--target-yield",
            target,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let (h, rows) = table(&out.join("limits.csv"));
        let col = |n: &str| h.iter().position(|c| c == n).unwrap();
        assert_eq!(h.last().map(String::as_str), Some("reason"));
        let mut blanks = 0;
        for r in &rows {
            assert_eq!(r[col("target")], target.parse::<f64>().unwrap().to_string());
            for cell in r {
                let l = cell.to_lowercase();
                assert!(!l.contains("inf") && !l.contains("nan"), "{r:?}");
            }
            let blank = ["margin_at_target", "margin_low", "margin_high"]
                .iter()
                .any(|c| r[col(c)].is_empty());
            if blank {
                blanks += 1;
                assert!(
                    !r[col("reason")].is_empty(),
                    "a blank without a reason: {r:?}"
                );
            } else {
                assert!(r[col("reason")].is_empty(), "{r:?}");
            }
        }
        let e = stderr(&o);
        if i < 2 {
            assert!(
                blanks > 0 && e.contains("expected beyond the margin"),
                "{e}"
            );
        } else {
            assert!(!e.contains("expected beyond the margin"), "{e}");
        }
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(
            summary["yield"]["target_yield"].as_f64(),
            Some(target.parse().unwrap())
        );
    }
}

#[test]
fn a_target_yield_outside_zero_one_and_sobol_in_a_shard_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = pendulum_with_requirement(dir.path());
    let out = dir.path().join("o");
    let m = model.to_str().unwrap();
    let o = out.to_str().unwrap();
    for (args, flag) in [
        (
            vec!["analyze", m, "-o", o, "--target-yield", "1"],
            "--target-yield",
        ),
        (
            vec!["analyze", m, "-o", o, "--target-yield", "0"],
            "--target-yield",
        ),
        (
            vec!["analyze", m, "-o", o, "--target-yield", "NaN"],
            "--target-yield",
        ),
        (
            vec!["analyze", m, "-o", o, "--target-yield", "-0.5"],
            "--target-yield",
        ),
        (
            vec!["allocate", m, "-o", o, "--target-yield", "1.5"],
            "--target-yield",
        ),
        (
            vec![
                "merge",
                "--model",
                m,
                "-o",
                o,
                "--target-yield",
                "2",
                "x.json",
            ],
            "--target-yield",
        ),
        (
            vec!["analyze", m, "-o", o, "--shard", "1/2", "--sobol", "16"],
            "--sobol",
        ),
    ] {
        let r = run(&args);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(flag), "{args:?}: {}", stderr(&r));
        assert!(!out.exists(), "{args:?}: nothing written");
    }
}

#[test]
fn sobol_indices_refused_for_a_correlated_case_are_said_on_stderr_and_in_the_summary() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("corr.toml");
    let text = std::fs::read_to_string(common::example_path("rotating_pendulum.toml")).unwrap();
    std::fs::write(
        &model,
        format!("{text}\n[[analysis.cases]]\nname = \"tied\"\ntolerances = {{ L = \"3%\", c = \"5%\" }}\ncorrelation = [[1, 0.5], [0.5, 1]]\n"),
    )
    .unwrap();
    let out = dir.path().join("o");
    let o = run(&[
        "analyze",
        model.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--speed",
        "4:5:0.5",
        "--no-monte-carlo",
        "--no-quadrature",
        "--case",
        "tied",
        "--sobol",
        "16",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no Sobol indices for case 'tied'"),
        "{}",
        stderr(&o)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let refused = summary["sobol_refused"].as_array().unwrap();
    assert_eq!(refused.len(), 1);
    assert_eq!(refused[0]["case"], "tied");
    assert!(
        refused[0]["reason"]
            .as_str()
            .unwrap()
            .contains("correlation")
    );
}
