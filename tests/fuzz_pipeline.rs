//! Fuzzing of the whole pipeline through the real binary: mutated models through `check`,
//! `modal`, a short `sweep` and, every few runs, a short `analyze`, a drawing (`draw`), a
//! sharded analysis and its `merge`, and an `allocate` (for a model with requirements), each
//! under a deadline.
//!
//! A run passes when nothing panics, nothing hangs, every exit code is 0, 1 or 2, no output
//! holds a non-finite number outside a row whose status is `failed`, every row of
//! `tolerance.csv` without a mean says why (and only those), a drawing is written whole or not
//! at all, and two shards of one model merge. The mutations aim at the defect classes found
//! before: extreme and degenerate numbers in place of any number of the model, non-finite
//! expressions, deleted and duplicated lines, random bytes; and at the newer vocabulary's
//! keywords: a coupler's coefficients, a derived parameter made of itself or of a later one, a
//! load on the ground, a requirement's speeds off the grid, the allocation's target and costs.
//!
//! The mutants start from the shipped examples and from the seeds in
//! `tests/fuzz_corpus/seeds/` (one small model for each part of the newer vocabulary: loads,
//! couplers, derived parameters, a ball joint's spherical damper, ports on a non-symmetric
//! system, a cut-joint loop, requirements of every kind with an allocation). The seeds and the
//! inputs that once broke something (`tests/fuzz_corpus/pipeline/`) are run through every stage
//! first. A failing mutant is written to `target/fuzz-failures/` for adding to that corpus.
//! Budget: `FUZZ_SECONDS` (default 70 s, the replay included, so CI stays short); seed:
//! `FUZZ_SEED`. A long run:
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

/// Values for the newer vocabulary's keys, each written in place of a whole value: a coupler's
/// coefficients and value, a load's body, frame and type, a port's direction, a requirement's
/// speeds, mode, orders, margin, band and bounds, the allocation's target, case and costs, and
/// a spherical element's stiffness and damping.
const KEYED: [(&str, &[&str]); 18] = [
    (
        "coefficients",
        &[
            "[0, 1]",
            "[\"-1e308\", 1]",
            "[1e308, 1e-308]",
            "[0, 0]",
            "[5e-324, -1]",
            "[\"1/0\", 1]",
            "[-1, -1]",
            "[1]",
        ],
    ),
    (
        "value",
        &["1e308", "\"-1e308\"", "3.2", "\"speed\"", "\"exp(1000)\""],
    ),
    (
        "coordinates",
        &["[\"spin\", \"hinge\"]", "[\"hinge\", \"hinge\"]", "[]"],
    ),
    (
        "coordinate",
        &["\"spin\"", "\"ground\"", "\"nope\"", "\"ball.rx\""],
    ),
    ("body", &["\"ground\"", "\"nope\"", "\"\""]),
    ("frame", &["\"body\"", "\"ground\"", "\"world\""]),
    (
        "type",
        &[
            "\"torque\"",
            "\"coordinate\"",
            "\"rotation\"",
            "\"translation\"",
            "\"point\"",
        ],
    ),
    (
        "direction",
        &[
            "[0, 0, 0]",
            "[1e-320, 0, 0]",
            "[1e308, 1e308, 0]",
            "[\"1/speed\", 0, 1]",
        ],
    ),
    (
        "speeds",
        &[
            "[-1, 2]",
            "[0, 1e308]",
            "[2, 1]",
            "[1.5, 1.5]",
            "[0.25, 0.75]",
            "[3, 9]",
            "[-1e308, 1e308]",
            "[]",
            "[1.9999999999, 2.0000000001]",
        ],
    ),
    ("mode", &["0", "-1", "99", "1e308", "2"]),
    ("orders", &["[]", "[0]", "[-1]", "[1e308]", "[1, 1]"]),
    (
        "margin",
        &[
            "\"0%\"",
            "\"-10%\"",
            "\"1e308%\"",
            "\"api684\"",
            "\"100%\"",
            "\"nan%\"",
        ],
    ),
    (
        "band",
        &["[2, 1]", "[0, 1e308]", "[-1, -1]", "[5e-324, 5e-324]"],
    ),
    ("min", &["-1e308", "1e308", "0", "5e-324"]),
    ("max", &["-1e308", "1e308", "0", "5e-324"]),
    (
        "target_yield",
        &[
            "0",
            "1",
            "1e-320",
            "0.9999999999999999",
            "2",
            "-0.5",
            "1e-300",
        ],
    ),
    (
        "cost",
        &[
            "{}",
            "{ nope = { b = 1 } }",
            "{ L = { b = 0 } }",
            "{ L = { b = 1e308, k = 400 } }",
            "{ spring_k = { b = -1, k = 0 } }",
            "{ ball_mass = { max = \"0%\" } }",
        ],
    ),
    (
        "damping",
        &["[\"-1\", 0, 0]", "-1e308", "\"1e308\"", "[0, 0, 0]", "0"],
    ),
];

/// Replaces the whole value of one line `key = …` of a key of [`KEYED`] present in `text`.
fn mutate_keyword(text: &str, rng: &mut ChaCha8Rng) -> Option<String> {
    let key_of = |l: &str| l.split('=').next().map(|k| k.trim().to_string());
    let lines: Vec<&str> = text.lines().collect();
    let hits: Vec<(usize, &[&str])> = lines
        .iter()
        .enumerate()
        .filter_map(|(i, l)| {
            let k = key_of(l)?;
            KEYED
                .iter()
                .find(|(key, _)| *key == k && l.contains('='))
                .map(|(_, values)| (i, *values))
        })
        .collect();
    if hits.is_empty() {
        return None;
    }
    let (i, values) = hits[rng.random_range(0..hits.len())];
    let key = key_of(lines[i]).unwrap_or_default();
    let value = values[rng.random_range(0..values.len())];
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    out[i] = format!("{key} = {value}");
    Some(out.join("\n"))
}

/// Rewrites one parameter of the `[parameters]` table as a derived parameter that is made of
/// itself, of a later parameter (a cycle through it where that one is made to use it back), of
/// the speed or of an unknown name, or as a derived one with a tolerance.
fn mutate_parameter(text: &str, rng: &mut ChaCha8Rng) -> Option<String> {
    let mut out: Vec<String> = text.lines().map(|l| l.to_string()).collect();
    let start = out.iter().position(|l| l.trim() == "[parameters]")? + 1;
    let end = (start..out.len())
        .find(|&i| out[i].trim_start().starts_with('['))
        .unwrap_or(out.len());
    let params: Vec<(usize, String)> = (start..end)
        .filter_map(|i| {
            let (name, _) = out[i].split_once('=')?;
            let name = name.trim();
            (!name.is_empty() && !name.starts_with('#')).then(|| (i, name.to_string()))
        })
        .collect();
    if params.is_empty() {
        return None;
    }
    let k = rng.random_range(0..params.len());
    let (line, name) = &params[k];
    let later = (k + 1 < params.len()).then(|| &params[rng.random_range(k + 1..params.len())]);
    out[*line] = match (rng.random_range(0..5), later) {
        (0, _) => format!("{name} = \"{name} + 1\""),
        (1, Some((_, other))) => format!("{name} = \"2*{other}\""),
        (2, Some((other_line, other))) => {
            out[*other_line] = format!("{other} = \"{name}/2\"");
            format!("{name} = \"2*{other}\"")
        }
        (3, _) => format!("{name} = \"speed + 1\""),
        _ => format!("{name} = {{ value = \"nope*2\", tolerance = \"1%\" }}"),
    };
    Some(out.join("\n"))
}

fn mutate(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut t = text.to_string();
    for _ in 0..rng.random_range(1..=3) {
        match rng.random_range(0..13) {
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
            8 => {
                let mut bytes = t.into_bytes();
                let k = rng.random_range(0..bytes.len());
                bytes[k] = rng.random_range(0x20..0x7f);
                t = String::from_utf8_lossy(&bytes).into_owned();
            }
            9..=10 => t = mutate_keyword(&t, rng).unwrap_or(t),
            _ => t = mutate_parameter(&t, rng).unwrap_or(t),
        }
    }
    t
}

/// Runs the binary under a deadline: `(exit code, stdout, stderr)`, or `Err` on a hang.
fn run(args: &[&str], limit: Duration) -> Result<(Option<i32>, String, String), String> {
    common::run_with_deadline(args, limit).map(|r| (r.code, r.stdout, r.stderr))
}

/// A run's stdout if it neither panicked nor exited with a code other than 0, 1 or 2.
fn judge(what: &str, r: (Option<i32>, String, String)) -> Result<(Option<i32>, String), String> {
    let (code, stdout, stderr) = r;
    if stderr.contains("panicked") {
        return Err(format!("{what} panicked: {stderr}"));
    }
    if !matches!(code, Some(0..=2)) {
        return Err(format!("{what} exit {code:?}: {stderr}"));
    }
    Ok((code, stdout))
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

/// Checks an analysis's `tolerance.csv` in `dir`, where one was written.
fn check_tolerance(dir: &Path) -> Result<(), String> {
    match std::fs::read_to_string(dir.join("tolerance.csv")) {
        Ok(text) => check_csv(&text).and_then(|()| check_reasons(&text)),
        Err(_) => Ok(()),
    }
}

/// Checks a drawing's text: whole (its closing tag last) and without a non-finite number (the
/// words JavaScript and SVG print for one).
fn check_drawing(text: &str, html: bool) -> Result<(), String> {
    let end = if html { "</html>" } else { "</svg>" };
    if !text.trim_end().ends_with(end) {
        return Err(format!("the drawing does not end with {end}"));
    }
    let bad = text
        .split(|c: char| !c.is_ascii_alphanumeric())
        .find(|w| matches!(*w, "NaN" | "nan" | "Infinity" | "inf"));
    match bad {
        Some(w) => Err(format!("the drawing holds the number '{w}'")),
        None => Ok(()),
    }
}

/// Checks `allocation.json`: every number finite (a non-finite one is written `null`; only
/// `cost_gap` may be `null`, where no design short of the target was tried).
fn check_allocation(text: &str) -> Result<(), String> {
    fn walk(key: &str, v: &serde_json::Value) -> Result<(), String> {
        match v {
            serde_json::Value::Null if key != "cost_gap" => Err(format!("{key} is null")),
            serde_json::Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => {
                Err(format!("{key} = {n}"))
            }
            serde_json::Value::Array(a) => a.iter().try_for_each(|x| walk(key, x)),
            serde_json::Value::Object(o) => o.iter().try_for_each(|(k, x)| walk(k, x)),
            _ => Ok(()),
        }
    }
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    walk("allocation", &v)
}

/// Which of the slower stages a run adds to `check`, `modal` and `sweep`.
#[derive(Clone, Copy)]
struct Stages {
    /// A short `analyze`.
    analyze: bool,
    /// A `draw`, a sharded `analyze` with its `merge`, and (for a model with requirements) an
    /// `allocate`.
    extra: bool,
}

impl Stages {
    /// Every stage: for the seeds and the corpus.
    const ALL: Stages = Stages {
        analyze: true,
        extra: true,
    };

    /// The stages of the `run`th mutant: an analysis every 8th run, the others every 8th run
    /// half-way between (their cost shared out, so the default budget still runs many mutants).
    fn of_run(run: usize) -> Stages {
        Stages {
            analyze: run.is_multiple_of(8),
            extra: run % 8 == 4,
        }
    }
}

/// The analysis's arguments shared by every stage that analyses (few speeds, few samples).
const ANALYSIS: [&str; 4] = ["--speed", "0:2:1", "--samples", "16"];

/// Draws the model (SVG or HTML, the `--mode 1` overlay or none, by `html`): the drawing is
/// written whole, without a non-finite number, or not at all.
fn draw_stage(m: &str, out: &Path, html: bool) -> Result<(), String> {
    let file = out.join(if html {
        "mechanism.html"
    } else {
        "mechanism.svg"
    });
    let _ = std::fs::remove_file(&file);
    let f = file.to_str().unwrap();
    let mut args = vec!["draw", m, "-o", f, "--speed", "1"];
    if html {
        args.extend(["--mode", "1"]);
    }
    let (code, _) = judge("draw", run(&args, Duration::from_secs(30))?)?;
    match std::fs::read_to_string(&file) {
        Ok(text) => check_drawing(&text, html).map_err(|e| format!("draw: {e}")),
        Err(_) if code == Some(0) => Err("draw exit 0 without a drawing".into()),
        Err(_) => Ok(()),
    }
}

/// Analyses the model in two shards and merges them: where both shards succeed, the merge
/// does too, and its `tolerance.csv` passes [`check_csv`] and [`check_reasons`].
fn shard_stage(m: &str, out: &Path) -> Result<(), String> {
    let mut files = Vec::new();
    for k in 1..=2 {
        let dir = out.join(format!("shard{k}"));
        let shard = format!("{k}/2");
        let mut args = vec!["analyze", m, "-o", dir.to_str().unwrap(), "--shard", &shard];
        args.extend(ANALYSIS);
        let (code, _) = judge("analyze --shard", run(&args, Duration::from_secs(120))?)?;
        if code != Some(0) {
            return Ok(());
        }
        files.push(dir.join(format!("shard-{k}-of-2.json")));
    }
    let merged = out.join("merged");
    let mut args = vec!["merge", "--model", m, "-o", merged.to_str().unwrap()];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    let (code, _, stderr) = run(&args, Duration::from_secs(120))?;
    if stderr.contains("panicked") {
        return Err(format!("merge panicked: {stderr}"));
    }
    if code != Some(0) {
        return Err(format!("merge of two good shards exit {code:?}: {stderr}"));
    }
    check_tolerance(&merged).map_err(|e| format!("merge: {e}"))
}

/// Allocates the tolerances of a model with requirements: exit 0, 1 or 2, and any
/// `allocation.json` finite.
fn allocate_stage(m: &str, out: &Path) -> Result<(), String> {
    let dir = out.join("allocation");
    let args = [
        "allocate",
        m,
        "-o",
        dir.to_str().unwrap(),
        "--speed",
        "0:2:1",
    ];
    judge("allocate", run(&args, Duration::from_secs(120))?)?;
    if let Ok(text) = std::fs::read_to_string(dir.join("allocation.json")) {
        check_allocation(&text).map_err(|e| format!("allocate: allocation.json: {e}"))?;
    }
    check_tolerance(&dir).map_err(|e| format!("allocate: {e}"))
}

/// Runs one model through the pipeline; `Err` says what went wrong.
fn pipeline(model: &Path, out: &Path, stages: Stages) -> Result<(), String> {
    let m = model.to_str().unwrap();
    let limit = Duration::from_secs(30);
    let (code, _, stderr) = run(&["check", m], limit)?;
    if stderr.contains("panicked") || !matches!(code, Some(0 | 2)) {
        return Err(format!("check exit {code:?}: {stderr}"));
    }
    if code != Some(0) {
        return Ok(());
    }
    let (_, table) = judge("modal", run(&["modal", m, "--speed", "1"], limit)?)?;
    // A failed point's reason may quote an infinite condition number; results may not.
    let results: String = table
        .lines()
        .filter(|l| !l.starts_with("FAILED"))
        .collect::<Vec<_>>()
        .join("\n");
    if results.to_ascii_lowercase().contains("nan") || results.contains(" inf") {
        return Err(format!("modal printed a non-finite number: {table}"));
    }
    let (_, csv) = judge("sweep", run(&["sweep", m, "--speed", "0:4:1"], limit)?)?;
    check_csv(&csv).map_err(|e| format!("sweep: {e}"))?;
    // A fresh output directory for each model: no stage reads what another model left.
    let _ = std::fs::remove_dir_all(out);
    if stages.analyze {
        let mut args = vec!["analyze", m, "-o", out.to_str().unwrap()];
        args.extend(ANALYSIS);
        judge("analyze", run(&args, Duration::from_secs(120))?)?;
        check_tolerance(out).map_err(|e| format!("analyze: {e}"))?;
    }
    if stages.extra {
        std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
        let text = std::fs::read_to_string(model).map_err(|e| e.to_string())?;
        // The page or the SVG, by the model's text (each about half of the runs).
        draw_stage(m, out, fxhash(text.as_bytes()).is_multiple_of(2))?;
        shard_stage(m, out)?;
        if text.contains("[[requirements]]") {
            allocate_stage(m, out)?;
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

/// The model files of a corpus folder, sorted.
fn corpus(folder: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// Every seed is a valid model: `check` accepts it, and `sweep` solves every speed from 0 to 4
/// rad/s (else its mutants would mostly test the refusal of the seed itself).
#[test]
fn the_fuzzing_seeds_are_valid_and_solve() {
    let seeds = corpus("tests/fuzz_corpus/seeds");
    assert!(seeds.len() >= 7, "the seeds: {seeds:?}");
    for seed in &seeds {
        let s = seed.to_str().unwrap();
        let limit = Duration::from_secs(60);
        let check = common::run_with_deadline(&["check", s], limit).unwrap();
        assert_eq!(check.code, Some(0), "{s}: {}", check.stderr);
        let sweep = common::run_with_deadline(&["sweep", s, "--speed", "0:4:1"], limit).unwrap();
        assert_eq!(sweep.code, Some(0), "{s}: {}", sweep.stderr);
        let rows: Vec<&str> = sweep.stdout.lines().skip(1).collect();
        assert!(!rows.is_empty(), "{s}: no modes");
        for speed in ["0", "1", "2", "3", "4"] {
            assert!(
                rows.iter().any(|r| r.starts_with(&format!("{speed},"))),
                "{s}: no mode at speed {speed}"
            );
        }
        assert!(
            rows.iter().all(|r| !r.contains(",failed,")),
            "{s}: a failed speed"
        );
    }
}

#[test]
fn mutated_models_through_the_whole_pipeline() {
    let budget = Duration::from_secs(
        std::env::var("FUZZ_SECONDS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(70),
    );
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(14);
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("mutant.toml");
    let out = dir.path().join("out");
    let mut failures = Vec::new();
    let t0 = Instant::now();
    // The seeds and the corpus first, through every stage.
    let seeds = corpus("tests/fuzz_corpus/seeds");
    let replay = corpus("tests/fuzz_corpus/pipeline");
    for f in seeds.iter().chain(&replay) {
        if let Err(e) = pipeline(f, &out, Stages::ALL) {
            failures.push(format!("{}: {e}", f.display()));
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let texts: Vec<String> = common::EXAMPLES
        .iter()
        .map(|e| common::example_text(e))
        .chain(seeds.iter().map(|f| std::fs::read_to_string(f).unwrap()))
        .collect();
    let mut runs = 0;
    while t0.elapsed() < budget {
        let text = mutate(&texts[rng.random_range(0..texts.len())], &mut rng);
        std::fs::write(&model, &text).unwrap();
        if let Err(e) = pipeline(&model, &out, Stages::of_run(runs)) {
            let kept = keep_failure(&text, &e);
            failures.push(format!("{}: {e}", kept.display()));
        }
        runs += 1;
    }
    eprintln!(
        "fuzz_pipeline: {} seeds, {} corpus inputs and {runs} mutants in {:.0} s (seed {seed}), {} failures",
        seeds.len(),
        replay.len(),
        t0.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(!replay.is_empty(), "the pipeline corpus is empty");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
