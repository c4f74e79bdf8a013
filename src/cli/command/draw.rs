//! `modaltol draw`.

use crate::cli::*;
use anyhow::Result;
use modaltol::cancel::Cancel;
use modaltol::drawing::{Drawing, html, svg};
use modaltol::files::Inputs;
use modaltol::program::Tier;
use modaltol::sweep::Options;
use std::io::Write;

/// `modaltol draw` (see its `--help`).
pub(crate) fn draw_command(args: DrawArgs, set: &[(String, f64)], cancel: &Cancel) -> Result<()> {
    let DrawArgs {
        model,
        speed,
        mode,
        branch,
        output,
    } = args;
    let html_page = match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("html") || e.eq_ignore_ascii_case("htm") => true,
        Some(e) if e.eq_ignore_ascii_case("svg") => false,
        _ => {
            return Err(InputError(format!(
                "-o {}: the drawing is written as .svg or .html",
                output.display()
            ))
            .into());
        }
    };
    let m = load(&model, set)?;
    // By default the middle of the analysed speeds, as the report draws it: where things spin
    // (the first speed is often 0, the mechanism at rest).
    let speed = speed.unwrap_or_else(|| {
        m.model().analysis.speed.as_ref().map_or(0.0, |r| {
            let speeds: Vec<f64> = r.speeds().collect();
            speeds.get(speeds.len() / 2).copied().unwrap_or(0.0)
        })
    });
    let request = point_request(&m, speed)?;
    let opt = Options {
        no_branch_switch: branch == BranchArg::AsGiven,
        tier: Tier::Few,
        ..Default::default()
    };
    let p = &request.parameters;
    let pt = request
        .solve(&m, &opt)
        .map_err(|e| Failed(format!("speed {speed:?} rad/s failed: {e}")))?;
    stop_if_cancelled(cancel, &Some(output.clone()))?;
    let mode = match mode {
        None => None,
        Some(k) if (1..=pt.modes.len()).contains(&k) => Some(k - 1),
        Some(k) => {
            return Err(InputError(format!(
                "--mode {k}: the mechanism has modes 1 to {} at {speed} rad/s",
                pt.modes.len()
            ))
            .into());
        }
    };
    let d = Drawing::new(m.model(), p, &pt).map_err(|e| Failed(e.to_string()))?;
    let text = if html_page {
        html(&d, mode)
    } else {
        svg(&d, mode)
    };
    let mut w = Sink::to(&Some(output), &Inputs::new(&[&model]))?;
    w.write_all(text.as_bytes())?;
    w.finish()
}
