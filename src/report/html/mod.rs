//! `report.html`: one page per analysis, built from named sections in the order a reader needs
//! them: a table of contents; the tolerance cases (what was toleranced); the answer in short
//! (mean ± 3σ of the outputs that matter, what drives them, whether the requirements hold); the
//! tolerance allocation that made the design where there is one; the specification (yield,
//! what the design meets at the target, the Sobol indices); the numeric summary; the critical
//! speeds and near-tangencies; the response peaks; where first order is off; the failures, the
//! rows without a value and the notes; the mechanism; the timings; a reading guide and the
//! plots. The paper's comparisons (its timings, "the paper's method") appear for its two
//! models only. Sections big enough to be read on their own are submodules.

mod allocation;
mod first_order;
mod mechanism;
mod short;
mod sigma;
mod specification;

use super::{inadmissible_warnings, outside_request_lines, paper_timings, unfilled};
use crate::allocate::Allocation;
use crate::analyze::Analysis;
use crate::drawing::Drawing;
use crate::model::Model;
use crate::montecarlo::McOptions;
use crate::plots::{
    CriticalSpeed, Display, LOWEST_PLOTTED, Meeting, NEAR, Plot, campbell_case, plotted_modes,
};
use allocation::allocation_section;
use first_order::first_order_table;
pub use mechanism::MODES_DRAWN;
use mechanism::mechanism_section;
use short::in_short;
use sigma::summary_table;
use specification::{limits_table, sobol_table, specification};
use std::fmt::Write;

/// `report.html` of an analysis (the sections of the module documentation), with the plots
/// (each an `<stem>.svg` in the same directory), the allocation that made the design
/// (`extra.allocation`) and the mechanism (`extra.drawing`) where there are, in the display
/// units `extra.display`.
pub fn report_html(
    model: &Model,
    a: &Analysis,
    plots: &[&Plot],
    critical: &[CriticalSpeed],
    extra: Extra<'_>,
) -> String {
    let Extra {
        allocation,
        drawing,
        mc,
        display: d,
    } = extra;
    let mut h = String::new();
    page_head(&mut h, model);
    notices(&mut h, a, mc);
    let _ = writeln!(
        h,
        "<p>Model file <code>{}</code>. Speeds {} points. Speeds in {}, frequencies in {} here; the CSV and JSON files are in SI units (rad/s).</p>",
        esc(&model.file),
        a.nominal.len(),
        d.speed.symbol(),
        d.frequency.symbol()
    );
    // The sections, in the order a reader needs them: what was toleranced, the answer in
    // short, the specification, the numbers, where the modes meet the orders, the checks of
    // the methods, then the machinery (timings) and the plots.
    let mut b = String::new();
    cases_table(&mut b, model, a);
    in_short(&mut b, model, a, critical, d);
    if let Some(al) = allocation {
        allocation_section(&mut b, model, al);
    }
    specification(&mut b, model, a);
    limits_table(&mut b, model, a);
    sobol_table(&mut b, model, a);
    let _ = writeln!(b, "{}", summary_table(model, a, critical, d));
    critical_table(&mut b, a, critical, d);
    peaks_table(&mut b, model, a, d);
    let _ = writeln!(b, "{}", first_order_table(model, a, d));
    failures(&mut b, a);
    b.push_str(&unfilled_table(a));
    for line in outside_request_lines(a) {
        let _ = writeln!(b, "<p><b>Note:</b> {}</p>", esc(&line));
    }
    if let Some(dr) = drawing {
        mechanism_section(&mut b, a, dr);
    }
    timing_table(&mut b, model, a, mc);
    reading_guide(&mut b);
    figures(&mut b, model, a, plots);
    h.push_str(&contents(&mut b));
    h.push_str(&b);
    let _ = writeln!(h, "</body></html>");
    h
}

/// The table of contents of the sections in `body` (its `<h2>` headings), each heading given
/// an `id` to link to where it has none.
fn contents(body: &mut String) -> String {
    let mut out = String::from("<nav><b>Contents:</b> ");
    let mut entries: Vec<String> = Vec::new();
    let mut rest = body.as_str();
    let mut rebuilt = String::with_capacity(body.len() + 256);
    while let Some(at) = rest.find("<h2") {
        rebuilt.push_str(&rest[..at]);
        rest = &rest[at..];
        let open_end = rest.find('>').map_or(rest.len(), |e| e + 1);
        let close = rest.find("</h2>").unwrap_or(rest.len());
        let open = &rest[..open_end];
        let title = rest.get(open_end..close).unwrap_or("");
        let id = match open.find("id=\"") {
            Some(i) => open[i + 4..].split('"').next().unwrap_or("").to_string(),
            None => format!("section-{}", entries.len() + 1),
        };
        if open.contains("id=\"") {
            rebuilt.push_str(open);
        } else {
            let _ = write!(rebuilt, "<h2 id=\"{id}\">");
        }
        // The title without its markup, for the list.
        let plain: String = {
            let mut t = String::new();
            let mut tag = false;
            for c in title.chars() {
                match c {
                    '<' => tag = true,
                    '>' => tag = false,
                    c if !tag => t.push(c),
                    _ => {}
                }
            }
            t
        };
        entries.push(format!("<a href=\"#{id}\">{plain}</a>"));
        rest = &rest[open_end..];
    }
    rebuilt.push_str(rest);
    *body = rebuilt;
    out.push_str(&entries.join(" · "));
    out.push_str("</nav>\n");
    out
}

/// What a report shows besides the analysis, and in which units.
#[derive(Debug, Default, Clone, Copy)]
pub struct Extra<'a> {
    /// The Monte Carlo's options, where the run had one (its sample count and seed in the
    /// notices and the timings).
    pub mc: Option<&'a McOptions>,
    /// The units speeds and frequencies are shown in.
    pub display: Display,
    /// The tolerance allocation that made the design, opening the report.
    pub allocation: Option<&'a Allocation>,
    /// The mechanism drawn at the middle of the speeds, its files (`mechanism.svg`,
    /// `mechanism.html`, `mode_K.svg`) beside the report.
    pub drawing: Option<&'a Drawing>,
}

/// The page up to its heading: the document head with its style sheet, and the title.
fn page_head(h: &mut String, model: &Model) {
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>modaltol: {}</title>\n<style>body{{font-family:sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;color:#222}}table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:4px 10px;text-align:right}}th{{background:#eee}}img{{max-width:100%;border:1px solid #ddd;margin:0.5em 0}}code{{background:#f4f4f4}}</style></head><body>\n",
        esc(&model.name)
    );
    let _ = writeln!(h, "<h1>Tolerance analysis: {}</h1>", esc(&model.name));
}

/// What the reader must know before the numbers: a Monte Carlo cut short, samples that were
/// not physically admissible.
fn notices(h: &mut String, a: &Analysis, mc: Option<&McOptions>) {
    if let Some(m) = mc.filter(|m| a.interrupted(m.samples)) {
        let _ = writeln!(
            h,
            "<p><b>Partial result:</b> the Monte Carlo was interrupted; samples done per case {:?} of {} asked.</p>",
            a.samples_done, m.samples
        );
    }
    for w in inadmissible_warnings(a) {
        let _ = writeln!(h, "<p><b>Warning:</b> {}</p>", esc(&w));
    }
}

/// The tolerance cases: per case, each variable's nominal value and tolerance.
fn cases_table(h: &mut String, model: &Model, a: &Analysis) {
    let _ = writeln!(
        h,
        "<h2>Tolerance cases</h2><p>What was toleranced: each case is one scenario of \
         tolerances on the model's parameters, analysed on its own (a variable outside a case \
         keeps its nominal value there). A tolerance is ±3σ of a normal distribution unless \
         the parameter says uniform (then its half-width).</p><table><tr><th>case</th>\
         <th>variable</th><th>nominal</th><th>tolerance (±)</th><th>% of nominal</th>\
         <th>distribution</th></tr>"
    );
    for c in &a.cases {
        for (b, t) in &c.tolerances {
            let p = &model.parameters[*b];
            let abs = t.absolute(p.value);
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&c.name),
                esc(&p.name),
                p.value,
                sig(abs),
                if p.value != 0.0 {
                    format!("{} %", crate::plots::percent(abs / p.value.abs()))
                } else {
                    "–".into()
                },
                match p.distribution {
                    crate::model::Distribution::Normal => "normal (±3σ)",
                    crate::model::Distribution::Uniform => "uniform",
                }
            );
        }
    }
    let _ = writeln!(h, "</table>");
}

/// The timing table: the paper's timings for its two examples beside this run's (analytic,
/// quadrature, Monte Carlo and their ratios), and the quadrature's rules per case.
fn timing_table(h: &mut String, model: &Model, a: &Analysis, mc: Option<&McOptions>) {
    let _ = writeln!(
        h,
        "<h2>Timing</h2><table><tr><th></th><th>analytic, Taylor methods (s)</th><th>quadrature (s)</th><th>Monte Carlo (s)</th><th>ratio Monte Carlo / analytic</th><th>ratio Monte Carlo / quadrature</th></tr>"
    );
    if let Some((example, analytic, mc, ratio)) = paper_timings(model) {
        let _ = writeln!(
            h,
            "<tr><td>paper, {example} (2007 hardware, 3000 samples)</td><td>{analytic}</td><td>–</td><td>{mc}</td><td>{ratio}</td><td>–</td></tr>"
        );
    }
    let secs = |t: Option<f64>| t.map_or("not run".to_string(), |t| format!("{t:.3}"));
    let ratio = |b: Option<f64>| {
        a.monte_carlo_seconds
            .zip(b)
            .map_or("–".to_string(), |(m, b)| format!("{:.0}", m / b))
    };
    let samples = mc.map_or(String::new(), |m| {
        format!(
            ", {} samples, {:?} sampling, seed {}",
            m.samples, m.sampling, m.seed
        )
    });
    let _ = writeln!(
        h,
        "<tr><td>this run ({} case(s), {} speeds{samples})</td><td>{:.3}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr></table>",
        a.cases.len(),
        a.nominal.len(),
        a.analytic_seconds,
        secs(a.quadrature_seconds),
        secs(a.monte_carlo_seconds),
        ratio(Some(a.analytic_seconds)),
        ratio(a.quadrature_seconds),
    );
    let _ = writeln!(
        h,
        "<p>The analytic time covers the nominal sweep, exact gradients and Hessians at every speed and the Taylor methods for all cases (the sweep and gradients {:.3} s, the Hessians {:.3} s){}. The quadrature sweeps its nodes across all speeds like Monte Carlo samples ({}). The ratios say how many times longer the Monte Carlo took.</p>",
        a.first_order_seconds,
        a.second_order_seconds,
        if paper_timings(model).is_some() {
            "; the paper's covers first order only"
        } else {
            ""
        },
        a.cases
            .iter()
            .zip(&a.quadrature_rules)
            .map(|(c, (rule, _))| format!("{}: {}", esc(&c.name), esc(rule)))
            .collect::<Vec<_>>()
            .join("; ")
    );
}

/// The critical speeds of the Campbell diagram with their σ, and the near-tangencies (none: no
/// section).
fn critical_table(h: &mut String, a: &Analysis, critical: &[CriticalSpeed], d: Display) {
    if !critical.is_empty() {
        let u = d.speed.symbol();
        let case = &a.cases[campbell_case(a, d)].name;
        let _ = writeln!(
            h,
            "<h2>Critical speeds</h2><p>Where a mode's damped natural frequency meets an engine \
             order: a crossing, with σ of its speed under case {} (first order), or a \
             near-tangency, where the mode comes within {:.0} % of the line (or within 3σ of its \
             frequency) without crossing it, at the speed of its closest approach: a tolerance \
             or a speed between those analysed can make it a crossing.</p>\
             <table><tr><th>mode</th><th>engine order</th><th>meets it</th><th>speed ({u})</th><th>σ ({u})</th></tr>",
            esc(case),
            100.0 * NEAR
        );
        let f = d.speed.per_rad_per_second();
        for c in critical {
            let (meets, sd) = match c.meeting {
                Meeting::Crossing => ("crosses".to_string(), format!("{:.4}", c.std * f)),
                Meeting::Tangency {
                    gap,
                    within_3_sigma,
                } => (
                    format!(
                        "comes within {:.2} % ({}){}",
                        100.0 * gap.abs(),
                        if gap > 0.0 { "above" } else { "below" },
                        if within_3_sigma {
                            ", inside its ±3σ"
                        } else {
                            ""
                        }
                    ),
                    "–".to_string(),
                ),
            };
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}×</td><td>{meets}</td><td>{:.4}</td><td>{sd}</td></tr>",
                c.mode + 1,
                c.order,
                c.speed * f,
            );
        }
        let _ = writeln!(h, "</table>");
    }
}

/// The transfer function's peaks along the speed, located between the swept speeds, with
/// their first-order σ under the first case (none: no section).
fn peaks_table(h: &mut String, model: &Model, a: &Analysis, d: Display) {
    let Some(t) = model.analysis.transfer.filter(|_| !a.peaks.is_empty()) else {
        return;
    };
    let (u, unit) = (d.speed.symbol(), model.transfer_unit(&t));
    let f = d.speed.per_rad_per_second();
    let _ = writeln!(
        h,
        "<h2>Response peaks</h2><p>Where |H| peaks along the speed, found between the swept \
         speeds (Newton on the exact derivative in speed), with σ by first order under case \
         {} (exact gradients; <code>peaks.csv</code> has every case). The amplification \
         factor is API 684's: the speed of the peak over the width between its half-power \
         speeds. A resonance is an \
         undamped mode at the excitation frequency: |H| is unbounded there.</p>\
         <table><tr><th>kind</th><th>speed ({u})</th><th>σ ({u})</th><th>|H| ({})</th>\
         <th>σ ({})</th><th>amplification factor (API 684)</th><th>σ</th><th>mode</th></tr>",
        esc(&a.cases[0].name),
        esc(&unit),
        esc(&unit)
    );
    let sd = |r: &Result<crate::tolerance::Stat, String>, show: &dyn Fn(f64) -> String| {
        r.as_ref().map_or_else(|why| esc(why), |s| show(s.std))
    };
    for row in &a.peaks {
        let _ = match row {
            Ok((peak, cases)) => writeln!(
                h,
                "<tr><td>{}</td><td>{:.4}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
                 <td>{}</td><td>{}</td></tr>",
                peak.kind.as_str(),
                peak.speed * f,
                sd(&cases[0].speed, &|v| format!("{:.4}", v * f)),
                peak.magnitude
                    .map_or("unbounded".to_string(), |m| format!("{m:.4e}")),
                (peak.magnitude).map_or(String::new(), |_| sd(&cases[0].magnitude, &|v| format!(
                    "{v:.4e}"
                ))),
                (peak.amplification.as_ref())
                    .map_or_else(|why| esc(why), |a| format!("{:.3}", a.0)),
                (peak.amplification.as_ref()).map_or(String::new(), |_| sd(
                    &cases[0].amplification,
                    &|v| format!("{v:.3}")
                )),
                peak.mode.map_or(String::new(), |k| (k + 1).to_string()),
            ),
            Err(e) => writeln!(
                h,
                "<tr><td colspan=8>not located near {:.4} {u}: {}</td></tr>",
                e.near * f,
                esc(&e.why)
            ),
        };
    }
    let _ = writeln!(h, "</table>");
}

/// The speeds where the nominal analysis failed, with why (none: no section).
fn failures(h: &mut String, a: &Analysis) {
    if !a.failures.is_empty() {
        let _ = writeln!(h, "<h2>Failed speeds</h2><ul>");
        for (w, m) in &a.failures {
            let _ = writeln!(h, "<li>{w} rad/s: {}</li>", esc(m));
        }
        let _ = writeln!(h, "</ul>");
    }
}

/// The reading guide: what each method is, which to read, and what the plots show.
fn reading_guide(h: &mut String) {
    let _ = writeln!(
        h,
        "<h2>Reading guide</h2><ul>\
<li><b>first_order</b> is the classical method (Kim &amp; Yoo 2007's): mean = nominal value, σ² = Σ (∂f/∂b)² σ_b² with exact derivatives. It is right where the output is smooth and the tolerances small.</li>\
<li><b>second_order</b> adds the curvature (Hessians): a mean shift and variance terms. It repairs points where first order gives σ = 0 but the output does vary (|H| at the undamped resonance).</li>\
<li><b>invariant</b> (ω_d only) propagates the pair discriminant D = λ₁λ₂ − (λ₁+λ₂)²/4, which stays smooth where a mode turns overdamped, and maps it through ω_d = √max(0, D). Use it near class changes, where first and second order fail.</li>\
<li><b>quadrature</b> integrates the whole nonlinear analysis (equilibrium, modes, |H|) over the distribution of the design variables, deterministically: every node is swept from the lowest speed like a Monte Carlo sample, the integral is split where a mode turns overdamped or a design passes its own bifurcation, and every mean and σ comes with an error estimate (<code>mean_error</code>, <code>std_error</code>) and the 5/50/95 % quantiles. It is right at every speed, class changes and branch switches included.</li>\
<li><b>analytic</b> is the answer to read: the quadrature where it ran (its <code>basis</code> says so), else the automatic Taylor choice (invariant near a change of class, else second order). Red marks in the band plots show the speeds where first order's σ is more than 10 % off.</li>\
<li><b>monte_carlo</b> re-runs the whole nonlinear analysis per sample, with 95 % confidence intervals in <code>tolerance.csv</code> and counts of failed samples and of samples whose mode changed class. Where the distribution is a mixture (most samples overdamped, a few far out), a few thousand samples are far from converged; the quadrature is not.</li>\
<li><b>Probabilities</b> (<code>probabilities.csv</code>): per speed, the probability that a mode is overdamped, that the equilibrium is unstable, and that a design is on another equilibrium branch than the nominal one, by quadrature (± its error estimate) and Monte Carlo (95 % Wilson interval).</li>\
<li>Band plots shade the analytic mean ± σ; the Campbell diagram shows ±3σ (analytic) of one case (<code>--campbell-case</code>; by default the one with the most toleranced variables), the engine orders and where a mode crosses or comes near one.</li></ul>"
    );
}

/// The plots, each an `<stem>.svg` beside the page, with its caption; which modes have their
/// own plots where not all do ([`plotted_modes`]).
fn figures(h: &mut String, model: &Model, a: &Analysis, plots: &[&Plot]) {
    let _ = writeln!(h, "<h2>Plots</h2>");
    let modes = (a.nominal.iter().flatten())
        .map(|p| p.modes.len())
        .next()
        .unwrap_or(0);
    let plotted = plotted_modes(model, a);
    if plotted.len() < modes {
        let _ = writeln!(
            h,
            "<p>Band and σ plots of modes {} of {modes}: the lowest {LOWEST_PLOTTED} and those an \
             engine order reaches within the speeds analysed. The other modes lie above every \
             excitation drawn; their rows are in <code>tolerance.csv</code>.</p>",
            ranges(&plotted)
        );
    }
    for p in plots {
        let _ = writeln!(
            h,
            "<figure><img src=\"{}.svg\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            esc(&p.stem),
            esc(&p.title),
            esc(&p.caption)
        );
    }
}

/// The rows without a value, per case, method, output and reason, with their speeds.
fn unfilled_table(a: &Analysis) -> String {
    let groups = unfilled(a);
    if groups.is_empty() {
        return String::new();
    }
    let mut h = String::from(
        "<h2>Rows without a value</h2><p>Where a method gives no mean and σ, and why          (<code>tolerance.csv</code>'s <code>reason</code> column; speeds in rad/s).</p>         <table><tr><th>case</th><th>method</th><th>output</th><th>rows</th><th>speeds</th>         <th>reason</th></tr>",
    );
    for u in &groups {
        let output = u.mode.map_or(u.quantity.as_str().to_string(), |m| {
            format!("{} mode {}", u.quantity.as_str(), m + 1)
        });
        let lo = u.speeds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = u.speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let speeds = if lo.to_bits() == hi.to_bits() {
            format!("{lo}")
        } else {
            format!("{lo}–{hi}")
        };
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>             <td style=\"text-align:left\">{}</td></tr>",
            esc(&a.cases[u.case].name),
            u.method.as_str(),
            esc(&output),
            u.speeds.len(),
            speeds,
            esc(&u.reason)
        );
    }
    h.push_str("</table>");
    h
}

/// `x` to three significant digits, without trailing zeros (a spread in per cent: `0.762`,
/// `2.2`, `1010`).
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exp = x.abs().log10().floor() as i32;
    let s = format!("{x:.*}", (2 - exp).max(0) as usize);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A number to five significant digits, in fixed notation where that stays short.
fn sig(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let exp = x.abs().log10().floor() as i32;
    if (-3..5).contains(&exp) {
        format!("{x:.*}", (4 - exp).max(0) as usize)
    } else {
        format!("{x:.4e}")
    }
}

/// [`sig`] without trailing zeros: a value read off a grid as it was given (a speed of
/// `3` rad/s, not `3.0000`).
fn plain(x: f64) -> String {
    let s = sig(x);
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// 0-based indices as 1-based numbers with runs joined: `1–6, 9, 11–12`.
fn ranges(modes: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut k = 0;
    while k < modes.len() {
        let mut end = k;
        while end + 1 < modes.len() && modes[end + 1] == modes[end] + 1 {
            end += 1;
        }
        parts.push(if end == k {
            format!("{}", modes[k] + 1)
        } else {
            format!("{}–{}", modes[k] + 1, modes[end] + 1)
        });
        k = end + 1;
    }
    parts.join(", ")
}

/// Escapes text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
