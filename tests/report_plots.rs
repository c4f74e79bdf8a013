//! The report's plots read as a person would: from the generated SVG's text and shapes, no
//! legend text covers data, no axis repeats a tick label, every shaded band is in the legend
//! with a colour of its own, and the plots and report say what the issue asks (ζ plots for a
//! damped system, the answer drawn first, units, engine orders, the paper's rows only for the
//! paper's examples).

mod common;

use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::Sampling;
use modaltol::montecarlo::McOptions;
use modaltol::plots::{Display, FrequencyUnit, Plot, plots};
use modaltol::report;

/// An analysis of `model` over `speeds` for its first tolerance case, with a small Monte Carlo.
fn run(model: &Compiled, speeds: &[f64]) -> modaltol::analyze::Analysis {
    let cases = model.model().tolerance_cases(&[]).unwrap()[..1].to_vec();
    let opt = AnalyzeOptions {
        speeds: speeds.to_vec(),
        cases,
        monte_carlo: Some(McOptions {
            samples: 200,
            seed: 3,
            sampling: Sampling::Random,
        }),
        ..Default::default()
    };
    analyze(model, &opt, &|_: &str, _: usize, _: usize| {})
}

fn range(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|i| from + step * i as f64).collect()
}

/// A `<text>` element: position, anchor, size and content.
#[derive(Debug)]
struct Text {
    x: f64,
    y: f64,
    anchor: String,
    /// plotters' vertical placement: `0.76em` hangs the text below `y`, `0.5ex` centres it,
    /// `-0.5ex` sets it above; none is a baseline.
    dy: String,
    size: f64,
    rotated: bool,
    content: String,
}

impl Text {
    /// Its box, from an average glyph width of 0.62 em (DejaVu Sans is about 0.55–0.6).
    fn bounds(&self) -> (f64, f64, f64, f64) {
        let w = 0.62 * self.size * self.content.chars().count() as f64;
        let x0 = match self.anchor.as_str() {
            "end" => self.x - w,
            "middle" => self.x - w / 2.0,
            _ => self.x,
        };
        let (top, bottom) = match self.dy.as_str() {
            "0.76em" => (self.y, self.y + self.size),
            "0.5ex" => (self.y - 0.5 * self.size, self.y + 0.5 * self.size),
            "-0.5ex" => (self.y - self.size, self.y),
            _ => (self.y - 0.8 * self.size, self.y + 0.2 * self.size),
        };
        (x0, top, x0 + w, bottom)
    }
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let at = tag.find(&key)? + key.len();
    Some(tag[at..].split('"').next()?.to_string())
}

fn num(tag: &str, name: &str) -> Option<f64> {
    attr(tag, name)?.trim_end_matches("px").parse().ok()
}

/// Every element `<name …>` of the SVG, as its opening tag (and for text, its content).
fn elements<'a>(svg: &'a str, name: &str) -> Vec<(&'a str, &'a str)> {
    let open = format!("<{name} ");
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find(&open) {
        rest = &rest[i..];
        let end = rest.find('>').unwrap();
        let tag = &rest[..end];
        let content = if name == "text" {
            let close = rest.find("</text>").unwrap();
            &rest[end + 1..close]
        } else {
            ""
        };
        out.push((tag, content));
        rest = &rest[end..];
    }
    out
}

fn texts(svg: &str) -> Vec<Text> {
    elements(svg, "text")
        .into_iter()
        .map(|(tag, content)| Text {
            x: num(tag, "x").unwrap(),
            y: num(tag, "y").unwrap(),
            anchor: attr(tag, "text-anchor").unwrap_or_default(),
            dy: attr(tag, "dy").unwrap_or_default(),
            size: num(tag, "font-size").unwrap_or(14.0),
            rotated: attr(tag, "transform").is_some(),
            content: content.trim().to_string(),
        })
        .collect()
}

fn points(list: &str) -> Vec<(f64, f64)> {
    list.split_whitespace()
        .filter_map(|p| {
            let (x, y) = p.split_once(',')?;
            Some((x.parse().ok()?, y.parse().ok()?))
        })
        .collect()
}

/// The data drawn: points along every curve (each segment sampled every 2 px; curves are the
/// lines of width 2, the axes and grid are thinner), the vertices of every band, the centre of
/// every dot.
fn data_points(svg: &str) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for (tag, _) in elements(svg, "polyline") {
        if num(tag, "stroke-width").unwrap_or(1.0) < 2.0 {
            continue;
        }
        let p = points(&attr(tag, "points").unwrap());
        for w in p.windows(2) {
            let len = ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt();
            let n = (len / 2.0).ceil().max(1.0) as usize;
            for k in 0..=n {
                let t = k as f64 / n as f64;
                out.push((
                    w[0].0 + t * (w[1].0 - w[0].0),
                    w[0].1 + t * (w[1].1 - w[0].1),
                ));
            }
        }
    }
    for (tag, _) in elements(svg, "polygon") {
        out.extend(points(&attr(tag, "points").unwrap()));
    }
    for (tag, _) in elements(svg, "circle") {
        out.push((num(tag, "cx").unwrap(), num(tag, "cy").unwrap()));
    }
    out
}

/// What a reader would object to in one plot, as messages.
fn defects(p: &Plot) -> Vec<String> {
    let mut out = Vec::new();
    let texts = texts(&p.svg);
    let data = data_points(&p.svg);
    // Text over data: a legend (or any label) covering the curves.
    for t in texts.iter().filter(|t| !t.rotated) {
        let (x0, y0, x1, y1) = t.bounds();
        if let Some(d) = data
            .iter()
            .find(|d| d.0 > x0 && d.0 < x1 && d.1 > y0 && d.1 < y1)
        {
            out.push(format!("text '{}' covers data at {d:?}", t.content));
        }
    }
    // Tick labels: texts of one axis share their x (y axis) or their y (x axis).
    let mut by_x: std::collections::BTreeMap<i64, Vec<&str>> = Default::default();
    let mut by_y: std::collections::BTreeMap<i64, Vec<&str>> = Default::default();
    for t in &texts {
        by_x.entry((t.x * 10.0) as i64)
            .or_default()
            .push(&t.content);
        by_y.entry((t.y * 10.0) as i64)
            .or_default()
            .push(&t.content);
    }
    for axis in by_x.values().chain(by_y.values()).filter(|v| v.len() >= 3) {
        let mut seen = std::collections::HashSet::new();
        for label in axis {
            if !seen.insert(label) {
                out.push(format!("label '{label}' repeats on one axis: {axis:?}"));
            }
        }
    }
    // Bands: each in the legend (a swatch of its colour), colours distinct.
    let fills: Vec<String> = elements(&p.svg, "polygon")
        .iter()
        .map(|(tag, _)| attr(tag, "fill").unwrap())
        .collect();
    let swatches: Vec<String> = elements(&p.svg, "rect")
        .iter()
        .filter_map(|(tag, _)| attr(tag, "fill"))
        .collect();
    for f in &fills {
        if !swatches.contains(f) {
            out.push(format!("band {f} is not in the legend"));
        }
    }
    let distinct: std::collections::HashSet<&String> = fills.iter().collect();
    if distinct.len() != fills.len() {
        out.push(format!("bands share colours: {fills:?}"));
    }
    out
}

fn check_all(plots: &[Plot]) {
    let mut bad = Vec::new();
    for p in plots {
        for d in defects(p) {
            bad.push(format!("{}: {d}", p.stem));
        }
        assert!(!p.caption.is_empty() && p.caption != p.title, "{}", p.stem);
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn the_checker_sees_a_legend_over_data_and_repeated_ticks() {
    // A hand-made SVG with both faults: the checks must be able to fail.
    let svg = r##"<svg><polyline fill="none" stroke-width="2" points="100,100 300,100"/>
<text x="150" y="102" font-size="14">legend entry</text>
<text x="50" y="100" text-anchor="end" font-size="12">0.00004</text>
<text x="50" y="150" text-anchor="end" font-size="12">0.00004</text>
<text x="50" y="200" text-anchor="end" font-size="12">0.00005</text>
<polygon points="100,100 200,100 200,200" fill="#123456"/></svg>"##;
    let p = Plot {
        stem: "fake".into(),
        title: "t".into(),
        caption: "c".into(),
        svg: svg.into(),
    };
    let d = defects(&p);
    assert!(d.iter().any(|m| m.contains("covers data")), "{d:?}");
    assert!(d.iter().any(|m| m.contains("repeats")), "{d:?}");
    assert!(d.iter().any(|m| m.contains("not in the legend")), "{d:?}");
}

#[test]
fn pendulum_plots_are_readable_and_complete() {
    let m = common::example("rotating_pendulum.toml");
    let a = run(&m, &range(3.0, 4.5, 0.05));
    let (plots, critical) = plots(m.model(), &a, Display::default());
    check_all(&plots);
    let stems: Vec<&str> = plots.iter().map(|p| p.stem.as_str()).collect();
    // ζ is plotted (the pendulum is damped), next to ω_d and |H|.
    for s in [
        "band_L3_damped_frequency_mode1",
        "band_L3_damping_ratio_mode1",
        "std_L3_damping_ratio_mode1",
        "band_L3_transfer_magnitude",
        "campbell",
    ] {
        assert!(stems.contains(&s), "{s} missing from {stems:?}");
    }
    // The answer is drawn first: its band, then its mean, before the other methods.
    let band = plots
        .iter()
        .find(|p| p.stem == "band_L3_damped_frequency_mode1")
        .unwrap();
    let legend: Vec<String> = texts(&band.svg)
        .into_iter()
        .filter(|t| t.x > modaltol::plots::AXES_WIDTH as f64)
        .map(|t| t.content)
        .collect();
    assert!(legend[0].starts_with("analytic"), "{legend:?}");
    assert!(legend[1].starts_with("analytic"), "{legend:?}");
    // |H| with its unit; the paper's timings in the pendulum's report.
    let h = plots
        .iter()
        .find(|p| p.stem == "band_L3_transfer_magnitude")
        .unwrap();
    assert!(h.svg.contains("|H| (rad/(N·m))"), "no unit on |H|");
    let refs: Vec<&Plot> = plots.iter().collect();
    let html = report::report_html(m.model(), &a, &refs, &critical, Default::default());
    assert!(html.contains("paper, pendulum"));
    assert!(html.contains("Summary: σ where it matters"));
    assert!(html.contains("largest σ"));
}

#[test]
fn campbell_marks_engine_order_crossings_in_the_units_asked() {
    // The universal pendulum's two modes cross 1×Ω (not a paper example).
    let m = common::example("spinning_universal_pendulum.toml");
    let a = run(&m, &range(0.0, 6.0, 0.1));
    let d = Display {
        speed: FrequencyUnit::Rpm,
        frequency: FrequencyUnit::Hertz,
        campbell_case: None,
    };
    let (plots, critical) = plots(m.model(), &a, d);
    check_all(&plots);
    let c = plots.iter().find(|p| p.stem == "campbell").unwrap();
    assert!(c.svg.contains("speed Ω (rpm)"), "speed axis not in rpm");
    assert!(
        c.svg.contains("damped natural frequency (Hz)") && !c.svg.contains("ω_d (Hz)"),
        "frequency axis not named in Hz"
    );
    for o in ["1×Ω", "2×Ω", "3×Ω"] {
        assert!(c.svg.contains(o), "{o} missing");
    }
    assert!(!critical.is_empty(), "no crossing found");
    for cs in &critical {
        // At a crossing ω_d(Ω) = order·Ω: check against the nominal sweep's own ω_d.
        let pts: Vec<(f64, f64)> = a
            .nominal
            .iter()
            .flatten()
            .map(|p| {
                (
                    p.speed,
                    p.modes[cs.mode].damped_frequency - cs.order * p.speed,
                )
            })
            .collect();
        let w = pts
            .windows(2)
            .find(|w| w[0].0 <= cs.speed && cs.speed <= w[1].0)
            .unwrap();
        assert!(
            w[0].1 * w[1].1 <= 0.0,
            "{cs:?} is not between a sign change: {w:?}"
        );
    }
    assert!(c.svg.contains("critical speeds"), "crossings not marked");
    let refs: Vec<&Plot> = plots.iter().collect();
    let html = report::report_html(
        m.model(),
        &a,
        &refs,
        &critical,
        report::Extra {
            display: d,
            ..Default::default()
        },
    );
    assert!(
        !html.contains("paper,"),
        "paper rows in another model's report"
    );
    assert!(html.contains("Speeds in rpm, frequencies in Hz"));
}

#[test]
fn tick_labels_keep_the_digits_their_spacing_needs() {
    for (lo, hi) in [
        (0.0, 4e-5),
        (3.9e-5, 4.1e-5),
        (0.0, 6.0),
        (1e6, 1.2e6),
        (-1.0, 1.0),
        (0.0, 4010.7),
        (0.0, 99.0),
    ] {
        let f = modaltol::plots::tick_label(lo, hi);
        let labels: Vec<String> = (0..=10)
            .map(|k| f(&(lo + (hi - lo) * k as f64 / 10.0)))
            .collect();
        let unique: std::collections::HashSet<&String> = labels.iter().collect();
        assert_eq!(unique.len(), labels.len(), "{lo}..{hi}: {labels:?}");
    }
    // No decimals a spacing of 10 or more does not need.
    assert_eq!(modaltol::plots::tick_label(0.0, 4010.7)(&500.0), "500");
    assert_eq!(modaltol::plots::tick_label(0.0, 6.0)(&0.6), "0.60");
}

/// The texts inside a plot's axes (not the legend, the tick labels or the axis names).
fn texts_in_axes(svg: &str) -> Vec<String> {
    texts(svg)
        .into_iter()
        .filter(|t| !t.rotated && t.x > 110.0 && t.x < modaltol::plots::AXES_WIDTH as f64)
        .filter(|t| t.content.ends_with('×'))
        .map(|t| t.content)
        .collect()
}

/// The Friswell rotor's 42 modes reach 8 kHz; its Campbell diagram shows the ones an engine
/// order reaches within the speeds (by hand from the nominal sweep), says how many it leaves
/// out, labels each order on the axes, names the frequency axis in words, and passes the
/// reader's checks (no label over data).
#[test]
fn campbell_shows_the_modes_an_order_reaches_and_labels_the_orders() {
    let m = common::example("friswell_5_9_1.toml");
    let cases = m.model().tolerance_cases(&[]).unwrap();
    let opt = AnalyzeOptions {
        speeds: range(0.0, 420.0, 30.0),
        cases,
        quadrature: None,
        ..Default::default()
    };
    let a = analyze(&m, &opt, &|_: &str, _: usize, _: usize| {});
    let (plots, _) = plots(m.model(), &a, Display::default());
    let c = plots.iter().find(|p| p.stem == "campbell").unwrap();
    check_all(std::slice::from_ref(c));
    let modes = a.nominal[0].as_ref().unwrap().modes.len();
    let reached: Vec<usize> = (0..modes)
        .filter(|&k| {
            a.nominal
                .iter()
                .flatten()
                .any(|p| p.modes[k].damped_frequency <= 3.0 * 420.0)
        })
        .collect();
    assert!(reached.len() >= 8 && reached.len() < modes, "{reached:?}");
    let legend: Vec<String> = texts(&c.svg)
        .into_iter()
        .filter(|t| t.x > modaltol::plots::AXES_WIDTH as f64 && t.content.starts_with("mode "))
        .map(|t| t.content)
        .collect();
    assert_eq!(legend.len(), reached.len(), "{legend:?}");
    for k in &reached {
        let name = format!("mode {} ", k + 1);
        assert!(
            legend.iter().any(|l| l.starts_with(&name)),
            "{name} not in {legend:?}"
        );
    }
    assert!(
        c.caption
            .contains(&format!("{} higher mode(s)", modes - reached.len())),
        "{}",
        c.caption
    );
    let mut labels = texts_in_axes(&c.svg);
    labels.sort();
    assert_eq!(labels, ["1×", "2×", "3×"]);
    assert!(c.svg.contains("damped natural frequency ω_d (rad/s)"));
}

/// The Campbell diagram's bands and its critical speeds' σ are those of the case with the most
/// toleranced variables (the governor's `all3`), not the first case's, and the report says so.
#[test]
fn campbell_shows_the_case_with_the_most_variables() {
    let m = common::example("governor.toml");
    let cases = m.model().tolerance_cases(&[]).unwrap();
    assert_eq!(cases[0].name, "k3");
    let opt = AnalyzeOptions {
        speeds: range(1.0, 3.0, 0.1),
        cases,
        quadrature: None,
        ..Default::default()
    };
    let a = analyze(&m, &opt, &|_: &str, _: usize, _: usize| {});
    assert_eq!(
        a.cases[modaltol::plots::campbell_case(&a, Display::default())].name,
        "all3"
    );
    let (plots, critical) = plots(m.model(), &a, Display::default());
    let c = plots.iter().find(|p| p.stem == "campbell").unwrap();
    assert!(c.title.contains("(case all3)"), "{}", c.title);
    let refs: Vec<&Plot> = plots.iter().collect();
    let html = report::report_html(m.model(), &a, &refs, &critical, Default::default());
    assert!(!critical.is_empty(), "the governor's mode crosses no order");
    assert!(html.contains("under case all3"));
    // A case chosen (`--campbell-case`): its bands, its σ, its "In short".
    let names: Vec<&str> = a.cases.iter().map(|c| c.name.as_str()).collect();
    let k3 = Display::case_named("k3", &names).unwrap();
    assert_eq!(names[k3], "k3");
    let d = Display {
        campbell_case: Some(k3),
        ..Display::default()
    };
    assert_eq!(modaltol::plots::campbell_case(&a, d), k3);
    let (chosen, critical) = modaltol::plots::plots(m.model(), &a, d);
    let c = chosen.iter().find(|p| p.stem == "campbell").unwrap();
    assert!(c.title.contains("(case k3)"), "{}", c.title);
    let refs: Vec<&Plot> = chosen.iter().collect();
    let extra = report::Extra {
        display: d,
        ..Default::default()
    };
    let html = report::report_html(m.model(), &a, &refs, &critical, extra);
    assert!(html.contains("under case k3") && html.contains("<p>Case <b>k3</b>"));
    assert!(
        Display::case_named("k4", &names)
            .unwrap_err()
            .contains("(k3, k6, k12")
    );
}

/// A 42-mode rotor plots the bands and σ of its lowest six modes and of every mode an engine
/// order reaches (ω_d within 1 % of 3× the top speed somewhere, read here from the nominal
/// sweep), not of the axial and high bending modes far above every excitation, and the report
/// says which; the tables keep every mode.
#[test]
fn a_many_mode_rotor_plots_the_modes_the_excitation_reaches() {
    let m = common::example("friswell_5_9_1.toml");
    let cases = m.model().tolerance_cases(&[]).unwrap()[..1].to_vec();
    let opt = AnalyzeOptions {
        speeds: vec![100.0, 400.0],
        cases,
        quadrature: None,
        ..Default::default()
    };
    let a = analyze(&m, &opt, &|_: &str, _: usize, _: usize| {});
    let modes = a.nominal[0].as_ref().unwrap().modes.len();
    assert_eq!(modes, 42);
    let want: Vec<usize> = (0..modes)
        .filter(|&k| {
            k < 6
                || a.nominal.iter().flatten().any(|p| {
                    p.modes[k].damped_frequency <= 1.01 * 3.0 * 400.0
                        && p.modes[k].class != modaltol::modal::ModeClass::Rigid
                })
        })
        .collect();
    assert!(want.len() > 6 && want.len() < modes / 2, "{want:?}");
    assert_eq!(modaltol::plots::plotted_modes(m.model(), &a), want);
    let (all, critical) = plots(m.model(), &a, Display::default());
    let case = &a.cases[0].name;
    for k in 0..modes {
        let stem = format!("band_{case}_damped_frequency_mode{}", k + 1);
        assert_eq!(
            all.iter().any(|p| p.stem == stem),
            want.contains(&k),
            "mode {}",
            k + 1
        );
    }
    assert!(
        a.rows.iter().any(|r| r.mode == Some(modes - 1)),
        "every mode in the table"
    );
    let refs: Vec<&Plot> = all.iter().collect();
    let html = report::report_html(m.model(), &a, &refs, &critical, Default::default());
    // The modes named as runs of consecutive numbers.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for &k in &want {
        match runs.last_mut() {
            Some(r) if r.1 + 1 == k + 1 => r.1 = k + 1,
            _ => runs.push((k + 1, k + 1)),
        }
    }
    let named: Vec<String> = (runs.iter())
        .map(|&(a, b)| {
            if a == b {
                format!("{a}")
            } else {
                format!("{a}–{b}")
            }
        })
        .collect();
    let line = format!("Band and σ plots of modes {} of 42", named.join(", "));
    assert!(html.contains(&line), "{line}");
    // "In short" opens with the modes that cross an engine order (its lateral modes, not the
    // 0.94 rad/s torsional coupling to the drive that is mode 1), each with its lowest
    // crossing.
    let mut crossing: Vec<usize> = (critical.iter())
        .filter(|c| c.meeting == modaltol::plots::Meeting::Crossing)
        .map(|c| c.mode)
        .collect();
    crossing.sort();
    crossing.dedup();
    assert!(crossing.len() >= 3 && crossing[0] > 0, "{crossing:?}");
    let short = html
        .split("In short</h2>")
        .nth(1)
        .unwrap()
        .split("</ul>")
        .next()
        .unwrap();
    let items: Vec<&str> = short.split("<li>").skip(1).collect();
    for (item, &k) in items.iter().zip(&crossing[..3]) {
        assert!(
            item.starts_with(&format!("Mode {}'s damped natural frequency", k + 1)),
            "{item}"
        );
        let lowest = (critical.iter())
            .filter(|c| c.mode == k && c.meeting == modaltol::plots::Meeting::Crossing)
            .min_by(|a, b| a.speed.total_cmp(&b.speed))
            .unwrap();
        assert!(
            item.contains(&format!(" It crosses {}× at Ω = ", lowest.order)),
            "{item}"
        );
    }
}
