//! Where the real binary's results land: on a mount point, through links, with the umask's
//! permissions, never over an input; complete or absent.

mod common;

use common::Run;
use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

fn run(args: &[&str]) -> Run {
    common::run_with_deadline(args, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `script` in `sh` with `$M` the binary (under a deadline).
fn shell(script: &str) -> Run {
    let mut cmd = Command::new("sh");
    cmd.env("M", env!("CARGO_BIN_EXE_modaltol"))
        .arg("-c")
        .arg(script);
    common::command_with_deadline(cmd, Duration::from_secs(120)).unwrap_or_else(|e| panic!("{e}"))
}

fn pendulum() -> String {
    common::example_path("rotating_pendulum.toml")
        .display()
        .to_string()
}

/// What every command writes with `-o OUT` (`OUT` where the output goes), cheaply.
fn commands(model: &str) -> Vec<Vec<String>> {
    let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    vec![
        v(&["modal", model, "--speed", "1", "-o", "OUT"]),
        v(&[
            "modal", model, "--speed", "1", "--format", "csv", "-o", "OUT",
        ]),
        v(&["sweep", model, "--speed", "0:1:0.5", "-o", "OUT"]),
        v(&["sensitivity", model, "--speed", "1", "-o", "OUT"]),
        v(&["frf", model, "--speed", "1", "--freq", "1:2:1", "-o", "OUT"]),
        v(&[
            "frf", model, "--speed", "1", "--freq", "1:2:1", "--out", "OUT",
        ]),
    ]
}

fn with_output(args: &[String], out: &str) -> Vec<String> {
    args.iter()
        .map(|a| {
            if a == "OUT" {
                out.to_string()
            } else {
                a.clone()
            }
        })
        .collect()
}

#[test]
fn an_output_that_is_an_input_is_refused_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = d.join("m.toml");
    std::fs::write(&model, common::example_text("rotating_pendulum.toml")).unwrap();
    std::fs::hard_link(&model, d.join("hard.toml")).unwrap();
    std::os::unix::fs::symlink("m.toml", d.join("soft.toml")).unwrap();
    let original = std::fs::read(&model).unwrap();
    let m = model.to_str().unwrap();
    for args in commands(m) {
        for out in ["m.toml", "hard.toml", "soft.toml"] {
            let args = with_output(&args, d.join(out).to_str().unwrap());
            let o = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
            assert_eq!(o.code, Some(2), "{args:?}: {}", o.stderr);
            assert!(o.stderr.contains("is the input"), "{args:?}: {}", o.stderr);
            assert_eq!(std::fs::read(&model).unwrap(), original, "{args:?}");
        }
    }
    // The model through a link, the output its target.
    let o = run(&[
        "sweep",
        d.join("soft.toml").to_str().unwrap(),
        "--speed",
        "0:1:1",
        "-o",
        m,
    ]);
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    // A shard whose file would be the model; a merge whose directory would replace a shard.
    let shard_dir = d.join("s");
    std::fs::create_dir(&shard_dir).unwrap();
    let as_shard = shard_dir.join("shard-1-of-1.json");
    std::fs::copy(&model, &as_shard).unwrap();
    let o = run(&[
        "analyze",
        as_shard.to_str().unwrap(),
        "-o",
        shard_dir.to_str().unwrap(),
        "--shard",
        "1/1",
        "--speed",
        "0:1:1",
        "--samples",
        "10",
    ]);
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    assert_eq!(std::fs::read(&as_shard).unwrap(), original);
    // A model lying in the result directory under a result's name is never replaced, and is
    // refused as bad arguments before anything is computed (5·10⁴ speeds × 10⁵ samples would
    // not finish within the test's time).
    let results = d.join("results");
    std::fs::create_dir(&results).unwrap();
    for name in ["report.html", "tolerance.csv", "summary.json", "x.svg"] {
        let inside = results.join(name);
        std::fs::copy(&model, &inside).unwrap();
        let o = run(&[
            "analyze",
            inside.to_str().unwrap(),
            "-o",
            results.to_str().unwrap(),
            "--speed",
            "0:5:0.0001",
            "--samples",
            "100000",
        ]);
        assert_eq!(o.code, Some(2), "{name}: {}", o.stderr);
        assert!(o.stderr.contains("is the input"), "{name}: {}", o.stderr);
        assert_eq!(std::fs::read(&inside).unwrap(), original);
        assert_eq!(
            std::fs::read_dir(&results).unwrap().count(),
            1,
            "{name}: a result was written"
        );
        std::fs::remove_file(&inside).unwrap();
    }
    // A shard lying in the merge's result directory under a result's name, likewise.
    let o = run(&[
        "analyze",
        m,
        "-o",
        shard_dir.to_str().unwrap(),
        "--shard",
        "1/1",
        "--speed",
        "0:1:1",
        "--samples",
        "10",
    ]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let shard = results.join("summary.json");
    std::fs::rename(shard_dir.join("shard-1-of-1.json"), &shard).unwrap();
    let shard_bytes = std::fs::read(&shard).unwrap();
    let o = run(&[
        "merge",
        "--model",
        m,
        "-o",
        results.to_str().unwrap(),
        shard.to_str().unwrap(),
    ]);
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    assert!(o.stderr.contains("is the input"), "{}", o.stderr);
    assert_eq!(std::fs::read(&shard).unwrap(), shard_bytes);
}

#[test]
fn files_and_directories_get_the_permissions_the_umask_allows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let m = pendulum();
    for (umask, file, directory) in [
        ("022", 0o644, 0o755),
        ("027", 0o640, 0o750),
        ("002", 0o664, 0o775),
    ] {
        let o = shell(&format!(
            "umask {umask} && \"$M\" sweep {m} --speed 0:1:1 -o {d}/s{umask}.csv && \
             \"$M\" analyze {m} -o {d}/r{umask} --speed 0:1:1 --samples 10 && \
             \"$M\" analyze {m} -o {d}/h{umask} --speed 0:1:1 --samples 10 --shard 1/1"
        ));
        assert_eq!(o.code, Some(0), "{}", o.stderr);
        let mode = |p: String| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(
            mode(format!("{d}/s{umask}.csv")),
            file,
            "umask {umask}: sweep"
        );
        assert_eq!(
            mode(format!("{d}/r{umask}")),
            directory,
            "umask {umask}: analyze"
        );
        for f in ["tolerance.csv", "report.html", "manifest.json"] {
            assert_eq!(
                mode(format!("{d}/r{umask}/{f}")),
                file,
                "umask {umask}: {f}"
            );
        }
        assert_eq!(
            mode(format!("{d}/h{umask}/shard-1-of-1.json")),
            file,
            "umask {umask}: shard"
        );
    }
}

#[test]
fn an_output_named_by_a_link_is_written_where_the_link_points() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = pendulum();
    std::fs::create_dir(d.join("real")).unwrap();
    std::os::unix::fs::symlink("real", d.join("results")).unwrap();
    std::os::unix::fs::symlink("real/s.csv", d.join("s.csv")).unwrap();
    for seed in ["1", "2"] {
        let o = run(&[
            "analyze",
            &m,
            "-o",
            d.join("results").to_str().unwrap(),
            "--speed",
            "0:1:1",
            "--samples",
            "10",
            "--seed",
            seed,
        ]);
        assert_eq!(o.code, Some(0), "{}", o.stderr);
        let o = run(&[
            "sweep",
            &m,
            "--speed",
            "0:1:1",
            "-o",
            d.join("s.csv").to_str().unwrap(),
        ]);
        assert_eq!(o.code, Some(0), "{}", o.stderr);
        for link in ["results", "s.csv"] {
            assert!(
                d.join(link)
                    .symlink_metadata()
                    .unwrap()
                    .file_type()
                    .is_symlink(),
                "{link}"
            );
        }
        assert!(d.join("real/tolerance.csv").is_file() && d.join("real/s.csv").is_file());
        let summary = std::fs::read_to_string(d.join("real/summary.json")).unwrap();
        assert!(
            summary.contains(&format!("\"seed\": {seed}")),
            "seed {seed}"
        );
    }
}

/// Runs `script` in a private mount namespace where `$VOL` is the root of a fresh tmpfs
/// mount whose parent is read-only (a container's volume); `None` where this system gives no
/// mount namespaces to an unprivileged user.
fn in_a_volume(dir: &Path, script: &str) -> Option<Run> {
    let vol = dir.join("vol");
    std::fs::create_dir(&vol).unwrap();
    let probe = Command::new("unshare").args(["-rm", "true"]).status();
    if !probe.is_ok_and(|s| s.success()) {
        eprintln!("no mount namespace here (unshare -rm): the mount-point test did not run");
        return None;
    }
    let file = dir.join("script.sh");
    std::fs::write(
        &file,
        format!(
            "mount -t tmpfs none \"$VOL\" && chmod 555 {} && {script}",
            dir.display()
        ),
    )
    .unwrap();
    Some(shell(&format!(
        "VOL={vol} unshare -rm sh {file}; status=$?; chmod 755 {dir}; exit $status",
        vol = vol.display(),
        file = file.display(),
        dir = dir.display(),
    )))
}

#[test]
fn an_output_onto_a_mount_point_is_written_on_its_file_system() {
    let dir = tempfile::tempdir().unwrap();
    let m = pendulum();
    let script = format!(
        "echo mine > \"$VOL/notes.txt\" && \
         \"$M\" analyze {m} -o \"$VOL\" --speed 0:1:1 --samples 10 --seed 1 && \
         \"$M\" analyze {m} -o \"$VOL\" --speed 0:1:1 --samples 10 --seed 2 && \
         \"$M\" sweep {m} --speed 0:1:1 -o \"$VOL/s.csv\" && \
         \"$M\" analyze {m} -o \"$VOL/sub\" --speed 0:1:1 --samples 10 && \
         grep -q '\"seed\": 2' \"$VOL/summary.json\" && cat \"$VOL/notes.txt\" && \
         ls -a \"$VOL\" \"$VOL/sub\" && ls -a {dir}",
        dir = dir.path().display()
    );
    let Some(o) = in_a_volume(dir.path(), &script) else {
        return;
    };
    assert_eq!(o.code, Some(0), "{}\n{}", o.stdout, o.stderr);
    assert!(o.stdout.starts_with("mine\n"), "{}", o.stdout);
    // Nothing staged is left, in the volume or beside it.
    assert!(!o.stdout.contains(".partial"), "{}", o.stdout);
    for f in ["manifest.json", "tolerance.csv", "s.csv", "sub"] {
        assert!(
            o.stdout.lines().any(|l| l == f),
            "{f} missing: {}",
            o.stdout
        );
    }
}

/// Runs the binary with `args` as an unprivileged user (`setpriv` to `nobody` when the tests
/// run as root, for whom permissions do not hold).
fn unprivileged(args: &[&str]) -> Run {
    let root = std::fs::metadata("/proc/self").is_ok_and(|m| {
        use std::os::unix::fs::MetadataExt;
        m.uid() == 0
    });
    let mut cmd = if root {
        let mut c = Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_modaltol"));
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_modaltol"))
    };
    cmd.args(args);
    common::command_with_deadline(cmd, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_target_that_cannot_take_the_results_is_refused_before_anything_is_computed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mode = |p: &Path, m: u32| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
    mode(d, 0o777).unwrap();
    let m = pendulum();
    // A directory of the user's that they may not write: refused at once, untouched.
    let locked = d.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::write(locked.join("notes.txt"), b"mine").unwrap();
    mode(&locked, 0o555).unwrap();
    let t = std::time::Instant::now();
    let long = ["--speed", "0:6:0.01", "--samples", "100000"];
    let mut args = vec!["analyze", &m, "-o", locked.to_str().unwrap()];
    args.extend(long);
    let o = unprivileged(&args);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(
        o.stderr.contains("locked") && o.stderr.contains("ermission"),
        "{}",
        o.stderr
    );
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "refused only after computing"
    );
    let o = unprivileged(&[
        "sweep",
        &m,
        "--speed",
        "0:6000:0.01",
        "-o",
        locked.join("s.csv").to_str().unwrap(),
    ]);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "refused only after computing"
    );
    // A writable target in a parent that is not: staged inside, written.
    let parent = d.join("parent");
    let target = parent.join("results");
    std::fs::create_dir_all(&target).unwrap();
    mode(&target, 0o777).unwrap();
    mode(&parent, 0o555).unwrap();
    let o = unprivileged(&[
        "analyze",
        &m,
        "-o",
        target.to_str().unwrap(),
        "--speed",
        "0:1:1",
        "--samples",
        "10",
    ]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    modaltol::files::Manifest::read(&target)
        .unwrap()
        .verify(&target)
        .unwrap();
    assert!(
        !std::fs::read_dir(&target).unwrap().any(|e| e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .starts_with('.'))
    );
    mode(&parent, 0o755).unwrap();
    mode(&locked, 0o755).unwrap();
}

/// A device or a named pipe given to `-o` is written to, as a shell's `>` writes, never
/// replaced by a file (which, run as root on `/dev/null`, would destroy the device).
#[test]
fn an_output_onto_a_device_or_a_pipe_is_written_to_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let m = common::example_path("rotating_pendulum.toml");
    let m = m.to_str().unwrap();
    for args in [
        vec!["sweep", m, "--speed", "0:2:1", "-o", "/dev/null"],
        vec!["modal", m, "--speed", "1", "-o", "/dev/null"],
        vec!["sensitivity", m, "--speed", "1", "-o", "/dev/null"],
    ] {
        let o = run(&args);
        assert_eq!(o.code, Some(0), "{args:?}: {}", o.stderr);
        let kind = std::fs::metadata("/dev/null").unwrap().file_type();
        assert!(kind.is_char_device(), "{args:?}: /dev/null was replaced");
    }
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let o = run(&["sweep", m, "--speed", "0:2:1", "-o", fifo.to_str().unwrap()]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let text = reader.join().unwrap();
    assert!(text.starts_with("speed,mode,"), "{text}");
    assert_eq!(text.lines().count(), 4, "{text}");
    let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(kind.is_fifo(), "the pipe was replaced");
    // `/dev/stdout` is the process's standard output, whatever it is (here a pipe).
    let o = run(&["sweep", m, "--speed", "0:2:1", "-o", "/dev/stdout"]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(o.stdout.starts_with("speed,mode,"), "{}", o.stdout);
}
