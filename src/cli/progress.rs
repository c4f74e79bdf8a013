//! Progress of long runs on stderr.

use modaltol::settings;
use std::io::{IsTerminal, Write};

/// Progress on stderr: on a terminal one line rewritten in place; otherwise (a batch job's
/// log) one line per tenth of each stage, so that logs show how far a run got.
pub(crate) fn progress_printer() -> impl Fn(&str, usize, usize) + Sync {
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

/// Says on stderr where the Monte Carlo of `mc` cannot bound the margin met at the model's
/// target yield (too few samples expected beyond it: [`settings::unresolved_target`]).
pub(crate) fn note_unresolved_target(
    m: &modaltol::compiled::Compiled,
    mc: Option<&modaltol::montecarlo::McOptions>,
) {
    let md = m.model();
    if let Some(mc) = mc
        && !md.requirements.is_empty()
        && let Some(why) = settings::unresolved_target(md.allocation.target_yield, mc.samples)
    {
        note!("modaltol: {why}");
    }
}
