//! `docs/tutorial.md` runs as written: its model blocks are the files it names, every command
//! in its `sh` blocks runs (outputs to a temporary directory), every `text` block is in the
//! output of the command before it, and each number its prose quotes is recomputed here, from
//! the hand formulas it gives and from the files the commands wrote.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The fenced blocks of a markdown text: (language, body).
fn blocks(md: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut open: Option<(String, String)> = None;
    for line in md.lines() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(lang)) => open = Some((lang.trim().to_string(), String::new())),
            (Some(_), Some(_)) => out.push(open.take().expect("open")),
            (Some((_, body)), None) => {
                body.push_str(line);
                body.push('\n');
            }
            (None, None) => {}
        }
    }
    out
}

/// Runs one `modaltol …` line from the repository root, `-o X` written under `dir`; its
/// standard output, and the directory or file it wrote.
fn run(line: &str, dir: &Path) -> (String, Option<PathBuf>) {
    let words: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(words[0], "modaltol", "{line}");
    let mut args: Vec<String> = Vec::new();
    let mut out = None;
    let mut it = words[1..].iter();
    while let Some(&w) = it.next() {
        args.push(w.to_string());
        if w == "-o" {
            let p = dir.join(it.next().expect("-o names its output"));
            args.push(p.to_str().unwrap().to_string());
            out = Some(p);
        }
    }
    let o = Command::new(env!("CARGO_BIN_EXE_modaltol"))
        .args(&args)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{line}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    (String::from_utf8(o.stdout).unwrap(), out)
}

/// The value of `column` in the CSV row whose leading cells are `key` (`a,b,…`).
fn cell(csv: &str, key: &str, column: &str) -> f64 {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|h| *h == column).unwrap();
    let row = lines
        .find(|l| l.starts_with(&format!("{key},")))
        .unwrap_or_else(|| panic!("no row {key}"));
    row.split(',').nth(at).unwrap().parse().unwrap()
}

#[test]
fn the_tutorial_runs_as_written_and_quotes_what_the_tool_prints() {
    let md = std::fs::read_to_string(root().join("docs/tutorial.md")).unwrap();
    let tutorial = |f: &str| std::fs::read_to_string(root().join("examples/tutorial").join(f));
    let (first, second) = (
        tutorial("pendulum.toml").unwrap(),
        tutorial("pendulum_tolerances.toml").unwrap(),
    );
    let dir = tempfile::tempdir().unwrap();
    let all = blocks(&md);
    // The model blocks: the first file whole, then parts of the second.
    let tomls: Vec<&String> = all.iter().filter(|b| b.0 == "toml").map(|b| &b.1).collect();
    assert_eq!(
        tomls[0], &first,
        "the first model block is not examples/tutorial/pendulum.toml"
    );
    assert!(tomls.len() >= 3);
    for part in &tomls[1..] {
        assert!(
            second.contains(part.as_str()),
            "not in pendulum_tolerances.toml:\n{part}"
        );
    }
    // The commands, and the printed lines each quotes after it.
    let mut last = String::new();
    let mut analysis: Option<PathBuf> = None;
    let mut commands = 0;
    for (lang, body) in &all {
        match lang.as_str() {
            "sh" => {
                for line in body.lines().filter(|l| l.starts_with("modaltol ")) {
                    let (stdout, out) = run(line, dir.path());
                    commands += 1;
                    assert!(!stdout.contains("warning:"), "{line}: {stdout}");
                    last = stdout;
                    if line.contains(" analyze ") {
                        let out = out.expect("analyze -o");
                        let report = std::fs::read_to_string(out.join("report.html")).unwrap();
                        // The report's sentences as text, for the blocks quoting it.
                        last = report.replace("<li>", "\n").replace("</li>", "\n");
                        analysis = Some(out);
                    }
                }
            }
            "text" if !last.is_empty() => {
                for line in body
                    .lines()
                    .filter(|l| l.contains(|c: char| c.is_ascii_digit() || c == '\''))
                {
                    assert!(last.contains(line), "not printed:\n{line}\nin:\n{last}");
                }
            }
            _ => {}
        }
    }
    assert_eq!(commands, 5);
    let quoted = |s: String| assert!(md.contains(&s), "the tutorial does not quote {s}");
    // Section 3: the hand formulas' numbers.
    let (g, m, l, c) = (9.81f64, 1.0f64, 0.5f64, 0.05f64);
    for w in [0.0f64, 2.0] {
        let wn = (g / l - w * w).sqrt();
        let zeta = c / (2.0 * m * l * l * wn);
        quoted(format!("{wn:.8}"));
        quoted(format!("{zeta:.6}"));
        quoted(format!("{:.8}", wn * (1.0 - zeta * zeta).sqrt()));
    }
    let theta = (g / (l * 4.5 * 4.5)).acos();
    quoted(format!("= {theta:.4} rad (arccos"));
    quoted(format!("ω_n = Ω sin θ = {:.4}", 4.5 * theta.sin()));
    // Section 5, from the files analyze wrote.
    let out = analysis.expect("the analysis ran");
    let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
    let tolerance = read("tolerance.csv");
    let key = |method: &str| format!("2,damped_frequency,1,parameters,{method}");
    let first = cell(&tolerance, &key("first_order"), "std");
    let wd = (g / l - 4.0 - (c / (2.0 * m * l * l)).powi(2)).sqrt();
    let d = |d2: f64| d2 / (2.0 * wd);
    let by_hand = ((d(-g / (l * l) + c * c / (m * m * l.powi(5))) * 0.05 * l / 3.0).powi(2)
        + (d(c * c / (2.0 * m.powi(3) * l.powi(4))) * 0.02 * m / 3.0).powi(2)
        + (d(-c / (2.0 * m * m * l.powi(4))) * 0.2 * c / 3.0).powi(2))
    .sqrt();
    assert!(
        (first - by_hand).abs() <= 1e-9 * by_hand,
        "{first} vs {by_hand}"
    );
    quoted(format!("σ = {first:.5}"));
    let quad = cell(&tolerance, &key("quadrature"), "std");
    quoted(format!("gives {quad:.5}"));
    let (lo, hi) = (
        cell(&tolerance, &key("monte_carlo"), "std_ci_low"),
        cell(&tolerance, &key("monte_carlo"), "std_ci_high"),
    );
    assert!(lo <= quad && quad <= hi, "{quad} outside [{lo}, {hi}]");
    let yields = read("yield.csv");
    quoted(format!(
        "probability {:.4} (quadrature",
        cell(&yields, "parameters,quadrature,all", "probability")
    ));
    quoted(format!(
        "Monte Carlo says {:.3}",
        cell(&yields, "parameters,monte_carlo,all", "probability")
    ));
    let limits = read("limits.csv");
    let row = "parameters,quadrature,clear_of_1x";
    quoted(format!("up to {} rad/s", cell(&limits, row, "reach")));
    quoted(format!(
        "margin of {:.3} rad/s",
        cell(&limits, row, "margin_at_target")
    ));
}

/// The minimal model at the top of `docs/model-format.md` loads and gives the frequency its
/// text quotes (ω_n = √(g/L − Ω²) at Ω = 2 rad/s).
#[test]
fn the_model_format_s_minimal_model_runs() {
    let md = std::fs::read_to_string(root().join("docs/model-format.md")).unwrap();
    let (_, text) = blocks(&md).into_iter().find(|b| b.0 == "toml").unwrap();
    assert!(text.lines().count() <= 40, "not minimal");
    let m = modaltol::compiled::Compiled::from_str(&text, "minimal.toml").unwrap();
    let p = m.model().nominal();
    let q0 = modaltol::sweep::initial_guess(m.model(), &p, 2.0).unwrap();
    let pt = modaltol::sweep::point(&m, &p, 2.0, &q0, &Default::default()).unwrap();
    let wn = (9.81f64 / 0.5 - 4.0).sqrt();
    assert!((pt.modes[0].natural_frequency - wn).abs() <= 1e-10 * wn);
    assert!(md.contains(&format!("= {wn:.4} rad/s")));
    assert!(modaltol::report::check_summary(m.model()).contains("is valid"));
}
