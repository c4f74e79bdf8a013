//! The `modaltol` command line: a thin layer over the library that parses arguments, reads the
//! model, writes results and maps errors to exit codes (2: bad input, 1: other failures).

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use modaltol::model::{Model, SpeedRange};
use modaltol::report;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use std::io::{IsTerminal, Write};
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
#[command(name = "modaltol", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Table,
    Json,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a model and summarise its bodies, joints, coordinates, constraints, degrees of
    /// freedom and parameters.
    Check {
        /// Model file (TOML).
        model: PathBuf,
    },
    /// Equilibrium, drive force, M̂, Ĉ, K̂ and damped modes at one speed.
    Modal {
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
        /// Write to this file instead of stdout.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Sweep the operating speed: one CSV row per (speed, mode).
    ///
    /// Columns: speed (rad/s), mode (1-based, tracked across speeds by mode shape), status
    /// (underdamped|overdamped|unstable|failed), damped_frequency, natural_frequency (rad/s),
    /// damping_ratio, eigen_re, eigen_im (the reported root, 1/s), eigen2_re, eigen2_im (its
    /// partner root), q:<joint> (equilibrium coordinates, rad or m), drive:<joint> (drive force,
    /// N·m or N), iterations (Newton), message (why a speed failed, or a branch switch).
    Sweep {
        /// Model file (TOML).
        model: PathBuf,
        /// Speeds FROM:TO:STEP in rad/s (TO included); default: the model's [analysis] speed.
        #[arg(long)]
        speed: Option<String>,
        /// Independent coordinates (joint names, comma separated), overriding the model.
        #[arg(long, value_delimiter = ',')]
        independent: Option<Vec<String>>,
        /// Write the CSV to this file instead of stdout.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

/// Bad input (model, arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct InputError(String);

fn load(path: &std::path::Path) -> Result<Model> {
    Model::from_file(path).map_err(|e| InputError(e.to_string()).into())
}

fn independent(model: &Model, names: &Option<Vec<String>>) -> Result<Option<Vec<usize>>> {
    let Some(names) = names else { return Ok(None) };
    let mut out = Vec::new();
    for n in names {
        let i = model
            .coordinate(n)
            .filter(|&i| !model.coordinates[i].driven)
            .ok_or_else(|| {
                InputError(format!(
                    "--independent: '{n}' is not a free joint coordinate of the model"
                ))
            })?;
        out.push(i);
    }
    if out.len() != model.dof() {
        return Err(InputError(format!(
            "--independent names {} coordinate(s) but the model has {} degree(s) of freedom",
            out.len(),
            model.dof()
        ))
        .into());
    }
    Ok(Some(out))
}

fn writer(output: &Option<PathBuf>) -> Result<Box<dyn Write>> {
    Ok(match output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    })
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check { model } => {
            let m = load(&model)?;
            print!("{}", report::check_summary(&m));
        }
        Command::Modal {
            model,
            speed,
            format,
            independent: ind,
            output,
        } => {
            let m = load(&model)?;
            if !speed.is_finite() {
                return Err(InputError("--speed must be finite".into()).into());
            }
            let opt = Options {
                independent: independent(&m, &ind)?,
                ..Default::default()
            };
            let p = m.nominal();
            let q0 = initial_guess(&m, &p, speed).map_err(|e| InputError(e.to_string()))?;
            let result = point(&m, &p, speed, &q0, &opt);
            let mut w = writer(&output)?;
            match format {
                Format::Json => writeln!(
                    w,
                    "{}",
                    serde_json::to_string_pretty(&report::modal_json(&m, speed, &result))?
                )?,
                Format::Table => write!(w, "{}", report::modal_table(&m, speed, &result))?,
            }
            w.flush()?;
            if let Err(e) = result {
                eprintln!("modaltol: speed {speed} rad/s failed: {e}");
            }
        }
        Command::Sweep {
            model,
            speed,
            independent: ind,
            output,
        } => {
            let m = load(&model)?;
            let range = match &speed {
                Some(s) => SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
                None => m.analysis.speed.ok_or_else(|| {
                    InputError("no --speed given and the model has no [analysis] speed".into())
                })?,
            };
            let opt = Options {
                independent: independent(&m, &ind)?,
                ..Default::default()
            };
            let mut sweep = Sweep::new(&m, m.nominal(), opt);
            let mut csv = csv::Writer::from_writer(writer(&output)?);
            csv.write_record(report::sweep_header(&m))?;
            let n = range.len();
            let progress = std::io::stderr().is_terminal() && n >= 2000;
            let mut failed = 0usize;
            for (i, w) in range.speeds().enumerate() {
                let r = sweep.step(w);
                if r.is_err() {
                    failed += 1;
                }
                for row in report::sweep_rows(&m, w, &r) {
                    csv.write_record(&row)?;
                }
                if progress && i % 500 == 0 {
                    eprint!("\rsweep: {i}/{n} speeds");
                }
            }
            csv.flush()?;
            if progress {
                eprintln!("\rsweep: {n}/{n} speeds");
            }
            if failed > 0 {
                eprintln!(
                    "modaltol: {failed} of {n} speeds failed (status 'failed', reason in the message column)"
                );
            }
        }
    }
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("modaltol: error: {e:#}");
        let code = if e.downcast_ref::<InputError>().is_some() {
            2
        } else {
            1
        };
        std::process::exit(code);
    }
}
