//! Plots of an analysis as SVG (plotters) and PNG (the same SVG rasterised by resvg), and the
//! critical speeds of the Campbell diagram. Returns file contents; writing is the caller's job.
//!
//! Per tolerance case: mean ± σ bands against speed for every mode's ω_d and for |H| (the paper's
//! Figs. 2, 5, 8, 10), σ against speed by every method (Figs. 3, 4, 6, 9, 11), each variable's
//! share of the first-order variance (Fig. 12) when a case has several; and one Campbell diagram
//! (ω_d of every mode against speed with ±3σ bands of the first case and the order line).

use crate::analyze::{Analysis, Method, Row};
use crate::model::Model;
use crate::tolerance::Quantity;
use plotters::prelude::*;

/// A finished plot: a file stem and its SVG text.
pub struct Plot {
    pub stem: String,
    pub title: String,
    pub svg: String,
}

/// A mode crossing the order line: `ω_d(Ω) = order·Ω`.
#[derive(Debug, Clone, Copy)]
pub struct CriticalSpeed {
    pub mode: usize,
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

struct Line {
    name: String,
    pts: Vec<(f64, f64)>,
    color: RGBColor,
}

struct Band {
    lower: Vec<(f64, f64)>,
    upper: Vec<(f64, f64)>,
    color: RGBColor,
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

fn draw(title: &str, ylabel: &str, lines: &[Line], bands: &[Band]) -> Result<String, String> {
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
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (960, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(86)
            .build_cartesian_2d(x0..x1.max(x0 + 1e-9), y0..y1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("speed Ω (rad/s)")
            .y_desc(ylabel)
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
                .draw_series(std::iter::once(Polygon::new(poly, b.color.mix(0.18))))
                .map_err(|e| e.to_string())?;
        }
        for l in lines {
            let color = l.color;
            let mut first = true;
            for seg in segments(&l.pts) {
                let s = chart
                    .draw_series(LineSeries::new(seg, color.stroke_width(2)))
                    .map_err(|e| e.to_string())?;
                if first {
                    s.label(l.name.clone()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(2))
                    });
                    first = false;
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn series(a: &Analysis, case: usize, q: Quantity, mode: Option<usize>, m: Method) -> Vec<&Row> {
    a.rows
        .iter()
        .filter(|r| r.case == case && r.quantity == q && r.mode == mode && r.method == m)
        .collect()
}

/// The axis label of a quantity, with its unit (the transfer function's from the model's
/// `[analysis] transfer`: response per excitation).
fn unit(model: &Model, q: Quantity) -> String {
    match q {
        Quantity::DampedFrequency => "ω_d (rad/s)".into(),
        Quantity::DampingRatio => "ζ".into(),
        Quantity::TransferMagnitude => match &model.analysis.transfer {
            Some(t) => format!("|H| ({})", model.transfer_unit(t)),
            None => "|H|".into(),
        },
    }
}

/// All plots of an analysis, and the Campbell diagram's critical speeds.
pub fn plots(model: &Model, a: &Analysis) -> (Vec<Plot>, Vec<CriticalSpeed>) {
    let mut out = Vec::new();
    let modes = a
        .nominal
        .iter()
        .flatten()
        .map(|p| p.modes.len())
        .next()
        .unwrap_or(0);
    let mut quantities: Vec<(Quantity, Option<usize>)> = (0..modes)
        .map(|m| (Quantity::DampedFrequency, Some(m)))
        .collect();
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
            // The answer to read first, then the paper's method beside it.
            let methods: Vec<Method> = [
                Method::Quadrature,
                Method::FirstOrder,
                Method::SecondOrder,
                Method::Invariant,
                Method::MonteCarlo,
            ]
            .into_iter()
            .filter(|&m| !series(a, ci, q, mode, m).is_empty())
            .collect();
            // Mean ± σ bands.
            let mut lines = Vec::new();
            let mut bands = Vec::new();
            for (k, &m) in methods.iter().enumerate() {
                if m == Method::SecondOrder || m == Method::Invariant {
                    continue;
                }
                let rows = series(a, ci, q, mode, m);
                let color = COLORS[k % COLORS.len()];
                lines.push(Line {
                    name: format!("{} mean", m.as_str()),
                    pts: rows.iter().map(|r| (r.speed, r.mean)).collect(),
                    color,
                });
                // ω_d and |H| cannot be negative: the band stops at zero.
                let floor = if q == Quantity::DampingRatio {
                    f64::NEG_INFINITY
                } else {
                    0.0
                };
                bands.push(Band {
                    lower: rows
                        .iter()
                        .map(|r| (r.speed, (r.mean - r.std).max(floor)))
                        .collect(),
                    upper: rows.iter().map(|r| (r.speed, r.mean + r.std)).collect(),
                    color,
                });
            }
            // The speeds where first order's σ is more than 10 % off the quadrature's.
            let off = first_order_off(a, ci, q, mode);
            if off.iter().any(|p| p.1.is_finite()) {
                lines.push(Line {
                    name: "first order > 10 % off".into(),
                    pts: off,
                    color: RED,
                });
            }
            let title = format!("{}: {label}, mean ± σ, case {}", model.name, case.name);
            if let Ok(svg) = draw(&title, &unit(model, q), &lines, &bands) {
                out.push(Plot {
                    stem: format!("band_{}_{}{tag}", case.name, q.as_str()),
                    title,
                    svg,
                });
            }
            // σ by method.
            let lines: Vec<Line> = methods
                .iter()
                .enumerate()
                .map(|(k, &m)| Line {
                    name: m.as_str().into(),
                    pts: series(a, ci, q, mode, m)
                        .iter()
                        .map(|r| (r.speed, r.std))
                        .collect(),
                    color: COLORS[k % COLORS.len()],
                })
                .collect();
            let title = format!("{}: σ of {label}, case {}", model.name, case.name);
            if let Ok(svg) = draw(&title, &format!("σ of {}", unit(model, q)), &lines, &[]) {
                out.push(Plot {
                    stem: format!("std_{}_{}{tag}", case.name, q.as_str()),
                    title,
                    svg,
                });
            }
        }
        if let Some(p) = probabilities(model, a, ci, modes) {
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
                .map(|(k, &b)| Line {
                    name: model.parameters[b].name.clone(),
                    pts: rows
                        .iter()
                        .map(|r| {
                            (
                                r.speed,
                                r.shares.as_ref().map_or(f64::NAN, |s| 100.0 * s[k]),
                            )
                        })
                        .collect(),
                    color: COLORS[k % COLORS.len()],
                })
                .collect();
            let title = format!(
                "{}: share of the variance of ω_d (mode 1), case {}",
                model.name, case.name
            );
            if let Ok(svg) = draw(&title, "share of variance (%)", &lines, &[]) {
                out.push(Plot {
                    stem: format!("shares_{}", case.name),
                    title,
                    svg,
                });
            }
        }
    }
    let (campbell, critical) = campbell(model, a, modes);
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
/// per event and method); `None` when every probability stays below 0.1 %.
fn probabilities(model: &Model, a: &Analysis, case: usize, modes: usize) -> Option<Plot> {
    use crate::quadrature::Event;
    let mut events: Vec<(Event, Option<usize>)> =
        (0..modes).map(|m| (Event::Overdamped, Some(m))).collect();
    events.extend([(Event::Unstable, None), (Event::OtherBranch, None)]);
    let mut lines = Vec::new();
    for (k, &(event, mode)) in events.iter().enumerate() {
        for (j, method) in [Method::Quadrature, Method::MonteCarlo]
            .into_iter()
            .enumerate()
        {
            let pts: Vec<(f64, f64)> = a
                .probabilities
                .iter()
                .filter(|p| {
                    p.case == case && p.event == event && p.mode == mode && p.method == method
                })
                .map(|p| (p.speed, 100.0 * p.probability))
                .collect();
            // Below 0.1 % at every speed: left to probabilities.csv (far-tail noise otherwise).
            if pts.iter().all(|p| p.1 < 0.1) {
                continue;
            }
            let name = match mode {
                Some(m) => format!("{} mode {}, {}", event.as_str(), m + 1, method.as_str()),
                None => format!("{}, {}", event.as_str(), method.as_str()),
            };
            lines.push(Line {
                name,
                pts,
                color: COLORS[(2 * k + j) % COLORS.len()],
            });
        }
    }
    if lines.is_empty() {
        return None;
    }
    let title = format!(
        "{}: probability of a change of character, case {}",
        model.name, a.cases[case].name
    );
    draw(&title, "probability (%)", &lines, &[])
        .ok()
        .map(|svg| Plot {
            stem: format!("probability_{}", a.cases[case].name),
            title,
            svg,
        })
}

/// Campbell diagram: nominal ω_d of every mode with ±3σ (first case, the automatic `analytic`
/// choice, so the bands stay right through changes of class), the order
/// line, and the critical speeds where a mode crosses it.
fn campbell(model: &Model, a: &Analysis, modes: usize) -> (Option<Plot>, Vec<CriticalSpeed>) {
    let order = model.analysis.transfer.map_or(1.0, |t| t.order);
    let mut lines = Vec::new();
    let mut bands = Vec::new();
    let mut critical = Vec::new();
    for m in 0..modes {
        let rows = series(a, 0, Quantity::DampedFrequency, Some(m), Method::Analytic);
        let color = COLORS[m % COLORS.len()];
        let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.speed, r.mean)).collect();
        for w in rows.windows(2) {
            let (f0, f1) = (
                w[0].mean - order * w[0].speed,
                w[1].mean - order * w[1].speed,
            );
            if f0.is_finite()
                && f1.is_finite()
                && f0 * f1 < 0.0
                && w[0].mean > 0.0
                && w[1].mean > 0.0
            {
                let t = f0 / (f0 - f1);
                let speed = w[0].speed + t * (w[1].speed - w[0].speed);
                let slope = (w[1].mean - w[0].mean) / (w[1].speed - w[0].speed);
                let sd = w[0].std + t * (w[1].std - w[0].std);
                critical.push(CriticalSpeed {
                    mode: m,
                    speed,
                    std: sd / (order - slope).abs(),
                });
            }
        }
        bands.push(Band {
            lower: rows
                .iter()
                .map(|r| (r.speed, (r.mean - 3.0 * r.std).max(0.0)))
                .collect(),
            upper: rows
                .iter()
                .map(|r| (r.speed, r.mean + 3.0 * r.std))
                .collect(),
            color,
        });
        lines.push(Line {
            name: format!("mode {}", m + 1),
            pts,
            color,
        });
    }
    let speeds: Vec<f64> = a.nominal.iter().flatten().map(|p| p.speed).collect();
    if let (Some(&lo), Some(&hi)) = (speeds.first(), speeds.last()) {
        lines.push(Line {
            name: format!("{order}×Ω"),
            pts: vec![(lo, order * lo), (hi, order * hi)],
            color: BLACK,
        });
    }
    let case = a.cases.first().map_or("", |c| c.name.as_str());
    let title = format!("{}: Campbell diagram, ω_d ± 3σ (case {case})", model.name);
    let plot = draw(&title, "ω_d (rad/s)", &lines, &bands)
        .ok()
        .map(|svg| Plot {
            stem: "campbell".into(),
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
const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// The font database for [`png`]: the bundled DejaVu Sans as every generic family.
pub fn fonts() -> std::sync::Arc<resvg::usvg::fontdb::Database> {
    let mut db = resvg::usvg::fontdb::Database::new();
    db.load_font_data(FONT.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    db.set_serif_family("DejaVu Sans");
    db.set_monospace_family("DejaVu Sans");
    std::sync::Arc::new(db)
}
