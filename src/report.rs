//! Formatting of results: CSV rows, JSON documents and text tables. Builds strings and values;
//! writing them anywhere is the CLI's business.
//!
//! Units: speeds and frequencies in rad/s, angles in rad, translations in m, drive forces in
//! N·m (revolute) or N (prismatic), damping ratios dimensionless.

use crate::model::{JointKind, Model};
use crate::sweep::{Point, PointError};
use nalgebra::DMatrix;
use serde_json::{Value, json};
use std::fmt::Write;

/// Unit of a coordinate of the given joint kind.
pub fn coordinate_unit(kind: JointKind) -> &'static str {
    match kind {
        JointKind::Prismatic => "m",
        _ => "rad",
    }
}

/// Unit of the generalised force on a coordinate of the given kind.
pub fn force_unit(kind: JointKind) -> &'static str {
    match kind {
        JointKind::Prismatic => "N",
        _ => "N·m",
    }
}

/// Header of the sweep CSV.
pub fn sweep_header(model: &Model) -> Vec<String> {
    let mut h: Vec<String> = [
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
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    h.extend(model.coordinates.iter().map(|c| format!("q:{}", c.name)));
    h.extend(
        model
            .driven()
            .iter()
            .map(|&i| format!("drive:{}", model.coordinates[i].name)),
    );
    h.push("iterations".into());
    h.push("message".into());
    h
}

/// Rows of the sweep CSV for one speed: one per mode (a failed speed gets one `failed` row per
/// degree of freedom, with the reason).
pub fn sweep_rows(
    model: &Model,
    speed: f64,
    result: &Result<Point, PointError>,
) -> Vec<Vec<String>> {
    let ncols = sweep_header(model).len();
    match result {
        Ok(p) => p
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let mut r = vec![
                    speed.to_string(),
                    (i + 1).to_string(),
                    m.class.as_str().to_string(),
                    m.damped_frequency.to_string(),
                    m.natural_frequency.to_string(),
                    m.damping_ratio.to_string(),
                    m.root.lambda.re.to_string(),
                    m.root.lambda.im.to_string(),
                    m.partner.lambda.re.to_string(),
                    m.partner.lambda.im.to_string(),
                ];
                r.extend(p.equilibrium.q.iter().map(|v| v.to_string()));
                r.extend(
                    model
                        .driven()
                        .iter()
                        .map(|&d| p.equilibrium.drive_force[d].to_string()),
                );
                r.push(p.equilibrium.iterations.to_string());
                r.push(p.note.clone().unwrap_or_default());
                r
            })
            .collect(),
        Err(e) => (0..model.dof().max(1))
            .map(|i| {
                let mut r = vec![String::new(); ncols];
                r[0] = speed.to_string();
                r[1] = (i + 1).to_string();
                r[2] = "failed".into();
                r[ncols - 1] = e.to_string();
                r
            })
            .collect(),
    }
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
            json!({"name": c.name, "value": eq.q[i], "unit": coordinate_unit(c.kind), "driven": c.driven,
                   "speed": eq.qd[i]})
        })
        .collect();
    let drives: Vec<Value> = model
        .driven()
        .iter()
        .map(|&i| {
            let c = &model.coordinates[i];
            json!({"name": c.name, "force": eq.drive_force[i], "unit": force_unit(c.kind)})
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
                   "shape": p.shapes[i].iter().map(|z| json!({"re": z.re, "im": z.im})).collect::<Vec<_>>()})
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
    let _ = writeln!(s, "model: {}    speed: {speed} rad/s", model.name);
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
            format!("  driven at {} {}/s", eq.qd[i], coordinate_unit(c.kind))
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {:<16} {:>16.10} {}{tag}",
            c.name,
            eq.q[i],
            coordinate_unit(c.kind)
        );
    }
    for &i in &model.driven() {
        let c = &model.coordinates[i];
        let _ = writeln!(
            s,
            "  drive force on {:<8} {:>14.8e} {}",
            c.name,
            eq.drive_force[i],
            force_unit(c.kind)
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
            "  {:>4}  {:<12} {:>14.8} {:>14.8} {:>12.6} {:>12.6} {:+12.6}i",
            i + 1,
            m.class.as_str(),
            m.damped_frequency,
            m.natural_frequency,
            m.damping_ratio,
            m.root.lambda.re,
            m.root.lambda.im
        );
    }
    if let Some(n) = &p.note {
        let _ = writeln!(s, "\nnote: {n}");
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
    for j in &model.joints {
        let kind = format!("{:?}", j.kind).to_lowercase();
        let drive = if j.drive.is_some() { ", driven" } else { "" };
        let _ = writeln!(
            s,
            "    {:<12} {:<10} {} → {}{drive}",
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
        let _ = writeln!(s, "    {:<14} {}{tol}", p.name, p.value);
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
    s
}
