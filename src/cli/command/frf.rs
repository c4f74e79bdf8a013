//! `modaltol frf`.

use crate::cli::*;
use anyhow::{Context, Result};
use modaltol::cancel::Cancel;
use modaltol::files::Inputs;
use modaltol::model::SpeedRange;
use modaltol::report;
use modaltol::sensitivity::DesignPoint;
use modaltol::sweep::Options;
use std::io::Write;
use std::path::PathBuf;

/// `modaltol frf` (see its `--help`).
pub(crate) fn frf_command(args: FrfArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
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
    let request = point_request(&m, speed)?;
    let range = SpeedRange::parse(&freq).map_err(|e| InputError(format!("--freq: {e}")))?;
    let wrt = design_variables(m.model(), &wrt)?;
    let mut csv = csv::Writer::from_writer(Sink::to(&file, &Inputs::new(&[&model]))?);
    let p = &request.parameters;
    let pt = request
        .solve(&m, &Options::single())
        .with_context(|| format!("speed {speed:?} rad/s"))?;
    // Stops at the frequency after a signal.
    let frequencies = range.speeds().take_while(|_| !cancel.is_cancelled());
    let rows = DesignPoint::new(&m, p, &pt)
        .frequency_response((tf.input, tf.output), &wrt, frequencies)
        .with_context(|| format!("sensitivities at {speed:?} rad/s"))?;
    stop_if_cancelled(cancel, &file)?;
    csv.write_record(report::frf_header(m.model(), &wrt))?;
    for row in report::frf_rows(&pt.linear, &rows) {
        csv.write_record(&row)?;
    }
    csv.into_inner().map_err(|e| e.into_error())?.finish()?;

    Ok(())
}
