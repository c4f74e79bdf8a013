//! How every plot is drawn: the axes with tick labels that never repeat, the lines (solid,
//! dashed, dots, marks) and shaded bands in a fixed stacking order, and the legend in a panel of
//! its own right of the axes. The plot kinds only say what to draw.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

pub(super) const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// How a line is drawn.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Style {
    Solid,
    Dashed,
    /// Short dashes close together (told from [`Style::Dashed`] at a glance).
    Dotted,
    /// Long dashes.
    LongDashed,
    /// Small dots at the points (Monte Carlo), under the lines.
    Dots,
    /// Large marks at the points (speeds flagged, crossings), over everything.
    Marks,
}

/// The `i`-th colour: the six of [`COLORS`], then hues a golden angle apart, so that many modes
/// keep colours of their own.
pub(super) fn palette(i: usize) -> RGBColor {
    if let Some(&c) = COLORS.get(i) {
        return c;
    }
    let hue = (i as f64 * 0.381_966_011_250_105).fract();
    let (r, g, b) = HSLColor(hue, 0.65, 0.42).rgb();
    RGBColor(r, g, b)
}

pub(super) struct Line {
    name: String,
    pts: Vec<(f64, f64)>,
    color: RGBColor,
    style: Style,
    /// Text written in the axes at the line's last point (an engine order's `2×`).
    label: Option<String>,
}

impl Line {
    pub(super) fn new(name: impl Into<String>, pts: Vec<(f64, f64)>, color: RGBColor) -> Line {
        Line {
            name: name.into(),
            pts,
            color,
            style: Style::Solid,
            label: None,
        }
    }

    pub(super) fn styled(mut self, style: Style) -> Line {
        self.style = style;
        self
    }

    /// The line with `label` written at its last point, inside the axes.
    pub(super) fn labelled(mut self, label: impl Into<String>) -> Line {
        self.label = Some(label.into());
        self
    }
}

/// A shaded band between two curves, named in the legend.
pub(super) struct Band {
    pub(super) name: String,
    pub(super) lower: Vec<(f64, f64)>,
    pub(super) upper: Vec<(f64, f64)>,
    pub(super) color: RGBColor,
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
            // One decimal more than the spacing's first digit needs, none from a spacing of
            // 10 on (a speed axis to 4000 rpm reads 500, not 500.0).
            let decimals = ((-step.log10()).ceil() + 1.0).clamp(0.0, 14.0) as usize;
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

/// The axes of a plot: speed across, the quantity up.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws lines and bands against speed (`xlabel`) in the axes, and their legend in a panel to
/// the right.
pub(super) fn draw(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    lines: &[Line],
    bands: &[Band],
) -> Result<String, String> {
    draw_up_to(title, xlabel, ylabel, lines, bands, None)
}

/// [`draw`] with the vertical axis ending at `top` where given (the lines and bands all below
/// it: a line that should end on the frame is cut there by its maker).
pub(super) fn draw_up_to(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    lines: &[Line],
    bands: &[Band],
    top: Option<f64>,
) -> Result<String, String> {
    let Some((x0, x1, y0, mut y1)) = extent(lines, bands) else {
        return Err("nothing to plot".into());
    };
    if let Some(t) = top.filter(|&t| t > y0) {
        y1 = t;
    }
    let entries = lines.iter().filter(|l| !l.name.is_empty()).count()
        + bands.iter().filter(|b| !b.name.is_empty()).count();
    let height = 540.max(90 + 22 * entries as u32);
    panels(title, height, |axes, legend| {
        let mut chart = ChartBuilder::on(axes)
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
        draw_bands(&mut chart, bands)?;
        draw_lines(&mut chart, lines)?;
        draw_legend(legend, lines, bands)
    })
}

/// Part of a plot's SVG.
pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// An SVG `height` px high under `title`, its axes' part and its legend panel drawn by `body`.
pub(super) fn panels(
    title: &str,
    height: u32,
    body: impl for<'b> FnOnce(&Area<'b>, &Area<'b>) -> Result<(), String>,
) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (AXES_WIDTH + LEGEND_WIDTH, height))
            .into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(|e| e.to_string())?;
        let (axes, legend) = root.split_horizontally(AXES_WIDTH);
        body(&axes, &legend)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// The ranges of the axes, `(x0, x1, y0, y1)`: every finite point of the lines and bands, with
/// 5 % of room above and below; `None` where there is no such point.
fn extent(lines: &[Line], bands: &[Band]) -> Option<(f64, f64, f64, f64)> {
    let all: Vec<(f64, f64)> = lines
        .iter()
        .flat_map(|l| l.pts.iter())
        .chain(bands.iter().flat_map(|b| b.lower.iter().chain(&b.upper)))
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if all.is_empty() {
        return None;
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
    Some((x0, x1, y0, y1))
}

/// Shades each band between its curves, under everything else.
fn draw_bands(chart: &mut Chart, bands: &[Band]) -> Result<(), String> {
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
    Ok(())
}

/// Draws the lines in their stacking order ([`stacking`]), each split where it has no value.
fn draw_lines(chart: &mut Chart, lines: &[Line]) -> Result<(), String> {
    for l in stacking(lines) {
        let style = l.color.stroke_width(2);
        // Dots thinned to about 100 per series, so that they do not hide the lines.
        let every = (l.pts.len() / 100).max(1);
        for seg in segments(&l.pts) {
            match l.style {
                Style::Solid => chart.draw_series(LineSeries::new(seg, style)),
                Style::Dashed => chart.draw_series(DashedLineSeries::new(seg, 7, 5, style)),
                Style::Dotted => chart.draw_series(DashedLineSeries::new(seg, 2, 4, style)),
                Style::LongDashed => chart.draw_series(DashedLineSeries::new(seg, 16, 5, style)),
                Style::Dots => chart.draw_series(
                    seg.into_iter()
                        .step_by(every)
                        .map(|p| Circle::new(p, 2, l.color.filled())),
                ),
                Style::Marks => {
                    chart.draw_series(seg.into_iter().map(|p| Circle::new(p, 3, l.color.filled())))
                }
            }
            .map_err(|e| e.to_string())?;
        }
        if let Some(text) = &l.label {
            draw_label(chart, l, text)?;
        }
    }
    Ok(())
}

/// Writes `text` beside the end of a rising line `l`, up and left of its last point where the
/// axes have room above it, else below and far enough left that the line, rising to the end,
/// passes right of the text.
fn draw_label(chart: &mut Chart, l: &Line, text: &str) -> Result<(), String> {
    let [.., a, b] = l.pts.as_slice() else {
        return Ok(());
    };
    let (pa, pb) = (chart.backend_coord(a), chart.backend_coord(b));
    // The line's slope on the page (pixels up per pixel across).
    let slope = f64::from(pa.1 - pb.1) / f64::from((pb.0 - pa.0).max(1));
    const SIZE: i32 = 15;
    let width = (0.62 * f64::from(SIZE) * text.chars().count() as f64).ceil() as i32;
    let top = chart.plotting_area().get_pixel_range().1.start;
    let offset = if pb.1 - SIZE - 4 >= top {
        (-4 - width, -SIZE - 3)
    } else {
        let clear = (f64::from(SIZE + 3) / slope.max(0.25)).ceil() as i32;
        (-clear - 4 - width, 2)
    };
    let font = ("sans-serif", SIZE).into_font().color(&l.color);
    chart
        .draw_series(std::iter::once(
            EmptyElement::at(*b) + Text::new(text.to_string(), offset, font),
        ))
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// The order the lines are drawn in: dots under dashed lines under solid ones, and the first
/// line (the answer) on top of them, under the marks only.
fn stacking(lines: &[Line]) -> Vec<&Line> {
    let mut order: Vec<&Line> = lines.iter().collect();
    order.sort_by_key(|l| match l.style {
        Style::Dots => 0,
        Style::Dashed | Style::Dotted | Style::LongDashed => 1,
        Style::Solid => 2,
        Style::Marks => 4,
    });
    if let Some(i) = order.iter().position(|l| std::ptr::eq(*l, &lines[0])) {
        let first = order.remove(i);
        let marks = order.iter().position(|l| l.style == Style::Marks);
        order.insert(marks.unwrap_or(order.len()), first);
    }
    order
}

/// The legend panel: a swatch and a name per named entry, bands first (a band without a name
/// goes with the line of its colour).
fn draw_legend(
    legend: &DrawingArea<SVGBackend, Shift>,
    lines: &[Line],
    bands: &[Band],
) -> Result<(), String> {
    let font = ("sans-serif", 14).into_font();
    let mut y = 40;
    for b in bands.iter().filter(|b| !b.name.is_empty()) {
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
        if let Some(b) = bands
            .iter()
            .find(|b| b.name.is_empty() && b.color == l.color)
        {
            legend
                .draw(&Rectangle::new(
                    [(10, y - 7), (40, y + 7)],
                    b.color.mix(0.22).filled(),
                ))
                .map_err(|e| e.to_string())?;
        }
        let style = l.color.stroke_width(2);
        match l.style {
            Style::Solid => legend.draw(&PathElement::new(vec![(10, y), (40, y)], style)),
            Style::Dashed => legend
                .draw(&PathElement::new(vec![(10, y), (20, y)], style))
                .and_then(|_| legend.draw(&PathElement::new(vec![(28, y), (40, y)], style))),
            Style::Dotted => (0..5).try_for_each(|k| {
                let x = 10 + 6 * k;
                legend.draw(&PathElement::new(vec![(x, y), (x + 2, y)], style))
            }),
            Style::LongDashed => legend
                .draw(&PathElement::new(vec![(10, y), (32, y)], style))
                .and_then(|_| legend.draw(&PathElement::new(vec![(37, y), (40, y)], style))),
            Style::Dots => legend.draw(&Circle::new((25, y), 2, l.color.filled())),
            Style::Marks => legend.draw(&Circle::new((25, y), 3, l.color.filled())),
        }
        .map_err(|e| e.to_string())?;
        legend
            .draw(&Text::new(short(&l.name), (48, y - 7), font.clone()))
            .map_err(|e| e.to_string())?;
        y += 22;
    }
    Ok(())
}

/// A legend name cut to what the panel holds.
pub(super) fn short(name: &str) -> String {
    const MAX: usize = 32;
    if name.chars().count() <= MAX {
        name.to_string()
    } else {
        let mut s: String = name.chars().take(MAX - 1).collect();
        s.push('…');
        s
    }
}
