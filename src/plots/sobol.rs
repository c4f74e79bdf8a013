//! Which tolerance matters, as bars: per case, each variable's first-order Sobol index S
//! (solid) and total index S_T (light) of each target the report's table shows (every
//! requirement's worst margin, then each output at the speed of its largest σ), their 95 %
//! jackknife intervals as whiskers and the derivative-based bound on S_T as a dash.

use super::Plot;
use super::draw::{Area, palette, panels, short};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::table::{Method, SobolIndex, Target};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// At most this many targets per plot (the first of the table's order; all in `sobol.csv`).
const MAX_TARGETS: usize = 6;

/// The Sobol indices of `a` worth showing: every requirement's worst margin, and each output at
/// the speed where its analytic σ is largest; per case, margins first then outputs in
/// order, each target's variables by decreasing total index.
pub fn sobol_shown(a: &Analysis) -> Vec<&(usize, SobolIndex)> {
    // Per case and output: the speed index with the largest analytic σ.
    let worst = |case: usize, o: usize| -> Option<usize> {
        let out = a.outputs[o];
        let mut best: Option<(usize, f64)> = None;
        for r in &a.rows {
            if r.case == case
                && r.method() == Method::Analytic
                && r.quantity == out.quantity
                && r.mode == out.mode
                && r.std.is_finite()
                && best.is_none_or(|b| r.std > b.1)
            {
                let i = a
                    .speeds
                    .iter()
                    .position(|w| w.to_bits() == r.speed.to_bits())?;
                best = Some((i, r.std));
            }
        }
        best.map(|b| b.0)
    };
    // Margins first, then outputs in order.
    let key = |t: &Target| match *t {
        Target::Margin(r) => (0, r),
        Target::Output(_, o) => (1, o),
    };
    let mut shown: Vec<&(usize, SobolIndex)> = a
        .sobol
        .iter()
        .filter(|(case, s)| match s.target {
            Target::Margin(_) => true,
            Target::Output(i, o) => worst(*case, o) == Some(i),
        })
        .collect();
    shown.sort_by(|x, y| {
        (x.0, key(&x.1.target))
            .cmp(&(y.0, key(&y.1.target)))
            .then(y.1.total.total_cmp(&x.1.total))
    });
    shown
}

/// The Sobol bars of case `case`; `None` where it has no indices.
pub(super) fn sobol_bars(model: &Model, a: &Analysis, case: usize) -> Option<Plot> {
    let shown: Vec<&SobolIndex> = sobol_shown(a)
        .into_iter()
        .filter(|x| x.0 == case)
        .map(|x| &x.1)
        .collect();
    let mut targets: Vec<Target> = Vec::new();
    for s in &shown {
        if !targets.contains(&s.target) && targets.len() < MAX_TARGETS {
            targets.push(s.target);
        }
    }
    let mut variables: Vec<usize> = shown.iter().map(|s| s.variable).collect();
    variables.sort_unstable();
    variables.dedup();
    if targets.is_empty() || variables.is_empty() {
        return None;
    }
    let name = |t: &Target| {
        t.describe(&model.requirements, &a.speeds, &a.outputs, |w| {
            ((w * 1e4).round() / 1e4).to_string()
        })
    };
    let groups: Vec<String> = variables
        .iter()
        .map(|&v| model.parameters[a.vars[v]].name.clone())
        .collect();
    let series: Vec<String> = targets.iter().map(name).collect();
    let bars: Vec<Bar> = shown
        .iter()
        .filter_map(|s| {
            Some(Bar {
                group: variables.iter().position(|&v| v == s.variable)?,
                series: targets.iter().position(|t| *t == s.target)?,
                first: [s.first, s.first_ci.0, s.first_ci.1],
                total: [s.total, s.total_ci.0, s.total_ci.1],
                bound: s.bound,
            })
        })
        .collect();
    let title = format!("{}: Sobol indices, case {}", model.name, a.cases[case].name);
    draw_bars(&title, &groups, &series, &bars)
        .ok()
        .map(|svg| Plot {
            stem: format!("sobol_{}", a.cases[case].name),
            caption: format!(
                "Which tolerance matters, case {}: per variable, the first-order Sobol index S \
                 (solid: the share of the variance it causes alone) and the total index S_T \
                 (light: with its interactions) of each target, 95 % jackknife intervals as \
                 whiskers, the derivative-based upper bound on S_T as a black dash (an arrow \
                 where it is above the axes). The numbers are in the table above and sobol.csv.",
                a.cases[case].name
            ),
            title,
            svg,
        })
}

/// One variable's indices for one target.
struct Bar {
    group: usize,
    series: usize,
    /// Value, interval low and high.
    first: [f64; 3],
    total: [f64; 3],
    bound: Option<f64>,
}

/// Bars in groups (one per variable) of series (one per target): per series a solid S bar and a
/// light S_T bar side by side, whiskers, bound dashes; the legend in a panel to the right.
fn draw_bars(
    title: &str,
    groups: &[String],
    series: &[String],
    bars: &[Bar],
) -> Result<String, String> {
    let top = bars
        .iter()
        .flat_map(|b| [b.first[2], b.total[2]])
        .filter(|x| x.is_finite())
        .fold(1.0f64, f64::max)
        * 1.05;
    // Room under 0 for the variables' names.
    let bottom = -0.1 * top;
    let height = 540.max(130 + 22 * series.len() as u32);
    panels(title, height, |axes, legend| {
        let n = groups.len() as f64;
        let mut chart = ChartBuilder::on(axes)
            .margin(14)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..n - 0.5, bottom..top)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_labels(8)
            .light_line_style(WHITE)
            .x_desc("design variable")
            .y_desc("Sobol index")
            .y_label_formatter(&|v: &f64| {
                if *v < -1e-12 {
                    String::new()
                } else {
                    format!("{v:.1}")
                }
            })
            .draw()
            .map_err(|e| e.to_string())?;
        let baseline = [(-0.5, 0.0), (n - 0.5, 0.0)];
        chart
            .draw_series(std::iter::once(PathElement::new(baseline, BLACK)))
            .map_err(|e| e.to_string())?;
        let label = ("sans-serif", 15)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart
            .draw_series(
                groups.iter().enumerate().map(|(g, name)| {
                    Text::new(name.clone(), (g as f64, 0.5 * bottom), label.clone())
                }),
            )
            .map_err(|e| e.to_string())?;
        let slot = 0.8 / series.len() as f64;
        let whisker = |x: f64, lo: f64, hi: f64| {
            PathElement::new(vec![(x, lo.max(bottom)), (x, hi.min(top))], BLACK)
        };
        for b in bars {
            let colour = palette(b.series);
            let x0 = b.group as f64 - 0.4 + slot * b.series as f64;
            let (xm, x1) = (x0 + 0.5 * slot, x0 + slot);
            let (first, total) = (b.first[0].max(0.0), b.total[0].max(0.0));
            chart
                .draw_series([
                    Rectangle::new([(x0, 0.0), (xm, first.min(top))], colour.filled()),
                    Rectangle::new([(xm, 0.0), (x1, total.min(top))], colour.mix(0.4).filled()),
                ])
                .map_err(|e| e.to_string())?;
            chart
                .draw_series([
                    whisker(0.5 * (x0 + xm), b.first[1], b.first[2]),
                    whisker(0.5 * (xm + x1), b.total[1], b.total[2]),
                ])
                .map_err(|e| e.to_string())?;
            if let Some(bound) = b.bound.filter(|x| x.is_finite()) {
                let y = bound.min(top);
                let dash = PathElement::new(vec![(xm, y), (x1, y)], BLACK.stroke_width(3));
                chart
                    .draw_series(std::iter::once(dash))
                    .map_err(|e| e.to_string())?;
                if bound > top {
                    let arrow = Text::new("↑".to_string(), (0.5 * (xm + x1), y), label.clone());
                    chart
                        .draw_series(std::iter::once(arrow))
                        .map_err(|e| e.to_string())?;
                }
            }
        }
        draw_legend(legend, series)
    })
}

/// The legend: a swatch per target, then how to read the bars.
fn draw_legend(legend: &Area, series: &[String]) -> Result<(), String> {
    let font = ("sans-serif", 14).into_font();
    let mut y = 40;
    let mut entry = |swatch: &dyn Fn(i32) -> Result<(), String>, text: &str| {
        swatch(y)?;
        legend
            .draw(&Text::new(short(text), (48, y - 7), font.clone()))
            .map_err(|e| e.to_string())?;
        y += 22;
        Ok::<(), String>(())
    };
    for (s, name) in series.iter().enumerate() {
        let c = palette(s);
        entry(
            &|y| {
                legend
                    .draw(&Rectangle::new([(10, y - 7), (25, y + 7)], c.filled()))
                    .and_then(|_| {
                        legend.draw(&Rectangle::new(
                            [(25, y - 7), (40, y + 7)],
                            c.mix(0.4).filled(),
                        ))
                    })
                    .map_err(|e| e.to_string())
            },
            name,
        )?;
    }
    let grey = RGBColor(120, 120, 120);
    entry(
        &|y| {
            legend
                .draw(&Rectangle::new([(10, y - 7), (40, y + 7)], grey.filled()))
                .map_err(|e| e.to_string())
        },
        "S, first order (solid)",
    )?;
    entry(
        &|y| {
            legend
                .draw(&Rectangle::new(
                    [(10, y - 7), (40, y + 7)],
                    grey.mix(0.4).filled(),
                ))
                .map_err(|e| e.to_string())
        },
        "S_T, total (light)",
    )?;
    entry(
        &|y| {
            legend
                .draw(&PathElement::new(
                    vec![(10, y), (40, y)],
                    BLACK.stroke_width(3),
                ))
                .map_err(|e| e.to_string())
        },
        "derivative bound on S_T",
    )?;
    entry(
        &|y| {
            legend
                .draw(&PathElement::new(vec![(25, y - 7), (25, y + 7)], BLACK))
                .map_err(|e| e.to_string())
        },
        "95 % jackknife interval",
    )?;
    Ok(())
}
