//! The propagation layer: what every method that spreads the tolerances through the pipeline
//! takes and gives.
//!
//! A [`Study`] is the deterministic part of an analysis, shared by every method and every
//! tolerance case: the model, the design variables (the union over the cases), the speeds, the
//! nominal sweep and, at each of its points, the [`LocalModel`] (values, exact gradients and
//! Hessians of every output). A method is an object implementing [`Propagation`]: given the
//! study, one case's [`Spread`] and the [`Run`] control (cancellation, the worker threads,
//! progress), it returns an [`Estimate`]: its statistics with the reason it stopped. The
//! methods are [`crate::taylor::Taylor`] (first order, second order and the invariant method
//! from the local models), [`crate::quadrature::Quadrature`], [`crate::montecarlo::MonteCarlo`]
//! and [`crate::sobol::Sobol`]; the last three place their points through
//! [`crate::sampling`], each design swept by [`Study::sweep_design`]. [`crate::analyze`] runs
//! them per case.
//!
//! This is the seam a new method plugs into: one type, one `impl Propagation` and, for its
//! value, one `impl Tabulate` that writes its rows ([`crate::table`]); `analyze` runs it per
//! case. (In the manner of OpenTURNS' and chaospy's algorithm objects: inputs in, a result and
//! its termination out; a method's error estimates are part of its value, as the quadrature's
//! are.)

mod design;

pub use design::DesignAt;

use crate::cancel::Cancel;
use crate::compiled::Compiled;
use crate::model::Transfer;
use crate::output::{self, Output};
use crate::program::Workspace;
use crate::sampling::branch_counts;
use crate::sensitivity::DesignPoint;
use crate::sensitivity::TransferAt;
use crate::sweep::{Options, Point, Sweep};
use crate::table::Tables;
use crate::tolerance::{LocalModel, Spread};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// The deterministic part of an analysis, shared by every method and case (see the module
/// documentation).
#[derive(Debug)]
pub struct Study<'a> {
    pub model: &'a Compiled,
    /// Design variables (parameter indices, the union over the cases), the order of every
    /// gradient and spread.
    pub vars: Vec<usize>,
    /// Operating speeds (rad/s).
    pub speeds: Vec<f64>,
    /// The nominal point at each speed, `None` where it failed.
    pub nominal: Vec<Option<Point>>,
    /// The local model at each speed, `None` where the point or its derivatives failed.
    pub locals: Vec<Option<LocalModel>>,
    /// The outputs (every mode's ω_d and ζ, then |H|), the same at every speed.
    pub outputs: Vec<Output>,
    /// The model's transfer function, if it has one.
    pub transfer: Option<Transfer>,
    /// Branch switches of the nominal sweep up to each speed, counted as a sample's are
    /// ([`branch_counts`]).
    pub branches: Vec<usize>,
    /// Speeds whose nominal point or local model failed, with the reason, by speed.
    pub failures: Vec<(f64, String)>,
    /// [`Termination::Cancelled`] where the run was cancelled before the sweep's last speed
    /// (the speeds left are failures, "interrupted").
    pub termination: Termination,
    /// Wall time of the first-order stage (the nominal sweep and the exact gradients) and of
    /// the second-order stage (the exact Hessians), seconds.
    pub seconds: (f64, f64),
}

/// How a run is controlled from outside: cancellation, the worker threads, progress.
pub struct Run<'a> {
    /// Cancelling it stops the run at its next check (see [`Termination::Cancelled`]).
    pub cancel: &'a Cancel,
    /// The worker threads every parallel stage runs on (results do not depend on their
    /// number).
    pub pool: &'a rayon::ThreadPool,
    /// `(done, total)` of the current stage, called from any worker.
    pub progress: &'a (dyn Fn(usize, usize) + Sync),
}

impl Run<'_> {
    /// The same control reporting progress to `progress` instead.
    pub fn with_progress<'b>(&'b self, progress: &'b (dyn Fn(usize, usize) + Sync)) -> Run<'b> {
        Run {
            cancel: self.cancel,
            pool: self.pool,
            progress,
        }
    }
}

/// Why a method stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Termination {
    /// Everything asked was computed.
    #[default]
    Completed,
    /// The run was cancelled: the value covers what was done before (possibly nothing).
    Cancelled,
}

impl Termination {
    /// How a run of two stages ended: cancelled where either was.
    pub fn and(self, other: Termination) -> Termination {
        if self == Termination::Cancelled {
            self
        } else {
            other
        }
    }
}

/// What a method gives: its value and why it stopped.
#[derive(Debug, Clone)]
pub struct Estimate<T> {
    pub value: T,
    pub termination: Termination,
}

/// A propagation method: the statistics of a study's outputs under one case's spread.
pub trait Propagation {
    /// The method's statistics, which write their own rows.
    type Value: Tabulate;

    /// Propagates `spread` (over [`Study::vars`]) through the study.
    fn propagate(&self, study: &Study, spread: &Spread, run: &Run) -> Estimate<Self::Value>;
}

/// A method's value as rows of the result's tables: the method's own converter, next to the
/// method (its rows, probabilities, yields, indices). The tables put every method's rows in
/// their order ([`Tables::finish`]).
pub trait Tabulate {
    /// Writes the rows of case `case` (index into the analysis' cases, propagated with
    /// `spread`) into `tables`.
    fn tabulate(self, study: &Study, case: usize, spread: &Spread, tables: &mut Tables);
}

impl<'a> Study<'a> {
    /// The nominal sweep of `model` over `speeds` (with every requirement's range ends added:
    /// [`crate::model::Model::judged_speeds`]) and, at each point, the local model for
    /// `vars`, in two stages: the values and exact gradients (first order), then the exact
    /// Hessians (second order), each timed ([`Study::seconds`]). The sweep is sequential
    /// (continuation); each point's gradients are independent, so they are handed to the
    /// other workers as soon as the point is solved; the Hessians are computed point by point
    /// in parallel after. Failed speeds are recorded in [`Study::failures`] and the run goes
    /// on (a point whose Hessians fail keeps its first-order model, every Hessian saying why);
    /// a cancelled run leaves the speeds after it as failures ("interrupted") and the
    /// Hessians not yet computed as "not computed".
    pub fn build(model: &'a Compiled, vars: Vec<usize>, speeds: Vec<f64>, run: &Run) -> Self {
        // Every requirement judged over its range: its ends among the speeds.
        let speeds = model.model().judged_speeds(&speeds);
        let start = Instant::now();
        let first = FirstStage::run(model, &vars, &speeds, run);
        let first_order = start.elapsed().as_secs_f64();
        let mut study = Study {
            model,
            outputs: output::of_model(model.model()),
            branches: branch_counts(&first.nominal),
            vars,
            speeds,
            nominal: first.nominal,
            locals: first.locals,
            transfer: model.model().analysis.transfer,
            termination: first.termination,
            failures: first.failures,
            seconds: (first_order, 0.0),
        };
        let start = Instant::now();
        study.add_hessians(run);
        if run.cancel.is_cancelled() {
            study.termination = Termination::Cancelled;
        }
        study.seconds.1 = start.elapsed().as_secs_f64();
        study.failures.sort_by(|a, b| a.0.total_cmp(&b.0));
        study
    }

    /// The second stage of [`Study::build`]: the exact Hessians added to each local model, point
    /// by point in parallel (progress counted on from the first stage's).
    fn add_hessians(&mut self, run: &Run) {
        let (model, transfer) = (self.model, self.transfer);
        let p = model.model().nominal();
        let n = self.speeds.len();
        let (done, total) = (AtomicUsize::new(n), 2 * n);
        let nominal = &self.nominal;
        run.pool.install(|| {
            self.locals.par_iter_mut().zip(nominal).for_each_init(
                Workspace::default,
                |workspace, (lm, pt)| {
                    if let (Some(lm), Some(pt)) = (lm, pt)
                        && !run.cancel.is_cancelled()
                    {
                        DesignPoint::new(model, &p, pt)
                            .with_model_transfer(transfer.as_ref())
                            .with_workspace(workspace)
                            .add_hessians(lm);
                    }
                    let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                    (run.progress)(d, total);
                },
            )
        });
    }

    /// The transfer function at speed `i` (excited at its order times the speed).
    pub fn transfer_at(&self, i: usize) -> Option<TransferAt> {
        self.transfer
            .as_ref()
            .map(|t| TransferAt::at_speed(t, self.speeds[i]))
    }
}

/// The first stage of [`Study::build`]: the nominal sweep, and at each point its values and
/// exact gradients (handed to the other workers as soon as the point is solved).
struct FirstStage {
    nominal: Vec<Option<Point>>,
    locals: Vec<Option<LocalModel>>,
    failures: Vec<(f64, String)>,
    termination: Termination,
}

impl FirstStage {
    fn run(model: &Compiled, vars: &[usize], speeds: &[f64], run: &Run) -> FirstStage {
        let transfer = model.model().analysis.transfer;
        let p = model.model().nominal();
        let n = speeds.len();
        let slots: Vec<Mutex<Option<Result<LocalModel, String>>>> =
            (0..n).map(|_| Mutex::new(None)).collect();
        let done = AtomicUsize::new(0);
        let mut failures = Vec::new();
        let mut nominal = Vec::with_capacity(n);
        let mut termination = Termination::Completed;
        // The local models' working memory: one workspace per task running at once, taken
        // from and given back to this list.
        let memory: Mutex<Vec<Workspace>> = Mutex::new(Vec::new());
        // Progress counts both stages: the gradients, then the Hessians, of every speed.
        let total = 2 * n;
        run.pool.install(|| {
            rayon::scope(|scope| {
                let mut sweep = Sweep::new(model, p.clone(), Options::default());
                for (i, &w) in speeds.iter().enumerate() {
                    if run.cancel.is_cancelled() {
                        termination = Termination::Cancelled;
                        failures.push((w, "interrupted".to_string()));
                        nominal.push(None);
                        continue;
                    }
                    match sweep.step(w) {
                        Ok(pt) => {
                            let (slot, done, pt_local, p, memory) =
                                (&slots[i], &done, pt.clone(), &p, &memory);
                            scope.spawn(move |_| {
                                let lock = || memory.lock().unwrap_or_else(|e| e.into_inner());
                                let workspace = lock().pop().unwrap_or_default();
                                let lm = DesignPoint::new(model, p, &pt_local)
                                    .with_model_transfer(transfer.as_ref())
                                    .with_workspace(&workspace)
                                    .local_model(vars, false)
                                    .map_err(|e| format!("derivatives: {e}"));
                                lock().push(workspace);
                                *slot.lock().expect("unpoisoned") = Some(lm);
                                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                                (run.progress)(d, total);
                            });
                            nominal.push(Some(pt));
                        }
                        Err(e) => {
                            failures.push((w, e.to_string()));
                            nominal.push(None);
                        }
                    }
                }
            })
        });
        let locals: Vec<Option<LocalModel>> = slots
            .into_iter()
            .map(|m| m.into_inner().expect("unpoisoned"))
            .zip(speeds)
            .map(|(lm, &w)| match lm? {
                Ok(lm) => Some(lm),
                Err(e) => {
                    failures.push((w, e));
                    None
                }
            })
            .collect();
        FirstStage {
            nominal,
            locals,
            failures,
            termination,
        }
    }
}
