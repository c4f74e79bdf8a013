//! The main job: how the tolerance cases spread every mode's ω_d and ζ and the transfer
//! magnitude across the speed range, by every analytic method and by Monte Carlo.
//!
//! The [`Study`]: one nominal sweep and, at each speed (in parallel), one local model for the
//! union of the cases' variables (derivatives do not depend on the tolerances, so cases share
//! them). Then the propagation methods ([`crate::propagate`]) per case: the [`Quadrature`] (the
//! whole pipeline integrated over the distribution, the answer the `analytic` row takes), the
//! [`Taylor`] methods (first order, second order, invariant), optionally the [`Sobol`] indices
//! and the [`MonteCarlo`]. Each method's value writes its own rows ([`Tables`]); this module
//! only runs them and times them for the summary.

use crate::cancel::Cancel;
use crate::compiled::Compiled;
use crate::model::Case;
use crate::montecarlo::{CaseShard, McOptions, MonteCarlo, Split};
use crate::output::Output;
use crate::peaks::{PeakRow, peaks};
use crate::propagate::{Propagation, Run, Study, Tabulate, Termination};
use crate::quadrature::{QuadOptions, Quadrature};
use crate::sobol::{Sobol, SobolOptions};
use crate::sweep::Point;
use crate::table::{ProbabilityRow, Row, SobolIndex, Tables, YieldRow};
use crate::taylor::Taylor;
use crate::tolerance::Spread;

use std::time::Instant;

/// What to analyse.
#[derive(Debug, Clone)]
pub struct AnalyzeOptions {
    pub speeds: Vec<f64>,
    pub cases: Vec<Case>,
    /// The quadrature (on by default).
    pub quadrature: Option<QuadOptions>,
    pub monte_carlo: Option<McOptions>,
    pub split: Split,
    /// Worker threads of every stage (`None`: rayon's default); results do not depend on
    /// their number.
    pub threads: Option<usize>,
    /// Sobol indices (none by default).
    pub sobol: Option<SobolOptions>,
    /// Cancelling it stops the run at its next check: the sweep before its next speed (the
    /// speeds left are failures, "interrupted"), the quadrature before its next case, the Monte
    /// Carlo after its current chunk. The result then covers what was done
    /// ([`Analysis::interrupted`]).
    pub cancel: Cancel,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            speeds: Vec::new(),
            cases: Vec::new(),
            quadrature: Some(QuadOptions::default()),
            monte_carlo: None,
            split: Split::default(),
            threads: None,
            cancel: Cancel::new(),
            sobol: None,
        }
    }
}

/// Result of [`analyze`].
#[derive(Debug, Clone)]
pub struct Analysis {
    /// Design variables (union over the cases), the order of `shares`.
    pub vars: Vec<usize>,
    pub cases: Vec<Case>,
    pub rows: Vec<Row>,
    /// Probabilities of character per speed, case and method.
    pub probabilities: Vec<ProbabilityRow>,
    /// The yield of the model's requirements per case and method (empty without
    /// requirements).
    pub yields: Vec<YieldRow>,
    /// Sobol indices per case (with [`AnalyzeOptions::sobol`]), and per case the reason where
    /// none could be computed.
    pub sobol: Vec<(usize, SobolIndex)>,
    pub sobol_refused: Vec<(usize, String)>,
    /// The speeds analysed and the outputs at each (what the Sobol indices' targets index).
    pub speeds: Vec<f64>,
    pub outputs: Vec<Output>,
    /// The Taylor methods (nominal sweep, derivatives, first/second order, invariant).
    pub analytic_seconds: f64,
    /// Of which the first-order stage (the nominal sweep and the exact gradients at every
    /// speed) and the second-order stage (the exact Hessians).
    pub first_order_seconds: f64,
    pub second_order_seconds: f64,
    pub quadrature_seconds: Option<f64>,
    /// Per case: the quadrature's rule in words and its number of swept nodes.
    pub quadrature_rules: Vec<(String, usize)>,
    pub monte_carlo_seconds: Option<f64>,
    /// The peaks of the model's transfer function along the speeds (`[analysis] transfer`;
    /// none without one), located between the swept speeds, with their first-order spread per
    /// case ([`crate::peaks`]).
    pub peaks: Vec<PeakRow>,
    /// Speeds whose nominal point or local model failed, with the reason.
    pub failures: Vec<(f64, String)>,
    /// The nominal points (for plots), `None` where they failed.
    pub nominal: Vec<Option<Point>>,
    /// Monte Carlo samples evaluated per case (fewer than asked if the run was interrupted).
    pub samples_done: Vec<usize>,
    /// Per case (with a whole or merged Monte Carlo), the samples whose design is not physically
    /// admissible, by reason: `(reason, count, first value)`; they count as failed at every speed.
    pub inadmissible: Vec<Vec<(String, usize, f64)>>,
    /// With [`Split::Shard`]: this shard's chunk moments per case, in chunk order.
    pub shard_states: Vec<CaseShard>,
    /// How the run ended: [`Termination::Cancelled`] where a stage stopped early because the
    /// run's [`Cancel`] token was cancelled (see [`AnalyzeOptions::cancel`]), as the stages'
    /// estimates report it.
    pub termination: Termination,
}

impl Analysis {
    /// The nominal point nearest the middle of the speeds analysed (`None` where every one
    /// failed): the operating point the report draws and names the modes at.
    pub fn middle_point(&self) -> Option<&Point> {
        let mid = self.nominal.len() / 2;
        (0..self.nominal.len())
            .filter(|&i| self.nominal[i].is_some())
            .min_by_key(|&i| i.abs_diff(mid))
            .and_then(|i| self.nominal[i].as_ref())
    }

    /// Does some row of an output carry a mean or σ above what the evaluation resolves
    /// ([`Quantity::resolution`](crate::output::Quantity::resolution))? An undamped system's ζ
    /// does not: it is 0 with σ 0, up to rounding (10⁻²¹), at every speed and by every method.
    pub fn resolved(&self, q: crate::output::Quantity, mode: Option<usize>) -> bool {
        let floor = q.resolution(0.0, 0.0);
        (self.rows.iter())
            .filter(|r| r.quantity == q && r.mode == mode)
            .any(|r| r.mean.abs() > floor || r.std > floor)
    }

    /// Did a stage stop early (a speed of the sweep, a case of the quadrature, Monte Carlo
    /// samples left out)?
    pub fn cancelled(&self) -> bool {
        self.termination == Termination::Cancelled
    }

    /// Is the result partial: cancelled, or fewer Monte Carlo samples than the `asked` (a
    /// merge of the shards of a cancelled run)?
    pub fn interrupted(&self, asked: usize) -> bool {
        self.cancelled() || self.samples_done.iter().any(|&n| n < asked)
    }
}

/// Progress callback: (stage, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Runs the analysis. Failed speeds are reported in `failures` and skipped; the run goes on.
///
/// The stages, in order: the [`Study`] (nominal sweep and local models, shared by the cases);
/// per case the [`Quadrature`]; per case the [`Taylor`] methods; per case the [`Sobol`] indices;
/// per case the [`MonteCarlo`] (whole, one shard, or the shards' blocks merged).
pub fn analyze(model: &Compiled, opt: &AnalyzeOptions, progress: Progress) -> Analysis {
    let mut vars: Vec<usize> = opt
        .cases
        .iter()
        .flat_map(|c| c.tolerances.iter().map(|t| t.0))
        .collect();
    vars.sort_unstable();
    vars.dedup();
    let pool = crate::threads::pool(opt.threads);
    let derivatives = |d, n| progress("derivatives", d, n);
    let run = Run {
        cancel: &opt.cancel,
        pool: &pool,
        progress: &derivatives,
    };
    let t0 = Instant::now();
    let study = Study::build(model, vars, opt.speeds.clone(), &run);
    let spreads: Vec<Spread> = opt
        .cases
        .iter()
        .map(|c| Spread::new(model, c, &study.vars))
        .collect();
    let peaks = response_peaks(model, &study, &spreads);
    let study_seconds = t0.elapsed().as_secs_f64();
    let mut stages = Stages {
        study: &study,
        spreads: &spreads,
        cases: &opt.cases,
        run: &run,
        progress,
        tables: Tables::default(),
        termination: study.termination,
    };
    let quadrature_seconds = opt
        .quadrature
        .map(|options| stages.each_case("quadrature", |_| Quadrature { options }));
    let analytic_seconds = study_seconds + stages.each_case("taylor", |_| Taylor);
    if let Some(options) = opt.sobol {
        stages.each_case("sobol", |_| Sobol { options });
    }
    let mut shard_states = Vec::new();
    let monte_carlo_seconds = opt.monte_carlo.map(|mc| {
        let t = Instant::now();
        for ci in 0..spreads.len() {
            let method = MonteCarlo::of_case(mc, &opt.split, ci);
            let value = stages.propagate(ci, "monte carlo", &method);
            match value.into_shard() {
                Ok(shard) => shard_states.push(shard),
                Err(value) => stages.tabulate(ci, value),
            }
        }
        t.elapsed().as_secs_f64()
    });
    let Stages {
        mut tables,
        termination,
        ..
    } = stages;
    let rows = tables.finish();
    let Study {
        vars,
        speeds,
        outputs,
        failures,
        nominal,
        seconds: (first_order_seconds, second_order_seconds),
        ..
    } = study;
    Analysis {
        vars,
        cases: opt.cases.clone(),
        rows,
        probabilities: tables.probabilities,
        yields: tables.yields,
        sobol: tables.sobol,
        sobol_refused: tables.sobol_refused,
        speeds,
        outputs,
        analytic_seconds,
        first_order_seconds,
        second_order_seconds,
        quadrature_seconds,
        quadrature_rules: tables.quadrature_rules,
        monte_carlo_seconds,
        peaks,
        failures,
        nominal,
        samples_done: tables.samples_done,
        inadmissible: tables.inadmissible,
        shard_states,
        termination,
    }
}

/// The peaks of the model's transfer function along the nominal sweep, with each case's
/// first-order spread (none without a transfer function).
fn response_peaks(model: &Compiled, study: &Study, spreads: &[Spread]) -> Vec<PeakRow> {
    let Some(transfer) = model.model().analysis.transfer else {
        return Vec::new();
    };
    let p = model.model().nominal();
    peaks(model, &p, &study.nominal, &transfer, &study.vars)
        .into_iter()
        .map(|r| {
            r.map(|peak| {
                let cases = spreads.iter().map(|s| peak.first_order(s)).collect();
                (peak, cases)
            })
        })
        .collect()
}

/// The methods' runs over the cases, and what they have written so far.
struct Stages<'a> {
    study: &'a Study<'a>,
    spreads: &'a [Spread],
    cases: &'a [Case],
    run: &'a Run<'a>,
    progress: Progress<'a>,
    tables: Tables,
    termination: Termination,
}

impl Stages<'_> {
    /// Runs the method `method(case)` on every case and writes its rows; the seconds taken.
    fn each_case<P: Propagation>(&mut self, stage: &str, method: impl Fn(usize) -> P) -> f64 {
        let t = Instant::now();
        for ci in 0..self.spreads.len() {
            let value = self.propagate(ci, stage, &method(ci));
            self.tabulate(ci, value);
        }
        t.elapsed().as_secs_f64()
    }

    /// `method`'s value for case `ci`, its progress reported as `stage` and the case's name.
    fn propagate<P: Propagation>(&mut self, ci: usize, stage: &str, method: &P) -> P::Value {
        let name = format!("{stage} {}", self.cases[ci].name);
        let progress = |d, n| (self.progress)(&name, d, n);
        let run = self.run.with_progress(&progress);
        let estimate = method.propagate(self.study, &self.spreads[ci], &run);
        self.termination = self.termination.and(estimate.termination);
        estimate.value
    }

    fn tabulate(&mut self, ci: usize, value: impl Tabulate) {
        value.tabulate(self.study, ci, &self.spreads[ci], &mut self.tables);
    }
}
