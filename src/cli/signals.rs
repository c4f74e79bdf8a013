//! SIGINT and SIGTERM: a run stops at its next check and says what it wrote.

use crate::cli::*;
use anyhow::Result;
use modaltol::cancel::Cancel;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicI32, Ordering};

/// The signal that interrupted the run (0: none).
pub(crate) static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// SIGINT (Ctrl-C) and SIGTERM (what Slurm and Kubernetes send at a time limit) cancel
/// `cancel`, in every command alike: the run stops at its next check (a sweep before its next
/// speed, the Monte Carlo after its current chunk), writes what may be written (an analysis's
/// partial result, flagged; never a cut file) and exits with 128 + the signal's number (130,
/// 143). A second signal ends the process at once (the next run into the same place
/// removes what it left).
pub(crate) fn handle_interrupts(cancel: &Cancel) {
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
pub(crate) fn stop_if_cancelled(cancel: &Cancel, output: &Option<PathBuf>) -> Result<()> {
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
pub(crate) fn interrupted_code() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(128 + s),
    }
}
