//! The results of `modal` at one speed: the modes table (CSV), the JSON document and the text
//! table, each with the mode shapes scaled for display ([`display_shape`]). Together because
//! all three show the same point: its equilibrium, linearisation and modes.

use super::{MODE_COLUMNS, failed_rows, fixed, mode_cells, point_message};
use crate::mechanics::System;
use crate::modal::C64;
use crate::model::{FieldError, Model};
use crate::scene::{PhysicalShape, physical_shape};
use crate::sweep::{Point, PointError};
use crate::whirl::{self, Whirl};
use nalgebra::DMatrix;
use serde_json::{Value, json};
use std::fmt::Write;

/// A mode shape for display: scaled so that its largest component is 1 (real), the
/// convention of modal test reports; a zero shape stays zero. Where the largest component's
/// square under- or overflows, the division goes through its modulus first (a complex
/// division by it would give NaN).
pub fn display_shape(shape: &[C64]) -> Vec<C64> {
    let big = shape
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .filter(|z| z.norm() > 0.0);
    let divide = |z: C64, b: C64| {
        let square = b.norm_sqr();
        if square >= f64::MIN_POSITIVE && square.is_finite() {
            z / b
        } else {
            let r = b.norm();
            (z / r) * (b.conj() / r)
        }
    };
    shape
        .iter()
        .map(|&z| big.map_or(z, |b| divide(z, b)))
        .collect()
}

/// Header of the modes table (`modal --format csv`): the mode's frequencies, damping ratio,
/// its two roots, its `whirl` ([`crate::whirl`]: forward, backward, mixed or empty), then its
/// shape in the free coordinates, scaled by [`display_shape`]
/// (`shape_re:<joint>`, `shape_im:<joint>`), the displacement of each body's centre of mass
/// with that scaling (`cm_re:<body>.x` … `cm_im:<body>.z`, m per unit of the largest
/// coordinate, ground axes) and of each port along its direction (`port_re:<port>`,
/// `port_im:<port>`: m, or rad for a rotation port), then `branch` and `message` (the point's
/// note, or why it failed).
pub fn modes_header(model: &Model) -> Vec<String> {
    let mut h: Vec<String> = MODE_COLUMNS.iter().map(|s| s.to_string()).collect();
    h.push("whirl".into());
    for &i in &model.free() {
        let c = &model.coordinates[i].name;
        h.push(format!("shape_re:{c}"));
        h.push(format!("shape_im:{c}"));
    }
    for b in &model.bodies {
        for part in ["re", "im"] {
            for axis in ["x", "y", "z"] {
                h.push(format!("cm_{part}:{}.{axis}", b.name));
            }
        }
    }
    for p in &model.ports {
        h.push(format!("port_re:{}", p.name));
        h.push(format!("port_im:{}", p.name));
    }
    h.push("branch".into());
    h.push("message".into());
    h
}

/// Each mode's shape mapped onto the bodies and ports ([`physical_shape`]), scaled as
/// [`display_shape`] scales it (the largest coordinate component 1), at the point `pt` solved
/// with parameters `params`.
pub fn body_shapes(
    model: &Model,
    params: &[f64],
    pt: &Point,
) -> Result<Vec<PhysicalShape>, FieldError> {
    let sys = System::new(model, params, pt.speed)?;
    Ok(pt
        .shapes
        .iter()
        .map(|shape| {
            let shape: Vec<C64> = shape.iter().copied().collect();
            physical_shape(
                &sys,
                &pt.equilibrium.q,
                &pt.linear.free,
                &display_shape(&shape),
            )
        })
        .collect())
}

/// Rows of the modes table at the point `p` solved with parameters `params` (see
/// [`modes_header`]).
pub fn modes_rows(
    model: &Model,
    params: &[f64],
    p: &Point,
) -> Result<Vec<Vec<String>>, FieldError> {
    let bodies = body_shapes(model, params, p)?;
    let whirls = whirl::of_point(model, params, p)?;
    Ok(p.modes
        .iter()
        .zip(&p.shapes)
        .zip(&bodies)
        .enumerate()
        .map(|(i, ((m, shape), b))| {
            let mut r = mode_cells(p.speed, i, m);
            r.push(whirls[i].map_or("", Whirl::as_str).into());
            let shape: Vec<C64> = shape.iter().copied().collect();
            for z in display_shape(&shape) {
                r.push(z.re.to_string());
                r.push(z.im.to_string());
            }
            for d in &b.displacement {
                r.extend(d.iter().map(|z| z.re.to_string()));
                r.extend(d.iter().map(|z| z.im.to_string()));
            }
            for z in &b.ports {
                r.push(z.re.to_string());
                r.push(z.im.to_string());
            }
            r.push(p.branch.as_str().into());
            r.push(point_message(p, None));
            r
        })
        .collect())
}

/// Rows of the modes table of a point at `speed` that failed: one per degree of freedom,
/// status `failed`, the reason in `message` (as in a sweep).
pub fn modes_failed_rows(model: &Model, speed: f64, e: &PointError) -> Vec<Vec<String>> {
    failed_rows(model, modes_header(model).len(), speed, e)
}

fn matrix(m: &DMatrix<f64>) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// The `modal` result as JSON, the bodies' and ports' shapes at parameters `params`.
pub fn modal_json(
    model: &Model,
    params: &[f64],
    speed: f64,
    result: &Result<Point, PointError>,
) -> Value {
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
    let bodies = body_shapes(model, params, p).ok();
    let whirls = whirl::of_point(model, params, p).unwrap_or_default();
    let turned = model.turned_by();
    let frame = |i: usize| crate::scene::frame_of(&turned, &p.linear.free, p.shapes[i].as_slice());
    let pair = |z: &C64| json!({"re": z.re, "im": z.im});
    let motion = |i: usize| -> Value {
        let Some(b) = bodies.as_ref().and_then(|b| b.get(i)) else {
            return Value::Null;
        };
        json!({
            "bodies": model.bodies.iter().enumerate().map(|(k, body)| json!({
                "name": body.name,
                "displacement": b.displacement[k].iter().map(pair).collect::<Vec<_>>(),
                "rotation": b.rotation[k].iter().map(pair).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
            "ports": model.ports.iter().zip(&b.ports).map(|(port, z)| json!({
                "name": port.name, "re": z.re, "im": z.im,
                "unit": if port.rotation { "rad" } else { "m" },
            })).collect::<Vec<_>>(),
        })
    };
    let modes: Vec<Value> = p
        .modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            json!({"mode": i + 1, "status": m.class.as_str(),
                   "damped_frequency": m.damped_frequency, "natural_frequency": m.natural_frequency,
                   "damping_ratio": m.damping_ratio,
                   "whirl": whirls.get(i).copied().flatten().map(Whirl::as_str),
                   "frame": if frame(i).is_some() { "rotating" } else { "fixed" },
                   "frame_turned_by": frame(i).map(|j| model.joints[j].name.clone()),
                   "eigenvalue": {"re": m.root.lambda.re, "im": m.root.lambda.im},
                   "partner_eigenvalue": {"re": m.partner.lambda.re, "im": m.partner.lambda.im},
                   "shape": model.free().iter().zip(display_shape(p.shapes[i].as_slice())).map(|(&c, z)| json!({"coordinate": model.coordinates[c].name, "re": z.re, "im": z.im, "unit": model.coordinates[c].unit.symbol()})).collect::<Vec<_>>(),
                   "motion": motion(i)})
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
        "units": {"speed": "rad/s", "frequency": "rad/s", "revolute": "rad", "prismatic": "m",
                  "shape": "each mode's shape is scaled so that its largest coordinate component is 1 (rad or m); its motion gives, per unit of that component, each body's centre-of-mass displacement (m) and small rotation (rad) in ground axes, and each port's displacement along its direction (m, or rad for a rotation port)"},
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

/// The `modal` result as a text table, the modes' frequencies in `unit` (the eigenvalues stay
/// in 1/s).
pub fn modal_table(
    model: &Model,
    params: &[f64],
    speed: f64,
    result: &Result<Point, PointError>,
    unit: crate::plots::FrequencyUnit,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model: {}    speed: {speed:?} rad/s", model.name);
    let p = match result {
        Err(e) => {
            let _ = writeln!(s, "FAILED: {e}");
            return s;
        }
        Ok(p) => p,
    };
    write_equilibrium(&mut s, model, p);
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
    let _ = writeln!(
        s,
        "\nmodes (frequencies in {}, eigenvalues in 1/s; each frequency as seen from the \
         mode's frame: fixed = ground, rotating = turning with the driven joint named):",
        unit.symbol()
    );
    let f = unit.per_rad_per_second();
    // Angular frequencies in rad/s, cyclic ones (f = ω/2π) in Hz or rpm.
    let (wd, wn) = if unit == crate::plots::FrequencyUnit::RadPerSecond {
        ("ω_d", "ω_n")
    } else {
        ("f_d", "f_n")
    };
    let _ = writeln!(
        s,
        "  {:>4}  {:<12} {:>14} {:>14} {:>12} {:>26}  {:<8}  frame",
        "mode", "status", wd, wn, "ζ", "eigenvalue", "whirl"
    );
    let whirls = whirl::of_point(model, params, p).unwrap_or_default();
    let turned = model.turned_by();
    for (i, m) in p.modes.iter().enumerate() {
        let frame = crate::scene::frame_of(&turned, &p.linear.free, p.shapes[i].as_slice());
        let _ = writeln!(
            s,
            "  {:>4}  {:<12} {:>14.8} {:>14.8} {:>12} {:>12.6} {:+12.6}i  {:<8}  {}",
            i + 1,
            m.class.as_str(),
            m.damped_frequency * f,
            m.natural_frequency * f,
            fixed(m.damping_ratio, 6),
            m.root.lambda.re,
            m.root.lambda.im,
            whirls.get(i).copied().flatten().map_or("", Whirl::as_str),
            crate::scene::frame_words(model, frame)
        );
    }
    write_shapes(&mut s, model, p);
    let _ = writeln!(s, "\nbranch: {}: {}", p.branch.as_str(), p.branch);
    if let Some(n) = &p.note {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// The equilibrium of the `modal` text table: each coordinate's value (and speed, where it is
/// driven), then the drive forces.
fn write_equilibrium(s: &mut String, model: &Model, p: &Point) {
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
}

/// The mode shapes of the `modal` text table: one column per mode, one row per free
/// coordinate, scaled by [`display_shape`], as magnitude ∠ phase.
fn write_shapes(s: &mut String, model: &Model, p: &Point) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shape of subnormal or huge components is displayed with its largest component 1,
    /// never NaN (a complex division by a subnormal number is).
    #[test]
    fn shapes_of_any_scale_display_finite() {
        // The first scale has one significant bit: its components' ratios are rounded.
        for (k, s) in [5e-324, 1e-310, 1e-160, 1.0, 1e300].into_iter().enumerate() {
            let shape = [C64::new(3.0 * s, -s), C64::new(0.0, 2.0 * s)];
            let shown = display_shape(&shape);
            assert!(
                shown.iter().all(|z| z.re.is_finite() && z.im.is_finite()),
                "{s}: {shown:?}"
            );
            assert!(
                (shown[0] - C64::new(1.0, 0.0)).norm() < 1e-12 || k == 0,
                "{s}: {shown:?}"
            );
        }
    }
}
