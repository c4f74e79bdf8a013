//! The summary `check` prints: what a model file holds (bodies, joints, coordinates, beams
//! and their nodes, constraints, parameters, tolerance cases) and the physical limits its
//! tolerances reach. A file of its own because it formats the model, not a result.

use crate::compiled::Compiled;
use crate::modal::{C64, ModeClass};
use crate::model::Model;
use crate::scene::describe;
use crate::sweep::{Options, initial_guess, point};
use std::fmt::Write;

/// What `check` prints: [`check_summary`], then what solving the model at its first analysed
/// speed shows ([`solved_warnings`]).
pub fn check_report(model: &Compiled) -> String {
    let mut s = check_summary(model.model());
    for warning in solved_warnings(model) {
        let _ = writeln!(s, "  warning: {warning}");
    }
    s
}

/// The warnings that need a solve: the model at its nominal parameters and its first analysed
/// speed (0 where it gives none) has no equilibrium or no modes (why, and where to look), or
/// has a rigid-body mode: a zero root, a coordinate nothing restores (a rotor with no
/// bearing in one direction, a joint with neither spring nor drive). Such a mode loads without
/// an error and drops out of every frequency requirement, so where it is not meant only this
/// says so.
pub fn solved_warnings(model: &Compiled) -> Vec<String> {
    let m = model.model();
    let first = (m.analysis.speed).and_then(|g| g.speeds().next());
    let speed = first.unwrap_or(0.0);
    let p = m.nominal();
    let solved = initial_guess(m, &p, speed)
        .map_err(crate::sweep::PointError::from)
        .and_then(|q0| point(model, &p, speed, &q0, &Options::default()));
    let at = match first {
        Some(_) => format!("at {speed} rad/s (the first speed analysed)"),
        None => "at rest (the model gives no [analysis] speed)".to_string(),
    };
    let pt = match solved {
        Ok(pt) => pt,
        Err(e) => {
            return vec![format!(
                "{at} the model has no result: {e}; `modaltol modal MODEL --speed {speed}` \
                 says the same, and `draw` shows the configuration the solve starts from"
            )];
        }
    };
    (pt.modes.iter().zip(&pt.shapes).enumerate())
        .filter(|(_, (mode, _))| mode.class == ModeClass::Rigid)
        .map(|(k, (_, shape))| {
            let v: Vec<C64> = shape.iter().copied().collect();
            format!(
                "{at} mode {} is a rigid-body mode (a zero root): nothing restores its \
                 largest coordinate, {}, so the mechanism may drift along it, and the mode is \
                 left out of every frequency requirement; where that is not meant, restrain it \
                 (a spring, bushing or bearing on that joint, or drive it)",
                k + 1,
                describe(m, &pt.linear.free, &v, None)
            )
        })
        .collect()
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
    let jw = wide(model.joints.iter().map(|j| j.name.as_str()), 12);
    let kw = wide(model.joints.iter().map(|j| j.kind.name()), 10);
    let pw = wide(model.parameters.iter().map(|p| p.name.as_str()), 14);
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
    beams(&mut s, model);
    loads(&mut s, model);
    constraints(&mut s, model);
    let _ = writeln!(s, "  degrees of freedom: {}", model.dof());
    frames(&mut s, model);
    parameters(&mut s, model, pw);
    if !model.analysis.cases.is_empty() {
        let names: Vec<&str> = model
            .analysis
            .cases
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        let _ = writeln!(s, "  tolerance cases: {}", names.join(", "));
    }
    if !model.requirements.is_empty() {
        let _ = writeln!(s, "  requirements ({}):", model.requirements.len());
        let w = wide(model.requirements.iter().map(|r| r.name.as_str()), 12);
        for r in &model.requirements {
            let _ = writeln!(s, "    {:<w$} {}", r.name, super::yields::describe(r));
        }
    }
    for warning in model.warnings() {
        let _ = writeln!(s, "  warning: {warning}");
    }
    for (case, at, defect) in model.tolerance_limits() {
        let _ = writeln!(
            s,
            "  warning: case '{case}' reaches a physical limit within its tolerances: at {at}, {defect}; Monte Carlo samples beyond it count as failed"
        );
    }
    s
}

/// Which free coordinates a driven rotation turns (their modes' frequencies are seen from the
/// rotating frame) and which are measured from ground (the fixed frame), by joint.
fn frames(s: &mut String, model: &Model) {
    let turned = model.turned_by();
    let free = model.free();
    let mut rotating: Vec<(String, &str)> = Vec::new();
    let mut fixed: Vec<&str> = Vec::new();
    for (j, joint) in model.joints.iter().enumerate() {
        let Some(&c) = free.iter().find(|&&c| model.coordinates[c].joint == j) else {
            continue;
        };
        match turned[c] {
            Some(d) => rotating.push((model.joints[d].name.clone(), joint.name.as_str())),
            None => fixed.push(joint.name.as_str()),
        }
    }
    let _ = writeln!(
        s,
        "  frames (a mode's frequency is seen from the frame of its coordinates):"
    );
    let mut by: Vec<&str> = Vec::new();
    for (d, _) in &rotating {
        if !by.contains(&d.as_str()) {
            by.push(d);
        }
    }
    for d in by {
        let names: Vec<&str> = (rotating.iter())
            .filter(|(x, _)| *x == d)
            .map(|(_, n)| *n)
            .collect();
        let _ = writeln!(s, "    rotating with '{d}': {}", abbreviated(&names));
    }
    if !fixed.is_empty() {
        let _ = writeln!(s, "    fixed (ground): {}", abbreviated(&fixed));
    }
}

/// Names joined by commas, the middle of a long list left out (a meshed shaft has hundreds).
fn abbreviated(names: &[&str]) -> String {
    if names.len() <= 8 {
        names.join(", ")
    } else {
        format!(
            "{}, … ({} more), {}",
            names[..3].join(", "),
            names.len() - 5,
            names[names.len() - 2..].join(", ")
        )
    }
}

/// Columns as wide as the longest name (at least `least`), so that long names do not push
/// them out of line.
fn wide<'a>(names: impl Iterator<Item = &'a str>, least: usize) -> usize {
    names
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(least)
}

/// The applied loads, where there are any.
/// The beam elements (each with its two nodes' bodies and its section's form) and the bodies
/// that are their nodes.
fn beams(s: &mut String, model: &Model) {
    if model.beams.is_empty() {
        return;
    }
    let body = |b: Option<usize>| b.map_or("ground", |i| model.bodies[i].name.as_str());
    let _ = writeln!(s, "  beams ({}):", model.beams.len());
    let w = wide(model.beams.iter().map(|b| b.name.as_str()), 12);
    for b in &model.beams {
        let section = match b.section {
            crate::model::BeamSection::Tube(_) => "tube",
            crate::model::BeamSection::Properties(_) => "section properties",
        };
        let _ = writeln!(
            s,
            "    {:<w$} {} → {} ({section})",
            b.name,
            body(b.body1),
            body(b.body2)
        );
    }
    let mut nodes: Vec<usize> = (model.beams.iter())
        .flat_map(|b| [b.body1, b.body2])
        .flatten()
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let names: Vec<&str> = nodes
        .iter()
        .map(|&i| model.bodies[i].name.as_str())
        .collect();
    let _ = writeln!(s, "  beam nodes ({}): {}", names.len(), names.join(", "));
}

fn loads(s: &mut String, model: &Model) {
    if !model.loads.is_empty() {
        let _ = writeln!(s, "  loads ({}):", model.loads.len());
        for l in &model.loads {
            let what = match &l.kind {
                crate::model::LoadKind::Force { body, follower, .. } => format!(
                    "force on {}{}",
                    model.bodies[*body].name,
                    if *follower { ", turning with it" } else { "" }
                ),
                crate::model::LoadKind::Torque { body, follower, .. } => format!(
                    "torque on {}{}",
                    model.bodies[*body].name,
                    if *follower { ", turning with it" } else { "" }
                ),
                crate::model::LoadKind::Coordinate { coordinate, .. } => format!(
                    "generalised force on {}",
                    model.coordinates[*coordinate].name
                ),
            };
            let _ = writeln!(s, "    {}: {what}", l.name);
        }
    }
}

/// The cut joints (with their equations dropped as redundant) and the couplers.
fn constraints(s: &mut String, model: &Model) {
    let _ = writeln!(
        s,
        "  constraints: {} ({} equations)",
        model.constraints.len(),
        model.n_constraints()
    );
    for c in &model.constraints {
        if c.dropped.is_empty() {
            let _ = writeln!(s, "    {}", c.name);
        } else {
            let _ = writeln!(
                s,
                "    {} ({} of its {} equations redundant as drawn, dropped: {})",
                c.name,
                c.dropped.len(),
                c.kind.equations(),
                c.dropped
                    .iter()
                    .map(|e| format!("#{}", e + 1))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    for c in &model.couplers {
        let _ = writeln!(
            s,
            "    {} (coupler: {}, {})",
            c.name,
            model.coordinates[c.coordinates[0]].name,
            model.coordinates[c.coordinates[1]].name
        );
    }
}

/// The parameters with their tolerances (names in a column `pw` wide), and the derived ones.
fn parameters(s: &mut String, model: &Model, pw: usize) {
    let _ = writeln!(s, "  parameters ({}):", model.parameters.len());
    for p in &model.parameters {
        let tol = match p.tolerance {
            Some(crate::model::Tolerance::Relative(f)) => format!("  ± {}%", f * 100.0),
            Some(crate::model::Tolerance::Absolute(a)) => format!("  ± {a}"),
            None => String::new(),
        };
        let _ = writeln!(s, "    {:<pw$} {}{tol}", p.name, p.value);
    }
    if !model.derived.is_empty() {
        let dw = wide(model.derived.iter().map(|d| d.name.as_str()), 14);
        let _ = writeln!(
            s,
            "  derived parameters ({}, not design variables):",
            model.derived.len()
        );
        for d in &model.derived {
            let _ = writeln!(s, "    {:<dw$} {} = {}", d.name, d.value, d.text);
        }
    }
}
