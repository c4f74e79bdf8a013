//! Formatting of results: CSV rows, JSON documents and text tables. Builds strings and values;
//! writing them anywhere is the CLI's business.
//!
//! Units: speeds and frequencies in rad/s, angles in rad, translations in m, drive forces in
//! N·m (revolute) or N (prismatic), damping ratios dimensionless.

use crate::analyze::{Analysis, Method, Row};
use crate::frf::{NoTransfer, transfer_defect};
use crate::linearize::Linearization;
use crate::modal::{C64, Mode};
use crate::model::Model;
use crate::montecarlo::McOptions;
use crate::plots::{CriticalSpeed, Display, Plot};
use crate::sensitivity::{
    ResponseRow, Sensitivity, Status as SensStatus, TransferAt, nominal_transfer,
};
use crate::study::SweepExtras;
use crate::sweep::{Point, PointError};
use crate::tolerance::Quantity;
use nalgebra::DMatrix;
use serde_json::{Value, json};
use std::fmt::Write;

/// Optional column groups of the sweep CSV.
#[derive(Debug, Clone, Default)]
pub struct SweepColumns {
    /// Add `transfer_magnitude,transfer_phase`.
    pub transfer: bool,
    /// Design variables (parameter indices) for `d(…)/d(P)` columns; empty: none.
    pub wrt: Vec<usize>,
}

/// `x` with `decimals` decimals, or `–` where it is undefined (the damping ratio of a
/// rigid-body mode).
fn fixed(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "–".into()
    }
}

fn opt(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or(String::new(), |x| x.to_string())
}

/// A row's message: its parts that are there, joined.
fn message<'a>(parts: impl IntoIterator<Item = Option<&'a str>>) -> String {
    parts.into_iter().flatten().collect::<Vec<_>>().join("; ")
}

/// The columns every per-mode table starts with: where, which mode, its character and roots.
const MODE_COLUMNS: [&str; 10] = [
    "speed",
    "mode",
    "status",
    "damped_frequency",
    "natural_frequency",
    "damping_ratio",
    "eigen_re",
    "eigen_im",
    "eigen2_re",
    "eigen2_im",
];

/// The cells of [`MODE_COLUMNS`] for mode `i` (0-based) of a point at `speed`.
fn mode_cells(speed: f64, i: usize, m: &Mode) -> Vec<String> {
    vec![
        speed.to_string(),
        (i + 1).to_string(),
        m.class.as_str().to_string(),
        m.damped_frequency.to_string(),
        m.natural_frequency.to_string(),
        opt(Some(m.damping_ratio)),
        m.root.lambda.re.to_string(),
        m.root.lambda.im.to_string(),
        m.partner.lambda.re.to_string(),
        m.partner.lambda.im.to_string(),
    ]
}

/// Header of the sweep CSV.
pub fn sweep_header(model: &Model, cols: &SweepColumns) -> Vec<String> {
    let mut h: Vec<String> = MODE_COLUMNS.iter().map(|s| s.to_string()).collect();
    h.push("tuning_order".into());
    if cols.transfer {
        h.push("transfer_magnitude".into());
        h.push("transfer_phase".into());
    }
    for &b in &cols.wrt {
        let p = &model.parameters[b].name;
        h.push(format!("d(damped_frequency)/d({p})"));
        h.push(format!("d(natural_frequency)/d({p})"));
        h.push(format!("d(damping_ratio)/d({p})"));
        if cols.transfer {
            h.push(format!("d(transfer_magnitude)/d({p})"));
        }
    }
    if !cols.wrt.is_empty() {
        h.push("sensitivity_status".into());
    }
    h.extend(model.coordinates.iter().map(|c| format!("q:{}", c.name)));
    h.extend(
        model
            .driven()
            .iter()
            .map(|&i| format!("drive:{}", model.coordinates[i].name)),
    );
    h.push("iterations".into());
    h.push("branch".into());
    h.push("message".into());
    h
}

/// Rows of the sweep CSV for one speed: one per mode (a failed speed gets one `failed` row per
/// degree of freedom, with the reason). Derivatives that do not exist are left empty and
/// `sensitivity_status` says `not_differentiable`.
pub fn sweep_rows(
    model: &Model,
    cols: &SweepColumns,
    speed: f64,
    result: &Result<Point, PointError>,
    extras: &SweepExtras,
) -> Vec<Vec<String>> {
    let ncols = sweep_header(model, cols).len();
    match result {
        Ok(p) => p
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let mut r = mode_cells(speed, i, m);
                r.push(opt((speed != 0.0).then(|| m.damped_frequency / speed)));
                if cols.transfer {
                    r.push(opt(extras.transfer.map(|h| h.magnitude())));
                    r.push(opt(extras.transfer.map(|h| h.phase())));
                }
                if !cols.wrt.is_empty() {
                    let mut status = "ok";
                    for (k, _) in cols.wrt.iter().enumerate() {
                        let v = extras.sensitivity.as_ref().map(|s| &s.variables[k]);
                        let ms = v.map(|v| &v.modes[i]);
                        let ok = ms.is_some_and(|m| m.status == SensStatus::Ok);
                        if !ok {
                            status = "not_differentiable";
                        }
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_damped_frequency)));
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_natural_frequency)));
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_damping_ratio)));
                        if cols.transfer {
                            let d = v.and_then(|v| v.d_transfer_magnitude);
                            if d.is_none() {
                                status = "not_differentiable";
                            }
                            r.push(opt(d));
                        }
                    }
                    r.push(status.into());
                }
                r.extend(p.equilibrium.q.iter().map(|v| v.to_string()));
                r.extend(
                    model
                        .driven()
                        .iter()
                        .map(|&d| p.equilibrium.drive_force[d].to_string()),
                );
                r.push(p.equilibrium.iterations.to_string());
                r.push(p.branch.as_str().into());
                let why = extras.transfer_defect.map(NoTransfer::message);
                r.push(point_message(p, why));
                r
            })
            .collect(),
        Err(e) => failed_rows(model, ncols, speed, e),
    }
}

/// A failed point's rows, `ncols` wide: one per degree of freedom, status `failed`, the
/// reason in the last column (`message`).
fn failed_rows(model: &Model, ncols: usize, speed: f64, e: &PointError) -> Vec<Vec<String>> {
    (0..model.dof().max(1))
        .map(|i| {
            let mut r = vec![String::new(); ncols];
            r[0] = speed.to_string();
            r[1] = (i + 1).to_string();
            r[2] = "failed".into();
            r[ncols - 1] = e.to_string();
            r
        })
        .collect()
}

/// A mode shape for display: scaled so that its largest component is 1 (real), the
/// convention of modal test reports; a zero shape stays zero.
pub fn display_shape(shape: &[C64]) -> Vec<C64> {
    let big = shape
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .filter(|z| z.norm() > 0.0);
    shape.iter().map(|&z| big.map_or(z, |b| z / b)).collect()
}

/// Header of the modes table (`modal --format csv`): the mode's frequencies, damping ratio,
/// its two roots, then its shape in the free coordinates, scaled by [`display_shape`]
/// (`shape_re:<joint>`, `shape_im:<joint>`), then `message` (the point's note, or why it
/// failed).
pub fn modes_header(model: &Model) -> Vec<String> {
    let mut h: Vec<String> = MODE_COLUMNS.iter().map(|s| s.to_string()).collect();
    for &i in &model.free() {
        let c = &model.coordinates[i].name;
        h.push(format!("shape_re:{c}"));
        h.push(format!("shape_im:{c}"));
    }
    h.push("branch".into());
    h.push("message".into());
    h
}

/// What a point's rows say beside their numbers: which branch and why where it is not simply
/// the stable equilibrium reached, then any note (a change of stability).
fn point_message(p: &Point, transfer: Option<&str>) -> String {
    let branch = (p.branch.as_str() != "stable").then(|| p.branch.to_string());
    message([branch.as_deref(), p.note.as_deref(), transfer])
}

/// Rows of the modes table at the point `p` (see [`modes_header`]).
pub fn modes_rows(p: &Point) -> Vec<Vec<String>> {
    p.modes
        .iter()
        .zip(&p.shapes)
        .enumerate()
        .map(|(i, (m, shape))| {
            let mut r = mode_cells(p.speed, i, m);
            let shape: Vec<C64> = shape.iter().copied().collect();
            for z in display_shape(&shape) {
                r.push(z.re.to_string());
                r.push(z.im.to_string());
            }
            r.push(p.branch.as_str().into());
            r.push(point_message(p, None));
            r
        })
        .collect()
}

/// Rows of the modes table of a point at `speed` that failed: one per degree of freedom,
/// status `failed`, the reason in `message` (as in a sweep).
pub fn modes_failed_rows(model: &Model, speed: f64, e: &PointError) -> Vec<Vec<String>> {
    failed_rows(model, modes_header(model).len(), speed, e)
}

/// The elasticity `(b/f)·df/db`: the relative change of `f` per relative change of `b`; none
/// where `f` is zero (an undamped mode's ζ, an overdamped mode's ω_d).
pub fn elasticity(b: f64, f: f64, df_db: f64) -> Option<f64> {
    let e = b / f * df_db;
    (f != 0.0 && e.is_finite()).then_some(e)
}

/// Header of the sensitivity table (`sensitivity --format csv`): one row per mode and design
/// variable, the derivatives per unit of the variable (`d_…`) and normalised (`elasticity_…`,
/// [`elasticity`]), then `message` (why |H| has no value, where it has none).
pub const SENSITIVITY_HEADER: [&str; 19] = [
    "speed",
    "mode",
    "status",
    "damped_frequency",
    "natural_frequency",
    "damping_ratio",
    "transfer_magnitude",
    "parameter",
    "value",
    "sensitivity_status",
    "d_damped_frequency",
    "d_natural_frequency",
    "d_damping_ratio",
    "d_transfer_magnitude",
    "elasticity_damped_frequency",
    "elasticity_natural_frequency",
    "elasticity_damping_ratio",
    "elasticity_transfer_magnitude",
    "message",
];

/// Why the transfer function `t` has no finite value at the point `pt`, where it has none.
pub fn transfer_defect_at(pt: &Point, t: Option<&TransferAt>) -> Option<NoTransfer> {
    t.and_then(|t| transfer_defect(&pt.linear, t.omega, nominal_transfer(pt, t).as_ref()))
}

/// Rows of the sensitivity table (see [`SENSITIVITY_HEADER`]); derivatives that do not exist
/// are empty and `sensitivity_status` says `not_differentiable`; `transfer` says why |H| has
/// no value, where it has none ([`transfer_defect`]).
pub fn sensitivity_rows(
    model: &Model,
    pt: &Point,
    s: &Sensitivity,
    transfer: Option<NoTransfer>,
) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for (i, m) in pt.modes.iter().enumerate() {
        for v in &s.variables {
            let b = model.parameters[v.param].value;
            let ms = &v.modes[i];
            let ok = ms.status == SensStatus::Ok;
            let d = |x: f64| ok.then_some(x);
            let dh = v.d_transfer_magnitude;
            let el = |f: f64, df: Option<f64>| df.and_then(|df| elasticity(b, f, df));
            rows.push(vec![
                pt.speed.to_string(),
                (i + 1).to_string(),
                m.class.as_str().to_string(),
                m.damped_frequency.to_string(),
                m.natural_frequency.to_string(),
                opt(Some(m.damping_ratio)),
                opt(s.transfer_magnitude),
                model.parameters[v.param].name.clone(),
                b.to_string(),
                if ok { "ok" } else { "not_differentiable" }.to_string(),
                opt(d(ms.d_damped_frequency)),
                opt(d(ms.d_natural_frequency)),
                opt(d(ms.d_damping_ratio)),
                opt(dh),
                opt(el(m.damped_frequency, d(ms.d_damped_frequency))),
                opt(el(m.natural_frequency, d(ms.d_natural_frequency))),
                opt(el(m.damping_ratio, d(ms.d_damping_ratio))),
                opt(s.transfer_magnitude.and_then(|h| el(h, dh))),
                message([transfer.map(NoTransfer::message)]),
            ]);
        }
    }
    rows
}

/// Header of the frequency-response table (`frf`): excitation frequency, |H|, arg H, its real
/// and imaginary parts, then `d(magnitude)/d(P)` per design variable, then `message` (why `H`
/// has no value, where it has none).
pub fn frf_header(model: &Model, wrt: &[usize]) -> Vec<String> {
    let mut header: Vec<String> = ["frequency", "magnitude", "phase", "real", "imag"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(
        wrt.iter()
            .map(|&b| format!("d(magnitude)/d({})", model.parameters[b].name)),
    );
    header.push("message".into());
    header
}

/// Rows of the frequency-response table (see [`frf_header`]) of the linearisation `lin`:
/// empty cells where `H` or a derivative does not exist, and where `H` has no finite value,
/// the reason ([`transfer_defect`]: a resonance, an overflow).
pub fn frf_rows(lin: &Linearization<f64>, rows: &[ResponseRow]) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| {
            let mut row = vec![r.frequency.to_string()];
            let why = transfer_defect(lin, r.frequency, r.h.as_ref());
            let h = r.h.filter(|_| why.is_none());
            row.extend([
                opt(h.map(|h| h.magnitude())),
                opt(h.map(|h| h.phase())),
                opt(h.map(|h| h.re)),
                opt(h.map(|h| h.im)),
            ]);
            row.extend(r.d_magnitude.iter().map(|&v| opt(v)));
            row.push(message([why.map(NoTransfer::message)]));
            row
        })
        .collect()
}

/// The `sensitivity` result as JSON.
pub fn sensitivity_json(
    model: &Model,
    speed: f64,
    method: &str,
    pt: &Point,
    s: &Sensitivity,
    transfer: Option<NoTransfer>,
) -> Value {
    let vars: Vec<Value> = s
        .variables
        .iter()
        .map(|v| {
            let p = &model.parameters[v.param];
            json!({
                "parameter": p.name, "value": p.value,
                "d_transfer_magnitude": v.d_transfer_magnitude, "d_transfer_phase": v.d_transfer_phase,
                "d_equilibrium": model.coordinates.iter().zip(&v.d_equilibrium).map(|(c, d)| json!({"name": c.name, "value": d})).collect::<Vec<_>>(),
                "modes": v.modes.iter().enumerate().map(|(i, m)| {
                    let ok = m.status == SensStatus::Ok;
                    json!({"mode": i + 1, "status": m.status,
                           "d_damped_frequency": ok.then_some(m.d_damped_frequency),
                           "d_natural_frequency": ok.then_some(m.d_natural_frequency),
                           "d_damping_ratio": ok.then_some(m.d_damping_ratio),
                           "d_eigen_re": m.d_eigen_re, "d_eigen_im": m.d_eigen_im})
                }).collect::<Vec<_>>(),
            })
        })
        .collect();
    json!({
        "model": model.name, "speed": speed, "derivatives": method,
        "units": {"frequency": "rad/s", "derivative": "quantity unit per parameter unit"},
        "modes": pt.modes.iter().enumerate().map(|(i, m)| json!({"mode": i + 1, "status": m.class.as_str(),
            "damped_frequency": m.damped_frequency, "natural_frequency": m.natural_frequency, "damping_ratio": m.damping_ratio})).collect::<Vec<_>>(),
        "transfer_magnitude": s.transfer_magnitude.filter(|_| transfer.is_none()),
        "transfer_phase": s.transfer_phase.filter(|_| transfer.is_none()),
        "transfer_message": transfer.map(NoTransfer::message),
        "variables": vars,
    })
}

/// The `sensitivity` result as a text table.
pub fn sensitivity_table(
    model: &Model,
    speed: f64,
    method: &str,
    pt: &Point,
    s: &Sensitivity,
    transfer: Option<NoTransfer>,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "model: {}    speed: {speed:?} rad/s    derivatives: {method}",
        model.name
    );
    if let Some(why) = transfer {
        let _ = writeln!(out, "transfer: {}", why.message());
    } else if let (Some(h), Some(ph)) = (s.transfer_magnitude, s.transfer_phase) {
        let _ = writeln!(out, "transfer |H| = {h:.8e}, arg H = {ph:.6} rad");
    }
    for (i, m) in pt.modes.iter().enumerate() {
        let _ = writeln!(
            out,
            "\nmode {} ({}): ω_d = {:.8} rad/s, ω_n = {:.8} rad/s, ζ = {}",
            i + 1,
            m.class.as_str(),
            m.damped_frequency,
            m.natural_frequency,
            fixed(m.damping_ratio, 6)
        );
        let pw = s
            .variables
            .iter()
            .map(|v| model.parameters[v.param].name.chars().count())
            .max()
            .unwrap_or(0)
            .max(14);
        let _ = writeln!(
            out,
            "  {:<pw$} {:>16} {:>16} {:>16} {:>16}",
            "parameter", "dω_d/dP", "dω_n/dP", "dζ/dP", "d|H|/dP"
        );
        for v in &s.variables {
            let ms = &v.modes[i];
            let f = |x: f64| {
                if ms.status == SensStatus::Ok {
                    format!("{x:>16.8e}")
                } else {
                    format!("{:>16}", "n/a")
                }
            };
            let dh = v
                .d_transfer_magnitude
                .map_or(format!("{:>16}", "-"), |x| format!("{x:>16.8e}"));
            let _ = writeln!(
                out,
                "  {:<pw$} {} {} {} {dh}",
                model.parameters[v.param].name,
                f(ms.d_damped_frequency),
                f(ms.d_natural_frequency),
                f(ms.d_damping_ratio)
            );
        }
        if s.variables
            .iter()
            .any(|v| v.modes[i].status != SensStatus::Ok)
        {
            let _ = writeln!(
                out,
                "  n/a: roots coalescing or the mode changes class here; ω_d is not differentiable"
            );
        }
    }
    out
}

fn matrix(m: &DMatrix<f64>) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// The `modal` result as JSON.
pub fn modal_json(model: &Model, speed: f64, result: &Result<Point, PointError>) -> Value {
    let p = match result {
        Err(e) => {
            return json!({"model": model.name, "speed": speed, "status": "failed", "message": e.to_string()});
        }
        Ok(p) => p,
    };
    let eq = &p.equilibrium;
    let coords: Vec<Value> = model
        .coordinates
        .iter()
        .enumerate()
        .map(|(i, c)| {
            json!({"name": c.name, "value": eq.q[i], "unit": c.unit.symbol(), "driven": c.driven,
                   "speed": eq.qd[i]})
        })
        .collect();
    let drives: Vec<Value> = model
        .driven()
        .iter()
        .map(|&i| {
            let c = &model.coordinates[i];
            json!({"name": c.name, "force": eq.drive_force[i], "unit": c.unit.force_symbol()})
        })
        .collect();
    let modes: Vec<Value> = p
        .modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            json!({"mode": i + 1, "status": m.class.as_str(),
                   "damped_frequency": m.damped_frequency, "natural_frequency": m.natural_frequency,
                   "damping_ratio": m.damping_ratio,
                   "eigenvalue": {"re": m.root.lambda.re, "im": m.root.lambda.im},
                   "partner_eigenvalue": {"re": m.partner.lambda.re, "im": m.partner.lambda.im},
                   "shape": model.free().iter().zip(display_shape(p.shapes[i].as_slice())).map(|(&c, z)| json!({"coordinate": model.coordinates[c].name, "re": z.re, "im": z.im})).collect::<Vec<_>>()})
        })
        .collect();
    let names = |v: &[usize]| {
        v.iter()
            .map(|&i| model.coordinates[i].name.clone())
            .collect::<Vec<_>>()
    };
    json!({
        "model": model.name,
        "speed": speed,
        "status": if p.stable() { "ok" } else { "unstable" },
        "units": {"speed": "rad/s", "frequency": "rad/s", "revolute": "rad", "prismatic": "m"},
        "equilibrium": {"coordinates": coords, "drive": drives, "lambda": eq.lambda,
                        "iterations": eq.iterations, "residual": eq.residual,
                        "constraint_violation": eq.constraint_violation},
        "free": names(&p.linear.free),
        "independent": names(&p.linear.independent),
        "basis": matrix(&p.linear.basis),
        "M": matrix(&p.linear.m),
        "C": matrix(&p.linear.c),
        "K": matrix(&p.linear.k),
        "modes": modes,
        "branch": {"kind": p.branch.as_str(), "origin": p.branch.origin, "detail": p.branch.kind,
                   "reason": p.branch.to_string()},
        "note": p.note,
    })
}

fn write_matrix(out: &mut String, name: &str, m: &DMatrix<f64>) {
    let _ = writeln!(out, "{name} =");
    for i in 0..m.nrows() {
        let row: Vec<String> = (0..m.ncols())
            .map(|j| format!("{:>14.6e}", m[(i, j)]))
            .collect();
        let _ = writeln!(out, "  [{}]", row.join(" "));
    }
}

/// The `modal` result as a text table.
pub fn modal_table(model: &Model, speed: f64, result: &Result<Point, PointError>) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model: {}    speed: {speed:?} rad/s", model.name);
    let p = match result {
        Err(e) => {
            let _ = writeln!(s, "FAILED: {e}");
            return s;
        }
        Ok(p) => p,
    };
    let eq = &p.equilibrium;
    let _ = writeln!(
        s,
        "\nequilibrium ({} Newton iterations, residual {:.2e}, |Φ| {:.2e}):",
        eq.iterations, eq.residual, eq.constraint_violation
    );
    for (i, c) in model.coordinates.iter().enumerate() {
        let tag = if c.driven {
            format!("  driven at {} {}/s", eq.qd[i], c.unit.symbol())
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {:<16} {:>16.10} {}{tag}",
            c.name,
            eq.q[i],
            c.unit.symbol()
        );
    }
    for &i in &model.driven() {
        let c = &model.coordinates[i];
        let _ = writeln!(
            s,
            "  drive force on {:<8} {:>14.8e} {}",
            c.name,
            eq.drive_force[i],
            c.unit.force_symbol()
        );
    }
    let ind: Vec<&str> = p
        .linear
        .independent
        .iter()
        .map(|&i| model.coordinates[i].name.as_str())
        .collect();
    let _ = writeln!(
        s,
        "\nlinearised in the independent coordinates [{}]:",
        ind.join(", ")
    );
    write_matrix(&mut s, "M̂", &p.linear.m);
    write_matrix(&mut s, "Ĉ", &p.linear.c);
    write_matrix(&mut s, "K̂", &p.linear.k);
    let _ = writeln!(s, "\nmodes (rad/s):");
    let _ = writeln!(
        s,
        "  {:>4}  {:<12} {:>14} {:>14} {:>12} {:>26}",
        "mode", "status", "ω_d", "ω_n", "ζ", "eigenvalue"
    );
    for (i, m) in p.modes.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {:>4}  {:<12} {:>14.8} {:>14.8} {:>12} {:>12.6} {:+12.6}i",
            i + 1,
            m.class.as_str(),
            m.damped_frequency,
            m.natural_frequency,
            fixed(m.damping_ratio, 6),
            m.root.lambda.re,
            m.root.lambda.im
        );
    }
    let free = model.free();
    let width = free
        .iter()
        .map(|&i| model.coordinates[i].name.chars().count())
        .max()
        .unwrap_or(0)
        .max(10);
    let _ = writeln!(
        s,
        "\nmode shapes in the free coordinates (largest component 1; magnitude ∠ phase):"
    );
    let _ = write!(s, "  {:<width$}", "coordinate");
    for i in 0..p.modes.len() {
        let _ = write!(s, " {:>18}", format!("mode {}", i + 1));
    }
    let _ = writeln!(s);
    let shapes: Vec<Vec<C64>> = p
        .shapes
        .iter()
        .map(|x| display_shape(x.as_slice()))
        .collect();
    for (k, &c) in free.iter().enumerate() {
        let _ = write!(s, "  {:<width$}", model.coordinates[c].name);
        for shape in &shapes {
            let z = shape[k];
            let _ = write!(
                s,
                " {:>18}",
                format!("{:.4} ∠ {:+7.2}°", z.norm(), z.arg().to_degrees())
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "\nbranch: {}: {}", p.branch.as_str(), p.branch);
    if let Some(n) = &p.note {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// Summary printed by `check`.
pub fn check_summary(model: &Model) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model '{}' ({}) is valid", model.name, model.file);
    let _ = writeln!(s, "  bodies ({}):", model.bodies.len());
    for b in &model.bodies {
        let _ = writeln!(s, "    {}", b.name);
    }
    let body = |b: Option<usize>| b.map_or("ground".to_string(), |i| model.bodies[i].name.clone());
    let _ = writeln!(s, "  joints ({}):", model.joints.len());
    // Columns as wide as the longest name, so that long names do not push them out of line.
    let wide = |names: &mut dyn Iterator<Item = &str>, least: usize| {
        names
            .map(|n| n.chars().count())
            .max()
            .unwrap_or(0)
            .max(least)
    };
    let jw = wide(&mut model.joints.iter().map(|j| j.name.as_str()), 12);
    let kw = wide(&mut model.joints.iter().map(|j| j.kind.name()), 10);
    let pw = wide(&mut model.parameters.iter().map(|p| p.name.as_str()), 14);
    for j in &model.joints {
        let kind = j.kind.name();
        let drive = if j.drive.is_some() { ", driven" } else { "" };
        let _ = writeln!(
            s,
            "    {:<jw$} {:<kw$} {} → {}{drive}",
            j.name,
            kind,
            body(j.parent),
            body(Some(j.child))
        );
    }
    let _ = writeln!(
        s,
        "  coordinates: {} ({} driven, {} free)",
        model.coordinates.len(),
        model.driven().len(),
        model.free().len()
    );
    let _ = writeln!(s, "  force elements: {}", model.forces.len());
    let _ = writeln!(
        s,
        "  constraints: {} ({} equations)",
        model.constraints.len(),
        model.n_constraints()
    );
    for c in &model.constraints {
        let _ = writeln!(s, "    {}", c.name);
    }
    let _ = writeln!(s, "  degrees of freedom: {}", model.dof());
    let _ = writeln!(s, "  parameters ({}):", model.parameters.len());
    for p in &model.parameters {
        let tol = match p.tolerance {
            Some(crate::model::Tolerance::Relative(f)) => format!("  ± {}%", f * 100.0),
            Some(crate::model::Tolerance::Absolute(a)) => format!("  ± {a}"),
            None => String::new(),
        };
        let _ = writeln!(s, "    {:<pw$} {}{tol}", p.name, p.value);
    }
    if !model.analysis.cases.is_empty() {
        let names: Vec<&str> = model
            .analysis
            .cases
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        let _ = writeln!(s, "  tolerance cases: {}", names.join(", "));
    }
    for (case, at, defect) in model.tolerance_limits() {
        let _ = writeln!(
            s,
            "  warning: case '{case}' reaches a physical limit within its tolerances: at {at}, {defect}; Monte Carlo samples beyond it count as failed"
        );
    }
    s
}

/// Header of `tolerance.csv`.
pub fn tolerance_header(model: &Model, a: &Analysis) -> Vec<String> {
    let mut h: Vec<String> = [
        "speed",
        "quantity",
        "mode",
        "case",
        "method",
        "mean",
        "std",
        "mean_ci_low",
        "mean_ci_high",
        "std_ci_low",
        "std_ci_high",
        "samples",
        "failed",
        "class_changed",
        "basis",
        "q05",
        "q50",
        "q95",
        "mean_error",
        "std_error",
        "partial",
        "reason",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    h.extend(
        a.vars
            .iter()
            .map(|&b| format!("share:{}", model.parameters[b].name)),
    );
    h
}

/// Rows of `tolerance.csv`: one per (speed, quantity, mode, case, method). Empty cells where a
/// method gives no answer (its `reason` says why: an output not differentiable there, a
/// rigid-body mode's damping ratio) or a column does not apply.
/// `partial` (a column of every row) says the run was interrupted: the Monte Carlo rows cover
/// fewer samples than asked.
pub fn tolerance_rows(a: &Analysis, partial: bool) -> Vec<Vec<String>> {
    a.rows
        .iter()
        .map(|r| {
            let mut v = vec![
                r.speed.to_string(),
                r.quantity.as_str().to_string(),
                r.mode.map_or(String::new(), |m| (m + 1).to_string()),
                a.cases[r.case].name.clone(),
                r.method.as_str().to_string(),
                opt(Some(r.mean)),
                opt(Some(r.std)),
            ];
            match &r.mc {
                Some(m) => v.extend([
                    opt(Some(m.mean_ci.0)),
                    opt(Some(m.mean_ci.1)),
                    opt(Some(m.std_ci.0)),
                    opt(Some(m.std_ci.1)),
                    m.n.to_string(),
                    m.failed.to_string(),
                    m.class_changed.to_string(),
                ]),
                None => v.extend(std::iter::repeat_n(String::new(), 7)),
            }
            v.push(r.basis.map_or(String::new(), |m| m.as_str().to_string()));
            match r.quantiles {
                Some(q) => v.extend(q.map(|x| opt(Some(x)))),
                None => v.extend(std::iter::repeat_n(String::new(), 3)),
            }
            match r.errors {
                Some((em, es)) => v.extend([opt(Some(em)), opt(Some(es))]),
                None => v.extend(std::iter::repeat_n(String::new(), 2)),
            }
            v.push(partial.to_string());
            v.push(r.missing.as_ref().map_or(String::new(), |m| m.to_string()));
            match &r.shares {
                Some(s) => v.extend(s.iter().map(|x| opt(Some(*x)))),
                None => v.extend(std::iter::repeat_n(String::new(), a.vars.len())),
            }
            v
        })
        .collect()
}

/// Header of `probabilities.csv`.
pub const PROBABILITY_HEADER: [&str; 8] = [
    "speed",
    "case",
    "method",
    "event",
    "mode",
    "probability",
    "ci_low",
    "ci_high",
];

/// Rows of `probabilities.csv`: one per (speed, case, method, event, mode); `mode` (1-based)
/// for `overdamped` only. The interval is the quadrature's probability ± its error estimate,
/// or the Monte Carlo's 95 % Wilson score interval.
pub fn probability_rows(a: &Analysis) -> Vec<Vec<String>> {
    a.probabilities
        .iter()
        .map(|p| {
            vec![
                p.speed.to_string(),
                a.cases[p.case].name.clone(),
                p.method.as_str().to_string(),
                p.event.as_str().to_string(),
                p.mode.map_or(String::new(), |m| (m + 1).to_string()),
                p.probability.to_string(),
                p.ci.0.to_string(),
                p.ci.1.to_string(),
            ]
        })
        .collect()
}

/// Per case, method, event and mode: the largest probability over the speeds and where it is.
fn probability_summary(a: &Analysis) -> Vec<Value> {
    let mut out: Vec<Value> = Vec::new();
    let mut keys: Vec<(usize, &str, &str, Option<usize>)> = a
        .probabilities
        .iter()
        .map(|p| (p.case, p.method.as_str(), p.event.as_str(), p.mode))
        .collect();
    keys.sort();
    keys.dedup();
    for (case, method, event, mode) in keys {
        let rows = a.probabilities.iter().filter(|p| {
            p.case == case
                && p.method.as_str() == method
                && p.event.as_str() == event
                && p.mode == mode
        });
        let (mut best, mut at, mut any) = (0.0f64, None, 0usize);
        for p in rows {
            if p.probability > 0.0 {
                any += 1;
            }
            if p.probability > best {
                (best, at) = (p.probability, Some(p.speed));
            }
        }
        out.push(
            json!({"case": a.cases[case].name, "method": method, "event": event,
                        "mode": mode.map(|m| m + 1), "max_probability": best, "at_speed": at,
                        "speeds_with_nonzero_probability": any}),
        );
    }
    out
}

/// The paper's timings (Kim & Yoo 2007, Tables 1–2: analytic s, Monte Carlo s, ratio) when the
/// model is one of its two examples: the rotating pendulum (parameters `m`, `L`, `c`, one
/// degree of freedom, no loop) or the governor (`ball_mass`, `spring_k`, `attach`, two loops).
pub fn paper_timings(model: &Model) -> Option<(&'static str, f64, f64, f64)> {
    let has = |names: &[&str]| names.iter().all(|n| model.parameter(n).is_some());
    if has(&["m", "L", "c"]) && model.dof() == 1 && model.constraints.is_empty() {
        Some(("pendulum", 0.703, 448.281, 638.0))
    } else if has(&["ball_mass", "spring_k", "attach"]) && model.n_constraints() == 2 {
        Some(("governor", 2.188, 2525.375, 1154.0))
    } else {
        None
    }
}

/// `summary.json` of an analysis: model, cases, timings (beside the paper's for its two
/// examples), failures.
pub fn summary_json(model: &Model, a: &Analysis, mc: Option<&McOptions>, threads: usize) -> Value {
    let cases: Vec<Value> = a
        .cases
        .iter()
        .map(|c| {
            json!({"name": c.name, "tolerances": c.tolerances.iter().map(|(b, t)| {
                let p = &model.parameters[*b];
                json!({"parameter": p.name, "nominal": p.value, "tolerance": t.absolute(p.value),
                       "distribution": p.distribution})
            }).collect::<Vec<_>>(), "correlated": c.correlation.is_some()})
        })
        .collect();
    let speeds: Vec<f64> = {
        let mut s: Vec<f64> = a.rows.iter().map(|r| r.speed).collect();
        s.dedup();
        s
    };
    let mc_failed: usize = a.rows.iter().filter_map(|r| r.mc.map(|m| m.failed)).sum();
    json!({
        "model": model.name,
        "file": model.file,
        "units": {"speed": "rad/s", "damped_frequency": "rad/s", "damping_ratio": "1", "time": "s"},
        "speeds": {"count": a.nominal.len(), "from": speeds.first(), "to": speeds.last()},
        "design_variables": a.vars.iter().map(|&b| model.parameters[b].name.clone()).collect::<Vec<_>>(),
        "cases": cases,
        "methods": ["first_order", "second_order", "invariant", "quadrature", "analytic", "monte_carlo"],
        "analytic_seconds": a.analytic_seconds,
        "quadrature_seconds": a.quadrature_seconds,
        "quadrature": a.quadrature_seconds.map(|t| json!({"seconds": t,
            "cases": a.cases.iter().zip(&a.quadrature_rules).map(|(c, (rule, nodes))|
                json!({"case": c.name, "rule": rule, "nodes_swept": nodes})).collect::<Vec<_>>()})),
        "probabilities": probability_summary(a),
        "monte_carlo": mc.map(|m| json!({"samples": m.samples, "seed": m.seed, "sampling": m.sampling, "threads": threads,
                                          "seconds": a.monte_carlo_seconds, "failed_sample_points": mc_failed,
                                          "samples_done": a.samples_done, "partial": a.interrupted(m.samples),
                                          "inadmissible_samples": inadmissible_summary(a)})),
        "partial": a.cancelled || mc.is_some_and(|m| a.interrupted(m.samples)),
        "ratio_monte_carlo_to_analytic": a.monte_carlo_seconds.map(|m| m / a.analytic_seconds),
        "ratio_monte_carlo_to_quadrature": a.monte_carlo_seconds.zip(a.quadrature_seconds).map(|(m, q)| m / q),
        "paper": paper_timings(model).map(|(example, analytic, mc, ratio)| json!({
            "note": "Kim & Yoo (2007), Tables 1–2, 2007 hardware, 3000 samples",
            "example": example, "analytic_seconds": analytic, "monte_carlo_seconds": mc, "ratio": ratio})),
        "failures": a.failures.iter().map(|(w, m)| json!({"speed": w, "message": m})).collect::<Vec<_>>(),
        "unfilled": unfilled(a).iter().map(|u| json!({
            "case": a.cases[u.case].name, "method": u.method.as_str(), "quantity": u.quantity.as_str(),
            "mode": u.mode.map(|m| m + 1), "reason": u.reason, "rows": u.speeds.len(),
            "speeds": u.speeds})).collect::<Vec<_>>(),
    })
}

/// Rows of one method for one output and case that have no value, for one reason.
#[derive(Debug, Clone)]
pub struct Unfilled {
    pub case: usize,
    pub method: Method,
    pub quantity: Quantity,
    pub mode: Option<usize>,
    pub reason: String,
    /// The speeds (rad/s) of those rows, in the rows' order.
    pub speeds: Vec<f64>,
}

/// Every row without a value, grouped by case, method, output and reason, in the rows' order.
pub fn unfilled(a: &Analysis) -> Vec<Unfilled> {
    let mut out: Vec<Unfilled> = Vec::new();
    for r in &a.rows {
        let Some(m) = &r.missing else { continue };
        let reason = m.to_string();
        let same = |u: &Unfilled| {
            u.case == r.case
                && u.method == r.method
                && u.quantity == r.quantity
                && u.mode == r.mode
                && u.reason == reason
        };
        match out.iter_mut().find(|u| same(u)) {
            Some(u) => u.speeds.push(r.speed),
            None => out.push(Unfilled {
                case: r.case,
                method: r.method,
                quantity: r.quantity,
                mode: r.mode,
                reason,
                speeds: vec![r.speed],
            }),
        }
    }
    out
}

/// Groups of [`unfilled`] shown on stderr at most (`summary.json` and the report list all).
const UNFILLED_LINES: usize = 12;

/// The rows without a value in a few lines: per method and reason, how many rows, which
/// outputs and speeds (empty when every row has a value).
pub fn unfilled_lines(a: &Analysis) -> Vec<String> {
    let groups = unfilled(a);
    // Per (method, reason): rows, outputs, speed range, cases.
    let mut merged: Vec<(Method, String, usize, Vec<String>, f64, f64)> = Vec::new();
    for u in &groups {
        let output = u.mode.map_or(u.quantity.as_str().to_string(), |m| {
            format!("{} of mode {}", u.quantity.as_str(), m + 1)
        });
        let lo = u.speeds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = u.speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        match merged
            .iter_mut()
            .find(|x| x.0 == u.method && x.1 == u.reason)
        {
            Some(x) => {
                x.2 += u.speeds.len();
                if !x.3.contains(&output) {
                    x.3.push(output);
                }
                x.4 = x.4.min(lo);
                x.5 = x.5.max(hi);
            }
            None => merged.push((
                u.method,
                u.reason.clone(),
                u.speeds.len(),
                vec![output],
                lo,
                hi,
            )),
        }
    }
    let mut lines: Vec<String> = merged
        .iter()
        .take(UNFILLED_LINES)
        .map(|(method, reason, rows, outputs, lo, hi)| {
            let speeds = if lo.to_bits() == hi.to_bits() {
                format!("at {lo} rad/s")
            } else {
                format!("between {lo} and {hi} rad/s")
            };
            format!(
                "{}: {rows} row(s) without a value ({}; {speeds}): {reason}",
                method.as_str(),
                outputs.join(", ")
            )
        })
        .collect();
    if merged.len() > UNFILLED_LINES {
        lines.push(format!(
            "… and {} more groups of rows without a value (summary.json lists them all)",
            merged.len() - UNFILLED_LINES
        ));
    }
    lines
}

/// Per case, the Monte Carlo samples that are not physically admissible, by reason.
fn inadmissible_summary(a: &Analysis) -> Vec<serde_json::Value> {
    a.cases
        .iter()
        .zip(&a.inadmissible)
        .map(|(c, t)| {
            json!({"case": c.name, "samples": t.iter().map(|x| x.1).sum::<usize>(),
                   "reasons": t.iter().map(|(r, n, v)| json!({"reason": r, "samples": n, "first_value": v})).collect::<Vec<_>>()})
        })
        .collect()
}

/// Warnings of a Monte Carlo whose samples crossed a physical limit, one line per case and
/// reason (empty when none did).
pub fn inadmissible_warnings(a: &Analysis) -> Vec<String> {
    let mut out = Vec::new();
    for (ci, t) in a.inadmissible.iter().enumerate() {
        let done = a.samples_done.get(ci).copied().unwrap_or(0);
        for (reason, n, v) in t {
            out.push(format!(
                "case '{}': {n} of {done} Monte Carlo samples are not physically admissible ({reason}, e.g. {v:e}); they count as failed at every speed",
                a.cases[ci].name
            ));
        }
    }
    out
}

/// Per case and output: the speeds where first order's σ is more than 10 % off the
/// quadrature's (where the quadrature's σ is at least 2 % of its largest), as ranges.
fn first_order_table(a: &Analysis) -> String {
    let mut h = String::from(
        "<h2>Where the paper's first-order method is off</h2><table><tr><th>case</th><th>output</th><th>speeds (rad/s) where first order's σ is &gt; 10 % off the quadrature's</th><th>worst</th></tr>",
    );
    let mut outputs: Vec<(Quantity, Option<usize>)> = a
        .rows
        .iter()
        .filter(|r| r.method == Method::Quadrature && r.quantity != Quantity::DampingRatio)
        .map(|r| (r.quantity, r.mode))
        .collect();
    outputs.sort_by_key(|o| (o.0 as u8, o.1));
    outputs.dedup();
    let mut any = false;
    for (ci, c) in a.cases.iter().enumerate() {
        for &(q, mode) in &outputs {
            let off = crate::plots::first_order_off(a, ci, q, mode);
            let mut ranges: Vec<(f64, f64)> = Vec::new();
            let mut open = false;
            for &(w, v) in &off {
                if v.is_finite() {
                    match (open, ranges.last_mut()) {
                        (true, Some(r)) => r.1 = w,
                        _ => ranges.push((w, w)),
                    }
                }
                open = v.is_finite();
            }
            if ranges.is_empty() {
                continue;
            }
            any = true;
            let worst = a
                .rows
                .iter()
                .filter(|r| r.case == ci && r.quantity == q && r.mode == mode)
                .filter(|r| r.method == Method::Quadrature && r.std > 0.0)
                .filter_map(|r| {
                    a.rows
                        .iter()
                        .find(|f| {
                            f.case == ci
                                && f.quantity == q
                                && f.mode == mode
                                && f.method == Method::FirstOrder
                                && f.speed.to_bits() == r.speed.to_bits()
                        })
                        .map(|f| ((f.std - r.std).abs() / r.std, r.speed))
                })
                .filter(|x| x.0.is_finite())
                .fold((0.0f64, f64::NAN), |m, x| if x.0 > m.0 { x } else { m });
            let label = mode.map_or(q.as_str().to_string(), |m| {
                format!("{} mode {}", q.as_str(), m + 1)
            });
            let text: Vec<String> = ranges
                .iter()
                .map(|(a, b)| {
                    if a.to_bits() == b.to_bits() {
                        format!("{a:.3}")
                    } else {
                        format!("{a:.3}–{b:.3}")
                    }
                })
                .collect();
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td style=\"text-align:left\">{}</td><td>{:.0} % at {:.3}</td></tr>",
                esc(&c.name),
                label,
                text.join(", "),
                100.0 * worst.0,
                worst.1
            );
        }
    }
    if !any {
        h.push_str("<tr><td colspan=\"4\">first order is within 10 % of the quadrature's σ at every speed</td></tr>");
    }
    h.push_str("</table>");
    h
}

/// The numeric summary of an analysis, per case: for the first modes' ω_d and ζ and for |H|,
/// σ by every method where it matters (the speed of the largest σ, the critical speeds of the
/// 1×Ω line, the |H| peak), and how the methods agree there: first order against the answer,
/// and whether the answer lies inside Monte Carlo's 95 % interval of σ.
fn summary_table(model: &Model, a: &Analysis, critical: &[CriticalSpeed], d: Display) -> String {
    const MODES: usize = 3;
    let fs = d.speed.per_rad_per_second();
    let mut outputs: Vec<(Quantity, Option<usize>)> = a
        .rows
        .iter()
        .filter(|r| r.method == Method::Analytic)
        .filter(|r| r.mode.is_none_or(|m| m < MODES))
        .filter(|r| r.quantity != Quantity::DampingRatio || r.mean != 0.0 || r.std > 0.0)
        .map(|r| (r.quantity, r.mode))
        .collect();
    outputs.sort_by_key(|o| (o.1, o.0 as u8));
    outputs.dedup();
    let label = |q: Quantity, mode: Option<usize>| -> String {
        let name = match q {
            Quantity::DampedFrequency => format!("ω_d ({})", d.frequency.symbol()),
            Quantity::DampingRatio => "ζ".into(),
            Quantity::TransferMagnitude => match &model.analysis.transfer {
                Some(t) => format!("|H| ({})", model.transfer_unit(t)),
                None => "|H|".into(),
            },
        };
        mode.map_or(name.clone(), |m| format!("{name}, mode {}", m + 1))
    };
    let mut h = format!(
        "<h2>Summary: σ where it matters</h2><p>Per case, σ of each output by every method at \
         the speed of its largest σ, at the critical speeds (1×Ω) and at the |H| peak. \
         “first order vs answer” is first order's σ against the answer's (analytic); \
         “Monte Carlo agrees” says whether the answer lies inside Monte Carlo's 95 % interval \
         of σ. Speeds in {}.</p>",
        d.speed.symbol()
    );
    for (ci, c) in a.cases.iter().enumerate() {
        let find = |q: Quantity, mode: Option<usize>, m: Method, w: f64| {
            a.rows.iter().find(|r| {
                r.case == ci
                    && r.quantity == q
                    && r.mode == mode
                    && r.method == m
                    && r.speed.to_bits() == w.to_bits()
            })
        };
        let answers = |q: Quantity, mode: Option<usize>| -> Vec<&Row> {
            a.rows
                .iter()
                .filter(|r| r.case == ci && r.quantity == q && r.mode == mode)
                .filter(|r| r.method == Method::Analytic && r.std.is_finite())
                .collect()
        };
        // (output, where, speed) triples.
        let mut places: Vec<(Quantity, Option<usize>, String, f64)> = Vec::new();
        for &(q, mode) in &outputs {
            if let Some(r) = answers(q, mode)
                .into_iter()
                .max_by(|x, y| x.std.total_cmp(&y.std))
            {
                places.push((q, mode, "largest σ".into(), r.speed));
            }
        }
        for cs in critical
            .iter()
            .filter(|c| c.order.to_bits() == 1f64.to_bits() && c.mode < MODES)
        {
            let rows = answers(Quantity::DampedFrequency, Some(cs.mode));
            if let Some(r) = rows.iter().min_by(|x, y| {
                (x.speed - cs.speed)
                    .abs()
                    .total_cmp(&(y.speed - cs.speed).abs())
            }) {
                places.push((
                    Quantity::DampedFrequency,
                    Some(cs.mode),
                    format!("critical speed {:.4}", cs.speed * fs),
                    r.speed,
                ));
            }
        }
        if let Some(r) = answers(Quantity::TransferMagnitude, None)
            .into_iter()
            .max_by(|x, y| x.mean.total_cmp(&y.mean))
        {
            places.push((
                Quantity::TransferMagnitude,
                None,
                "|H| peak".into(),
                r.speed,
            ));
        }
        if places.is_empty() {
            continue;
        }
        let _ = write!(
            h,
            "<h3>case {}</h3><table><tr><th>output</th><th>where</th><th>speed</th><th>mean</th>\
             <th>σ analytic (the answer)</th><th>σ first order</th><th>σ second order</th>\
             <th>σ Monte Carlo [95 %]</th><th>first order vs answer</th><th>Monte Carlo agrees</th></tr>",
            esc(&c.name)
        );
        let num = |v: Option<f64>| v.filter(|x| x.is_finite()).map_or("–".to_string(), sig);
        for (q, mode, place, w) in places {
            let ys = if q == Quantity::DampedFrequency {
                d.frequency.per_rad_per_second()
            } else {
                1.0
            };
            let get = |m: Method| find(q, mode, m, w);
            let answer = get(Method::Analytic);
            let sa = answer.map(|r| r.std);
            let sf = get(Method::FirstOrder).map(|r| r.std);
            let mc = get(Method::MonteCarlo).and_then(|r| r.mc);
            let vs = sa
                .zip(sf)
                .filter(|(a, f)| *a > 0.0 && a.is_finite() && f.is_finite())
                .map_or("–".to_string(), |(a, f)| {
                    // No "-0 %": a difference that rounds to nothing is 0.
                    let pct = (100.0 * (f - a) / a).round();
                    format!("{:+.0} %", if pct == 0.0 { 0.0 } else { pct })
                });
            let agrees = sa.zip(mc).map_or("–", |(s, m)| {
                if s >= m.std_ci.0 && s <= m.std_ci.1 {
                    "yes"
                } else {
                    "no"
                }
            });
            let mc_text = mc.map_or("–".to_string(), |m| {
                format!(
                    "{} [{}, {}]",
                    num(Some(m.std * ys)),
                    num(Some(m.std_ci.0 * ys)),
                    num(Some(m.std_ci.1 * ys))
                )
            });
            let _ = write!(
                h,
                "<tr><td style=\"text-align:left\">{}</td><td style=\"text-align:left\">{}</td><td>{:.4}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{vs}</td><td>{agrees}</td></tr>",
                esc(&label(q, mode)),
                esc(&place),
                w * fs,
                num(answer.map(|r| r.mean * ys)),
                num(sa.map(|s| s * ys)),
                num(sf.map(|s| s * ys)),
                num(get(Method::SecondOrder).map(|r| r.std * ys)),
                mc_text,
            );
        }
        h.push_str("</table>");
    }
    h
}

/// The rows without a value, per case, method, output and reason, with their speeds.
fn unfilled_table(a: &Analysis) -> String {
    let groups = unfilled(a);
    if groups.is_empty() {
        return String::new();
    }
    let mut h = String::from(
        "<h2>Rows without a value</h2><p>Where a method gives no mean and σ, and why          (<code>tolerance.csv</code>'s <code>reason</code> column; speeds in rad/s).</p>         <table><tr><th>case</th><th>method</th><th>output</th><th>rows</th><th>speeds</th>         <th>reason</th></tr>",
    );
    for u in &groups {
        let output = u.mode.map_or(u.quantity.as_str().to_string(), |m| {
            format!("{} mode {}", u.quantity.as_str(), m + 1)
        });
        let lo = u.speeds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = u.speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let speeds = if lo.to_bits() == hi.to_bits() {
            format!("{lo}")
        } else {
            format!("{lo}–{hi}")
        };
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>             <td style=\"text-align:left\">{}</td></tr>",
            esc(&a.cases[u.case].name),
            u.method.as_str(),
            esc(&output),
            u.speeds.len(),
            speeds,
            esc(&u.reason)
        );
    }
    h.push_str("</table>");
    h
}

/// A number to five significant digits, in fixed notation where that stays short.
fn sig(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let exp = x.abs().log10().floor() as i32;
    if (-3..5).contains(&exp) {
        format!("{x:.*}", (4 - exp).max(0) as usize)
    } else {
        format!("{x:.4e}")
    }
}

/// Escapes text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `report.html`: the numeric summary per case, the timing table (beside the paper's Tables 1–2
/// for its two examples), the critical speeds, a short reading guide and the plots (each an
/// `<stem>.svg` in the same directory), in the display units `d`.
pub fn report_html(
    model: &Model,
    a: &Analysis,
    plots: &[&Plot],
    critical: &[crate::plots::CriticalSpeed],
    mc: Option<&McOptions>,
    d: Display,
) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>modaltol: {}</title>\n<style>body{{font-family:sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;color:#222}}table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:4px 10px;text-align:right}}th{{background:#eee}}img{{max-width:100%;border:1px solid #ddd;margin:0.5em 0}}code{{background:#f4f4f4}}</style></head><body>\n",
        esc(&model.name)
    );
    let _ = writeln!(h, "<h1>Tolerance analysis: {}</h1>", esc(&model.name));
    if let Some(m) = mc.filter(|m| a.interrupted(m.samples)) {
        let _ = writeln!(
            h,
            "<p><b>Partial result:</b> the Monte Carlo was interrupted; samples done per case {:?} of {} asked.</p>",
            a.samples_done, m.samples
        );
    }
    for w in inadmissible_warnings(a) {
        let _ = writeln!(h, "<p><b>Warning:</b> {}</p>", esc(&w));
    }
    let _ = writeln!(
        h,
        "<p>Model file <code>{}</code>. Speeds {} points. Speeds in {}, frequencies in {} here; the CSV and JSON files are in SI units (rad/s).</p>",
        esc(&model.file),
        a.nominal.len(),
        d.speed.symbol(),
        d.frequency.symbol()
    );
    let _ = writeln!(h, "{}", summary_table(model, a, critical, d));
    let _ = writeln!(
        h,
        "<h2>Tolerance cases</h2><table><tr><th>case</th><th>variable</th><th>nominal</th><th>tolerance (±, = 3σ for normal)</th></tr>"
    );
    for c in &a.cases {
        for (b, t) in &c.tolerances {
            let p = &model.parameters[*b];
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.6}</td></tr>",
                esc(&c.name),
                esc(&p.name),
                p.value,
                t.absolute(p.value)
            );
        }
    }
    let _ = writeln!(h, "</table>");
    let _ = writeln!(
        h,
        "<h2>Timing</h2><table><tr><th></th><th>analytic, Taylor methods (s)</th><th>quadrature (s)</th><th>Monte Carlo (s)</th><th>ratio Monte Carlo / analytic</th><th>ratio Monte Carlo / quadrature</th></tr>"
    );
    if let Some((example, analytic, mc, ratio)) = paper_timings(model) {
        let _ = writeln!(
            h,
            "<tr><td>paper, {example} (2007 hardware, 3000 samples)</td><td>{analytic}</td><td>–</td><td>{mc}</td><td>{ratio}</td><td>–</td></tr>"
        );
    }
    let secs = |t: Option<f64>| t.map_or("not run".to_string(), |t| format!("{t:.3}"));
    let ratio = |b: Option<f64>| {
        a.monte_carlo_seconds
            .zip(b)
            .map_or("–".to_string(), |(m, b)| format!("{:.0}", m / b))
    };
    let samples = mc.map_or(String::new(), |m| {
        format!(
            ", {} samples, {:?} sampling, seed {}",
            m.samples, m.sampling, m.seed
        )
    });
    let _ = writeln!(
        h,
        "<tr><td>this run ({} case(s), {} speeds{samples})</td><td>{:.3}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr></table>",
        a.cases.len(),
        a.nominal.len(),
        a.analytic_seconds,
        secs(a.quadrature_seconds),
        secs(a.monte_carlo_seconds),
        ratio(Some(a.analytic_seconds)),
        ratio(a.quadrature_seconds),
    );
    let _ = writeln!(
        h,
        "<p>The analytic time covers the nominal sweep, exact gradients and Hessians at every speed and the Taylor methods for all cases; the paper's covers first order only. The quadrature sweeps its nodes across all speeds like Monte Carlo samples ({}).</p>",
        a.cases
            .iter()
            .zip(&a.quadrature_rules)
            .map(|(c, (rule, _))| format!("{}: {}", esc(&c.name), esc(rule)))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let _ = writeln!(h, "{}", first_order_table(a));
    if !critical.is_empty() {
        let u = d.speed.symbol();
        let _ = writeln!(
            h,
            "<h2>Critical speeds</h2><table><tr><th>mode</th><th>engine order</th><th>speed ({u})</th><th>σ ({u}), case {}</th></tr>",
            esc(&a.cases[0].name)
        );
        let f = d.speed.per_rad_per_second();
        for c in critical {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}×</td><td>{:.4}</td><td>{:.4}</td></tr>",
                c.mode + 1,
                c.order,
                c.speed * f,
                c.std * f
            );
        }
        let _ = writeln!(h, "</table>");
    }
    if !a.failures.is_empty() {
        let _ = writeln!(h, "<h2>Failed speeds</h2><ul>");
        for (w, m) in &a.failures {
            let _ = writeln!(h, "<li>{w} rad/s: {}</li>", esc(m));
        }
        let _ = writeln!(h, "</ul>");
    }
    h.push_str(&unfilled_table(a));
    let _ = writeln!(
        h,
        "<h2>Reading guide</h2><ul>\
<li><b>first_order</b> is the paper's method: mean = nominal value, σ² = Σ (∂f/∂b)² σ_b² with exact derivatives. It is right where the output is smooth and the tolerances small.</li>\
<li><b>second_order</b> adds the curvature (Hessians): a mean shift and variance terms. It repairs points where first order gives σ = 0 but the output does vary (|H| at the undamped resonance).</li>\
<li><b>invariant</b> (ω_d only) propagates the pair discriminant D = λ₁λ₂ − (λ₁+λ₂)²/4, which stays smooth where a mode turns overdamped, and maps it through ω_d = √max(0, D). Use it near class changes, where first and second order fail.</li>\
<li><b>quadrature</b> integrates the whole nonlinear analysis (equilibrium, modes, |H|) over the distribution of the design variables, deterministically: every node is swept from the lowest speed like a Monte Carlo sample, the integral is split where a mode turns overdamped or a design passes its own bifurcation, and every mean and σ comes with an error estimate (<code>mean_error</code>, <code>std_error</code>) and the 5/50/95 % quantiles. It is right at every speed, class changes and branch switches included.</li>\
<li><b>analytic</b> is the answer to read: the quadrature where it ran (its <code>basis</code> says so), else the automatic Taylor choice (invariant near a change of class, else second order). Red marks in the band plots show the speeds where first order's σ is more than 10 % off.</li>\
<li><b>monte_carlo</b> re-runs the whole nonlinear analysis per sample, with 95 % confidence intervals in <code>tolerance.csv</code> and counts of failed samples and of samples whose mode changed class. Where the distribution is a mixture (most samples overdamped, a few far out), a few thousand samples are far from converged; the quadrature is not.</li>\
<li><b>Probabilities</b> (<code>probabilities.csv</code>): per speed, the probability that a mode is overdamped, that the equilibrium is unstable, and that a design is on another equilibrium branch than the nominal one, by quadrature (± its error estimate) and Monte Carlo (95 % Wilson interval).</li>\
<li>Band plots shade the analytic mean ± σ; the Campbell diagram shows ±3σ (analytic) of the first case, the engine orders and the critical speeds where a mode crosses one.</li></ul>"
    );
    let _ = writeln!(h, "<h2>Plots</h2>");
    for p in plots {
        let _ = writeln!(
            h,
            "<figure><img src=\"{}.svg\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            esc(&p.stem),
            esc(&p.title),
            esc(&p.caption)
        );
    }
    let _ = writeln!(h, "</body></html>");
    h
}
