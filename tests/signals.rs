//! The real binary interrupted and deprived of its standard streams: SIGINT and SIGTERM stop
//! every command alike (exit 128 + the signal, a result complete or absent, nothing left
//! behind); a killed run's leftovers go with the next run; stderr that cannot be written
//! stops nothing; a closed stdout is an error, a reader that stops reading is not.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_modaltol"))
}

fn example(name: &str) -> String {
    common::example_path(name).display().to_string()
}

/// Hidden entries of `dir` (staging files and directories).
fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// Starts `args` with stderr piped and waits for its first progress line (or, for commands
/// without progress, `wait`).
fn start(args: &[&str], wait: Option<Duration>) -> (Child, Vec<String>) {
    let mut child = bin()
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut seen = Vec::new();
    match wait {
        Some(d) => std::thread::sleep(d),
        None => {
            let mut err = BufReader::new(child.stderr.as_mut().unwrap());
            let mut line = String::new();
            err.read_line(&mut line).unwrap();
            seen.push(line);
        }
    }
    (child, seen)
}

/// Sends `signal` (`INT`, `TERM`, `KILL`) to `child`.
fn kill(child: &Child, signal: &str) {
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
}

/// Waits for `child` at most a minute; its exit code and the rest of its stderr.
fn finish(mut child: Child) -> (Option<i32>, String) {
    let t = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "still running a minute after the signal"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let o = child.wait_with_output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn sigint_and_sigterm_stop_every_command_with_128_plus_the_signal() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let governor = example("governor.toml");
    let pendulum = example("rotating_pendulum.toml");
    let out = |name: &str| d.join(name).display().to_string();
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        // Commands whose output is a file: nothing of it is written, nothing is left.
        let sweep = out("sweep.csv");
        let frf = out("frf.csv");
        let shard = out("shard");
        let runs: Vec<(Vec<&str>, Option<Duration>, String)> = vec![
            (
                vec!["sweep", &governor, "--speed", "0:1000:0.0001", "-o", &sweep],
                None,
                sweep.clone(),
            ),
            (
                vec!["sweep", &governor, "--speed", "0:1000:0.0001"],
                None,
                String::new(),
            ),
            (
                vec![
                    "frf",
                    &pendulum,
                    "--speed",
                    "1",
                    "--freq",
                    "0:600:0.0001",
                    "-o",
                    &frf,
                ],
                Some(Duration::from_millis(800)),
                frf.clone(),
            ),
            (
                vec![
                    "analyze",
                    &pendulum,
                    "-o",
                    &shard,
                    "--speed",
                    "1:1.5:0.5",
                    "--samples",
                    "100000000",
                    "--shard",
                    "1/2",
                ],
                None,
                format!("{shard}/shard-1-of-2.json"),
            ),
        ];
        for (args, wait, file) in runs {
            let (child, _) = start(&args, wait);
            kill(&child, signal);
            let (got, stderr) = finish(child);
            assert_eq!(got, Some(code), "SIG{signal} {args:?}: {stderr}");
            assert!(
                stderr.contains("interrupted"),
                "SIG{signal} {args:?}: {stderr}"
            );
            if !file.is_empty() {
                assert!(
                    !Path::new(&file).exists(),
                    "SIG{signal} {args:?}: {file} written"
                );
            }
            assert!(
                hidden(d).is_empty(),
                "SIG{signal} {args:?}: left {:?}",
                hidden(d)
            );
        }
        // An analysis writes its partial result, flagged.
        let results = out(&format!("results-{signal}"));
        let (child, _) = start(
            &[
                "analyze",
                &pendulum,
                "-o",
                &results,
                "--speed",
                "1:1.5:0.5",
                "--samples",
                "100000000",
            ],
            None,
        );
        std::thread::sleep(Duration::from_millis(500));
        kill(&child, signal);
        let (got, stderr) = finish(child);
        assert_eq!(got, Some(code), "SIG{signal} analyze: {stderr}");
        let summary = std::fs::read_to_string(Path::new(&results).join("summary.json")).unwrap();
        assert!(summary.contains("\"partial\": true"), "SIG{signal}");
        assert!(
            hidden(d).is_empty(),
            "SIG{signal} analyze: left {:?}",
            hidden(d)
        );
    }
}

#[test]
fn a_second_signal_stops_at_once_and_the_next_run_removes_what_a_killed_run_left() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let governor = example("governor.toml");
    let target = d.join("s.csv").display().to_string();
    let args = [
        "sweep",
        &governor,
        "--speed",
        "0:1000:0.0001",
        "-o",
        &target,
    ];
    let (child, _) = start(&args, None);
    kill(&child, "KILL");
    let _ = finish(child);
    let (child, _) = start(
        &[
            "analyze",
            &governor,
            "-o",
            d.join("r").to_str().unwrap(),
            "--samples",
            "100000000",
        ],
        None,
    );
    kill(&child, "KILL");
    let _ = finish(child);
    assert_eq!(
        hidden(d).len(),
        2,
        "the killed runs left no staging: {:?}",
        hidden(d)
    );
    let o = bin()
        .args(["sweep", &governor, "--speed", "0:1:1", "-o", &target])
        .output()
        .unwrap();
    assert!(o.status.success());
    let o = bin()
        .args([
            "analyze",
            &governor,
            "-o",
            d.join("r").to_str().unwrap(),
            "--speed",
            "1:1:1",
            "--samples",
            "10",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(hidden(d).is_empty(), "left {:?}", hidden(d));
    // The same signal twice: the run ends at once, with its code.
    let (child, _) = start(&args, None);
    kill(&child, "TERM");
    kill(&child, "TERM");
    assert_eq!(finish(child).0, Some(143));
}

/// Runs `script` in `sh` with `$M` the binary.
fn sh(script: &str) -> common::Run {
    let mut cmd = Command::new("sh");
    cmd.env("M", env!("CARGO_BIN_EXE_modaltol"))
        .arg("-c")
        .arg(script);
    common::command_with_deadline(cmd, Duration::from_secs(120)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn stderr_that_cannot_be_written_stops_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let m = example("rotating_pendulum.toml");
    for stderr in ["2>/dev/full", "2>&-"] {
        let o = sh(&format!(
            "\"$M\" analyze {m} -o {d}/r --speed 0:1:0.5 --samples 50 {stderr} && \
             \"$M\" sweep {m} --speed 0:3000:0.5 -o {d}/s.csv {stderr} && \
             \"$M\" modal {m} --speed 1e308 {stderr}; echo \"modal $?\""
        ));
        assert_eq!(o.code, Some(0), "{stderr}: {}", o.stderr);
        assert!(o.stdout.ends_with("modal 1\n"), "{stderr}: {}", o.stdout);
        assert!(!o.stdout.contains("panicked") && !o.stderr.contains("panicked"));
        modaltol::files::Manifest::read(&dir.path().join("r"))
            .unwrap()
            .verify(&dir.path().join("r"))
            .unwrap();
    }
}

#[test]
fn a_closed_stdout_is_an_error_and_other_write_failures_too() {
    let m = example("rotating_pendulum.toml");
    for command in [
        format!("sweep {m} --speed 0:1:0.5"),
        format!("check {m}"),
        format!("modal {m} --speed 1 --format json"),
        format!("sensitivity {m} --speed 1"),
        format!("frf {m} --speed 1 --freq 1:2:1"),
    ] {
        for (redirect, why) in [(">&-", "stdout is closed"), (">/dev/full", "No space left")] {
            let o = sh(&format!("\"$M\" {command} {redirect}"));
            assert_eq!(o.code, Some(1), "{command} {redirect}: {}", o.stderr);
            assert!(o.stderr.contains(why), "{command} {redirect}: {}", o.stderr);
        }
        // Thrown away on purpose: a success.
        assert_eq!(sh(&format!("\"$M\" {command} >/dev/null")).code, Some(0));
    }
}

#[test]
fn a_partial_result_goes_beside_a_complete_one_and_never_replaces_it() {
    let dir = tempfile::tempdir().unwrap();
    let pendulum = example("rotating_pendulum.toml");
    let results = dir.path().join("results");
    let r = results.display().to_string();
    // A complete result first.
    let done = bin()
        .args([
            "analyze",
            &pendulum,
            "-o",
            &r,
            "--speed",
            "1:1.5:0.5",
            "--samples",
            "50",
        ])
        .output()
        .unwrap();
    assert!(done.status.success());
    let before = std::fs::read(results.join("summary.json")).unwrap();
    let manifest = std::fs::read(results.join("manifest.json")).unwrap();
    for (round, signal) in ["TERM", "INT"].into_iter().enumerate() {
        let (child, _) = start(
            &[
                "analyze",
                &pendulum,
                "-o",
                &r,
                "--speed",
                "1:1.5:0.5",
                "--samples",
                "100000000",
            ],
            None,
        );
        std::thread::sleep(Duration::from_millis(500));
        kill(&child, signal);
        let (_, stderr) = finish(child);
        // The complete result is as it was; the partial one is beside it, flagged, and the
        // message says where (the second replaces the first partial one there).
        assert_eq!(std::fs::read(results.join("summary.json")).unwrap(), before);
        assert_eq!(
            std::fs::read(results.join("manifest.json")).unwrap(),
            manifest
        );
        let beside = dir.path().join("results.partial");
        let summary = std::fs::read_to_string(beside.join("summary.json")).unwrap();
        assert!(summary.contains("\"partial\": true"), "round {round}");
        assert!(
            stderr.contains("is kept") && stderr.contains("results.partial"),
            "{stderr}"
        );
        assert!(
            hidden(dir.path()).is_empty(),
            "left {:?}",
            hidden(dir.path())
        );
    }
    // A complete run replaces the complete one as before; the partial one beside it stays.
    let again = bin()
        .args([
            "analyze",
            &pendulum,
            "-o",
            &r,
            "--speed",
            "1:1.5:0.5",
            "--samples",
            "60",
        ])
        .output()
        .unwrap();
    assert!(again.status.success());
    assert_ne!(std::fs::read(results.join("summary.json")).unwrap(), before);
}
