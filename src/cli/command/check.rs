//! `modaltol check`.

use crate::cli::*;
use anyhow::Result;
use modaltol::files::Inputs;
use modaltol::report;
use std::io::Write;

/// `modaltol check` (see its `--help`).
pub(crate) fn check_command(args: CheckArgs, set: &[(String, f64)]) -> Result<()> {
    let CheckArgs { model } = args;
    let m = load(&model, set)?;
    let mut w = Sink::to(&None, &Inputs::default())?;
    write!(w, "{}", report::check_report(&m))?;
    w.finish()?;

    Ok(())
}
