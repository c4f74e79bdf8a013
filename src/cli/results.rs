//! What `analyze` and `merge` write: the result directory or a shard, and the notes on it.

use crate::cli::*;
use anyhow::Result;
use modaltol::compiled::Compiled;
use modaltol::files::ResultDir;
use modaltol::report;
use modaltol::results::WriteOptions;
use std::io::Write;

/// Writes tolerance.csv, the plots, report.html and summary.json of an analysis.
pub(crate) fn write_outputs(
    m: &Compiled,
    a: &modaltol::analyze::Analysis,
    o: WriteOptions,
    dir: ResultDir,
    output: &std::path::Path,
) -> Result<()> {
    let written = modaltol::results::write(m, a, o, dir)?;
    for (stem, e) in &written.missing_png {
        note!("modaltol: no PNG for {stem}: {e}");
    }
    let partial = written.partial;
    note!(
        "modaltol: analytic (Taylor) {:.3} s (gradients {:.3} s, Hessians {:.3} s){}{}; wrote {}",
        a.analytic_seconds,
        a.first_order_seconds,
        a.second_order_seconds,
        a.quadrature_seconds
            .map_or(String::new(), |t| format!(", quadrature {t:.3} s")),
        a.monte_carlo_seconds.map_or(String::new(), |t| format!(
            ", Monte Carlo {t:.3} s ({:.0}× the analytic time)",
            t / a.analytic_seconds
        )),
        written.place.display()
    );
    if written.place != modaltol::files::write_target(output) {
        note!(
            "modaltol: the complete earlier result in {} is kept: a partial result does not \
             replace it; this one is in {}",
            output.display(),
            written.place.display()
        );
    }
    for w in report::inadmissible_warnings(a) {
        note!("modaltol: warning: {w}");
    }
    if !a.failures.is_empty() {
        note!(
            "modaltol: {} speed(s) failed; see summary.json",
            a.failures.len()
        );
    }
    for line in report::unfilled_lines(a) {
        note!("modaltol: note: {line}");
    }
    for line in report::outside_request_lines(a) {
        note!("modaltol: note: {line}");
    }
    for (case, why) in &a.sobol_refused {
        note!(
            "modaltol: note: no Sobol indices for case '{}': {why}",
            a.cases[*case].name
        );
    }
    if partial {
        if a.samples_done.is_empty() {
            note!("modaltol: partial result (interrupted): not every speed was analysed");
        } else {
            note!(
                "modaltol: partial result (interrupted): Monte Carlo samples done per case {:?}",
                a.samples_done
            );
        }
        return Err(Interrupted("the outputs hold a partial result".into()).into());
    }
    Ok(())
}
