//! The report's opening answer, "In short": one sentence per output that matters of the
//! Campbell diagram's case (by default the one with the most toleranced variables: the whole
//! design's spread): three modes' damped natural frequencies and |H| at the speed of their
//! largest relative spread, as mean ± 3σ and per cent of the mean, the tolerances that drive
//! them, and whether the requirements hold. The modes are those that cross an engine order
//! first (their critical speeds, with ±3σ: what a tolerance moves onto a running speed; a
//! rotor's lateral modes before its soft torsional coupling to the drive), then the lowest.

use super::{esc, plain, short, sig};
use crate::analyze::Analysis;
use crate::model::Model;
use crate::output::Quantity;
use crate::plots::{CriticalSpeed, Display, Meeting, campbell_case};
use crate::table::{Method, Row};
use std::fmt::Write;

/// The number of modes the sentences cover.
const MODES: usize = 3;

/// A variable's share of the first-order variance below which it is not named as a driver.
const DRIVER_SHARE: f64 = 0.05;

/// The "In short" section (none where the analysis has no answer rows).
pub(super) fn in_short(
    h: &mut String,
    model: &Model,
    a: &Analysis,
    critical: &[CriticalSpeed],
    d: Display,
) {
    let ci = campbell_case(a, d);
    let Some(case) = a.cases.get(ci) else {
        return;
    };
    let mut lines: Vec<String> = Vec::new();
    let modes = a.nominal.iter().flatten().map(|p| p.modes.len()).next();
    // Each crossing mode's lowest crossing, by mode, then the modes without one.
    let mut crossings: Vec<&CriticalSpeed> = Vec::new();
    for c in critical.iter().filter(|c| c.meeting == Meeting::Crossing) {
        match crossings.iter_mut().find(|o| o.mode == c.mode) {
            Some(o) if o.speed <= c.speed => {}
            Some(o) => *o = c,
            None => crossings.push(c),
        }
    }
    crossings.sort_by_key(|c| c.mode);
    let order = (crossings.iter().map(|c| c.mode))
        .chain((0..modes.unwrap_or(0)).filter(|m| !crossings.iter().any(|c| c.mode == *m)));
    let mut shown = 0;
    for m in order {
        if shown == MODES {
            break;
        }
        if let Some(mut line) = sentence(model, a, ci, Quantity::DampedFrequency, Some(m), d) {
            if let Some(c) = crossings.iter().find(|c| c.mode == m) {
                let xs = d.speed.per_rad_per_second();
                let _ = write!(
                    line,
                    " It crosses {}× at Ω = {}{} {}.",
                    plain(c.order),
                    plain(c.speed * xs),
                    if c.std.is_finite() {
                        format!(" ± {}", sig(3.0 * c.std * xs))
                    } else {
                        String::new()
                    },
                    d.speed.symbol()
                );
            }
            lines.push(line);
            shown += 1;
        }
    }
    if let Some(line) = sentence(model, a, ci, Quantity::TransferMagnitude, None, d) {
        lines.push(line);
    }
    if let Some(line) = requirements(model, a, ci) {
        lines.push(line);
    }
    if lines.is_empty() {
        return;
    }
    let _ = writeln!(
        h,
        "<h2>In short</h2><p>Case <b>{}</b> ({} toleranced variable(s)); mean ± 3σ at the \
         speed where each output spreads most relative to its mean; the drivers are the \
         variables' shares of the first-order variance there.</p><ul>",
        esc(&case.name),
        case.tolerances.len()
    );
    for l in lines {
        let _ = writeln!(h, "<li>{l}</li>");
    }
    let _ = writeln!(h, "</ul>");
}

/// The sentence of one output: where its 3σ is largest relative to its mean, its mean ± 3σ
/// there and what drives it; `None` where it has no resolved σ (a rigid mode, an undamped
/// system's ζ, an output no tolerance moves).
fn sentence(
    model: &Model,
    a: &Analysis,
    ci: usize,
    q: Quantity,
    mode: Option<usize>,
    d: Display,
) -> Option<String> {
    let rows: Vec<&Row> = (a.rows.iter())
        .filter(|r| r.case == ci && r.quantity == q && r.mode == mode)
        .filter(|r| r.method() == Method::Analytic && r.mean.is_finite() && r.mean != 0.0)
        .filter(|r| r.std.is_finite() && r.std > q.resolution(r.mean, r.std))
        .collect();
    let r = rows
        .iter()
        .max_by(|x, y| (x.std / x.mean.abs()).total_cmp(&(y.std / y.mean.abs())))?;
    let (ys, unit) = match q {
        Quantity::DampedFrequency => (d.frequency.per_rad_per_second(), d.frequency.symbol()),
        _ => (1.0, ""),
    };
    let unit = if q == Quantity::TransferMagnitude {
        model
            .analysis
            .transfer
            .map_or(String::new(), |t| model.transfer_unit(&t))
    } else {
        unit.to_string()
    };
    let what = match mode {
        Some(m) => format!("Mode {}'s damped natural frequency", m + 1),
        None => "The transfer magnitude |H|".to_string(),
    };
    Some(format!(
        "{what}: {} ± {} {} (±{} %) at Ω = {} {}{}.",
        sig(r.mean * ys),
        sig(3.0 * r.std * ys),
        esc(&unit),
        short(300.0 * r.std / r.mean.abs()),
        plain(r.speed * d.speed.per_rad_per_second()),
        d.speed.symbol(),
        drivers(model, a, r)
    ))
}

/// The variables that drive an output at a speed: those with at least [`DRIVER_SHARE`] of its
/// first-order variance, largest first (empty where first order has no shares there).
fn drivers(model: &Model, a: &Analysis, at: &Row) -> String {
    let Some(shares) = (a.rows.iter())
        .find(|r| {
            r.case == at.case
                && r.quantity == at.quantity
                && r.mode == at.mode
                && r.method() == Method::FirstOrder
                && r.speed.to_bits() == at.speed.to_bits()
        })
        .and_then(|r| r.shares())
    else {
        return String::new();
    };
    let mut named: Vec<(f64, &str)> = (shares.iter().zip(&a.vars))
        .filter(|(s, _)| **s >= DRIVER_SHARE)
        .map(|(s, &b)| (*s, model.parameters[b].name.as_str()))
        .collect();
    named.sort_by(|x, y| y.0.total_cmp(&x.0));
    if named.is_empty() {
        return String::new();
    }
    let list: Vec<String> = (named.iter())
        .map(|(s, n)| format!("{} ({:.0} %)", esc(n), 100.0 * s))
        .collect();
    format!(", driven by {}", list.join(", "))
}

/// Whether the design meets all its requirements together at the target yield, by the
/// quadrature (else the Monte Carlo): `None` without requirements.
fn requirements(model: &Model, a: &Analysis, ci: usize) -> Option<String> {
    if model.requirements.is_empty() {
        return None;
    }
    let target = model.allocation.target_yield;
    let all = |m: Method| {
        (a.yields.iter())
            .find(|y| y.case == ci && y.method == m && y.requirement.is_none() && y.speed.is_none())
    };
    let y = all(Method::Quadrature).or_else(|| all(Method::MonteCarlo))?;
    let verdict = match crate::report::verdict(y.ci, target) {
        "yes" => "meets",
        "no" => "does not meet",
        _ => "cannot be told (the interval holds the target) to meet",
    };
    Some(format!(
        "Requirements: the design meets all {} together with probability {} [{}, {}] ({}); it \
         {verdict} the target yield {} %.",
        model.requirements.len(),
        sig(y.probability),
        sig(y.ci.0),
        sig(y.ci.1),
        y.method.as_str(),
        crate::plots::percent(target)
    ))
}
