//! Plots of an analysis as SVG (plotters) and PNG (the same SVG rasterised by resvg), and the
//! critical speeds of the Campbell diagram. Returns file contents; writing is the caller's job.
//!
//! Per tolerance case and output (every mode's ω_d, and ζ where the system is damped, and |H|):
//! the answer to read (`analytic`: mean and ±σ band) with every method's mean (the paper's
//! Figs. 2, 5, 8, 10), σ against speed by every method (Figs. 3, 4, 6, 9, 11), each variable's
//! share of the first-order variance (Fig. 12) when a case has several; and one Campbell
//! diagram (ω_d of every mode against speed with ±3σ bands of the first case, engine-order lines
//! and their crossings marked).
//!
//! Every legend sits in a panel of its own right of the axes, so it never covers data; tick
//! labels carry as many digits as their spacing needs, so they never repeat; speeds and
//! frequencies are shown in the units asked for ([`Display`]).

use crate::analyze::{Analysis, Method, Row};
use crate::model::Model;
use crate::tolerance::Quantity;
use plotters::prelude::*;

/// A finished plot: a file stem and its SVG text.
pub struct Plot {
    pub stem: String,
    pub title: String,
    /// What the plot shows and how to read it (not a repeat of its title).
    pub caption: String,
    pub svg: String,
}

/// A unit for speeds or frequencies in plots and the report; the CSV and JSON files stay in
/// rad/s.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrequencyUnit {
    #[default]
    RadPerSecond,
    Hertz,
    Rpm,
}

impl FrequencyUnit {
    /// Value in this unit per rad/s.
    pub fn per_rad_per_second(self) -> f64 {
        match self {
            FrequencyUnit::RadPerSecond => 1.0,
            FrequencyUnit::Hertz => 1.0 / std::f64::consts::TAU,
            FrequencyUnit::Rpm => 60.0 / std::f64::consts::TAU,
        }
    }

    pub fn symbol(self) -> &'static str {
        match self {
            FrequencyUnit::RadPerSecond => "rad/s",
            FrequencyUnit::Hertz => "Hz",
            FrequencyUnit::Rpm => "rpm",
        }
    }
}

/// Units of the plots and the report: operating speeds and the system's frequencies.
#[derive(Debug, Clone, Copy, Default)]
pub struct Display {
    pub speed: FrequencyUnit,
    pub frequency: FrequencyUnit,
}

/// A mode crossing an engine-order line: `ω_d(Ω) = order·Ω`.
#[derive(Debug, Clone, Copy)]
pub struct CriticalSpeed {
    pub mode: usize,
    pub order: f64,
    /// rad/s.
    pub speed: f64,
    /// σ of the critical speed under the first case (first order): σ_ωd / |order − dω_d/dΩ|.
    pub std: f64,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// How a line is drawn.
#[derive(Clone, Copy, PartialEq)]
enum Style {
    Solid,
    Dashed,
    /// Small dots at the points (Monte Carlo), under the lines.
    Dots,
    /// Large marks at the points (speeds flagged, crossings), over everything.
    Marks,
}

/// The `i`-th colour: the six of [`COLORS`], then hues a golden angle apart, so that many modes
/// keep colours of their own.
fn palette(i: usize) -> RGBColor {
    if let Some(&c) = COLORS.get(i) {
        return c;
    }
    let hue = (i as f64 * 0.381_966_011_250_105).fract();
    let (r, g, b) = HSLColor(hue, 0.65, 0.42).rgb();
    RGBColor(r, g, b)
}

struct Line {
    name: String,
    pts: Vec<(f64, f64)>,
    color: RGBColor,
    style: Style,
}

impl Line {
    fn new(name: impl Into<String>, pts: Vec<(f64, f64)>, color: RGBColor) -> Line {
        Line {
            name: name.into(),
            pts,
            color,
            style: Style::Solid,
        }
    }

    fn styled(mut self, style: Style) -> Line {
        self.style = style;
        self
    }
}

/// A shaded band between two curves, named in the legend.
struct Band {
    name: String,
    lower: Vec<(f64, f64)>,
    upper: Vec<(f64, f64)>,
    color: RGBColor,
}

/// Width of the legend panel right of the axes (px).
pub const LEGEND_WIDTH: u32 = 290;
/// Width of the axes' part of a plot (px).
pub const AXES_WIDTH: u32 = 900;

/// Labels for ticks between `lo` and `hi`: as many digits as a tenth of the range needs (so
/// neighbouring ticks never read the same), in scientific notation for very large or small
/// magnitudes.
pub fn tick_label(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let step = ((hi - lo).abs() / 10.0).max(f64::MIN_POSITIVE);
    let big = lo.abs().max(hi.abs());
    let scientific = big >= 1e5 || (big > 0.0 && big < 1e-2);
    move |&v| {
        if v == 0.0 || v.abs() < step * 1e-9 {
            return "0".into();
        }
        if scientific {
            let digits = ((big / step).log10().ceil().max(0.0) as usize).min(14);
            format!("{v:.digits$e}")
        } else {
            let decimals = ((-step.log10()).ceil().max(0.0) as usize + 1).min(14);
            format!("{v:.decimals$}")
        }
    }
}

/// Splits a polyline at non-finite points.
fn segments(pts: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![Vec::new()];
    for &(x, y) in pts {
        if y.is_finite() {
            out.last_mut().expect("non-empty").push((x, y));
        } else if !out.last().expect("non-empty").is_empty() {
            out.push(Vec::new());
        }
    }
    out.retain(|s| !s.is_empty());
    out
}

/// Draws lines and bands against speed (`xlabel`) in the axes, and their legend in a panel to
/// the right.
fn draw(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    lines: &[Line],
    bands: &[Band],
) -> Result<String, String> {
    let all: Vec<(f64, f64)> = lines
        .iter()
        .flat_map(|l| l.pts.iter())
        .chain(bands.iter().flat_map(|b| b.lower.iter().chain(&b.upper)))
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if all.is_empty() {
        return Err("nothing to plot".into());
    }
    let (x0, x1) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (mut y0, mut y1) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    let pad = ((y1 - y0) * 0.05).max(1e-12 * y1.abs().max(1e-300));
    y0 -= pad;
    y1 += pad;
    let x1 = x1.max(x0 + 1e-9);
    let entries = lines.iter().filter(|l| !l.name.is_empty()).count() + bands.len();
    let height = 540.max(90 + 22 * entries as u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (AXES_WIDTH + LEGEND_WIDTH, height))
            .into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(|e| e.to_string())?;
        let (axes, legend) = root.split_horizontally(AXES_WIDTH);
        let mut chart = ChartBuilder::on(&axes)
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(96)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        let (xfmt, yfmt) = (tick_label(x0, x1), tick_label(y0, y1));
        chart
            .configure_mesh()
            .x_desc(xlabel)
            .y_desc(ylabel)
            .x_label_formatter(&xfmt)
            .y_label_formatter(&yfmt)
            .draw()
            .map_err(|e| e.to_string())?;
        for b in bands {
            let mut poly: Vec<(f64, f64)> = b
                .upper
                .iter()
                .copied()
                .filter(|p| p.1.is_finite())
                .collect();
            poly.extend(b.lower.iter().rev().copied().filter(|p| p.1.is_finite()));
            chart
                .draw_series(std::iter::once(Polygon::new(poly, b.color.mix(0.22))))
                .map_err(|e| e.to_string())?;
        }
        // Dots under dashed lines under solid ones, and the first line (the answer) on top.
        let mut order: Vec<&Line> = lines.iter().collect();
        order.sort_by_key(|l| match l.style {
            Style::Dots => 0,
            Style::Dashed => 1,
            Style::Solid => 2,
            Style::Marks => 4,
        });
        if let Some(i) = order.iter().position(|l| std::ptr::eq(*l, &lines[0])) {
            let first = order.remove(i);
            let marks = order.iter().position(|l| l.style == Style::Marks);
            order.insert(marks.unwrap_or(order.len()), first);
        }
        for l in order {
            let style = l.color.stroke_width(2);
            // Dots thinned to about 100 per series, so that they do not hide the lines.
            let every = (l.pts.len() / 100).max(1);
            for seg in segments(&l.pts) {
                match l.style {
                    Style::Solid => chart.draw_series(LineSeries::new(seg, style)),
                    Style::Dashed => chart.draw_series(DashedLineSeries::new(seg, 7, 5, style)),
                    Style::Dots => chart.draw_series(
                        seg.into_iter()
                            .step_by(every)
                            .map(|p| Circle::new(p, 2, l.color.filled())),
                    ),
                    Style::Marks => chart
                        .draw_series(seg.into_iter().map(|p| Circle::new(p, 3, l.color.filled()))),
                }
                .map_err(|e| e.to_string())?;
            }
        }
        // The legend panel: a swatch and a name per entry, bands first.
        let font = ("sans-serif", 14).into_font();
        let mut y = 40;
        for b in bands {
            legend
                .draw(&Rectangle::new(
                    [(10, y - 7), (40, y + 7)],
                    b.color.mix(0.22).filled(),
                ))
                .map_err(|e| e.to_string())?;
            legend
                .draw(&Text::new(short(&b.name), (48, y - 7), font.clone()))
                .map_err(|e| e.to_string())?;
            y += 22;
        }
        for l in lines.iter().filter(|l| !l.name.is_empty()) {
            let style = l.color.stroke_width(2);
            match l.style {
                Style::Solid => legend.draw(&PathElement::new(vec![(10, y), (40, y)], style)),
                Style::Dashed => legend
                    .draw(&PathElement::new(vec![(10, y), (20, y)], style))
                    .and_then(|_| legend.draw(&PathElement::new(vec![(28, y), (40, y)], style))),
                Style::Dots => legend.draw(&Circle::new((25, y), 2, l.color.filled())),
                Style::Marks => legend.draw(&Circle::new((25, y), 3, l.color.filled())),
            }
            .map_err(|e| e.to_string())?;
            legend
                .draw(&Text::new(short(&l.name), (48, y - 7), font.clone()))
                .map_err(|e| e.to_string())?;
            y += 22;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// A legend name cut to what the panel holds.
fn short(name: &str) -> String {
    const MAX: usize = 32;
    if name.chars().count() <= MAX {
        name.to_string()
    } else {
        let mut s: String = name.chars().take(MAX - 1).collect();
        s.push('…');
        s
    }
}

fn series(a: &Analysis, case: usize, q: Quantity, mode: Option<usize>, m: Method) -> Vec<&Row> {
    a.rows
        .iter()
        .filter(|r| r.case == case && r.quantity == q && r.mode == mode && r.method == m)
        .collect()
}

/// The axis label of a quantity, with its unit (the transfer function's from the model's
/// `[analysis] transfer`: response per excitation).
fn unit(model: &Model, q: Quantity, d: Display) -> String {
    match q {
        Quantity::DampedFrequency => format!("ω_d ({})", d.frequency.symbol()),
        Quantity::DampingRatio => "ζ (–)".into(),
        Quantity::TransferMagnitude => match &model.analysis.transfer {
            Some(t) => format!("|H| ({})", model.transfer_unit(t)),
            None => "|H|".into(),
        },
    }
}

/// Display factor of a quantity's values (frequencies in the unit asked for).
fn scale(q: Quantity, d: Display) -> f64 {
    match q {
        Quantity::DampedFrequency => d.frequency.per_rad_per_second(),
        _ => 1.0,
    }
}

/// Colours of the methods, the same in every plot.
fn method_color(m: Method) -> RGBColor {
    match m {
        Method::Analytic | Method::Quadrature => COLORS[0],
        Method::FirstOrder => COLORS[1],
        Method::SecondOrder => COLORS[2],
        Method::Invariant => COLORS[4],
        Method::MonteCarlo => COLORS[5],
    }
}

/// All plots of an analysis, and the Campbell diagram's critical speeds.
pub fn plots(model: &Model, a: &Analysis, d: Display) -> (Vec<Plot>, Vec<CriticalSpeed>) {
    let mut out = Vec::new();
    let modes = a
        .nominal
        .iter()
        .flatten()
        .map(|p| p.modes.len())
        .next()
        .unwrap_or(0);
    let xs = d.speed.per_rad_per_second();
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    let mut quantities: Vec<(Quantity, Option<usize>)> = Vec::new();
    for m in 0..modes {
        quantities.push((Quantity::DampedFrequency, Some(m)));
        // ζ where some design is damped (an undamped system's ζ is 0 with σ 0 everywhere).
        let damped = a.rows.iter().any(|r| {
            r.quantity == Quantity::DampingRatio
                && r.mode == Some(m)
                && (r.mean != 0.0 || r.std > 0.0)
        });
        if damped {
            quantities.push((Quantity::DampingRatio, Some(m)));
        }
    }
    if a.rows
        .iter()
        .any(|r| r.quantity == Quantity::TransferMagnitude)
    {
        quantities.push((Quantity::TransferMagnitude, None));
    }
    for (ci, case) in a.cases.iter().enumerate() {
        for &(q, mode) in &quantities {
            let tag = mode.map_or(String::new(), |m| format!("_mode{}", m + 1));
            let label = mode.map_or(q.as_str().to_string(), |m| {
                format!("{} of mode {}", q.as_str(), m + 1)
            });
            let ys = scale(q, d);
            let pts = |rows: &[&Row], f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
                rows.iter().map(|r| (r.speed * xs, f(r) * ys)).collect()
            };
            // The answer to read first, then the paper's method and the others.
            let methods: Vec<Method> = [
                Method::Analytic,
                Method::FirstOrder,
                Method::SecondOrder,
                Method::Invariant,
                Method::MonteCarlo,
            ]
            .into_iter()
            .filter(|&m| !series(a, ci, q, mode, m).is_empty())
            .collect();
            // ω_d and |H| cannot be negative: bands stop at zero.
            let floor = if q == Quantity::DampingRatio {
                f64::NEG_INFINITY
            } else {
                0.0
            };
            // Mean ± σ: the answer as a band, every method's mean, first order's ± σ dashed.
            let answer = series(a, ci, q, mode, Method::Analytic);
            let bands = vec![Band {
                name: "analytic mean ± σ (the answer)".into(),
                lower: pts(&answer, &|r| (r.mean - r.std).max(floor)),
                upper: pts(&answer, &|r| r.mean + r.std),
                color: method_color(Method::Analytic),
            }];
            let mut lines = Vec::new();
            for &m in &methods {
                if m == Method::SecondOrder || m == Method::Invariant {
                    continue;
                }
                let rows = series(a, ci, q, mode, m);
                let style = if m == Method::MonteCarlo {
                    Style::Dots
                } else {
                    Style::Solid
                };
                lines.push(
                    Line::new(
                        format!("{} mean", m.as_str()),
                        pts(&rows, &|r| r.mean),
                        method_color(m),
                    )
                    .styled(style),
                );
                if m == Method::FirstOrder {
                    lines.push(
                        Line::new(
                            "first_order mean ± σ",
                            pts(&rows, &|r| r.mean + r.std),
                            method_color(m),
                        )
                        .styled(Style::Dashed),
                    );
                    lines.push(
                        Line::new(
                            "",
                            pts(&rows, &|r| (r.mean - r.std).max(floor)),
                            method_color(m),
                        )
                        .styled(Style::Dashed),
                    );
                }
            }
            // The speeds where first order's σ is more than 10 % off the quadrature's.
            let off = first_order_off(a, ci, q, mode);
            if off.iter().any(|p| p.1.is_finite()) {
                lines.push(
                    Line::new(
                        "first order σ > 10 % off",
                        off.iter().map(|&(x, y)| (x * xs, y * ys)).collect(),
                        RED,
                    )
                    .styled(Style::Marks),
                );
            }
            let title = format!("{}: {label}, case {}", model.name, case.name);
            if let Ok(svg) = draw(&title, &xlabel, &unit(model, q, d), &lines, &bands) {
                out.push(Plot {
                    stem: format!("band_{}_{}{tag}", case.name, q.as_str()),
                    caption: format!(
                        "Mean ± σ of {label} against speed for case {}. The shaded band is the \
                         answer to read (analytic); dashed lines are the paper's first-order \
                         band; red dots mark the speeds where first order's σ is more than 10 % \
                         off.",
                        case.name
                    ),
                    title,
                    svg,
                });
            }
            // σ by method.
            let lines: Vec<Line> = methods
                .iter()
                .map(|&m| {
                    let style = match m {
                        Method::MonteCarlo => Style::Dots,
                        Method::SecondOrder | Method::Invariant => Style::Dashed,
                        _ => Style::Solid,
                    };
                    Line::new(
                        m.as_str(),
                        pts(&series(a, ci, q, mode, m), &|r| r.std),
                        method_color(m),
                    )
                    .styled(style)
                })
                .collect();
            let title = format!("{}: σ of {label}, case {}", model.name, case.name);
            let ylabel = format!("σ of {}", unit(model, q, d));
            if let Ok(svg) = draw(&title, &xlabel, &ylabel, &lines, &[]) {
                out.push(Plot {
                    stem: format!("std_{}_{}{tag}", case.name, q.as_str()),
                    caption: format!(
                        "σ of {label} by each method, case {}. Where the methods part, read \
                         analytic (the quadrature: its error estimate is in tolerance.csv); \
                         Monte Carlo scatters by its own sampling error.",
                        case.name
                    ),
                    title,
                    svg,
                });
            }
        }
        if let Some(p) = probabilities(model, a, ci, modes, d) {
            out.push(p);
        }
        // Shares of the first-order variance (cases with several variables).
        if case.tolerances.len() > 1 && modes > 0 {
            let rows = series(
                a,
                ci,
                Quantity::DampedFrequency,
                Some(0),
                Method::FirstOrder,
            );
            let lines: Vec<Line> = a
                .vars
                .iter()
                .enumerate()
                .filter(|(_, b)| case.tolerances.iter().any(|t| t.0 == **b))
                .map(|(k, &b)| {
                    Line::new(
                        model.parameters[b].name.clone(),
                        rows.iter()
                            .map(|r| {
                                (
                                    r.speed * xs,
                                    r.shares.as_ref().map_or(f64::NAN, |s| 100.0 * s[k]),
                                )
                            })
                            .collect(),
                        palette(k),
                    )
                })
                .collect();
            let title = format!(
                "{}: share of the variance of ω_d (mode 1), case {}",
                model.name, case.name
            );
            if let Ok(svg) = draw(&title, &xlabel, "share of variance (%)", &lines, &[]) {
                out.push(Plot {
                    stem: format!("shares_{}", case.name),
                    caption: format!(
                        "Each design variable's share of the first-order variance of mode 1's \
                         ω_d, case {}: which tolerance to tighten at each speed.",
                        case.name
                    ),
                    title,
                    svg,
                });
            }
        }
    }
    let (campbell, critical) = campbell(model, a, modes, d);
    out.extend(campbell);
    (out, critical)
}

/// Speeds where first order's σ is more than 10 % off the quadrature's (the quadrature's σ
/// at least 2 % of its largest): `(speed, first-order mean)` there, NaN elsewhere.
pub fn first_order_off(
    a: &Analysis,
    case: usize,
    q: Quantity,
    mode: Option<usize>,
) -> Vec<(f64, f64)> {
    let quad = series(a, case, q, mode, Method::Quadrature);
    let first = series(a, case, q, mode, Method::FirstOrder);
    let largest = quad.iter().map(|r| r.std).fold(0.0f64, f64::max);
    quad.iter()
        .map(|r| {
            let f = first
                .iter()
                .find(|f| f.speed.to_bits() == r.speed.to_bits());
            let off = f.is_some_and(|f| {
                r.std >= 0.02 * largest && ((f.std - r.std).abs() > 0.1 * r.std || f.std.is_nan())
            });
            (
                r.speed,
                if off {
                    f.map_or(f64::NAN, |f| f.mean)
                } else {
                    f64::NAN
                },
            )
        })
        .collect()
}

/// Probabilities of character of one case against speed, quadrature and Monte Carlo (a colour
/// per event, solid for the quadrature and dots for Monte Carlo); `None` when every
/// probability stays below 0.1 %.
fn probabilities(
    model: &Model,
    a: &Analysis,
    case: usize,
    modes: usize,
    d: Display,
) -> Option<Plot> {
    use crate::quadrature::Event;
    let mut events: Vec<(Event, Option<usize>)> =
        (0..modes).map(|m| (Event::Overdamped, Some(m))).collect();
    events.extend([(Event::Unstable, None), (Event::OtherBranch, None)]);
    let xs = d.speed.per_rad_per_second();
    let mut lines = Vec::new();
    for (k, &(event, mode)) in events.iter().enumerate() {
        for method in [Method::Quadrature, Method::MonteCarlo] {
            let pts: Vec<(f64, f64)> = a
                .probabilities
                .iter()
                .filter(|p| {
                    p.case == case && p.event == event && p.mode == mode && p.method == method
                })
                .map(|p| (p.speed * xs, 100.0 * p.probability))
                .collect();
            // Below 0.1 % at every speed: left to probabilities.csv (far-tail noise otherwise).
            if pts.iter().all(|p| p.1 < 0.1) {
                continue;
            }
            let name = match mode {
                Some(m) => format!("{} mode {}, {}", event.as_str(), m + 1, method.as_str()),
                None => format!("{}, {}", event.as_str(), method.as_str()),
            };
            let style = if method == Method::MonteCarlo {
                Style::Dots
            } else {
                Style::Solid
            };
            lines.push(Line::new(name, pts, palette(k)).styled(style));
        }
    }
    if lines.is_empty() {
        return None;
    }
    let title = format!(
        "{}: probability of a change of character, case {}",
        model.name, a.cases[case].name
    );
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    draw(&title, &xlabel, "probability (%)", &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("probability_{}", a.cases[case].name),
            caption: format!(
                "Probability that a mode is overdamped, that the equilibrium is unstable or that a \
                 design sits on another equilibrium branch, case {}: quadrature (lines, ± its \
                 error estimate in probabilities.csv) and Monte Carlo (dots, 95 % Wilson \
                 intervals there).",
                a.cases[case].name
            ),
            title,
            svg,
        })
}

/// The engine orders drawn on the Campbell diagram: 1, 2, 3 and the model's transfer order.
fn orders(model: &Model) -> Vec<f64> {
    let mut o = vec![1.0, 2.0, 3.0];
    if let Some(t) = model.analysis.transfer
        && !o.contains(&t.order)
        && t.order > 0.0
    {
        o.push(t.order);
    }
    o.sort_by(f64::total_cmp);
    o
}

/// Where `ω_d` of one mode (rows of the `analytic` method) crosses `order × Ω`, with σ of the
/// crossing speed (first order in σ of ω_d: σ_ωd / |order − dω_d/dΩ|).
fn crossings(rows: &[&Row], mode: usize, order: f64) -> Vec<CriticalSpeed> {
    let mut out = Vec::new();
    for w in rows.windows(2) {
        let (f0, f1) = (
            w[0].mean - order * w[0].speed,
            w[1].mean - order * w[1].speed,
        );
        if f0.is_finite() && f1.is_finite() && f0 * f1 < 0.0 && w[0].mean > 0.0 && w[1].mean > 0.0 {
            let t = f0 / (f0 - f1);
            let speed = w[0].speed + t * (w[1].speed - w[0].speed);
            let slope = (w[1].mean - w[0].mean) / (w[1].speed - w[0].speed);
            let sd = w[0].std + t * (w[1].std - w[0].std);
            out.push(CriticalSpeed {
                mode,
                order,
                speed,
                std: sd / (order - slope).abs(),
            });
        }
    }
    out
}

/// Campbell diagram: nominal ω_d of every mode with ±3σ (first case, the automatic `analytic`
/// choice, so the bands stay right through changes of class), the engine-order lines (cut at
/// the top of the modes) and the critical speeds where a mode crosses one, marked.
fn campbell(
    model: &Model,
    a: &Analysis,
    modes: usize,
    d: Display,
) -> (Option<Plot>, Vec<CriticalSpeed>) {
    let (xs, ys) = (
        d.speed.per_rad_per_second(),
        d.frequency.per_rad_per_second(),
    );
    let mut lines = Vec::new();
    let mut bands = Vec::new();
    let mut critical = Vec::new();
    let orders = orders(model);
    let mut top = 0.0f64;
    for m in 0..modes {
        let rows = series(a, 0, Quantity::DampedFrequency, Some(m), Method::Analytic);
        let color = palette(m);
        for &o in &orders {
            critical.extend(crossings(&rows, m, o));
        }
        top = rows
            .iter()
            .map(|r| r.mean + 3.0 * r.std)
            .filter(|v| v.is_finite())
            .fold(top, f64::max);
        bands.push(Band {
            name: format!("mode {} ± 3σ", m + 1),
            lower: rows
                .iter()
                .map(|r| (r.speed * xs, (r.mean - 3.0 * r.std).max(0.0) * ys))
                .collect(),
            upper: rows
                .iter()
                .map(|r| (r.speed * xs, (r.mean + 3.0 * r.std) * ys))
                .collect(),
            color,
        });
        lines.push(Line::new(
            format!("mode {}", m + 1),
            rows.iter().map(|r| (r.speed * xs, r.mean * ys)).collect(),
            color,
        ));
    }
    let speeds: Vec<f64> = a.nominal.iter().flatten().map(|p| p.speed).collect();
    if let (Some(&lo), Some(&hi)) = (speeds.first(), speeds.last()) {
        for &o in &orders {
            // Cut where the line leaves the modes' range, so that it does not squash them.
            let end = if top > 0.0 { hi.min(top / o) } else { hi };
            if end > lo {
                lines.push(
                    Line::new(
                        format!("{o}×Ω"),
                        vec![(lo * xs, o * lo * ys), (end * xs, o * end * ys)],
                        BLACK,
                    )
                    .styled(if o.to_bits() == 1f64.to_bits() {
                        Style::Solid
                    } else {
                        Style::Dashed
                    }),
                );
            }
        }
    }
    if !critical.is_empty() {
        lines.push(
            Line::new(
                "critical speeds (crossings)",
                critical
                    .iter()
                    .map(|c| (c.speed * xs, c.order * c.speed * ys))
                    .collect(),
                RED,
            )
            .styled(Style::Marks),
        );
    }
    critical.sort_by(|a, b| a.speed.total_cmp(&b.speed));
    let case = a.cases.first().map_or("", |c| c.name.as_str());
    let title = format!("{}: Campbell diagram (case {case})", model.name);
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    let ylabel = format!("ω_d ({})", d.frequency.symbol());
    let plot = draw(&title, &xlabel, &ylabel, &lines, &bands)
        .ok()
        .map(|svg| Plot {
            stem: "campbell".into(),
            caption: format!(
                "Damped natural frequency of every mode against speed with its ±3σ band (case \
                 {case}, analytic), the engine orders 1×, 2×, 3×Ω{} and, in red, the critical \
                 speeds where a mode crosses one (listed with their σ above).",
                model
                    .analysis
                    .transfer
                    .filter(|t| ![1.0, 2.0, 3.0].contains(&t.order))
                    .map_or(String::new(), |t| format!(" and the model's {}×Ω", t.order))
            ),
            title,
            svg,
        });
    (plot, critical)
}

/// Rasterises an SVG to PNG bytes (text in the bundled font, see [`fonts`]).
pub fn png(
    svg: &str,
    fonts: &std::sync::Arc<resvg::usvg::fontdb::Database>,
) -> Result<Vec<u8>, String> {
    let opt = resvg::usvg::Options {
        fontdb: fonts.clone(),
        ..Default::default()
    };
    let tree = resvg::usvg::Tree::from_str(svg, &opt).map_err(|e| e.to_string())?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        resvg::tiny_skia::Pixmap::new(size.width(), size.height()).ok_or("empty image")?;
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::default(),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}

/// DejaVu Sans, shipped with the project (`assets/fonts`, Bitstream Vera licence), so PNG text
/// looks the same on every machine, with or without system fonts.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The font database for [`png`]: the bundled DejaVu Sans as every generic family.
pub fn fonts() -> std::sync::Arc<resvg::usvg::fontdb::Database> {
    let mut db = resvg::usvg::fontdb::Database::new();
    db.load_font_data(FONT.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    db.set_serif_family("DejaVu Sans");
    db.set_monospace_family("DejaVu Sans");
    std::sync::Arc::new(db)
}
