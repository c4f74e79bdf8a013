//! Plots of an analysis as SVG (plotters) and PNG (the same SVG rasterised by resvg), and the
//! critical speeds of the Campbell diagram. Returns file contents; writing is the caller's job.
//!
//! Per tolerance case and output (every mode's ω_d, and ζ where the system is damped, and |H|):
//! the answer to read (`analytic`: mean and ±σ band) with every method's mean (the paper's
//! Figs. 2, 5, 8, 10), σ against speed by every method (Figs. 3, 4, 6, 9, 11), each variable's
//! share of the first-order variance (Fig. 12) when a case has several; and one Campbell
//! diagram (ω_d of the modes an engine order reaches against speed, with ±3σ bands of the case
//! with the most toleranced variables, labelled engine-order lines, and the crossings and
//! near-tangencies marked).
//!
//! Every legend sits in a panel of its own right of the axes, so it never covers data; tick
//! labels carry as many digits as their spacing needs, so they never repeat; speeds and
//! frequencies are shown in the units asked for ([`Display`]).
//!
//! Submodules: `draw` (the axes, lines, bands and legend panel every plot is drawn with),
//! `bands`, `sigma`, `shares`, `probability`, `yields`, `sobol` (bars) and `campbell` (one per
//! kind of plot), and `png`
//! (rasterising). This module holds what the kinds share (the display units, an output's rows
//! and points, the methods' colours) and [`plots`], which makes them all.

mod bands;
mod campbell;
mod draw;
mod png;
mod probability;
mod shares;
mod sigma;
mod sobol;
mod yields;

pub use bands::first_order_off;
pub use campbell::{CriticalSpeed, LOWEST_PLOTTED, Meeting, NEAR, campbell_case, plotted_modes};
pub use draw::{AXES_WIDTH, LEGEND_WIDTH, tick_label};
pub use png::{fonts, png};
pub use sobol::sobol_shown;

use crate::analyze::Analysis;
use crate::model::{Case, Model};
use crate::output::Quantity;
use crate::table::Method;
use crate::table::Row;
use bands::band;
use campbell::campbell;
use draw::COLORS;
use plotters::prelude::RGBColor;
use probability::probabilities;
use shares::shares;
use sigma::sigma;
use sobol::sobol_bars;
use yields::yield_curves;

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

/// How the plots and the report show an analysis: the units of operating speeds and of the
/// system's frequencies, and the tolerance case the Campbell diagram and "In short" are about.
#[derive(Debug, Clone, Copy, Default)]
pub struct Display {
    pub speed: FrequencyUnit,
    pub frequency: FrequencyUnit,
    /// The case the Campbell diagram's bands, its critical speeds' σ and the report's "In
    /// short" are of, as an index into the analysis's cases ([`Display::case_named`]); `None`:
    /// the one with the most toleranced variables ([`campbell_case`]).
    pub campbell_case: Option<usize>,
}

impl Display {
    /// The index of the case `name` among `cases` (the cases an analysis runs, in its order),
    /// for [`Display::campbell_case`]; an error naming the cases where none is called so.
    pub fn case_named(name: &str, cases: &[&str]) -> Result<usize, String> {
        cases.iter().position(|c| *c == name).ok_or_else(|| {
            format!(
                "no tolerance case '{name}' among the cases analysed ({})",
                cases.join(", ")
            )
        })
    }
}

fn series(a: &Analysis, case: usize, q: Quantity, mode: Option<usize>, m: Method) -> Vec<&Row> {
    a.rows
        .iter()
        .filter(|r| r.case == case && r.quantity == q && r.mode == mode && r.method() == m)
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

/// A probability `p` in per cent as a person writes it: 0.9973 → `99.73` (not
/// `99.72999999999999`), to twelve significant digits.
pub fn percent(p: f64) -> String {
    let v = 100.0 * p;
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let digits = (11 - v.abs().log10().floor() as i32).clamp(0, 17) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
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
    let xlabel = format!("speed Ω ({})", d.speed.symbol());
    let quantities = outputs(a, &plotted_modes(model, a));
    for (ci, case) in a.cases.iter().enumerate() {
        for &(q, mode) in &quantities {
            let o = Output {
                model,
                a,
                ci,
                q,
                mode,
                d,
            };
            out.extend(band(&o, &xlabel));
            out.extend(sigma(&o, &xlabel));
        }
        if let Some(p) = probabilities(model, a, ci, modes, d) {
            out.push(p);
        }
        if let Some(p) = yield_curves(model, a, ci, d) {
            out.push(p);
        }
        if let Some(p) = sobol_bars(model, a, ci) {
            out.push(p);
        }
        // Shares of the first-order variance (cases with several variables).
        if case.tolerances.len() > 1 && modes > 0 {
            out.extend(shares(model, a, ci, d, &xlabel));
        }
    }
    let (campbell, critical) = campbell(model, a, modes, d);
    out.extend(campbell);
    (out, critical)
}

/// The outputs plotted per case: the ω_d of each of `modes` ([`plotted_modes`]), its ζ where
/// the system is damped, and |H| where the analysis has it.
fn outputs(a: &Analysis, modes: &[usize]) -> Vec<(Quantity, Option<usize>)> {
    let mut quantities: Vec<(Quantity, Option<usize>)> = Vec::new();
    for &m in modes {
        quantities.push((Quantity::DampedFrequency, Some(m)));
        // ζ where some design is damped (an undamped system's ζ is 0 with σ 0 everywhere, up
        // to rounding).
        if a.resolved(Quantity::DampingRatio, Some(m)) {
            quantities.push((Quantity::DampingRatio, Some(m)));
        }
    }
    if a.rows
        .iter()
        .any(|r| r.quantity == Quantity::TransferMagnitude)
    {
        quantities.push((Quantity::TransferMagnitude, None));
    }
    quantities
}

/// One output of one case, as its band and σ plots show it.
struct Output<'a> {
    model: &'a Model,
    a: &'a Analysis,
    /// The case's index.
    ci: usize,
    q: Quantity,
    mode: Option<usize>,
    d: Display,
}

impl<'a> Output<'a> {
    /// The case.
    fn case(&self) -> &'a Case {
        &self.a.cases[self.ci]
    }

    /// The end of the plots' stems: `_mode<k>` for a mode's output.
    fn tag(&self) -> String {
        self.mode
            .map_or(String::new(), |m| format!("_mode{}", m + 1))
    }

    /// The output in words, for titles and captions.
    fn label(&self) -> String {
        let q = self.q;
        self.mode.map_or(q.as_str().to_string(), |m| {
            format!("{} of mode {}", q.as_str(), m + 1)
        })
    }

    /// The output's rows of method `m`.
    fn rows(&self, m: Method) -> Vec<&'a Row> {
        series(self.a, self.ci, self.q, self.mode, m)
    }

    /// `f` of each of `rows` against its speed, in the display units.
    fn pts(&self, rows: &[&Row], f: &dyn Fn(&Row) -> f64) -> Vec<(f64, f64)> {
        let (xs, ys) = (self.d.speed.per_rad_per_second(), scale(self.q, self.d));
        rows.iter().map(|r| (r.speed * xs, f(r) * ys)).collect()
    }

    /// The methods that have rows for the output: the answer to read first, then the paper's
    /// method and the others.
    fn methods(&self) -> Vec<Method> {
        [
            Method::Analytic,
            Method::FirstOrder,
            Method::SecondOrder,
            Method::Invariant,
            Method::MonteCarlo,
        ]
        .into_iter()
        .filter(|&m| !self.rows(m).is_empty())
        .collect()
    }
}
