//! The result directory of an analysis: `tolerance.csv`, `probabilities.csv`, `yield.csv` and
//! `limits.csv` (models with requirements), `sobol.csv`, the plots (SVG
//! and PNG), `report.html` and `summary.json`, staged and put in place together by
//! [`ResultDir`]. Shared by the command line and the Python package so that both write the
//! same files.

use crate::allocate::Allocation;
use crate::analyze::Analysis;
use crate::compiled::Compiled;
use crate::drawing::{self, Drawing};
use crate::files::{FileError, ResultDir};
use crate::model::Model;
use crate::montecarlo::McOptions;
use crate::plots::{self, Display};
use crate::report;
use rayon::prelude::*;
use resvg::usvg::fontdb::Database;
use std::sync::Arc;

/// Is `name` one that [`write()`] may put in a result directory (its tables, report, summary,
/// plots and manifest)? An input of that name there would be replaced.
pub fn is_result_file(name: &str) -> bool {
    matches!(
        name,
        "tolerance.csv"
            | "probabilities.csv"
            | "yield.csv"
            | "limits.csv"
            | "sobol.csv"
            | "peaks.csv"
            | "report.html"
            | "mechanism.html"
            | "summary.json"
            | "manifest.json"
    ) || name.ends_with(".svg")
        || name.ends_with(".png")
}

/// What [`write()`] leaves for its caller to tell the user.
#[derive(Debug, Default)]
pub struct Written {
    /// The result is partial (the run was cancelled); the directory says so too.
    pub partial: bool,
    /// Where the result went: the target, or beside it where a partial result would have
    /// replaced a complete one ([`crate::files::ResultDir::commit`]).
    pub place: std::path::PathBuf,
    /// Plots that got no PNG, with the reason (their SVG is written).
    pub missing_png: Vec<(String, String)>,
}

/// One table as CSV bytes.
pub fn csv_bytes(header: &[impl AsRef<[u8]>], rows: &[Vec<String>]) -> Vec<u8> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    // Writing to memory cannot fail.
    csv.write_record(header).expect("in memory");
    for row in rows {
        csv.write_record(row).expect("in memory");
    }
    csv.into_inner().expect("in memory")
}

/// What the files say besides the analysis, and how they are made.
#[derive(Debug, Clone, Copy, Default)]
pub struct WriteOptions<'a> {
    /// The Monte Carlo the analysis ran (its samples, seed and sampling, in the report).
    pub mc: Option<&'a McOptions>,
    /// Worker threads for the plots (and in the summary).
    pub threads: usize,
    /// The units of the plots and the report.
    pub display: Display,
    /// The tolerance allocation that made the design, opening the report.
    pub allocation: Option<&'a Allocation>,
}

/// Writes every file of the analysis `a` of `m` into `dir` as `o` says, and commits it.
pub fn write(
    m: &Compiled,
    a: &Analysis,
    o: WriteOptions,
    mut dir: ResultDir,
) -> Result<Written, FileError> {
    let WriteOptions {
        mc,
        threads,
        display,
        allocation,
    } = o;
    let partial = a.cancelled() || mc.is_some_and(|mc| a.interrupted(mc.samples));
    write_tables(m.model(), a, partial, &mut dir)?;
    let (plots, critical) = plots::plots(m.model(), a, display);
    let fonts = plots::fonts();
    // Rendered on the run's threads (a big model's hundreds of plots took longer to render than
    // its analysis), written in order.
    let render = || -> Vec<Result<Vec<u8>, String>> {
        plots
            .par_iter()
            .map(|p| plots::png(&p.svg, &fonts))
            .collect()
    };
    let pngs = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool.install(render),
        Err(_) => render(),
    };
    let mut missing_png = Vec::new();
    for (p, png) in plots.iter().zip(pngs) {
        let svg = format!("{}.svg", p.stem);
        dir.write(&svg, p.svg.as_bytes())?;
        match png {
            Ok(png) => dir.write(&format!("{}.png", p.stem), &png)?,
            Err(e) => missing_png.push((p.stem.clone(), e)),
        }
    }
    let drawing = write_drawings(m.model(), a, &fonts, &mut dir, &mut missing_png)?;
    dir.write(
        "report.html",
        report::report_html(
            m.model(),
            a,
            &plots.iter().collect::<Vec<_>>(),
            &critical,
            report::Extra {
                mc,
                display,
                allocation,
                drawing: drawing.as_ref(),
            },
        )
        .as_bytes(),
    )?;
    let summary = report::summary_json(m.model(), a, mc, threads);
    dir.write(
        "summary.json",
        serde_json::to_string_pretty(&summary)
            .expect("a JSON value")
            .as_bytes(),
    )?;
    let place = dir.commit(partial)?;
    Ok(Written {
        partial,
        place,
        missing_png,
    })
}

/// The tables: `tolerance.csv` (`partial`: of a run cut short), `probabilities.csv`, and where
/// the model has them `yield.csv`, `limits.csv`, `peaks.csv` (a transfer function's peaks
/// along the speed) and `sobol.csv`.
fn write_tables(
    model: &Model,
    a: &Analysis,
    partial: bool,
    dir: &mut ResultDir,
) -> Result<(), FileError> {
    dir.write(
        "tolerance.csv",
        &csv_bytes(
            &report::tolerance_header(model, a),
            &report::tolerance_rows(a, partial),
        ),
    )?;
    dir.write(
        "probabilities.csv",
        &csv_bytes(&report::PROBABILITY_HEADER, &report::probability_rows(a)),
    )?;
    if !model.requirements.is_empty() {
        dir.write(
            "yield.csv",
            &csv_bytes(&report::YIELD_HEADER, &report::yield_rows(model, a)),
        )?;
        dir.write(
            "limits.csv",
            &csv_bytes(&report::LIMITS_HEADER, &report::limit_rows(model, a)),
        )?;
    }
    if model.analysis.transfer.is_some() {
        dir.write(
            "peaks.csv",
            &csv_bytes(&report::PEAK_HEADER, &report::peak_rows(model, a)),
        )?;
    }
    if !a.sobol.is_empty() {
        dir.write(
            "sobol.csv",
            &csv_bytes(&report::SOBOL_HEADER, &report::sobol_rows(model, a)),
        )?;
    }
    Ok(())
}

/// The mechanism at the middle of the speeds, its first modes, and the 3-D page, each drawing
/// as every plot (SVG, and PNG beside it: a PNG that does not render is added to `missing_png`);
/// the drawing, where the point draws.
fn write_drawings(
    model: &Model,
    a: &Analysis,
    fonts: &Arc<Database>,
    dir: &mut ResultDir,
    missing_png: &mut Vec<(String, String)>,
) -> Result<Option<Drawing>, FileError> {
    let drawing = a
        .middle_point()
        .and_then(|pt| Drawing::new(model, &model.nominal(), pt).ok());
    if let Some(d) = &drawing {
        dir.write("mechanism.html", drawing::html(d, None).as_bytes())?;
        let views = std::iter::once(("mechanism".to_string(), drawing::svg(d, None))).chain(
            (0..d.modes.len().min(report::MODES_DRAWN))
                .map(|k| (format!("mode_{}", k + 1), drawing::svg(d, Some(k)))),
        );
        for (stem, svg) in views {
            dir.write(&format!("{stem}.svg"), svg.as_bytes())?;
            match plots::png(&svg, fonts) {
                Ok(png) => dir.write(&format!("{stem}.png"), &png)?,
                Err(e) => missing_png.push((stem, e)),
            }
        }
    }
    Ok(drawing)
}
