//! Fuzzing of the whole pipeline through the real binary: mutated example models through
//! `check`, `modal`, a short `sweep` and a short `analyze`, each under a deadline.
//!
//! A run passes when nothing panics, nothing hangs, every exit code is 0, 1 or 2, no output
//! holds a non-finite number outside a row whose status is `failed`, and every row of
//! `tolerance.csv` without a mean says why (and only those). The mutations aim at the
//! defect classes found before: extreme and degenerate numbers in place of any number of the
//! model, non-finite expressions, deleted and duplicated lines, random bytes.
//!
//! The inputs that once broke something are kept in `tests/fuzz_corpus/pipeline/` and replayed
//! first. A failing mutant is written to `target/fuzz-failures/` for adding to that corpus.
//! Budget: `FUZZ_SECONDS` (default 40 s, so CI stays short); seed: `FUZZ_SEED`. A long run:
//! `FUZZ_SECONDS=1800 cargo test --release --test fuzz_pipeline -- --nocapture`.

mod common;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Numbers that broke things before, and their neighbours.
const EXTREMES: [&str; 22] = [
    "0",
    "-0.0",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "-5e-324",
    "1e-300",
    "1e200",
    "-1e200",
    "1e-12",
    "-1",
    "1e15",
    "\"exp(1000)\"",
    "\"0*exp(1000)\"",
    "\"exp(speed*1000)\"",
    "\"1/(speed-1)\"",
    "\"sqrt(-1)\"",
    "\"ln(0)\"",
    "\"speed^400\"",
    "\"1e308*speed\"",
    "\"-speed*1e300\"",
];

/// Byte ranges of the number literals of a TOML text (outside comments).
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_comment = false;
    while i < b.len() {
        match b[i] {
            b'#' => in_comment = true,
            b'\n' => in_comment = false,
            c if !in_comment
                && (c.is_ascii_digit() || c == b'-')
                && (i == 0 || matches!(b[i - 1], b' ' | b'[' | b',' | b'=' | b'{')) =>
            {
                let start = i;
                i += 1;
                while i < b.len() && matches!(b[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+')
                {
                    i += 1;
                }
                if i - start > 1 || c.is_ascii_digit() {
                    out.push((start, i));
                }
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

fn mutate(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut t = text.to_string();
    for _ in 0..rng.random_range(1..=3) {
        match rng.random_range(0..10) {
            0..=5 => {
                let nums = numbers(&t);
                if nums.is_empty() {
                    continue;
                }
                let (a, b) = nums[rng.random_range(0..nums.len())];
                let with = EXTREMES[rng.random_range(0..EXTREMES.len())];
                t.replace_range(a..b, with);
            }
            6 => {
                let lines: Vec<&str> = t.lines().collect();
                let k = rng.random_range(0..lines.len());
                t = lines
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != k)
                    .map(|(_, l)| *l)
                    .collect::<Vec<_>>()
                    .join("\n");
            }
            7 => {
                let lines: Vec<&str> = t.lines().collect();
                let k = rng.random_range(0..lines.len());
                let mut v: Vec<&str> = lines.clone();
                v.insert(k, lines[k]);
                t = v.join("\n");
            }
            _ => {
                let mut bytes = t.into_bytes();
                let k = rng.random_range(0..bytes.len());
                bytes[k] = rng.random_range(0x20..0x7f);
                t = String::from_utf8_lossy(&bytes).into_owned();
            }
        }
    }
    t
}

/// Runs the binary under a deadline: `(exit code, stdout, stderr)`, or `Err` on a hang.
fn run(args: &[&str], limit: Duration) -> Result<(Option<i32>, String, String), String> {
    common::run_with_deadline(args, limit).map(|r| (r.code, r.stdout, r.stderr))
}

fn non_finite(cell: &str) -> bool {
    let c = cell.trim().to_ascii_lowercase();
    c == "nan" || c == "inf" || c == "-inf" || c == "+inf" || c.contains("nan") && c.len() <= 4
}

/// Checks a CSV: no non-finite cell unless the row says `failed`.
fn check_csv(text: &str) -> Result<(), String> {
    for line in text.lines().skip(1) {
        if line.contains(",failed,") {
            continue;
        }
        if let Some(c) = line.split(',').find(|c| non_finite(c)) {
            return Err(format!("non-finite cell '{c}' in: {line}"));
        }
    }
    Ok(())
}

/// Checks `tolerance.csv`: a row without a mean or a σ says why (its `reason`), and only such
/// a row.
fn check_reasons(text: &str) -> Result<(), String> {
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header = rows.headers().map_err(|e| e.to_string())?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| h == n)
            .ok_or(format!("no column {n}"))
    };
    let (mean, std, reason) = (col("mean")?, col("std")?, col("reason")?);
    for row in rows.records() {
        let row = row.map_err(|e| e.to_string())?;
        let incomplete = row[mean].is_empty() || row[std].is_empty();
        if incomplete == row[reason].is_empty() {
            return Err(format!("a row's mean and reason: {row:?}"));
        }
    }
    Ok(())
}

/// Runs one model through the pipeline; `Err` says what went wrong.
fn pipeline(model: &Path, out: &Path, analyze: bool) -> Result<(), String> {
    let m = model.to_str().unwrap();
    let limit = Duration::from_secs(30);
    let judge = |what: &str, r: (Option<i32>, String, String)| -> Result<String, String> {
        let (code, stdout, stderr) = r;
        if stderr.contains("panicked") {
            return Err(format!("{what} panicked: {stderr}"));
        }
        if !matches!(code, Some(0..=2)) {
            return Err(format!("{what} exit {code:?}: {stderr}"));
        }
        Ok(stdout)
    };
    let (code, _, stderr) = run(&["check", m], limit)?;
    if stderr.contains("panicked") || !matches!(code, Some(0 | 2)) {
        return Err(format!("check exit {code:?}: {stderr}"));
    }
    if code != Some(0) {
        return Ok(());
    }
    let table = judge("modal", run(&["modal", m, "--speed", "1"], limit)?)?;
    // A failed point's reason may quote an infinite condition number; results may not.
    let results: String = table
        .lines()
        .filter(|l| !l.starts_with("FAILED"))
        .collect::<Vec<_>>()
        .join("\n");
    if results.to_ascii_lowercase().contains("nan") || results.contains(" inf") {
        return Err(format!("modal printed a non-finite number: {table}"));
    }
    let csv = judge("sweep", run(&["sweep", m, "--speed", "0:4:1"], limit)?)?;
    check_csv(&csv).map_err(|e| format!("sweep: {e}"))?;
    if analyze {
        let o = out.to_str().unwrap();
        judge(
            "analyze",
            run(
                &["analyze", m, "-o", o, "--speed", "0:2:1", "--samples", "16"],
                Duration::from_secs(120),
            )?,
        )?;
        if let Ok(text) = std::fs::read_to_string(out.join("tolerance.csv")) {
            check_csv(&text).map_err(|e| format!("analyze: {e}"))?;
            check_reasons(&text).map_err(|e| format!("analyze: {e}"))?;
        }
    }
    Ok(())
}

fn keep_failure(text: &str, why: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-failures");
    std::fs::create_dir_all(&dir).unwrap();
    let name = format!("{:016x}.toml", fxhash(text.as_bytes()));
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!("# {}\n{text}", why.lines().next().unwrap_or("")),
    )
    .unwrap();
    path
}

/// A small stable hash for file names (FNV-1a).
fn fxhash(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf29ce484222325u64, |h, &x| {
        (h ^ x as u64).wrapping_mul(0x100000001b3)
    })
}

#[test]
fn mutated_models_through_the_whole_pipeline() {
    let budget = Duration::from_secs(
        std::env::var("FUZZ_SECONDS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(40),
    );
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(14);
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("mutant.toml");
    let out = dir.path().join("out");
    let mut failures = Vec::new();
    // The corpus first.
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_corpus/pipeline");
    let mut replayed = 0;
    if let Ok(entries) = std::fs::read_dir(&corpus) {
        let mut files: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        files.sort();
        for f in files {
            if let Err(e) = pipeline(&f, &out, true) {
                failures.push(format!("{}: {e}", f.display()));
            }
            replayed += 1;
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let texts: Vec<String> = common::EXAMPLES
        .iter()
        .map(|e| common::example_text(e))
        .collect();
    let t0 = Instant::now();
    let mut runs = 0;
    while t0.elapsed() < budget {
        let text = mutate(&texts[rng.random_range(0..texts.len())], &mut rng);
        std::fs::write(&model, &text).unwrap();
        let analyze = runs % 8 == 0;
        if let Err(e) = pipeline(&model, &out, analyze) {
            let kept = keep_failure(&text, &e);
            failures.push(format!("{}: {e}", kept.display()));
        }
        runs += 1;
    }
    eprintln!(
        "fuzz_pipeline: {replayed} corpus inputs and {runs} mutants in {:.0} s (seed {seed}), {} failures",
        t0.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(replayed >= 1, "the pipeline corpus is empty");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
