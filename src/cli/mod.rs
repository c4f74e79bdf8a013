//! The command line's parts: the arguments, the inputs they name, where the results go,
//! signals and progress, and one file per command. The numbers and the formats are the
//! library's; this layer parses, reads, writes and maps errors to exit codes.

mod args;
mod command;
mod inputs;
mod progress;
mod results;
mod signals;
mod sink;

pub(crate) use args::*;
pub(crate) use command::*;
pub(crate) use inputs::*;
pub(crate) use progress::*;
pub(crate) use results::*;
pub(crate) use signals::*;
pub(crate) use sink::*;

use anyhow::Result;
use modaltol::cancel::Cancel;

/// The run was interrupted (SIGINT, SIGTERM); the message says what was written: exit code
/// 128 + the signal's number.
#[derive(Debug, thiserror::Error)]
#[error("interrupted; {0}")]
pub(crate) struct Interrupted(String);

/// The computation asked for failed (its reason is the message): exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct Failed(String);

/// Bad input (model, arguments): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct InputError(String);

pub(crate) fn run(cli: Cli, cancel: &Cancel) -> Result<()> {
    let set = &cli.set;
    match cli.command {
        Command::Check(args) => check_command(args, set),
        Command::Modal(args) => modal_command(args, set, cancel),
        Command::Draw(args) => draw_command(args, set, cancel),
        Command::Sweep(args) => sweep_command(args, set, cancel),
        Command::Sensitivity(args) => sensitivity_command(args, set, cancel),
        Command::Analyze(args) => analyze_command(args, set, cancel),
        Command::Merge(args) => merge_command(args, set, cancel),
        Command::Frf(args) => frf_command(args, set, cancel),
        Command::Allocate(args) => allocate_command(args, set, cancel),
    }
}
