//! `modaltol sensitivity`.

use crate::cli::*;
use anyhow::{Context, Result};
use modaltol::cancel::Cancel;
use modaltol::files::Inputs;
use modaltol::report;
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::Options;
use std::io::Write;

/// `modaltol sensitivity` (see its `--help`).
pub(crate) fn sensitivity_command(
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
    let request = point_request(&m, speed)?;
    let wrt = design_variables(m.model(), &wrt)?;
    let tf = transfer_or_model(m.model(), tspec.as_deref())?;
    let mut w = Sink::to(&output, &Inputs::new(&[&model]))?;
    let p = &request.parameters;
    let pt = request
        .solve(&m, &Options::single())
        .with_context(|| format!("speed {speed:?} rad/s"))?;
    let at = tf.map(|t| TransferAt::at_speed(&t, speed));
    let s = DesignPoint::new(&m, p, &pt)
        .with_transfer(at)
        .sensitivities(&wrt, how(derivatives))
        .with_context(|| format!("sensitivities at {speed:?} rad/s"))?;
    let why = report::transfer_defect_at(&pt, at.as_ref());
    stop_if_cancelled(cancel, &output)?;
    let method = if derivatives == Derivatives::Ad {
        "ad"
    } else {
        "fd"
    };
    let shown = report::SensitivityReport {
        model: m.model(),
        point: &pt,
        sensitivity: &s,
        no_transfer: why,
    };
    match format {
        Format::Json => writeln!(
            w,
            "{}",
            serde_json::to_string_pretty(&shown.json(speed, method))?
        )?,
        Format::Table => write!(w, "{}", shown.table(speed, method))?,
        Format::Csv => write_csv(&mut w, &report::SENSITIVITY_HEADER, &shown.rows())?,
    }
    w.finish()?;

    Ok(())
}
