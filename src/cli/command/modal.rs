//! `modaltol modal`.

use crate::cli::*;
use anyhow::Result;
use modaltol::cancel::Cancel;
use modaltol::files::Inputs;
use modaltol::program::Tier;
use modaltol::report;
use modaltol::sweep::Options;
use std::io::Write;

/// `modaltol modal` (see its `--help`).
pub(crate) fn modal_command(args: ModalArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let ModalArgs {
        model,
        speed,
        format,
        independent: ind,
        branch,
        frequency_unit,
        output,
    } = args;
    let m = load(&model, set)?;
    let request = point_request(&m, speed)?;
    let opt = Options {
        independent: independent(m.model(), &ind)?,
        no_branch_switch: branch == BranchArg::AsGiven,
        tier: Tier::Few,
        ..Default::default()
    };
    let mut w = Sink::to(&output, &Inputs::new(&[&model]))?;
    let p = &request.parameters;
    let result = request.solve(&m, &opt);
    stop_if_cancelled(cancel, &output)?;
    match format {
        Format::Json => writeln!(
            w,
            "{}",
            serde_json::to_string_pretty(&report::modal_json(m.model(), p, speed, &result))?
        )?,
        Format::Table => write!(
            w,
            "{}",
            report::modal_table(m.model(), p, speed, &result, frequency_unit.into())
        )?,
        Format::Csv => {
            let rows = match &result {
                Ok(pt) => {
                    report::modes_rows(m.model(), p, pt).map_err(|e| Failed(e.to_string()))?
                }
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
