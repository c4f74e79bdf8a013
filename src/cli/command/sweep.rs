//! `modaltol sweep`.

use crate::cli::*;
use anyhow::Result;
use modaltol::cancel::Cancel;
use modaltol::files::Inputs;
use modaltol::model::SpeedRange;
use modaltol::nominal_sweep::NominalSweep;
use modaltol::report::{self, SweepColumns};
use modaltol::sweep::Options;
use std::io::Write;

/// `modaltol sweep` (see its `--help`).
pub(crate) fn sweep_command(args: SweepArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let SweepArgs {
        model,
        speed,
        independent: ind,
        branch,
        transfer: tspec,
        sensitivity: sens,
        wrt,
        derivatives,
        output,
    } = args;
    let m = load(&model, set)?;
    let range = match &speed {
        Some(s) => SpeedRange::parse(s).map_err(|e| InputError(format!("--speed: {e}")))?,
        None => m.model().analysis.speed.ok_or_else(|| {
            InputError("no --speed given and the model has no [analysis] speed".into())
        })?,
    };
    let tf = transfer_or_model(m.model(), tspec.as_deref())?;
    let cols = SweepColumns {
        transfer: tf.is_some(),
        wrt: if sens {
            design_variables(m.model(), &wrt)?
        } else {
            Vec::new()
        },
    };
    let opt = Options {
        independent: independent(m.model(), &ind)?,
        no_branch_switch: branch == BranchArg::AsGiven,
        ..Default::default()
    };
    let mut study = NominalSweep::new(&m, opt, tf, cols.wrt.clone(), how(derivatives));
    let mut csv = csv::Writer::from_writer(Sink::to(&output, &Inputs::new(&[&model]))?);
    csv.write_record(report::sweep_header(m.model(), &cols))?;
    let n = range.len();
    // Long sweeps (sensitivities at each speed, or many speeds) report their progress.
    let progress = (sens || n >= 2000).then(progress_printer);
    let mut failed = 0usize;
    for (i, w) in range.speeds().enumerate() {
        if cancel.is_cancelled() {
            // Streamed rows stay on stdout; a file is complete or absent.
            return Err(Interrupted(match &output {
                Some(f) => format!("{} not written ({i} of {n} speeds done)", f.display()),
                None => format!("after {i} of {n} speeds"),
            })
            .into());
        }
        let (r, extras) = study.step(w);
        if r.is_err() {
            failed += 1;
        }
        for row in report::sweep_rows(m.model(), &cols, w, &r, &extras) {
            csv.write_record(&row)?;
        }
        if let Some(p) = &progress {
            p("sweep speeds", i + 1, n);
        }
    }
    csv.into_inner().map_err(|e| e.into_error())?.finish()?;
    if failed == n {
        return Err(Failed(format!(
            "all {n} speeds failed (status 'failed', reason in the message column)"
        ))
        .into());
    }
    if failed > 0 {
        note!(
            "modaltol: {failed} of {n} speeds failed (status 'failed', reason in the message column)"
        );
    }

    Ok(())
}
