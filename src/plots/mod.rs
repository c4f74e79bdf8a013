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
//!
//! Submodules: `draw` (the axes, lines, bands and legend panel every plot is drawn with),
//! `bands`, `probability` and `campbell` (one per kind of plot), and `png` (rasterising).

mod bands;
mod campbell;
mod draw;
mod png;
mod probability;

pub use bands::first_order_off;
pub use campbell::CriticalSpeed;
pub use draw::{AXES_WIDTH, LEGEND_WIDTH, tick_label};
pub use png::{fonts, png};

use crate::analyze::{Analysis, Method, Row};
use crate::model::Model;
use crate::tolerance::Quantity;
use campbell::campbell;
use draw::{Band, COLORS, Line, Style, draw, palette};
use plotters::prelude::*;
use probability::probabilities;

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
