//! The `modaltol` command line: a thin layer over the library that parses arguments, reads the
//! model, writes results and maps errors to exit codes (2: bad input, 1: other failures, 130
//! and 143: interrupted by SIGINT or SIGTERM).

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use modaltol::analyze::{AnalyzeOptions, Split, analyze};
use modaltol::cancel::Cancel;
use modaltol::compiled::Compiled;
use modaltol::files::{AtomicFile, Inputs, ResultDir};
use modaltol::model::Sampling;
use modaltol::model::{Model, SpeedRange, Transfer};
use modaltol::montecarlo::McOptions;
use modaltol::quadrature::QuadOptions;
use modaltol::report::{self, SweepColumns};
use modaltol::request::{Request, RequestError, Resolved, Setting, Speeds};
use modaltol::sensitivity::{self, TransferAt};
use modaltol::settings::{self, ThreadsError};
use modaltol::shard::{RunSettings, ShardFile};
use modaltol::study::SweepStudy;
use modaltol::sweep::{Options, initial_guess, point_at};
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

/// Writes a line to stderr, best effort: progress and notes must not stop a run whose stderr
/// cannot be written (closed, a full disk), as `eprintln!` would by panicking.
macro_rules! note {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// [`note!`] without the newline (a progress line rewritten in place).
macro_rules! note_inline {
    ($($arg:tt)*) => {{
        let _ = write!(std::io::stderr(), $($arg)*);
    }};
}

/// Analytical tolerance analysis of the modal characteristics of multibody systems in dynamic
/// equilibrium.
///
/// A mechanism is read from a TOML model file (see docs/model-format.md). At each operating
/// speed modaltol finds the dynamic equilibrium, linearises the equations of motion to M̂, Ĉ, K̂
/// in minimal coordinates and solves the damped eigenproblem.
///
/// Units: SI throughout. Speeds and frequencies in rad/s, angles in rad, translations in m,
/// drive forces in N·m (revolute) or N (prismatic).
#[derive(Parser)]
#[command(
    name = "modaltol",
    version,
    about,
    long_about,
    after_long_help = "Exit codes: 0 success (also when a reader closes the pipe); 1 the \
        computation failed, or an I/O error (a closed stdout, a full disk); 2 bad input (model \
        or arguments); 130 interrupted by SIGINT (Ctrl-C), 143 by SIGTERM: the command stops \
        at its next check, an analysis writes its partial result (flagged), a file is never \
        written cut; a second signal stops it at once."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Replace a parameter's nominal value, as if the model file said so (repeatable):
    /// `--set L=1.02 --set m=3.1`. The value is in the parameter's unit; a tolerance given in
    /// percent applies to the new value.
    #[arg(long = "set", global = true, value_name = "NAME=VALUE", value_parser = parse_set)]
    set: Vec<(String, f64)>,
}

/// Parses a count or seed, saying what was wrong with a negative or fractional one (clap's own
/// parser mistakes `-5` for a flag and suggests `-- -5`).
fn whole_number<T: std::str::FromStr>(s: &str) -> Result<T, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("expected a whole number ≥ 0, got '{s}'"))
}

/// Parses `--set NAME=VALUE`.
fn parse_set(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, e.g. L=1.02 (got '{s}')"))?;
    let v: f64 = value
        .trim()
        .parse()
        .map_err(|_| format!("'{}' is not a number", value.trim()))?;
    if !v.is_finite() {
        return Err(format!("{name}: the value must be finite (got {v})"));
    }
    Ok((name.trim().to_string(), v))
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    /// Text for reading.
    Table,
    /// Everything, for scripts.
    Json,
    /// The table of modes (`modal`: frequencies, damping, roots, shapes named by coordinate;
    /// at a speed that fails, one row per degree of freedom with status `failed`) or of
    /// derivatives (`sensitivity`: one row per mode and design variable); the last column,
    /// `message`, says why a speed failed or |H| has no value (a resonance, an overflow).
    Csv,
}

/// Writes a header and rows as CSV.
fn write_csv(mut w: impl Write, header: &[impl AsRef<[u8]>], rows: &[Vec<String>]) -> Result<()> {
    w.write_all(&modaltol::results::csv_bytes(header, rows))?;
    Ok(())
}

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum SamplingArg {
    /// Independent pseudo-random draws.
    Random,
    /// Latin hypercube.
    Lhs,
    /// Owen-scrambled Sobol sequence.
    Sobol,
}

/// A unit for speeds or frequencies in the plots and report.
#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum UnitArg {
    #[value(name = "rad/s")]
    RadPerSecond,
    #[value(name = "hz")]
    Hertz,
    #[value(name = "rpm")]
    Rpm,
}

impl From<UnitArg> for modaltol::plots::FrequencyUnit {
    fn from(u: UnitArg) -> Self {
        match u {
            UnitArg::RadPerSecond => Self::RadPerSecond,
            UnitArg::Hertz => Self::Hertz,
            UnitArg::Rpm => Self::Rpm,
        }
    }
}

/// The plots' and report's units (the CSV and JSON files stay in rad/s).
#[derive(clap::Args, Clone, Copy)]
struct DisplayArgs {
    /// Unit of the operating speed in the plots and report.html (rad/s, hz, rpm); the CSV and
    /// JSON files stay in rad/s.
    #[arg(long, value_enum, default_value = "rad/s")]
    speed_unit: UnitArg,
    /// Unit of the damped natural frequencies in the plots and report.html (rad/s, hz, rpm).
    #[arg(long, value_enum, default_value = "rad/s")]
    frequency_unit: UnitArg,
}

impl From<DisplayArgs> for modaltol::plots::Display {
    fn from(d: DisplayArgs) -> Self {
        Self {
            speed: d.speed_unit.into(),
            frequency: d.frequency_unit.into(),
        }
    }
}

/// Which equilibrium to report where several exist at a speed.
#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum BranchArg {
    /// Where the equilibrium Newton reaches is unstable (a root with positive real part:
    /// static divergence or flutter), step off it along its unstable modes' shapes, both ways
    /// at growing amplitudes, and report the stable equilibrium found (default).
    Stable,
    /// Report the equilibrium Newton reaches, stable or not (to see how an unstable one
    /// diverges).
    AsGiven,
}

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum Derivatives {
    /// Exact, by automatic differentiation through the equilibrium (default).
    Ad,
    /// Central finite differences of the whole pipeline, Richardson-extrapolated (a cross-check).
    Fd,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a model and summarise its bodies, joints, coordinates, constraints, degrees of
    /// freedom and parameters.
    Check(CheckArgs),
    /// Equilibrium, drive force, M̂, Ĉ, K̂ and damped modes at one speed.
    Modal(ModalArgs),
    /// Sweep the operating speed: one CSV row per (speed, mode).
    ///
    /// Columns: speed (rad/s), mode (1-based, tracked across speeds by mode shape), status
    /// (underdamped|overdamped|unstable|rigid|failed; rigid: a zero root, no frequency and no
    /// damping ratio), damped_frequency, natural_frequency (rad/s), damping_ratio (empty for a
    /// rigid mode), eigen_re, eigen_im (the reported root, 1/s), eigen2_re, eigen2_im (its
    /// partner root), tuning_order (ω_d/Ω: the engine order the mode sits at, as an absorber
    /// is tuned; empty at Ω = 0); with --transfer: transfer_magnitude (output unit per input unit, e.g.
    /// rad/(N·m) or m/N), transfer_phase (rad); with --sensitivity, for every design variable P:
    /// d(damped_frequency)/d(P), d(natural_frequency)/d(P), d(damping_ratio)/d(P) and with
    /// --transfer d(transfer_magnitude)/d(P) (per unit of P), then sensitivity_status
    /// (ok|not_differentiable; the derivative cells are empty where it does not exist);
    /// q:<joint> (equilibrium coordinates, rad or m), drive:<joint> (drive force, N·m or N),
    /// iterations (Newton), branch (stable|switched|unstable: whether the equilibrium continued
    /// from the previous speed was kept, or a stable one found instead), message (why a speed
    /// failed, why the branch was switched or left unstable, a change of stability, or why |H|
    /// has no value: "resonance" where an undamped mode sits at the excitation frequency,
    /// "overflow" where a number is beyond floating point).
    Sweep(SweepArgs),
    /// Derivatives of ω_d, ω_n, ζ of every mode and of the transfer magnitude with respect to
    /// the design variables at one speed, through the move of the equilibrium.
    Sensitivity(SensitivityArgs),
    /// Tolerance analysis across the speed range: every mode's ω_d and ζ and the transfer
    /// magnitude, per tolerance case of the model's [analysis] table, by first order (the
    /// paper's method), second order, the invariant-based method for ω_d, the quadrature (the
    /// whole nonlinear analysis integrated over the distribution of the design variables,
    /// deterministically, with error estimates: right at class changes and branch switches),
    /// "analytic" (the answer to read: the quadrature), and Monte Carlo.
    ///
    /// Writes DIR/tolerance.csv (columns speed, quantity, mode, case, method, mean, std,
    /// mean_ci_low, mean_ci_high, std_ci_low, std_ci_high, samples, failed, class_changed,
    /// basis (the method an "analytic" row took), q05, q50, q95 (quantiles: quadrature and
    /// Monte Carlo), mean_error, std_error (the quadrature's error estimates), partial, reason
    /// (why a row has no mean and σ), share:<parameter>; SI units, rad/s for speeds and
    /// frequencies), DIR/probabilities.csv
    /// (speed, case, method, event = overdamped|unstable|other_branch, mode, probability,
    /// ci_low, ci_high), DIR/summary.json (cases, wall times of the Taylor methods, the
    /// quadrature and the Monte Carlo, beside the paper's for its two examples, failures, the
    /// rows without a value grouped with their reasons under "unfilled"),
    /// the plots (SVG and PNG: mean ± σ and σ by method of every mode's ω_d and ζ and of |H|,
    /// probabilities, variance shares, a Campbell diagram with engine orders 1–3 and the
    /// critical speeds marked) and DIR/report.html (a summary of σ by method at the largest σ,
    /// the critical speeds and the |H| peak, then the plots). --speed-unit and
    /// --frequency-unit show the plots and report in rpm or Hz. Without MODEL, runs the
    /// governor example built into the binary.
    Analyze(AnalyzeArgs),
    /// Combine the shard files of `analyze --shard K/N` runs into exactly the result of one run
    /// (same seed, same numbers): writes the same files as `analyze`, except the Monte Carlo
    /// quantiles q05, q50, q95 (they need every sample at once; a merge leaves them empty).
    ///
    /// Every shard must come from the same model (with the same --set), tolerance cases,
    /// speeds, samples, seed, sampling and quadrature options: a shard computed from anything
    /// else is refused, naming the file and what differs. The quadrature runs with the
    /// options the shards' run was given.
    Merge(MergeArgs),
    /// Frequency response at one speed: H(jω) from a generalised force on a joint coordinate,
    /// or a force or torque at a [[ports]] entry, to the response of another coordinate or
    /// port, over a range of excitation frequencies.
    ///
    /// Columns: frequency (rad/s), magnitude (output unit per input unit), phase (rad), real,
    /// imag, and d(magnitude)/d(P) for every design variable P (empty where |H| has no
    /// derivative), message (why H has no value where it has none: "resonance", "overflow").
    Frf(FrfArgs),
}

// Each command's arguments (their help text is on the `Command` variant).
#[derive(clap::Args)]
struct CheckArgs {
    /// Model file (TOML).
    model: PathBuf,
}

#[derive(clap::Args)]
struct ModalArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    speed: f64,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    format: Format,
    /// Independent coordinates (joint names, comma separated), overriding the model.
    #[arg(long, value_delimiter = ',')]
    independent: Option<Vec<String>>,
    /// Which equilibrium to report, Newton starting from the model's initial guess: every
    /// format says which was taken and why (text: `branch:`, JSON: "branch", CSV: the
    /// `branch` and `message` columns).
    #[arg(long, value_enum, default_value = "stable")]
    branch: BranchArg,
    /// Write to this file instead of stdout.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
struct SweepArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Speeds FROM:TO:STEP in rad/s (TO included); default: the model's [analysis] speed.
    #[arg(long, allow_hyphen_values = true)]
    speed: Option<String>,
    /// Independent coordinates (joint names, comma separated), overriding the model.
    #[arg(long, value_delimiter = ',')]
    independent: Option<Vec<String>>,
    /// Which equilibrium to follow: `stable` switches to a stable one where the one continued
    /// from the previous speed has lost its stability (the `branch` column says `switched`
    /// and the message why); `as-given` follows the continued one, stable or not.
    #[arg(long, value_enum, default_value = "stable")]
    branch: BranchArg,
    /// Transfer function `input=NAME,output=NAME[,order=K]` (NAME a free joint coordinate or a
    /// [[ports]] entry): generalised force (or port force/torque) on `input`,
    /// response of `output`, excitation at K × speed (K = 1 by default). `--transfer model`
    /// uses the model's [analysis] transfer.
    #[arg(long)]
    transfer: Option<String>,
    /// Add the derivatives of every mode (and of |H|) with respect to the design variables.
    #[arg(long)]
    sensitivity: bool,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    wrt: Option<Vec<String>>,
    /// How derivatives are computed.
    #[arg(long, value_enum, default_value = "ad")]
    derivatives: Derivatives,
    /// Write the CSV to this file instead of stdout.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
struct SensitivityArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    speed: f64,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    wrt: Option<Vec<String>>,
    /// How derivatives are computed.
    #[arg(long, value_enum, default_value = "ad")]
    derivatives: Derivatives,
    /// Transfer function `input=NAME,output=NAME[,order=K]` (free coordinates or ports);
    /// default: the model's.
    #[arg(long)]
    transfer: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    format: Format,
    /// Write to this file instead of stdout.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
struct AnalyzeArgs {
    /// Model file (TOML); default: the built-in governor example.
    model: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// Speeds FROM:TO:STEP in rad/s; default: the model's [analysis] speed.
    #[arg(long, allow_hyphen_values = true)]
    speed: Option<String>,
    /// Monte Carlo samples; default: the model's (3000 unless it says otherwise).
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    samples: Option<usize>,
    /// Random seed; default: the model's.
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<u64>)]
    seed: Option<u64>,
    /// Worker threads for the derivatives, the quadrature and the Monte Carlo (results do
    /// not depend on it): 1 to 1024; default: all cores.
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    threads: Option<usize>,
    /// Skip the Monte Carlo.
    #[arg(long)]
    no_monte_carlo: bool,
    /// Requested error of the quadrature's mean and σ, relative to the output's σ at that
    /// speed (or 2 % of its largest σ over the speeds, if larger); the grid along each
    /// line is refined until its error estimate meets it or the largest grid is reached.
    #[arg(long, default_value_t = 1e-3, value_name = "REL")]
    quadrature_tolerance: f64,
    /// Skip the quadrature (the "analytic" rows then take the automatic Taylor choice).
    #[arg(long)]
    no_quadrature: bool,
    /// Sampling of the design variables; default: the model's.
    #[arg(long, value_enum)]
    sampling: Option<SamplingArg>,
    /// Compute only shard K of N of the Monte Carlo samples (e.g. 2/8, one per batch job)
    /// and write DIR/shard-K-of-N.json; combine the shards with `modaltol merge`.
    #[arg(long)]
    shard: Option<String>,
    /// Only this tolerance case of the model's [analysis] table (repeatable); default: all.
    #[arg(long = "case", value_name = "NAME")]
    cases: Vec<String>,
    #[command(flatten)]
    display: DisplayArgs,
}

#[derive(clap::Args)]
struct MergeArgs {
    /// Model file the shards were made from; default: the built-in governor example.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// The shard files (shard-K-of-N.json), all N of them, in any order.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// The tolerance cases the shards were run with (as given to `analyze --case`).
    #[arg(long = "case", value_name = "NAME")]
    cases: Vec<String>,
    #[command(flatten)]
    display: DisplayArgs,
}

#[derive(clap::Args)]
struct FrfArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    speed: f64,
    /// Transfer function `input=NAME,output=NAME` (NAME a free joint coordinate or a
    /// [[ports]] entry): generalised force (or port force/torque) on `input`, response of
    /// `output`; default: the model's [analysis] transfer.
    #[arg(long)]
    transfer: Option<String>,
    /// Excitation frequencies FROM:TO:STEP in rad/s.
    #[arg(long, allow_hyphen_values = true)]
    freq: String,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    wrt: Option<Vec<String>>,
    /// Write the CSV to this file instead of stdout. (With the older `--input A --output B`
    /// spelling of the transfer function, `--output` names the response and `--out` the file.)
    #[arg(short, long)]
    output: Option<String>,
    /// Older spelling: where the excitation enters (use --transfer input=…,output=…).
    #[arg(long, hide = true)]
    input: Option<String>,
    /// Older spelling of -o/--output, kept for scripts.
    #[arg(long, hide = true)]
    out: Option<PathBuf>,
}

/// The governor example, built into the binary so `analyze` runs with no model file.
const EMBEDDED_GOVERNOR: &str = include_str!("../examples/governor.toml");

/// The run was interrupted (SIGINT, SIGTERM); the message says what was written: exit code
/// 128 + the signal's number.
#[derive(Debug, thiserror::Error)]
#[error("interrupted; {0}")]
struct Interrupted(String);

/// The computation asked for failed (its reason is the message): exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct Failed(String);

/// Bad input (model, arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct InputError(String);

fn load(path: &std::path::Path, set: &[(String, f64)]) -> Result<Compiled> {
    Compiled::from_file_with(path, set).map_err(|e| InputError(e.to_string()).into())
}

fn independent(model: &Model, names: &Option<Vec<String>>) -> Result<Option<Vec<usize>>> {
    names
        .as_deref()
        .map(|n| {
            model
                .independent_coordinates(n)
                .map_err(|e| InputError(format!("--independent: {e}")).into())
        })
        .transpose()
}

/// Design variables by name, or those with a tolerance.
fn design_variables(model: &Model, names: &Option<Vec<String>>) -> Result<Vec<usize>> {
    model
        .design_variables(names.as_deref())
        .map_err(|e| InputError(format!("--wrt: {e}")).into())
}

/// Parses `input=NAME,output=NAME[,order=K]` (or `model` for the model's own transfer function).
fn parse_transfer(model: &Model, spec: &str) -> Result<Transfer> {
    model
        .parse_transfer(spec)
        .map_err(|e| InputError(format!("--transfer {spec}: {e}")).into())
}

/// The library's choice for the command line's.
fn how(d: Derivatives) -> sensitivity::Derivatives {
    match d {
        Derivatives::Ad => sensitivity::Derivatives::Exact,
        Derivatives::Fd => sensitivity::Derivatives::FiniteDifference,
    }
}
fn model_or_governor(model: &Option<PathBuf>, set: &[(String, f64)]) -> Result<Compiled> {
    match model {
        Some(path) => load(path, set),
        None => Compiled::from_bytes_with(
            EMBEDDED_GOVERNOR.as_bytes(),
            "governor.toml (built in)",
            set,
        )
        .map_err(|e| InputError(e.to_string()).into()),
    }
}

/// A refused analysis request, in the command line's spelling: bad input, or a failure where
/// the operating system refuses the threads.
fn refused(e: RequestError, shard: &Option<String>, cases_chosen: bool) -> anyhow::Error {
    let spec = shard.as_deref().unwrap_or_default();
    match e {
        RequestError::Threads(t @ ThreadsError::Refused { .. }) => {
            Failed(format!("--threads: {t}")).into()
        }
        RequestError::NoSpeeds => {
            InputError("no --speed given and the model has no [analysis] speed".into()).into()
        }
        RequestError::Speeds(s) | RequestError::ModelSpeeds(s) => {
            InputError(format!("--speed: {s}")).into()
        }
        RequestError::Cases(s) => {
            let flag = if cases_chosen { "--case: " } else { "" };
            InputError(format!("{flag}{s}")).into()
        }
        RequestError::ShardWithoutMonteCarlo => {
            InputError("--shard splits the Monte Carlo; it cannot go with --no-monte-carlo".into())
                .into()
        }
        RequestError::TooManyShards { .. } => InputError(format!("--shard {spec}: {e}")).into(),
        e => {
            let flag = match e.setting() {
                Setting::QuadratureTolerance => "--quadrature-tolerance",
                Setting::Threads => "--threads",
                Setting::Samples => "--samples",
                _ => unreachable!("named above"),
            };
            InputError(format!("{flag} {e}")).into()
        }
    }
}

/// The model's tolerance cases, or one made of the parameters' own tolerances.
fn tolerance_cases(m: &Model, only: &[String]) -> Result<Vec<modaltol::model::Case>> {
    m.tolerance_cases(only).map_err(|e| {
        let flag = if only.is_empty() { "" } else { "--case: " };
        InputError(format!("{flag}{e}")).into()
    })
}

/// Progress on stderr: on a terminal one line rewritten in place; otherwise (a batch job's
/// log) one line per tenth of each stage, so that logs show how far a run got.
fn progress_printer() -> impl Fn(&str, usize, usize) + Sync {
    let terminal = std::io::stderr().is_terminal();
    let last = std::sync::Mutex::new((String::new(), usize::MAX));
    move |stage: &str, done: usize, total: usize| {
        if terminal {
            if done == total || done.is_multiple_of(16) {
                note_inline!("\r{stage}: {done}/{total}          ");
                if done == total {
                    note!();
                }
            }
            return;
        }
        let tenth = (done * 10).checked_div(total).unwrap_or(10);
        let mut last = last.lock().unwrap_or_else(|e| e.into_inner());
        if last.0 != stage || last.1 != tenth {
            *last = (stage.to_string(), tenth);
            note!("{stage}: {done}/{total}");
        }
    }
}

/// The signal that interrupted the run (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// SIGINT (Ctrl-C) and SIGTERM (what Slurm and Kubernetes send at a time limit) cancel
/// `cancel`, in every command alike: the run stops at its next check (a sweep before its next
/// speed, the Monte Carlo after its current chunk), writes what may be written (an analysis's
/// partial result, flagged; never a cut file) and exits with 128 + the signal's number (130,
/// 143). A second signal ends the process at once (the next run into the same place
/// removes what it left).
fn handle_interrupts(cancel: &Cancel) {
    let Ok(mut signals) = Signals::new([SIGINT, SIGTERM]) else {
        return; // the default actions then stay: the process ends at the signal
    };
    let cancel = cancel.clone();
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if SIGNAL.swap(signal, Ordering::SeqCst) != 0 {
                std::process::exit(128 + signal);
            }
            let name = if signal == SIGTERM {
                "SIGTERM"
            } else {
                "SIGINT"
            };
            note!(
                "\nmodaltol: {name}: stopping at the next check and writing what is complete \
                 (again to stop at once)"
            );
            cancel.cancel();
        }
    });
}

/// Stops a command that a signal cancelled before it writes its output `output` (stdout
/// where `None`), which is then not written.
fn stop_if_cancelled(cancel: &Cancel, output: &Option<PathBuf>) -> Result<()> {
    if !cancel.is_cancelled() {
        return Ok(());
    }
    Err(Interrupted(match output {
        Some(f) => format!("{} not written", f.display()),
        None => "nothing written".into(),
    })
    .into())
}

/// The exit code of a run that a signal interrupted: 128 + its number.
fn interrupted_code() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(128 + s),
    }
}

/// Writes tolerance.csv, the plots, report.html and summary.json of an analysis.
fn write_outputs(
    m: &Compiled,
    a: &modaltol::analyze::Analysis,
    mc: Option<&McOptions>,
    threads: Option<usize>,
    display: modaltol::plots::Display,
    dir: ResultDir,
    output: &std::path::Path,
) -> Result<()> {
    let used = threads.unwrap_or_else(rayon::current_num_threads);
    let written = modaltol::results::write(m, a, mc, used, display, dir)?;
    for (stem, e) in &written.missing_png {
        note!("modaltol: no PNG for {stem}: {e}");
    }
    let partial = written.partial;
    note!(
        "modaltol: analytic (Taylor) {:.3} s{}{}; wrote {}",
        a.analytic_seconds,
        a.quadrature_seconds
            .map_or(String::new(), |t| format!(", quadrature {t:.3} s")),
        a.monte_carlo_seconds.map_or(String::new(), |t| format!(
            ", Monte Carlo {t:.3} s (ratio {:.0})",
            t / a.analytic_seconds
        )),
        output.display()
    );
    for w in report::inadmissible_warnings(a) {
        note!("modaltol: warning: {w}");
    }
    if !a.failures.is_empty() {
        note!(
            "modaltol: {} speed(s) failed; see summary.json",
            a.failures.len()
        );
    }
    for line in report::unfilled_lines(a) {
        note!("modaltol: note: {line}");
    }
    if partial {
        if a.samples_done.is_empty() {
            note!("modaltol: partial result (interrupted): not every speed was analysed");
        } else {
            note!(
                "modaltol: partial result (interrupted): Monte Carlo samples done per case {:?}",
                a.samples_done
            );
        }
        return Err(Interrupted("the outputs hold a partial result".into()).into());
    }
    Ok(())
}

/// An output named that is one of the run's inputs: bad arguments, refused before anything
/// is computed or written.
fn refuse_input(inputs: &Inputs, output: &std::path::Path) -> Result<()> {
    inputs
        .refuse_output(output)
        .map_err(|e| InputError(format!("{e}: {}", e.source)).into())
}

/// `dir`, refusing (as an input error, before the run) an input it would replace or remove.
fn protect(dir: ResultDir, inputs: Inputs) -> Result<ResultDir> {
    dir.protect(inputs, modaltol::results::is_result_file)
        .map_err(|e| InputError(format!("{e}: {}", e.source)).into())
}

/// Where `analyze` writes: a shard's file, or the whole run's directory.
enum Destination {
    Shard(AtomicFile, PathBuf),
    Directory(ResultDir),
}

/// Where a command's table goes: a file written beside its target and renamed into place by
/// [`Sink::finish`] (a failed or killed run leaves the earlier file untouched), or stdout.
enum Sink {
    File(std::io::BufWriter<AtomicFile>),
    Stdout(std::io::BufWriter<std::io::StdoutLock<'static>>),
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::File(w) => w.write(buf),
            Sink::Stdout(w) => w.write(buf),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::File(w) => w.flush(),
            Sink::Stdout(w) => w.flush(),
        }
    }
}

impl Sink {
    /// The file `output` (refused where it is one of `inputs`), or stdout.
    fn to(output: &Option<PathBuf>, inputs: &Inputs) -> Result<Sink> {
        Ok(match output {
            Some(p) => {
                refuse_input(inputs, p)?;
                Sink::File(std::io::BufWriter::new(AtomicFile::create(p)?))
            }
            None if STDOUT_CLOSED.load(Ordering::SeqCst) => {
                return Err(Failed(
                    "stdout is closed: nothing could be written (give -o FILE)".into(),
                )
                .into());
            }
            None => Sink::Stdout(std::io::BufWriter::new(std::io::stdout().lock())),
        })
    }

    /// Flushes, and puts a file in place.
    fn finish(self) -> Result<()> {
        match self {
            Sink::File(w) => w.into_inner().map_err(|e| e.into_error())?.commit()?,
            Sink::Stdout(mut w) => w.flush()?,
        }
        Ok(())
    }
}

fn run(cli: Cli, cancel: &Cancel) -> Result<()> {
    let set = &cli.set;
    match cli.command {
        Command::Check(args) => check_command(args, set),
        Command::Modal(args) => modal_command(args, set, cancel),
        Command::Sweep(args) => sweep_command(args, set, cancel),
        Command::Sensitivity(args) => sensitivity_command(args, set, cancel),
        Command::Analyze(args) => analyze_command(args, set, cancel),
        Command::Merge(args) => merge_command(args, set, cancel),
        Command::Frf(args) => frf_command(args, set, cancel),
    }
}

/// `modaltol check` (see its `--help`).
fn check_command(args: CheckArgs, set: &[(String, f64)]) -> Result<()> {
    let CheckArgs { model } = args;
    let m = load(&model, set)?;
    let mut w = Sink::to(&None, &Inputs::default())?;
    write!(w, "{}", report::check_summary(m.model()))?;
    w.finish()?;

    Ok(())
}

/// `modaltol modal` (see its `--help`).
fn modal_command(args: ModalArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let ModalArgs {
        model,
        speed,
        format,
        independent: ind,
        branch,
        output,
    } = args;
    let m = load(&model, set)?;
    settings::speed(speed).map_err(|e| InputError(format!("--speed {e}")))?;
    let opt = Options {
        independent: independent(m.model(), &ind)?,
        no_branch_switch: branch == BranchArg::AsGiven,
        ..Default::default()
    };
    let mut w = Sink::to(&output, &Inputs::new(&[&model]))?;
    let p = m.model().nominal();
    initial_guess(m.model(), &p, speed).map_err(|e| InputError(e.to_string()))?;
    let result = point_at(&m, &p, speed, &opt);
    stop_if_cancelled(cancel, &output)?;
    match format {
        Format::Json => writeln!(
            w,
            "{}",
            serde_json::to_string_pretty(&report::modal_json(m.model(), speed, &result))?
        )?,
        Format::Table => write!(w, "{}", report::modal_table(m.model(), speed, &result))?,
        Format::Csv => {
            let rows = match &result {
                Ok(pt) => report::modes_rows(pt),
                Err(e) => report::modes_failed_rows(m.model(), speed, e),
            };
            write_csv(&mut w, &report::modes_header(m.model()), &rows)?
        }
    }
    w.finish()?;
    if let Err(e) = result {
        return Err(Failed(format!("speed {speed:?} rad/s failed: {e}")).into());
    }

    Ok(())
}

/// `modaltol sweep` (see its `--help`).
fn sweep_command(args: SweepArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let SweepArgs {
        model,
        speed,
        independent: ind,
        branch,
        transfer: tspec,
        sensitivity: sens,
        wrt,
        derivatives,
        output,
    } = args;
    let m = load(&model, set)?;
    let range = match &speed {
        Some(s) => SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
        None => m.model().analysis.speed.ok_or_else(|| {
            InputError("no --speed given and the model has no [analysis] speed".into())
        })?,
    };
    let tf = tspec
        .as_deref()
        .map(|s| parse_transfer(m.model(), s))
        .transpose()?;
    let cols = SweepColumns {
        transfer: tf.is_some(),
        wrt: if sens {
            design_variables(m.model(), &wrt)?
        } else {
            Vec::new()
        },
    };
    let opt = Options {
        independent: independent(m.model(), &ind)?,
        no_branch_switch: branch == BranchArg::AsGiven,
        ..Default::default()
    };
    let mut study = SweepStudy::new(&m, opt, tf, cols.wrt.clone(), how(derivatives));
    let mut csv = csv::Writer::from_writer(Sink::to(&output, &Inputs::new(&[&model]))?);
    csv.write_record(report::sweep_header(m.model(), &cols))?;
    let n = range.len();
    // Long sweeps (sensitivities at each speed, or many speeds) report their progress.
    let progress = (sens || n >= 2000).then(progress_printer);
    let mut failed = 0usize;
    for (i, w) in range.speeds().enumerate() {
        if cancel.is_cancelled() {
            // Streamed rows stay on stdout; a file is complete or absent.
            return Err(Interrupted(match &output {
                Some(f) => format!("{} not written ({i} of {n} speeds done)", f.display()),
                None => format!("after {i} of {n} speeds"),
            })
            .into());
        }
        let (r, extras) = study.step(w);
        if r.is_err() {
            failed += 1;
        }
        for row in report::sweep_rows(m.model(), &cols, w, &r, &extras) {
            csv.write_record(&row)?;
        }
        if let Some(p) = &progress {
            p("sweep speeds", i + 1, n);
        }
    }
    csv.into_inner().map_err(|e| e.into_error())?.finish()?;
    if failed == n {
        return Err(Failed(format!(
            "all {n} speeds failed (status 'failed', reason in the message column)"
        ))
        .into());
    }
    if failed > 0 {
        note!(
            "modaltol: {failed} of {n} speeds failed (status 'failed', reason in the message column)"
        );
    }

    Ok(())
}

/// `modaltol sensitivity` (see its `--help`).
fn sensitivity_command(
    args: SensitivityArgs,
    set: &[(String, f64)],
    cancel: &Cancel,
) -> Result<()> {
    let SensitivityArgs {
        model,
        speed,
        wrt,
        derivatives,
        transfer: tspec,
        format,
        output,
    } = args;
    let m = load(&model, set)?;
    settings::speed(speed).map_err(|e| InputError(format!("--speed {e}")))?;
    let wrt = design_variables(m.model(), &wrt)?;
    let tf = match tspec.as_deref() {
        Some(s) => Some(parse_transfer(m.model(), s)?),
        None => m.model().analysis.transfer,
    };
    let mut w = Sink::to(&output, &Inputs::new(&[&model]))?;
    let p = m.model().nominal();
    initial_guess(m.model(), &p, speed).map_err(|e| InputError(e.to_string()))?;
    let pt = point_at(&m, &p, speed, &Options::default())
        .with_context(|| format!("speed {speed:?} rad/s"))?;
    let at = tf.map(|t| TransferAt::at_speed(&t, speed));
    let s = sensitivity::sensitivities(&m, &p, &pt, &wrt, at, how(derivatives))
        .with_context(|| format!("sensitivities at {speed:?} rad/s"))?;
    let why = report::transfer_defect_at(&pt, at.as_ref());
    stop_if_cancelled(cancel, &output)?;
    let method = if derivatives == Derivatives::Ad {
        "ad"
    } else {
        "fd"
    };
    match format {
        Format::Json => writeln!(
            w,
            "{}",
            serde_json::to_string_pretty(&report::sensitivity_json(
                m.model(),
                speed,
                method,
                &pt,
                &s,
                why
            ))?
        )?,
        Format::Table => write!(
            w,
            "{}",
            report::sensitivity_table(m.model(), speed, method, &pt, &s, why)
        )?,
        Format::Csv => write_csv(
            &mut w,
            &report::SENSITIVITY_HEADER,
            &report::sensitivity_rows(m.model(), &pt, &s, why),
        )?,
    }
    w.finish()?;

    Ok(())
}

/// `modaltol analyze` (see its `--help`).
fn analyze_command(args: AnalyzeArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let AnalyzeArgs {
        model,
        output,
        speed,
        samples,
        seed,
        threads,
        no_monte_carlo,
        quadrature_tolerance,
        no_quadrature,
        sampling,
        shard,
        cases: only,
        display,
    } = args;
    let request = Request {
        speeds: match &speed {
            Some(s) => Speeds::Range(
                SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
            ),
            None => Speeds::Model,
        },
        cases: only,
        samples,
        seed,
        sampling: sampling.map(|s| match s {
            SamplingArg::Random => Sampling::Random,
            SamplingArg::Lhs => Sampling::Lhs,
            SamplingArg::Sobol => Sampling::Sobol,
        }),
        monte_carlo: !no_monte_carlo,
        quadrature: !no_quadrature,
        quadrature_tolerance,
        threads,
        shard: shard
            .as_deref()
            .map(|spec| settings::shard(spec).map_err(|e| InputError(format!("--shard {e}"))))
            .transpose()?,
    };
    // The settings that need no model first: a bad flag is reported before a slow load.
    let chosen = !request.cases.is_empty();
    let request = request.check().map_err(|e| refused(e, &shard, chosen))?;
    let m = model_or_governor(&model, set)?;
    let Resolved {
        options: opt,
        range,
    } = request
        .resolve(m.model(), cancel.clone())
        .map_err(|e| refused(e, &shard, chosen))?;
    let (mc, split) = (opt.monte_carlo, opt.split.clone());
    // Fail early where the results cannot be written.
    let inputs = Inputs::new(&model.iter().collect::<Vec<_>>());
    let destination = match split {
        Split::Shard(k, n) => {
            std::fs::create_dir_all(&output)
                .with_context(|| format!("{}: cannot create the directory", output.display()))?;
            let path = output.join(format!("shard-{}-of-{n}.json", k + 1));
            refuse_input(&inputs, &path)?;
            Destination::Shard(AtomicFile::create(&path)?, path)
        }
        _ => {
            refuse_input(&inputs, &output)?;
            Destination::Directory(protect(ResultDir::create(&output)?, inputs)?)
        }
    };
    let a = analyze(&m, &opt, &progress_printer());
    if let (Split::Shard(k, n), Some(mc)) = (&opt.split, mc) {
        let Destination::Shard(mut f, path) = destination else {
            unreachable!("a shard's destination is its file")
        };
        let tolerance = (!no_quadrature).then_some(quadrature_tolerance);
        let range = range.expect("a command-line analysis runs over a range");
        let run = RunSettings::new(&range, &mc, tolerance, *n);
        let Some(file) = ShardFile::of_analysis(m.model(), &opt.cases, &a, &run, *k) else {
            return Err(Interrupted(format!(
                "{} not written (a shard is complete or absent)",
                path.display()
            ))
            .into());
        };
        f.write_all(file.to_json().as_bytes())
            .with_context(|| format!("{}: cannot write", path.display()))?;
        f.commit()?;
        note!(
            "modaltol: wrote {}; combine the shards with `modaltol merge`",
            path.display()
        );
        return Ok(());
    }
    let Destination::Directory(dir) = destination else {
        unreachable!("a whole run's destination is a directory")
    };
    write_outputs(
        &m,
        &a,
        mc.as_ref(),
        opt.threads,
        display.into(),
        dir,
        &output,
    )?;

    Ok(())
}

/// `modaltol merge` (see its `--help`).
fn merge_command(args: MergeArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let MergeArgs {
        model,
        output,
        shards,
        cases: only,
        display,
    } = args;
    let m = model_or_governor(&model, set)?;
    let cases = tolerance_cases(m.model(), &only)?;
    let (first, states) = modaltol::shard::read_all(m.model(), &cases, &shards)
        .map_err(|e| InputError(e.to_string()))?;
    let range = SpeedRange::parse(&first.speed).map_err(InputError)?;
    settings::analysis_speeds(range.len()).map_err(InputError)?;
    let mc = McOptions {
        samples: first.samples,
        seed: first.seed,
        sampling: first.sampling,
    };
    let opt = AnalyzeOptions {
        speeds: range.speeds().collect(),
        cases,
        // The quadrature of the run the shards belong to.
        quadrature: first.quadrature.map(|tolerance| QuadOptions { tolerance }),
        monte_carlo: Some(mc),
        split: Split::Merged(states),
        threads: None,
        cancel: cancel.clone(),
    };
    let mut inputs: Vec<&PathBuf> = model.iter().collect();
    inputs.extend(&shards);
    let inputs = Inputs::new(&inputs);
    refuse_input(&inputs, &output)?;
    let dir = protect(ResultDir::create(&output)?, inputs)?;
    let a = analyze(&m, &opt, &progress_printer());
    write_outputs(&m, &a, Some(&mc), None, display.into(), dir, &output)?;

    Ok(())
}

/// `modaltol frf` (see its `--help`).
fn frf_command(args: FrfArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let FrfArgs {
        model,
        speed,
        transfer,
        freq,
        wrt,
        output,
        input,
        out,
    } = args;
    let m = load(&model, set)?;
    // `--input A --output B [--out FILE]` is the older spelling; `-o/--output` is the file
    // otherwise, as in every other command.
    let (tf, file) = match (&transfer, &input) {
        (Some(_), Some(_)) => {
            return Err(InputError(
                "give the transfer function once: --transfer input=…,output=… (the older \
                 --input/--output pair is its other spelling)"
                    .into(),
            )
            .into());
        }
        (Some(spec), None) => {
            let tf = m
                .model()
                .parse_response(spec)
                .map_err(|e| InputError(format!("--transfer {spec}: {e}")))?;
            (tf, output.map(PathBuf::from).or(out))
        }
        (None, Some(inp)) => {
            let outp = output.ok_or_else(|| {
                InputError("--input needs --output (the response); or use --transfer".into())
            })?;
            note!(
                "modaltol: note: `--input {inp} --output {outp}` is the older spelling of \
                 `--transfer input={inp},output={outp}`; -o/--output now names the CSV file"
            );
            (
                parse_transfer(m.model(), &format!("input={inp},output={outp}"))?,
                out,
            )
        }
        (None, None) => {
            let tf = m.model().analysis.transfer.ok_or_else(|| {
                InputError(
                    "frf needs --transfer input=NAME,output=NAME (the model's [analysis] has \
                     no transfer function)"
                        .into(),
                )
            })?;
            (tf, output.map(PathBuf::from).or(out))
        }
    };
    settings::speed(speed).map_err(|e| InputError(format!("--speed {e}")))?;
    let range = SpeedRange::parse(&freq).map_err(|e| InputError(format!("--freq: {e}")))?;
    let wrt = design_variables(m.model(), &wrt)?;
    let mut csv = csv::Writer::from_writer(Sink::to(&file, &Inputs::new(&[&model]))?);
    let p = m.model().nominal();
    initial_guess(m.model(), &p, speed).map_err(|e| InputError(e.to_string()))?;
    let pt = point_at(&m, &p, speed, &Options::default())
        .with_context(|| format!("speed {speed:?} rad/s"))?;
    // Stops at the frequency after a signal.
    let frequencies = range.speeds().take_while(|_| !cancel.is_cancelled());
    let rows = sensitivity::frequency_response(&m, &p, &pt, tf.input, tf.output, &wrt, frequencies)
        .with_context(|| format!("sensitivities at {speed:?} rad/s"))?;
    stop_if_cancelled(cancel, &file)?;
    csv.write_record(report::frf_header(m.model(), &wrt))?;
    for row in report::frf_rows(&pt.linear, &rows) {
        csv.write_record(&row)?;
    }
    csv.into_inner().map_err(|e| e.into_error())?.finish()?;

    Ok(())
}

/// Was stdout closed when the process started (`modaltol … >&-`)? Rust's runtime opens
/// `/dev/null` in its place before `main`, and whatever is written there vanishes without a
/// word; so this is looked at before the runtime starts (an ELF initialiser), and a command
/// that would write to stdout refuses to run instead.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

#[cfg(target_os = "linux")]
#[used]
#[unsafe(link_section = ".init_array")]
static NOTE_A_CLOSED_STDOUT: extern "C" fn() = {
    extern "C" fn note() {
        // SAFETY: F_GETFD reads a descriptor's flags and nothing else; a closed one is EBADF.
        let closed = unsafe { libc::fcntl(1, libc::F_GETFD) } == -1;
        STDOUT_CLOSED.store(closed, Ordering::SeqCst);
    }
    note
};

fn main() {
    let cli = Cli::parse();
    let cancel = Cancel::new();
    handle_interrupts(&cancel);
    let result = run(cli, &cancel);
    if let Err(e) = result {
        // A reader that stopped reading (`… | head`) is not an error of ours.
        let pipe = |io: &std::io::Error| io.kind() == std::io::ErrorKind::BrokenPipe;
        let broken_pipe = e.chain().any(|c| {
            c.downcast_ref::<std::io::Error>().is_some_and(pipe)
                || c.downcast_ref::<csv::Error>()
                    .is_some_and(|e| match e.kind() {
                        csv::ErrorKind::Io(io) => pipe(io),
                        _ => false,
                    })
        });
        if broken_pipe {
            std::process::exit(0);
        }
        note!("modaltol: error: {e:#}");
        let code = if e.downcast_ref::<InputError>().is_some() {
            2
        } else if e.downcast_ref::<Interrupted>().is_some() {
            interrupted_code().unwrap_or(130)
        } else {
            1
        };
        std::process::exit(code);
    }
    // A signal that came when nothing was left to stop still ends the run as interrupted.
    if let Some(code) = interrupted_code() {
        std::process::exit(code);
    }
}
