//! `modaltol._modaltol`: the native half of the Python package `modaltol`.
//!
//! Every computation is the library's, and every table is built by the same functions as the
//! command line's CSV files ([`modaltol::report`]), so a DataFrame and the CLI's file hold the
//! same columns and the same numbers. This module hands tables to Python as dicts of typed
//! columns (float, int or str) and the pure-Python layer (`modaltol/__init__.py`) turns them
//! into pandas DataFrames and numpy arrays.
//!
//! Long calls run on a worker thread with the GIL released; the calling thread waits, looks at
//! Python's signals every 50 ms, and on Ctrl-C cancels the run ([`Cancel`]) and raises
//! `KeyboardInterrupt` once the worker has stopped.

use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::cancel::Cancel;
use modaltol::compiled::Compiled;
use modaltol::files::{Inputs, ResultDir};
use modaltol::model::{Model, Sampling, SpeedRange, Transfer};
use modaltol::montecarlo::McOptions;
use modaltol::nominal_sweep::NominalSweep;
use modaltol::plots::{Display, FrequencyUnit};
use modaltol::program::Tier;
use modaltol::report::{self, SweepColumns};
use modaltol::request::{
    PointRequest, PointRequestError, Request, RequestError, Resolved, Setting, Speeds,
};
use modaltol::sensitivity::{Derivatives, DesignPoint, TransferAt};
use modaltol::settings::{self, ThreadsError};
use modaltol::shard::{RunSettings, ShardFile};
use modaltol::sweep::Options;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

pyo3::create_exception!(
    _modaltol,
    ModelError,
    PyValueError,
    "The model is invalid; `file`, `line`, `column` (1-based, or None) say where."
);
pyo3::create_exception!(
    _modaltol,
    SolveError,
    PyRuntimeError,
    "A computation failed at the operating point asked for (no equilibrium, a singular \
     mass matrix, …); the message says why."
);

/// A model error as `ModelError`, carrying its place.
fn model_error(py: Python<'_>, e: modaltol::model::ModelError) -> PyErr {
    let err = ModelError::new_err(e.to_string());
    let v = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail.
    let _ = v.setattr("file", e.file.clone());
    let _ = v.setattr("line", e.line);
    let _ = v.setattr("column", e.column);
    let _ = v.setattr("reason", e.message.clone());
    err
}

/// Bad arguments (names, ranges): `ValueError`.
fn bad(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A refused analysis request in the package's spelling (the keyword's name): `ValueError`,
/// or `RuntimeError` where the operating system refuses the threads.
fn refused(e: RequestError) -> PyErr {
    match e {
        RequestError::Threads(t @ ThreadsError::Refused { .. }) => {
            PyRuntimeError::new_err(format!("threads: {t}"))
        }
        RequestError::NoSpeeds | RequestError::ModelSpeeds(_) => bad(e.to_string()),
        e => {
            let name = match e.setting() {
                Setting::Speeds => "speeds:",
                Setting::Cases => "cases:",
                Setting::Samples => "samples",
                Setting::Sobol => "sobol",
                Setting::QuadratureTolerance => "quadrature_tolerance",
                Setting::Threads => "threads",
                Setting::Shard => "shard",
                Setting::TargetYield => "target_yield",
            };
            bad(format!("{name} {e}"))
        }
    }
}

/// Runs `work` on a worker thread with the GIL released; Ctrl-C cancels `cancel`, waits for
/// the worker to stop at its next check and raises `KeyboardInterrupt`.
fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    std::thread::scope(|s| {
        let (tx, rx) = channel();
        let rx = Mutex::new(rx);
        s.spawn(move || {
            let _ = tx.send(work());
        });
        loop {
            let got = py.detach(|| {
                rx.lock()
                    .expect("unpoisoned")
                    .recv_timeout(Duration::from_millis(50))
            });
            match got {
                Ok(v) => return Ok(v),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        cancel.cancel();
                        let _ = py.detach(|| rx.lock().expect("unpoisoned").recv());
                        return Err(e);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "modaltol: internal error (the computation stopped without a result)",
                    ));
                }
            }
        }
    })
}

/// A table (header and string cells, as the CLI writes them) as a dict of typed columns: a
/// column whose cells all read `true`/`false` is bool; one whose cells all read as integers is
/// int; one whose non-empty cells all read `true`/`false` holds bools and None (a flag that
/// applies to some rows only, like `within_request`); one whose non-empty cells all read as
/// numbers is float (empty cells NaN); any other is str (empty cells None). The CLI's cells
/// are shortest round-trip decimals, so the floats are the library's bit for bit.
fn table<'py>(
    py: Python<'py>,
    header: &[impl AsRef<str>],
    rows: &[Vec<String>],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (j, name) in header.iter().enumerate() {
        let cells: Vec<&str> = rows.iter().map(|r| r[j].as_str()).collect();
        let ints: Option<Vec<i64>> = cells.iter().map(|c| c.parse().ok()).collect();
        let floats: Option<Vec<f64>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(f64::NAN)
                } else {
                    c.parse().ok()
                }
            })
            .collect();
        let bools: Option<Vec<bool>> = cells.iter().map(|c| c.parse().ok()).collect();
        // `true`/`false` where the column applies, empty where it does not.
        let some_bools: Option<Vec<Option<bool>>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(None)
                } else {
                    c.parse().ok().map(Some)
                }
            })
            .collect();
        let column = match (ints, floats, bools) {
            (_, _, Some(b)) if !cells.is_empty() => PyList::new(py, b)?,
            (Some(i), _, _) if !cells.is_empty() => PyList::new(py, i)?,
            _ if some_bools.is_some() && cells.iter().any(|c| !c.is_empty()) => {
                PyList::new(py, some_bools.unwrap_or_default())?
            }
            (_, Some(f), _) if cells.iter().any(|c| !c.is_empty()) || cells.is_empty() => {
                PyList::new(py, f)?
            }
            _ => PyList::new(
                py,
                cells
                    .iter()
                    .map(|c| (!c.is_empty()).then_some(*c))
                    .collect::<Vec<_>>(),
            )?,
        };
        out.set_item(name.as_ref(), column)?;
    }
    Ok(out)
}

/// How many speeds (or frequencies) a call may take: a check of their number
/// ([`settings::table`], [`settings::analysis_speeds`]), made before they are.
type Fits<'a> = &'a dyn Fn(usize) -> Result<(), String>;

/// Speeds from `"FROM:TO:STEP"` or a sequence of numbers, as many as `fits` allows.
fn speeds(spec: &Bound<'_, PyAny>, what: &str, fits: Fits<'_>) -> PyResult<Vec<f64>> {
    let v: Vec<f64> = if let Ok(s) = spec.extract::<String>() {
        let r = SpeedRange::parse(&s).map_err(|e| bad(format!("{what}: {e}")))?;
        range(&r, what, fits)?
    } else {
        spec.extract()
            .map_err(|_| bad(format!("{what}: expected \"FROM:TO:STEP\" or numbers")))?
    };
    let v = settings::values(v).map_err(|e| bad(format!("{what}: {e}")))?;
    fits(v.len()).map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(v)
}

/// The points of a range, as many as `fits` allows.
fn range(r: &SpeedRange, what: &str, fits: Fits<'_>) -> PyResult<Vec<f64>> {
    fits(r.len()).map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(r.speeds().collect())
}

/// A display unit for the plots and report.
fn unit(name: &str, what: &str) -> PyResult<FrequencyUnit> {
    match name {
        "rad/s" => Ok(FrequencyUnit::RadPerSecond),
        "hz" | "Hz" => Ok(FrequencyUnit::Hertz),
        "rpm" => Ok(FrequencyUnit::Rpm),
        _ => Err(bad(format!(
            "{what} must be \"rad/s\", \"hz\" or \"rpm\", got {name:?}"
        ))),
    }
}

fn derivatives(how: &str) -> PyResult<Derivatives> {
    match how {
        "ad" => Ok(Derivatives::Exact),
        "fd" => Ok(Derivatives::FiniteDifference),
        _ => Err(bad(format!(
            "derivatives must be \"ad\" (exact) or \"fd\" (finite differences), got {how:?}"
        ))),
    }
}

/// A validated model with its equations recorded on first use.
#[pyclass(frozen, module = "modaltol._modaltol")]
struct NativeModel {
    model: Arc<Compiled>,
    /// The file the model was read from, which no output may replace.
    source: Option<PathBuf>,
}

impl NativeModel {
    /// The model with the target yield asked for (checked), else itself.
    fn targeted(&self, target_yield: Option<f64>) -> Arc<Compiled> {
        match target_yield {
            Some(y) => Arc::new((*self.model).clone().with_target_yield(y)),
            None => self.model.clone(),
        }
    }

    fn m(&self) -> &Model {
        self.model.model()
    }

    fn transfer(&self, spec: Option<&str>) -> PyResult<Option<Transfer>> {
        spec.map(|s| {
            self.m()
                .parse_transfer(s)
                .map_err(|e| bad(format!("transfer {s:?}: {e}")))
        })
        .transpose()
    }

    fn wrt(&self, names: Option<Vec<String>>) -> PyResult<Vec<usize>> {
        self.m()
            .design_variables(names.as_deref())
            .map_err(|e| bad(format!("wrt: {e}")))
    }

    /// With the branch to report: `"stable"` (switch to a stable equilibrium where the one
    /// reached is unstable) or `"as-given"`.
    fn options_on(&self, independent: Option<Vec<String>>, branch: &str) -> PyResult<Options> {
        let no_branch_switch = match branch {
            "stable" => false,
            "as-given" => true,
            other => {
                return Err(bad(format!(
                    "branch must be \"stable\" or \"as-given\", got {other:?}"
                )));
            }
        };
        Ok(Options {
            no_branch_switch,
            independent: independent
                .map(|n| {
                    self.m()
                        .independent_coordinates(&n)
                        .map_err(|e| bad(format!("independent: {e}")))
                })
                .transpose()?,
            ..Default::default()
        })
    }

    /// The speeds asked for, or the model's `[analysis] speed`, as many as `fits` allows.
    fn speeds_or_model(
        &self,
        speeds: Option<&Bound<'_, PyAny>>,
        fits: Fits<'_>,
    ) -> PyResult<Vec<f64>> {
        match speeds {
            Some(s) => self::speeds(s, "speeds", fits),
            None => {
                let r =
                    self.m().analysis.speed.ok_or_else(|| {
                        bad("no speeds given and the model has no [analysis] speed")
                    })?;
                range(&r, "the model's [analysis] speed", fits)
            }
        }
    }

    /// The nominal point at `speed`.
    fn point(&self, speed: f64, opt: &Options) -> PyResult<modaltol::sweep::Point> {
        let at = PointRequest::new(&self.model, speed).map_err(|e| match e {
            PointRequestError::Speed(why) => bad(format!("speed {why}")),
            PointRequestError::Start(why) => bad(why),
        })?;
        at.solve(&self.model, opt)
            .map_err(|e| SolveError::new_err(format!("speed {speed:?} rad/s failed: {e}")))
    }
}

/// The keywords of `Model.sweep` (the Python wrapper passes them all, as a dict).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct SweepKeywords {
    transfer: Option<String>,
    sensitivity: bool,
    wrt: Option<Vec<String>>,
    derivatives: String,
    independent: Option<Vec<String>>,
    branch: String,
}

/// The keywords of `Model.analyze` (the Python wrapper passes them all, as a dict): the
/// package's spelling of a [`Request`], with the result directory and its display units.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct AnalyzeKeywords {
    cases: Option<Vec<String>>,
    samples: Option<i64>,
    seed: Option<u64>,
    sampling: Option<String>,
    monte_carlo: bool,
    quadrature: bool,
    quadrature_tolerance: f64,
    threads: Option<i64>,
    output: Option<PathBuf>,
    speed_unit: String,
    frequency_unit: String,
    sobol: Option<i64>,
    /// `(K, N)`: run shard K (1-based) of N of the Monte Carlo and return the shard's text.
    shard: Option<(i64, i64)>,
    target_yield: Option<f64>,
}

/// The keywords of `merge` (Python's `modaltol.merge`): the cases the shards were run with and
/// the result directory with its display units.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct MergeKeywords {
    cases: Option<Vec<String>>,
    target_yield: Option<f64>,
    threads: Option<i64>,
    output: Option<PathBuf>,
    speed_unit: String,
    frequency_unit: String,
}

impl NativeModel {
    /// The result directory `output` (none without one), refused where it is the model file
    /// or holds files other than a result's.
    fn result_dir(&self, output: &Option<PathBuf>) -> PyResult<Option<ResultDir>> {
        output
            .as_ref()
            .map(|o| {
                let inputs = Inputs::new(&self.source.iter().collect::<Vec<_>>());
                ResultDir::create(o)
                    .and_then(|d| d.protect(inputs, modaltol::results::is_result_file))
                    .map_err(|e| bad(format!("{e}: {}", e.source)))
            })
            .transpose()
    }
}

#[pymethods]
impl NativeModel {
    /// Tolerance allocation (see `modaltol::allocate`): `allocation.csv`'s table and
    /// `allocation.json`'s text.
    #[pyo3(signature = (speeds, target_yield, case, quadrature_tolerance, threads))]
    fn allocate<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<String>,
        target_yield: Option<f64>,
        case: Option<String>,
        quadrature_tolerance: f64,
        threads: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let m = self.m();
        settings::quadrature_tolerance(quadrature_tolerance)
            .map_err(|e| bad(format!("quadrature_tolerance {e}")))?;
        let threads = threads.map(|n| usize::try_from(n).unwrap_or(0));
        settings::threads(threads).map_err(|e| bad(format!("threads {e}")))?;
        let range = match speeds {
            Some(s) => SpeedRange::parse(&s).map_err(|e| bad(format!("speeds: {e}")))?,
            None => m
                .analysis
                .speed
                .ok_or_else(|| bad("no speeds given and the model has no [analysis] speed"))?,
        };
        settings::analysis_speeds(range.len()).map_err(|e| bad(format!("speeds: {e}")))?;
        let grid: Vec<f64> = range.speeds().collect();
        m.check_requirement_speeds(&grid)
            .map_err(|e| bad(format!("speeds: {e}")))?;
        let target = settings::target_yield(target_yield.unwrap_or(m.allocation.target_yield))
            .map_err(|e| bad(format!("target_yield {e}")))?;
        let start = match case.as_deref().or(m.allocation.case.as_deref()) {
            Some(n) => m
                .analysis
                .cases
                .iter()
                .find(|c| c.name == n)
                .cloned()
                .ok_or_else(|| bad(format!("case: no tolerance case '{n}' in the model")))?,
            None => modaltol::model::Case::from_parameters(m),
        };
        let opt = modaltol::allocate::AllocateOptions {
            speeds: m.judged_speeds(&grid),
            case: start,
            target,
            costs: Vec::new(),
            quadrature: modaltol::quadrature::QuadOptions {
                tolerance: quadrature_tolerance,
            },
            threads,
            cancel: Cancel::new(),
        };
        let model = &*self.model;
        let a = interruptible(py, &opt.cancel, || {
            modaltol::allocate::allocate(model, &opt, &|_| {})
        })?
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let d = PyDict::new(py);
        d.set_item(
            "allocation",
            table(
                py,
                &report::ALLOCATION_HEADER,
                &report::allocation_rows(m, &a),
            )?,
        )?;
        d.set_item(
            "summary",
            serde_json::to_string(&report::allocation_json(m, &a)).expect("a JSON value"),
        )?;
        Ok(d)
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> String {
        self.m().name.clone()
    }

    /// Degrees of freedom.
    #[getter]
    fn dof(&self) -> usize {
        self.m().dof()
    }

    /// The model's Monte Carlo samples (`[analysis] samples`).
    #[getter]
    fn samples(&self) -> usize {
        self.m().analysis.samples
    }

    /// The parameters: name, nominal value, tolerance (absolute, in the parameter's unit; NaN
    /// where none), distribution.
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = self.m();
        let d = PyDict::new(py);
        d.set_item(
            "name",
            m.parameters
                .iter()
                .map(|p| p.name.clone())
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "value",
            m.parameters.iter().map(|p| p.value).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "tolerance",
            m.parameters
                .iter()
                .map(|p| p.tolerance.map_or(f64::NAN, |t| t.absolute(p.value)))
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "distribution",
            m.parameters
                .iter()
                .map(|p| match p.distribution {
                    modaltol::model::Distribution::Normal => "normal",
                    modaltol::model::Distribution::Uniform => "uniform",
                })
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// The generalised coordinates: name, unit, driven.
    fn coordinates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = self.m();
        let d = PyDict::new(py);
        d.set_item(
            "name",
            m.coordinates
                .iter()
                .map(|c| c.name.clone())
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "unit",
            m.coordinates
                .iter()
                .map(|c| c.unit.symbol())
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "driven",
            m.coordinates.iter().map(|c| c.driven).collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// The names of the tolerance cases an analysis runs by default.
    fn cases(&self) -> Vec<String> {
        self.m()
            .tolerance_cases(&[])
            .map(|c| c.into_iter().map(|c| c.name).collect())
            .unwrap_or_default()
    }

    /// What `modaltol check` prints.
    fn check(&self) -> String {
        report::check_summary(self.m())
    }

    /// The speed sweep's table (the CLI's `sweep` columns).
    #[pyo3(signature = (speeds, options))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<&Bound<'py, PyAny>>,
        options: SweepKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        let SweepKeywords {
            transfer,
            sensitivity,
            wrt,
            derivatives,
            independent,
            branch,
        } = options;
        let (transfer, derivatives, branch) = (transfer.as_deref(), &*derivatives, &*branch);
        let m = self.m();
        let tf = self.transfer(transfer)?;
        let cols = SweepColumns {
            transfer: tf.is_some(),
            wrt: if sensitivity {
                self.wrt(wrt)?
            } else {
                Vec::new()
            },
        };
        let columns = report::sweep_header(m, &cols).len();
        let w = self.speeds_or_model(speeds, &|n| {
            settings::table(n.saturating_mul(m.dof().max(1)), columns)
        })?;
        let opt = self.options_on(independent, branch)?;
        let how = self::derivatives(derivatives)?;
        let cancel = Cancel::new();
        let model = &*self.model;
        let rows = interruptible(py, &cancel, || {
            let mut study = NominalSweep::new(model, opt, tf, cols.wrt.clone(), how);
            let mut rows = Vec::new();
            for &speed in &w {
                if cancel.is_cancelled() {
                    break;
                }
                let (r, extras) = study.step(speed);
                rows.extend(report::sweep_rows(model.model(), &cols, speed, &r, &extras));
            }
            rows
        })?;
        table(py, &report::sweep_header(m, &cols), &rows)
    }

    /// Equilibrium, M̂, Ĉ, K̂ and the modes at one speed.
    #[pyo3(signature = (speed, independent=None, branch="stable"))]
    fn modal<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        independent: Option<Vec<String>>,
        branch: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let opt = Options {
            tier: Tier::Few,
            ..self.options_on(independent, branch)?
        };
        let pt = py.detach(|| self.point(speed, &opt))?;
        let m = self.m();
        let d = PyDict::new(py);
        let matrix = |a: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
            (0..a.nrows())
                .map(|i| (0..a.ncols()).map(|j| a[(i, j)]).collect())
                .collect()
        };
        d.set_item("M", matrix(&pt.linear.m))?;
        d.set_item("C", matrix(&pt.linear.c))?;
        d.set_item("K", matrix(&pt.linear.k))?;
        let names = |v: &[usize]| {
            v.iter()
                .map(|&i| m.coordinates[i].name.clone())
                .collect::<Vec<_>>()
        };
        d.set_item("independent", names(&pt.linear.independent))?;
        d.set_item("free", names(&m.free()))?;
        let q = PyDict::new(py);
        for (c, v) in m.coordinates.iter().zip(&pt.equilibrium.q) {
            q.set_item(&c.name, v)?;
        }
        d.set_item("q", q)?;
        let drive = PyDict::new(py);
        for &i in &m.driven() {
            drive.set_item(&m.coordinates[i].name, pt.equilibrium.drive_force[i])?;
        }
        d.set_item("drive", drive)?;
        d.set_item("iterations", pt.equilibrium.iterations)?;
        d.set_item("note", pt.note.clone())?;
        d.set_item("branch", pt.branch.as_str())?;
        d.set_item("branch_reason", pt.branch.to_string())?;
        d.set_item(
            "modes",
            table(
                py,
                &report::modes_header(m),
                &report::modes_rows(m, &self.model.model().nominal(), &pt)
                    .map_err(|e| SolveError::new_err(e.to_string()))?,
            )?,
        )?;
        Ok(d)
    }

    /// Sensitivities at one speed (the CLI's `sensitivity --format csv` columns).
    #[pyo3(signature = (speed, wrt=None, transfer=None, derivatives="ad"))]
    fn sensitivity<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        wrt: Option<Vec<String>>,
        transfer: Option<&str>,
        derivatives: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let wrt = self.wrt(wrt)?;
        let tf = match transfer {
            Some(_) => self.transfer(transfer)?,
            None => self.m().analysis.transfer,
        };
        let how = self::derivatives(derivatives)?;
        let rows = py.detach(|| -> PyResult<Vec<Vec<String>>> {
            let pt = self.point(speed, &Options::single())?;
            let p = self.model.model().nominal();
            let at = tf.map(|t| TransferAt::at_speed(&t, speed));
            let s = DesignPoint::new(&self.model, &p, &pt)
                .with_transfer(at)
                .sensitivities(&wrt, how)
                .map_err(|e| {
                    SolveError::new_err(format!("sensitivities at {speed:?} rad/s: {e}"))
                })?;
            let why = report::transfer_defect_at(&pt, at.as_ref());
            Ok(report::sensitivity_rows(self.m(), &pt, &s, why))
        })?;
        table(py, &report::SENSITIVITY_HEADER, &rows)
    }

    /// Frequency response at one speed (the CLI's `frf` columns).
    #[pyo3(signature = (speed, freq, transfer=None, wrt=None))]
    fn frf<'py>(
        &self,
        py: Python<'py>,
        speed: f64,
        freq: &Bound<'py, PyAny>,
        transfer: Option<&str>,
        wrt: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let tf = match transfer {
            Some(s) => Some(
                self.m()
                    .parse_response(s)
                    .map_err(|e| bad(format!("transfer {s:?}: {e}")))?,
            ),
            None => self.m().analysis.transfer,
        }
        .ok_or_else(|| {
            bad("frf needs transfer=\"input=NAME,output=NAME\" (the model has no [analysis] transfer)")
        })?;
        let wrt = self.wrt(wrt)?;
        let header = report::frf_header(self.m(), &wrt);
        let freqs = self::speeds(freq, "freq", &|n| settings::table(n, header.len()))?;
        let cancel = Cancel::new();
        let rows = interruptible(py, &cancel, || -> PyResult<Vec<Vec<String>>> {
            let pt = self.point(speed, &Options::single())?;
            let p = self.model.model().nominal();
            // Stops at the frequency after a Ctrl-C (`interruptible` then raises).
            let freqs = freqs.into_iter().take_while(|_| !cancel.is_cancelled());
            let r = DesignPoint::new(&self.model, &p, &pt)
                .frequency_response((tf.input, tf.output), &wrt, freqs)
                .map_err(|e| {
                    SolveError::new_err(format!("sensitivities at {speed:?} rad/s: {e}"))
                })?;
            Ok(report::frf_rows(&pt.linear, &r))
        })??;
        table(py, &header, &rows)
    }

    /// The tolerance analysis (the CLI's `analyze`): tolerance and probability tables and the
    /// summary (JSON text); with `output`, also the CLI's result directory.
    #[pyo3(signature = (speeds, options))]
    fn analyze<'py>(
        &self,
        py: Python<'py>,
        speeds: Option<&Bound<'py, PyAny>>,
        options: AnalyzeKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        let AnalyzeKeywords {
            cases,
            samples,
            seed,
            sampling,
            monte_carlo,
            quadrature,
            quadrature_tolerance,
            threads,
            output,
            speed_unit,
            frequency_unit,
            sobol,
            shard,
            target_yield,
        } = options;
        let shard = shard
            .map(|(k, n)| {
                settings::shard(&format!("{k}/{n}")).map_err(|e| bad(format!("shard {e}")))
            })
            .transpose()?;
        let (sampling, speed_unit, frequency_unit) =
            (sampling.as_deref(), &*speed_unit, &*frequency_unit);
        let m = self.m();
        let display = Display {
            speed: unit(speed_unit, "speed_unit")?,
            frequency: unit(frequency_unit, "frequency_unit")?,
        };
        let sampling = match sampling {
            None => None,
            Some(s) => Some(Sampling::named(s).ok_or_else(|| {
                bad(format!(
                    "sampling must be {}, got {s:?}",
                    Sampling::names(true)
                ))
            })?),
        };
        let request = Request {
            speeds: match speeds {
                None => Speeds::Model,
                Some(s) => match s.extract::<String>() {
                    Ok(text) => Speeds::Range(
                        SpeedRange::parse(&text).map_err(|e| bad(format!("speeds: {e}")))?,
                    ),
                    Err(_) => Speeds::Values(
                        s.extract()
                            .map_err(|_| bad("speeds: expected \"FROM:TO:STEP\" or numbers"))?,
                    ),
                },
            },
            cases: cases.unwrap_or_default(),
            // A negative count is refused as the rule refuses any count out of range.
            samples: samples
                .map(|n| settings::samples(n).map_err(|e| bad(format!("samples {e}"))))
                .transpose()?,
            seed,
            sampling,
            monte_carlo,
            quadrature,
            quadrature_tolerance,
            // A negative count is refused as zero is (the command line's parser refuses it too).
            threads: threads.map(|n| usize::try_from(n).unwrap_or(0)),
            shard,
            // A negative count is refused as zero is.
            sobol: sobol.map(|n| usize::try_from(n).unwrap_or(0)),
            target_yield,
        };
        if shard.is_some() && output.is_some() {
            return Err(bad(
                "a shard is returned, not written as a result directory: merge the shards \
                 (modaltol.merge) with output=",
            ));
        }
        let Resolved {
            options: opt,
            range,
            target_yield,
        } = request
            .check()
            .and_then(|r| r.resolve(m, Cancel::new()))
            .map_err(refused)?;
        let (mc, threads) = (opt.monte_carlo, opt.threads);
        // Fail early where the results cannot be written.
        let dir = self.result_dir(&output)?;
        let targeted = self.targeted(target_yield);
        let model = &*targeted;
        let a = run_analysis(py, model, &opt)?;
        if let (Some((k, n)), Some(mc)) = (shard, mc) {
            let range = range
                .ok_or_else(|| bad("shards need speeds as \"FROM:TO:STEP\" (or the model's)"))?;
            let tolerance = quadrature.then_some(quadrature_tolerance);
            let run = RunSettings::new(&range, &mc, tolerance, n);
            let file = ShardFile::of_analysis(m, &opt.cases, &a, &run, k).ok_or_else(|| {
                PyRuntimeError::new_err(
                    "the shard was not completed (a shard is complete or absent)",
                )
            })?;
            let d = PyDict::new(py);
            d.set_item("shard", file.to_json())?;
            d.set_item("name", ShardFile::name(k, n))?;
            return Ok(d);
        }
        let used =
            threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        analysis_dict(py, model, &a, mc.as_ref(), used, dir, display)
    }

    /// Merges shards `(name, text)` of one run of this model exactly as the CLI's `merge` does
    /// (refusing what it refuses): the tables of `analyze`, and the result directory with
    /// `output`.
    #[pyo3(signature = (shards, options))]
    fn merge<'py>(
        &self,
        py: Python<'py>,
        shards: Vec<(String, String)>,
        options: MergeKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        let MergeKeywords {
            cases,
            target_yield,
            threads,
            output,
            speed_unit,
            frequency_unit,
        } = options;
        let m = self.m();
        let display = Display {
            speed: unit(&speed_unit, "speed_unit")?,
            frequency: unit(&frequency_unit, "frequency_unit")?,
        };
        let request = Request {
            speeds: Speeds::Model,
            cases: cases.unwrap_or_default(),
            samples: None,
            seed: None,
            sampling: None,
            monte_carlo: true,
            quadrature: true,
            quadrature_tolerance: 1e-3,
            threads: threads.map(|n| usize::try_from(n).unwrap_or(0)),
            shard: None,
            sobol: None,
            target_yield,
        };
        let Resolved {
            options: base,
            target_yield,
            ..
        } = request
            .check()
            .and_then(|r| r.resolve(m, Cancel::new()))
            .map_err(refused)?;
        let (first, states) =
            modaltol::shard::verify(m, &base.cases, shards).map_err(|e| bad(e.to_string()))?;
        let (opt, mc) = modaltol::shard::merged_options(&first, states, base).map_err(bad)?;
        let dir = self.result_dir(&output)?;
        let targeted = self.targeted(target_yield);
        let model = &*targeted;
        let a = run_analysis(py, model, &opt)?;
        let used = opt
            .threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        analysis_dict(py, model, &a, Some(&mc), used, dir, display)
    }
}

/// Runs the analysis `opt` of `model` without the GIL, stopping on Ctrl-C.
fn run_analysis(
    py: Python<'_>,
    model: &Compiled,
    opt: &AnalyzeOptions,
) -> PyResult<modaltol::analyze::Analysis> {
    let a = interruptible(py, &opt.cancel, || {
        analyze(model, opt, &|_: &str, _: usize, _: usize| {})
    })?;
    if a.cancelled() {
        // Ctrl-C arrived between the worker's last check and its end.
        return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(()));
    }
    Ok(a)
}

/// The tables and summary of an analysis (and its result directory where `dir` is given).
fn analysis_dict<'py>(
    py: Python<'py>,
    model: &Compiled,
    a: &modaltol::analyze::Analysis,
    mc: Option<&McOptions>,
    used: usize,
    dir: Option<ResultDir>,
    display: Display,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model.model();
    if let Some(dir) = dir {
        py.detach(|| {
            let o = modaltol::results::WriteOptions {
                mc,
                threads: used,
                display,
                allocation: None,
            };
            modaltol::results::write(model, a, o, dir)
        })
        .map_err(|e| PyRuntimeError::new_err(format!("{e}: {}", e.source)))?;
    }
    let d = PyDict::new(py);
    d.set_item(
        "tolerance",
        table(
            py,
            &report::tolerance_header(m, a),
            &report::tolerance_rows(a, false),
        )?,
    )?;
    d.set_item(
        "probabilities",
        table(
            py,
            &report::PROBABILITY_HEADER,
            &report::probability_rows(a),
        )?,
    )?;
    d.set_item(
        "yield",
        table(py, &report::YIELD_HEADER, &report::yield_rows(m, a))?,
    )?;
    d.set_item(
        "limits",
        table(py, &report::LIMITS_HEADER, &report::limit_rows(m, a))?,
    )?;
    d.set_item(
        "sobol",
        table(py, &report::SOBOL_HEADER, &report::sobol_rows(m, a))?,
    )?;
    d.set_item(
        "summary",
        serde_json::to_string(&report::summary_json(m, a, mc, used)).expect("a JSON value"),
    )?;
    Ok(d)
}

/// Parameter overrides from a dict (name → number).
fn overrides(parameters: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, f64)>> {
    let Some(d) = parameters else {
        return Ok(Vec::new());
    };
    d.iter()
        .map(|(k, v)| {
            let k: String = k
                .extract()
                .map_err(|_| bad("parameters: the keys must be parameter names (str)"))?;
            let v: f64 = v
                .extract()
                .map_err(|_| bad(format!("parameters[{k:?}]: expected a number")))?;
            Ok((k, v))
        })
        .collect()
}

/// Reads and validates a model file; `parameters` replaces nominal values.
#[pyfunction]
#[pyo3(signature = (path, parameters=None))]
fn load(
    py: Python<'_>,
    path: PathBuf,
    parameters: Option<&Bound<'_, PyDict>>,
) -> PyResult<NativeModel> {
    let set = overrides(parameters)?;
    Compiled::from_file_with(&path, &set)
        .map(|m| NativeModel {
            model: Arc::new(m),
            source: Some(path),
        })
        .map_err(|e| model_error(py, e))
}

/// Validates a model given as TOML text; `name` names it in messages.
#[pyfunction]
#[pyo3(signature = (text, parameters=None, name="<string>"))]
fn loads(
    py: Python<'_>,
    text: &str,
    parameters: Option<&Bound<'_, PyDict>>,
    name: &str,
) -> PyResult<NativeModel> {
    let set = overrides(parameters)?;
    Compiled::from_bytes_with(text.as_bytes(), name, &set)
        .map(|m| NativeModel {
            model: Arc::new(m),
            source: None,
        })
        .map_err(|e| model_error(py, e))
}

/// The native module.
#[pymodule]
fn _modaltol(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ModelError", m.py().get_type::<ModelError>())?;
    m.add("SolveError", m.py().get_type::<SolveError>())?;
    m.add_class::<NativeModel>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(loads, m)?)?;
    Ok(())
}
