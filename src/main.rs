//! The `modaltol` command line: a thin layer over the library that parses arguments, reads the
//! model, writes results and maps errors to exit codes (2: bad input, 1: other failures, 130
//! and 143: interrupted by SIGINT or SIGTERM).

use std::io::Write;

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

mod cli;

use clap::Parser;
use cli::{Cli, InputError, Interrupted, handle_interrupts, interrupted_code, run};
use modaltol::cancel::Cancel;

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
