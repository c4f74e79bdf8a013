//! The report speaks about the user's design (issue 58, item 3): the cases first, an answer in
//! short whose numbers are the analysis's own, a table of contents that reaches every section,
//! the paper's comparisons only for the paper's models, no σ compared where it is rounding, a
//! first-order "worst" only where first order is flagged, and notes that say how far off and
//! what to do.

mod common;

use modaltol::analyze::{Analysis, AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::output::Quantity;
use modaltol::plots::{Display, Plot, campbell_case, percent, plots};
use modaltol::quadrature::QuadOptions;
use modaltol::report;
use modaltol::table::Method;

fn range(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|i| from + step * i as f64).collect()
}

/// Every case of `model` over `speeds`, with the quadrature (`quadrature`) or without it.
fn run(model: &Compiled, speeds: Vec<f64>, quadrature: Option<QuadOptions>) -> Analysis {
    let opt = AnalyzeOptions {
        speeds,
        cases: model.model().tolerance_cases(&[]).unwrap(),
        quadrature,
        ..Default::default()
    };
    analyze(model, &opt, &|_: &str, _: usize, _: usize| {})
}

fn html(model: &Compiled, a: &Analysis, d: Display) -> (String, Vec<Plot>) {
    let (plots, critical) = plots(model.model(), a, d);
    let refs: Vec<&Plot> = plots.iter().collect();
    let extra = report::Extra {
        display: d,
        ..Default::default()
    };
    let h = report::report_html(model.model(), a, &refs, &critical, extra);
    (h, plots)
}

/// The text between `from` and the next `to` after it.
fn between<'a>(s: &'a str, from: &str, to: &str) -> &'a str {
    let i = s.find(from).unwrap_or_else(|| panic!("no {from}")) + from.len();
    let j = s[i..].find(to).map_or(s.len(), |j| i + j);
    &s[i..j]
}

#[test]
fn percentages_read_as_written() {
    assert_eq!(percent(0.9973), "99.73");
    assert_eq!(percent(0.5), "50");
    assert_eq!(percent(1.0), "100");
    assert_eq!(percent(0.999999), "99.9999");
    assert_eq!(percent(0.002), "0.2");
}

/// The governor: its cases come first, then "In short", whose sentence of mode 1 is the
/// analytic row at the speed of its largest relative spread (mean ± 3σ, and the variable with
/// the largest first-order share named first) in the case with the most variables; every
/// section is in the table of contents, and the paper's timings are there (it is the paper's
/// model).
#[test]
fn the_report_opens_with_the_cases_and_the_answer_in_short() {
    let m = common::example("governor.toml");
    let a = run(&m, range(1.0, 3.0, 0.1), None);
    let (h, _) = html(&m, &a, Display::default());
    let at = |s: &str| h.find(s).unwrap_or_else(|| panic!("no {s}"));
    assert!(at("Tolerance cases") < at("In short"));
    assert!(at("In short") < at("Summary: σ where it matters"));
    // The table of contents links every section, and each link has its heading.
    let nav = between(&h, "<nav>", "</nav>");
    let headings = h.matches("<h2").count();
    assert_eq!(nav.matches("<a href=\"#").count(), headings);
    for id in nav
        .split("href=\"#")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
    {
        assert!(h.contains(&format!("<h2 id=\"{id}\">")), "{id}");
    }
    // "In short", mode 1: the case with the most variables, at the largest 3σ/mean.
    let ci = campbell_case(&a, Display::default());
    assert_eq!(a.cases[ci].name, "all3");
    let rows: Vec<_> = (a.rows.iter())
        .filter(|r| r.case == ci && r.method() == Method::Analytic)
        .filter(|r| r.quantity == Quantity::DampedFrequency && r.mode == Some(0))
        .collect();
    let r = rows
        .iter()
        .max_by(|x, y| (x.std / x.mean).total_cmp(&(y.std / y.mean)))
        .unwrap();
    let line = between(&h, "<li>Mode 1's damped natural frequency: ", "</li>");
    let (mean, rest) = line.split_once(" ± ").unwrap();
    let three = rest.split(' ').next().unwrap();
    let rel = |x: f64, y: f64| (x - y).abs() / y.abs();
    assert!(
        rel(mean.parse().unwrap(), r.mean) < 1e-4,
        "{line}: {}",
        r.mean
    );
    assert!(
        rel(three.parse().unwrap(), 3.0 * r.std) < 1e-4,
        "{line}: {}",
        r.std
    );
    let first = (a.rows.iter())
        .find(|f| {
            f.case == ci
                && f.method() == Method::FirstOrder
                && f.quantity == Quantity::DampedFrequency
                && f.mode == Some(0)
                && f.speed.to_bits() == r.speed.to_bits()
        })
        .unwrap();
    let shares = first.shares().unwrap();
    let top = (0..shares.len())
        .max_by(|&i, &j| shares[i].total_cmp(&shares[j]))
        .unwrap();
    let name = &m.model().parameters[a.vars[top]].name;
    assert!(
        line.contains(&format!("driven by {name} (")),
        "{line}: {name} drives it"
    );
    assert!(h.contains("paper, governor"));
    assert!(h.contains("Where first order (the paper's method) is off"));
}

/// An undamped rotor (Friswell's): its ζ is rounding about 0, so the report and plots show
/// none (there were 42 ζ plots and "first order vs answer +31 %" on σ = 10⁻²¹); no `paper`
/// key in its `summary.json`, no "paper" in its report; tolerances in per cent of nominal.
#[test]
fn an_undamped_rotor_s_report_compares_no_rounding_and_names_no_paper() {
    let m = common::example("friswell_5_9_1.toml");
    let a = run(&m, range(0.0, 420.0, 60.0), None);
    assert!(!a.resolved(Quantity::DampingRatio, Some(1)));
    assert!(a.resolved(Quantity::DampedFrequency, Some(1)));
    let (h, plots) = html(&m, &a, Display::default());
    assert!(
        plots.iter().all(|p| !p.stem.contains("damping_ratio")),
        "ζ plotted"
    );
    let summary = between(&h, "Summary: σ where it matters", "</table>");
    assert!(!summary.contains("ζ"), "ζ in the summary");
    assert!(
        !h.contains("paper"),
        "the paper named in another model's report"
    );
    let json = report::summary_json(m.model(), &a, None, 1);
    assert!(json.get("paper").is_none(), "{}", json["paper"]);
    assert!(
        h.contains("<td>10 %</td>"),
        "k_bearing's 10 % not in per cent"
    );
    // The pendulum (the paper's) keeps its `paper` key.
    let p = common::example("rotating_pendulum.toml");
    let ap = run(&p, range(3.0, 3.4, 0.2), None);
    assert!(report::summary_json(p.model(), &ap, None, 1)["paper"].is_object());
}

/// The first-order table's "worst" lies at a speed it flags (σ not near zero there): on the
/// pendulum its |H| was "97–100 % off" at a speed where σ passes through zero.
#[test]
fn first_order_s_worst_is_where_it_is_flagged() {
    for name in ["rotating_pendulum.toml", "spinning_universal_pendulum.toml"] {
        let m = common::example(name);
        let a = run(&m, range(3.0, 4.5, 0.05), Some(QuadOptions::default()));
        let (h, _) = html(&m, &a, Display::default());
        let table = between(&h, "is off</h2>", "</table>");
        for row in table.split("<tr><td>").skip(1) {
            let cells: Vec<&str> = row.split("</td><td").collect();
            let (case, output) = (cells[0], cells[1].trim_start_matches('>'));
            let worst_at: f64 = between(row, "% at ", "</td>").parse().unwrap();
            let ci = a.cases.iter().position(|c| c.name == case).unwrap();
            let (q, mode) = [
                Quantity::DampedFrequency,
                Quantity::DampingRatio,
                Quantity::TransferMagnitude,
            ]
            .into_iter()
            .flat_map(|q| (0..4).map(move |k| (q, Some(k))).chain([(q, None)]))
            .find(|&(q, k)| {
                output
                    == k.map_or(q.as_str().to_string(), |k| {
                        format!("{} mode {}", q.as_str(), k + 1)
                    })
            })
            .unwrap();
            let flagged = modaltol::plots::first_order_off(&a, ci, q, mode);
            assert!(
                flagged
                    .iter()
                    .any(|&(w, v)| v.is_finite() && (w - worst_at).abs() < 6e-4),
                "{name} {case} {output}: worst at {worst_at} is not flagged"
            );
        }
    }
}

/// A quadrature held below its request says how far off it is (the largest error estimate in
/// σ, recomputed here from the rows) and what to do.
#[test]
fn the_quadrature_note_says_how_far_off_and_what_to_do() {
    let m = common::example("rotating_pendulum.toml");
    let q = QuadOptions {
        tolerance: 1e-12,
        nodes: Some(5),
    };
    let a = run(&m, range(3.0, 4.0, 0.25), Some(q));
    let lines = report::outside_request_lines(&a);
    assert!(!lines.is_empty());
    let line = &lines[0];
    let worst = (a.rows.iter())
        .filter(|r| r.case == 0 && r.method() == Method::Quadrature)
        .filter(|r| r.within_request() == Some(false) && r.std > 0.0)
        .filter_map(|r| {
            let d = r.detail.quadrature()?;
            Some(d.errors.0.max(d.errors.1) / r.std)
        })
        .filter(|e| e.is_finite())
        .fold(0.0f64, f64::max);
    assert!(
        line.contains(&format!("The largest error estimate is {worst:.2} σ")),
        "{line}: {worst}"
    );
    assert!(
        line.contains("--quadrature-nodes") && line.contains("nodes swept"),
        "{line}"
    );
}
