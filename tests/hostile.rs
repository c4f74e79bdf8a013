//! The real binary over the corpus of broken and adversarial models in `tests/bad_models/`:
//! every file gets exit code 2 and one bounded, clear error naming the file (and the line and
//! column where there is one), and nothing panics.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

fn check(path: &Path) -> (Option<i32>, String, Duration) {
    let t = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_modaltol"))
        .arg("check")
        .arg(path)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        t.elapsed(),
    )
}

#[test]
fn every_hostile_model_gets_a_located_error_and_no_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_models");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 30, "corpus has {} files", files.len());
    // Errors about the whole file have no line to point at.
    let whole_file = ["no_bodies.toml"];
    for f in &files {
        let (code, err, took) = check(f);
        let name = f.file_name().unwrap().to_str().unwrap();
        assert_eq!(code, Some(2), "{name}: exit code {code:?}, stderr {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(
            err.starts_with(&format!("modaltol: error: {}:", f.display())),
            "{name}: {err}"
        );
        if !whole_file.contains(&name) {
            let rest = &err[format!("modaltol: error: {}:", f.display()).len()..];
            let mut parts = rest.splitn(3, ':');
            let line: usize = parts
                .next()
                .unwrap()
                .parse()
                .unwrap_or_else(|_| panic!("{name}: no line in {err}"));
            let col: usize = parts
                .next()
                .unwrap()
                .parse()
                .unwrap_or_else(|_| panic!("{name}: no column in {err}"));
            assert!(line >= 1 && col >= 1);
        }
        assert!(err.len() < 1500, "{name}: message of {} bytes", err.len());
        assert!(took < Duration::from_secs(5), "{name}: took {took:?}");
    }
}

#[test]
fn a_ten_megabyte_file_is_refused_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("huge.toml");
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/rotating_pendulum.toml"),
    )
    .unwrap();
    let mut text = base.clone();
    while text.len() < 10 << 20 {
        text.push_str("# padding padding padding padding padding padding padding padding\n");
    }
    std::fs::write(&f, text).unwrap();
    let (code, err, took) = check(&f);
    assert_eq!(code, Some(2));
    assert!(err.contains("model files are limited"), "{err}");
    assert!(took < Duration::from_secs(2));
}
