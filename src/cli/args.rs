//! The command line's arguments: what `--help` teaches, parsed by clap.

use super::InputError;
use anyhow::Result;
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

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
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
    /// Replace a parameter's nominal value, as if the model file said so (repeatable):
    /// `--set L=1.02 --set m=3.1`. The value is in the parameter's unit; a tolerance given in
    /// percent applies to the new value.
    #[arg(long = "set", global = true, value_name = "NAME=VALUE", value_parser = parse_set)]
    pub(crate) set: Vec<(String, f64)>,
}

/// Parses a count or seed, saying what was wrong with a negative or fractional one (clap's own
/// parser mistakes `-5` for a flag and suggests `-- -5`).
pub(crate) fn whole_number<T: std::str::FromStr>(s: &str) -> Result<T, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("expected a whole number ≥ 0, got '{s}'"))
}

/// Parses `--set NAME=VALUE`.
pub(crate) fn parse_set(s: &str) -> Result<(String, f64), String> {
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
pub(crate) enum Format {
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
#[derive(Clone, Copy, PartialEq, ValueEnum)]
pub(crate) enum SamplingArg {
    /// Independent pseudo-random draws.
    Random,
    /// Latin hypercube.
    Lhs,
    /// Owen-scrambled Sobol sequence.
    Sobol,
}

/// A unit for speeds or frequencies in the plots and report.
#[derive(Clone, Copy, PartialEq, ValueEnum)]
pub(crate) enum UnitArg {
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

/// The plots' and report's units (the CSV and JSON files stay in rad/s) and the case they
/// are about.
#[derive(clap::Args, Clone)]
pub(crate) struct DisplayArgs {
    /// Unit of the operating speed in the plots and report.html (rad/s, hz, rpm); the CSV and
    /// JSON files stay in rad/s.
    #[arg(long, value_enum, default_value = "rad/s")]
    pub(crate) speed_unit: UnitArg,
    /// Unit of the damped natural frequencies in the plots and report.html (rad/s, hz, rpm).
    #[arg(long, value_enum, default_value = "rad/s")]
    pub(crate) frequency_unit: UnitArg,
    /// The tolerance case whose ±3σ bands the Campbell diagram draws, whose σ its critical
    /// speeds carry and which the report's "In short" is about; default: the case with the
    /// most toleranced variables.
    #[arg(long, value_name = "NAME")]
    pub(crate) campbell_case: Option<String>,
}

impl DisplayArgs {
    /// The display these flags ask for, of an analysis of `cases` (the Campbell case must be
    /// one of them).
    pub(crate) fn of(
        &self,
        cases: &[modaltol::model::Case],
    ) -> Result<modaltol::plots::Display, InputError> {
        let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
        let campbell_case = (self.campbell_case.as_deref())
            .map(|name| modaltol::plots::Display::case_named(name, &names))
            .transpose()
            .map_err(|e| InputError(format!("--campbell-case: {e}")))?;
        Ok(modaltol::plots::Display {
            speed: self.speed_unit.into(),
            frequency: self.frequency_unit.into(),
            campbell_case,
        })
    }
}

/// Which equilibrium to report where several exist at a speed.
#[derive(Clone, Copy, PartialEq, ValueEnum)]
pub(crate) enum BranchArg {
    /// Where the equilibrium Newton reaches is unstable (a root with positive real part:
    /// static divergence or flutter), step off it along its unstable modes' shapes, both ways
    /// at growing amplitudes, and report the stable equilibrium found (default).
    Stable,
    /// Report the equilibrium Newton reaches, stable or not (to see how an unstable one
    /// diverges).
    AsGiven,
}

#[derive(Clone, Copy, PartialEq, ValueEnum)]
pub(crate) enum Derivatives {
    /// Exact, by automatic differentiation through the equilibrium (default).
    Ad,
    /// Central finite differences of the whole pipeline, Richardson-extrapolated (a cross-check).
    Fd,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Validate a model and summarise its bodies, joints, coordinates, constraints, degrees of
    /// freedom, parameters and requirements; warn of mistakes that load without an error (no
    /// joint driven by the speed, a tolerance through zero, a requirement beyond the analysed
    /// speeds, a case reaching a physical limit), each with its fix.
    Check(CheckArgs),
    /// Equilibrium, drive force, M̂, Ĉ, K̂ and damped modes at one speed.
    Modal(ModalArgs),
    /// Draw the mechanism at its equilibrium, and its modes.
    ///
    /// SVG (`-o FILE.svg`): three orthographic views standing up against gravity (in a y-up
    /// model front: x right, y up; top: x right, −z up; side: −z right, y up; in a z-up model
    /// front: x right, z up; each view names its axes), one scale, in metres: each body's
    /// centre of mass (dot) linked to the points it is joined at, joints with their axes (red;
    /// a driven joint ringed), cut joints (crossed circles), force elements (green, dashed) and
    /// ports (orange arrows), named in the front view (one label per point, none over
    /// another). With `--mode K`, mode K drawn over the equilibrium
    /// (grey): its two extremes (φ = 0 blue, φ = π red) and quarter periods (dashed), the
    /// amplitude a tenth of the mechanism's size.
    ///
    /// HTML (`-o FILE.html`): the same views and a 3-D view (drag to turn, wheel to zoom) that
    /// animates any mode over one period, to first order in its amplitude (each body moved and
    /// turned by the mode's amplitude and phase, so whirl looks like whirl); it opens offline.
    /// The page carries six complex numbers a body per mode: every mode where 300,000 numbers
    /// hold them (about 150 bodies with all their modes), else the lowest modes that fit,
    /// which the page names. It opens animating the first mode that oscillates; `--mode K`
    /// chooses the mode shown first, and animates it in any case.
    Draw(DrawArgs),
    /// Sweep the operating speed: one CSV row per (speed, mode).
    ///
    /// Columns: speed (rad/s), mode (1-based, tracked across speeds by mode shape), status
    /// (underdamped|overdamped|unstable|rigid|failed; rigid: a zero root, no frequency and no
    /// damping ratio), damped_frequency, natural_frequency (rad/s), damping_ratio (empty for a
    /// rigid mode), eigen_re, eigen_im (the reported root, 1/s), eigen2_re, eigen2_im (its
    /// partner root), tuning_order (ω_d/Ω: the engine order the mode sits at, as an absorber
    /// is tuned; empty at Ω = 0), whirl (forward|backward|mixed, from the orbits of the
    /// spinning parts' centres; empty where nothing spins or nothing whirls, as at rest or in
    /// an axial or torsional mode); with a transfer function (--transfer, or the model's
    /// [analysis] transfer): transfer_magnitude (output unit per
    /// input unit, e.g. rad/(N·m) or m/N; an unbalance's response amplitude in m),
    /// transfer_phase (rad); with --sensitivity, for every design variable P:
    /// d(damped_frequency)/d(P), d(natural_frequency)/d(P), d(damping_ratio)/d(P) and with a
    /// transfer function d(transfer_magnitude)/d(P) (per unit of P), then sensitivity_status
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
    /// Tolerance analysis across the speed range: how the tolerances spread every mode's damped
    /// natural frequency ω_d and damping ratio ζ, and the transfer magnitude |H|, per tolerance
    /// case.
    ///
    /// Example: `modaltol analyze examples/tutorial/pendulum_tolerances.toml -o out`, then open
    /// out/report.html (docs/tutorial.md reads one). Without MODEL, runs the governor example
    /// built into the binary. --speed-unit and --frequency-unit show the plots and report in
    /// rpm or Hz; the CSV and JSON files stay in SI units (rad/s).
    ///
    /// Methods (the `method` column): first_order (the classical Taylor method), second_order,
    /// invariant (ω_d), quadrature (the whole nonlinear analysis integrated over the
    /// distribution of the design variables, deterministically, with error estimates: right at
    /// class changes and branch switches), analytic (the answer to read: the quadrature), and
    /// monte_carlo.
    ///
    /// DIR/report.html: the cases, the answer in short (mean ± 3σ, what drives it, whether the
    /// requirements hold), a specification section for a model with [[requirements]], σ by
    /// method where it matters (the largest σ, the critical speeds, the |H| peak), the critical
    /// speeds and near-tangencies, the response peaks, then the plots (SVG and PNG: mean ± σ
    /// and σ by method of every mode's ω_d and ζ and of |H|, probabilities, variance shares, a
    /// Campbell diagram of the modes the engine orders 1–3 reach, with the ±3σ bands of the case
    /// with the most toleranced variables and the critical speeds and near-tangencies marked).
    ///
    /// DIR/tolerance.csv: speed, quantity, mode, case, method, mean, std, mean_ci_low,
    /// mean_ci_high, std_ci_low, std_ci_high, samples, failed, class_changed, basis (the method
    /// an "analytic" row took), q05, q50, q95 (quantiles: quadrature and Monte Carlo),
    /// mean_error, std_error (the quadrature's error estimates), within_request (whether they
    /// meet --quadrature-tolerance; rows that do not are also named on stderr, in the report and
    /// in summary.json's quadrature_outside_request), partial, reason (why a row has no mean
    /// and σ), share:<parameter>; SI units, rad/s for speeds and frequencies.
    ///
    /// DIR/probabilities.csv: speed, case, method, event = overdamped|unstable|other_branch,
    /// mode, probability, ci_low, ci_high.
    ///
    /// DIR/yield.csv (a model with [[requirements]]): case, method =
    /// quadrature|monte_carlo|first_order, requirement (all: every one together), kind, mode,
    /// speed_from, speed_to, speed (empty: over the range, every speed at once), probability,
    /// ci_low, ci_high, target, meets_target = yes|no|undecided, margin_unit, margin_mean,
    /// margin_std (the worst margin over the range), cpk, evaluations, within_request (the
    /// quadrature's: whether its error estimate meets --quadrature-tolerance as an absolute
    /// error of the probability). Each requirement is judged over its whole range: its ends are
    /// added to the speeds analysed, and a range beyond --speed is refused.
    ///
    /// DIR/limits.csv (with requirements): what the design meets at the target yield
    /// (--target-yield), per case, method and requirement: reach, reach_low, reach_high = the
    /// highest speed up to which, from the range's start, it holds at the target yield;
    /// margin_at_target, margin_low, margin_high = the worst margin's 1 − target quantile and
    /// its interval; tightest = the tightest requirement of its kind met, in words; reason =
    /// why a value is blank.
    ///
    /// DIR/sobol.csv (with --sobol): case, target, speed, quantity, mode, variable, first,
    /// first_ci_low, first_ci_high, total, total_ci_low, total_ci_high, derivative_bound, rows.
    ///
    /// DIR/peaks.csv (a model with [analysis] transfer): case, kind = maximum|resonance, speed,
    /// speed_std, magnitude, magnitude_std, unit, amplification_factor,
    /// amplification_factor_std (API 684's half-power method), mode, message: where |H| peaks
    /// along the speed, located between the swept speeds, with σ by first order; a resonance is
    /// an undamped mode at the excitation frequency, its |H| unbounded and left empty.
    ///
    /// DIR/summary.json: the cases, wall times of the Taylor methods, the quadrature and the
    /// Monte Carlo (beside the paper's for its two examples), failures, the rows without a
    /// value grouped with their reasons under "unfilled".
    Analyze(AnalyzeArgs),
    /// Combine the shard files of `analyze --shard K/N` runs into exactly the result of one run
    /// (same seed, same numbers): writes the same files as `analyze`, bit for bit, the Monte
    /// Carlo quantiles included (each shard carries its samples' values for them).
    ///
    /// Every shard must come from the same model (with the same --set), tolerance cases,
    /// speeds, samples, seed, sampling and quadrature options: a shard computed from anything
    /// else is refused, naming the file and what differs. The quadrature runs with the
    /// options the shards' run was given.
    Merge(MergeArgs),
    /// Tolerance allocation: the tolerances of a case's variables that minimise the
    /// manufacturing cost (per variable a + b/T^k, T the ± tolerance in the parameter's unit;
    /// the model's [allocation] table, default 1/T) while every requirement of the model's
    /// [[requirements]] is met at the target yield.
    ///
    /// The search uses the requirements' exact first-order margins at every speed of their
    /// ranges (each must keep a reliability index β, starting from Φ⁻¹(target)); each design is
    /// verified by the quadrature through the whole nonlinear analysis, and β searched for (a
    /// safeguarded root-find, at most 12 rounds) until the cheapest design verified to meet the
    /// target costs at most 0.02 % more than the dearest found short of it: the table says how
    /// close (cost_gap). Prints the table; writes DIR/allocation.csv (parameter, nominal,
    /// distribution, tolerance_before, tolerance_after, relative_before, relative_after, max,
    /// at_max, cost_before, cost_after) and DIR/allocation.json (the target, whether the
    /// verified yield meets it, the verified yield, the chosen round, cost_gap, every round's
    /// β, predicted and verified yield with its error, the costs), then the whole analysis of
    /// the allocated tolerances (case "allocated": tolerance.csv, yield.csv, report.html, …).
    Allocate(AllocateArgs),
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
pub(crate) struct CheckArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
}

#[derive(clap::Args)]
pub(crate) struct ModalArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: f64,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
    /// Independent coordinates (joint names, comma separated), overriding the model.
    #[arg(long, value_delimiter = ',')]
    pub(crate) independent: Option<Vec<String>>,
    /// Which equilibrium to report, Newton starting from the model's initial guess: every
    /// format says which was taken and why (text: `branch:`, JSON: "branch", CSV: the
    /// `branch` and `message` columns).
    #[arg(long, value_enum, default_value = "stable")]
    pub(crate) branch: BranchArg,
    /// Unit of the modes' frequencies in the text table (rad/s, hz, rpm); JSON and CSV stay in
    /// rad/s.
    #[arg(long, value_enum, default_value = "rad/s")]
    pub(crate) frequency_unit: UnitArg,
    /// Write to this file instead of stdout.
    #[arg(short, long)]
    pub(crate) output: Option<PathBuf>,
}

#[derive(clap::Args)]
pub(crate) struct DrawArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Operating speed, rad/s (default: the middle of the model's [analysis] speeds, as the
    /// report draws it, so that what spins is drawn spinning; 0 without them).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: Option<f64>,
    /// The mode to draw (1-based, as `modal` numbers them): overlaid in the SVG; shown first,
    /// and animated whatever its number, in the page.
    #[arg(long)]
    pub(crate) mode: Option<usize>,
    /// Which equilibrium to draw (as for `modal`).
    #[arg(long, value_enum, default_value = "stable")]
    pub(crate) branch: BranchArg,
    /// The drawing: `.svg` (three views) or `.html` (the views and an animated 3-D view).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
}

#[derive(clap::Args)]
pub(crate) struct SweepArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Speeds FROM:TO:STEP in rad/s (TO included); default: the model's [analysis] speed.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: Option<String>,
    /// Independent coordinates (joint names, comma separated), overriding the model.
    #[arg(long, value_delimiter = ',')]
    pub(crate) independent: Option<Vec<String>>,
    /// Which equilibrium to follow: `stable` switches to a stable one where the one continued
    /// from the previous speed has lost its stability (the `branch` column says `switched`
    /// and the message why); `as-given` follows the continued one, stable or not.
    #[arg(long, value_enum, default_value = "stable")]
    pub(crate) branch: BranchArg,
    /// Transfer function `input=NAME,output=NAME[,order=K]` (NAME a free joint coordinate or a
    /// [[ports]] entry): generalised force (or port force/torque) on `input`,
    /// response of `output`, excitation at K × speed (K = 1 by default). An
    /// [[unbalances]] entry as `input` gives the unbalance response (m, at its body's spin
    /// rate; no order). Default: the model's [analysis] transfer, where it has one (as
    /// `sensitivity` and `analyze`); `--transfer none` leaves it out.
    #[arg(long)]
    pub(crate) transfer: Option<String>,
    /// Add the derivatives of every mode (and of |H|) with respect to the design variables.
    #[arg(long)]
    pub(crate) sensitivity: bool,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    pub(crate) wrt: Option<Vec<String>>,
    /// How derivatives are computed.
    #[arg(long, value_enum, default_value = "ad")]
    pub(crate) derivatives: Derivatives,
    /// Write the CSV to this file instead of stdout.
    #[arg(short, long)]
    pub(crate) output: Option<PathBuf>,
}

#[derive(clap::Args)]
pub(crate) struct SensitivityArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: f64,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    pub(crate) wrt: Option<Vec<String>>,
    /// How derivatives are computed.
    #[arg(long, value_enum, default_value = "ad")]
    pub(crate) derivatives: Derivatives,
    /// Transfer function `input=NAME,output=NAME[,order=K]` (free coordinates or ports);
    /// default: the model's [analysis] transfer; `none` leaves it out.
    #[arg(long)]
    pub(crate) transfer: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
    /// Write to this file instead of stdout.
    #[arg(short, long)]
    pub(crate) output: Option<PathBuf>,
}

#[derive(clap::Args)]
pub(crate) struct AnalyzeArgs {
    /// Model file (TOML); default: the built-in governor example.
    pub(crate) model: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Speeds FROM:TO:STEP in rad/s; default: the model's [analysis] speed.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: Option<String>,
    /// Monte Carlo samples; default: the model's (3000 unless it says otherwise).
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) samples: Option<usize>,
    /// Random seed; default: the model's.
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<u64>)]
    pub(crate) seed: Option<u64>,
    /// Worker threads for the derivatives, the quadrature and the Monte Carlo (results do
    /// not depend on it): 1 to 1024; default: all cores.
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) threads: Option<usize>,
    /// Skip the Monte Carlo.
    #[arg(long)]
    pub(crate) no_monte_carlo: bool,
    /// Requested error of the quadrature's mean and σ, relative to the output's σ at that
    /// speed (or 2 % of its largest σ over the speeds, if larger; an output the tolerances do
    /// not move, as the ζ of an undamped mode, is asked for what the evaluation resolves:
    /// 1e-8 of its size, of 1 for ζ); the grid along each line, or the rule across the lines,
    /// is refined until the error estimate meets it or the rule's largest stage or
    /// --quadrature-nodes is reached; rows that miss it say so (within_request).
    #[arg(long, default_value_t = 1e-3, value_name = "REL")]
    pub(crate) quadrature_tolerance: f64,
    /// The most nodes the quadrature sweeps per tolerance case (a node is a design swept
    /// across the speeds, as a Monte Carlo sample is, so N nodes cost about N samples);
    /// default: 300 (a tenth of the default Monte Carlo) with five or more variables, 3000
    /// with two to four, every node of the finest grid with one. The rule's first stage is
    /// swept whatever is asked (80 nodes with five or more variables; the summary says so).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) quadrature_nodes: Option<usize>,
    /// Skip the quadrature (the "analytic" rows then take the automatic Taylor choice).
    #[arg(long)]
    pub(crate) no_quadrature: bool,
    /// Sampling of the design variables; default: the model's.
    #[arg(long, value_enum)]
    pub(crate) sampling: Option<SamplingArg>,
    /// Compute only shard K of N of the Monte Carlo samples (e.g. 2/8, one per batch job)
    /// and write DIR/shard-K-of-N.json; combine the shards with `modaltol merge`.
    #[arg(long)]
    pub(crate) shard: Option<String>,
    /// Only this tolerance case of the model's [analysis] table (repeatable); default: all.
    #[arg(long = "case", value_name = "NAME")]
    pub(crate) cases: Vec<String>,
    /// Also the first-order and total Sobol indices of every output and of every
    /// requirement's worst margin, with 95 % jackknife intervals, by the pick-freeze Monte
    /// Carlo (Saltelli 2010) with N base samples (N·(d+2) sweeps for d variables), beside the
    /// derivative-based bound on the total index: DIR/sobol.csv and a table in the report.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) sobol: Option<usize>,
    /// The probability at which limits.csv says what the design meets (the largest operating
    /// range, the worst margin) and against which yield.csv's meets_target is judged, in (0,
    /// 1); default: the model's [allocation] target_yield (0.9973 unless it says otherwise).
    /// A target closer to 0 or 1 than about 3.7 samples' worth leaves the Monte Carlo's margin
    /// there unbounded (said on stderr and in limits.csv's reason).
    #[arg(long, allow_hyphen_values = true, value_name = "P")]
    pub(crate) target_yield: Option<f64>,
    #[command(flatten)]
    pub(crate) display: DisplayArgs,
}

#[derive(clap::Args)]
pub(crate) struct AllocateArgs {
    /// Model file (TOML) with [[requirements]].
    pub(crate) model: PathBuf,
    /// Output directory (created if missing).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// The probability of meeting every requirement to reach; default: the model's
    /// [allocation] target_yield (0.9973 unless it says otherwise).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) target_yield: Option<f64>,
    /// The tolerance case whose variables are allocated, from their tolerances there;
    /// default: the model's [allocation] case, else the parameters' own tolerances.
    #[arg(long = "case", value_name = "NAME")]
    pub(crate) case: Option<String>,
    /// A variable's cost model, replacing the model's: NAME=B (cost B/T) or NAME=B,K (cost
    /// B/T^K), T in the parameter's unit (repeatable).
    #[arg(long = "cost", value_name = "NAME=B[,K]")]
    pub(crate) costs: Vec<String>,
    /// Speeds FROM:TO:STEP in rad/s; default: the model's [analysis] speed.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: Option<String>,
    /// Requested accuracy of the verifying quadrature (as analyze's).
    #[arg(long, default_value_t = 1e-3, value_name = "REL")]
    pub(crate) quadrature_tolerance: f64,
    /// The most nodes the verifying quadrature sweeps (as analyze's).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) quadrature_nodes: Option<usize>,
    /// Worker threads: 1 to 1024; default: all cores.
    #[arg(long, allow_hyphen_values = true, value_parser = whole_number::<usize>)]
    pub(crate) threads: Option<usize>,
}

#[derive(clap::Args)]
pub(crate) struct MergeArgs {
    /// Model file the shards were made from; default: the built-in governor example.
    #[arg(long)]
    pub(crate) model: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// The shard files (shard-K-of-N.json), all N of them, in any order.
    #[arg(required = true)]
    pub(crate) shards: Vec<PathBuf>,
    /// The tolerance cases the shards were run with (as given to `analyze --case`); default:
    /// the cases the shards name.
    #[arg(long = "case", value_name = "NAME")]
    pub(crate) cases: Vec<String>,
    /// The target yield the merged result is judged against, as `analyze --target-yield`;
    /// default: the model's [allocation] target_yield.
    #[arg(long, allow_hyphen_values = true, value_name = "P")]
    pub(crate) target_yield: Option<f64>,
    #[command(flatten)]
    pub(crate) display: DisplayArgs,
}

#[derive(clap::Args)]
pub(crate) struct FrfArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Operating speed, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speed: f64,
    /// Transfer function `input=NAME,output=NAME` (NAME a free joint coordinate or a
    /// [[ports]] entry): generalised force (or port force/torque) on `input`, response of
    /// `output`; default: the model's [analysis] transfer.
    #[arg(long)]
    pub(crate) transfer: Option<String>,
    /// Excitation frequencies FROM:TO:STEP in rad/s.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) freq: String,
    /// Design variables (parameter names, comma separated); default: those with a tolerance.
    #[arg(long, value_delimiter = ',')]
    pub(crate) wrt: Option<Vec<String>>,
    /// Write the CSV to this file instead of stdout. (With the older `--input A --output B`
    /// spelling of the transfer function, `--output` names the response and `--out` the file.)
    #[arg(short, long)]
    pub(crate) output: Option<String>,
    /// Older spelling: where the excitation enters (use --transfer input=…,output=…).
    #[arg(long, hide = true)]
    pub(crate) input: Option<String>,
    /// Older spelling of -o/--output, kept for scripts.
    #[arg(long, hide = true)]
    pub(crate) out: Option<PathBuf>,
}
