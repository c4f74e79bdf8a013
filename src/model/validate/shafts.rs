//! The `[[shafts]]` tables: a straight shaft or blade given as stations (a length, a section,
//! a number of elements), written out as the tables a user would otherwise write by hand: a
//! massless body per node on a `free` joint from the parent (and, for a spinning shaft, a
//! massless frame on the free joint and the node on a `revolute` about the axis driven at
//! `spin`: the stationary-frame model of rotordynamics), and a `[[beams]]` element between
//! consecutive nodes. The later stages then check what was generated like anything written,
//! and their messages point at the field the generated item came from.
//!
//! Names: node `k` (from 0 at `start`) is the body `<shaft>_<k>` on the joint `<shaft>_<k>`
//! (coordinates `<shaft>_<k>.x` … `.rz`); a spinning node's frame is the body
//! `<shaft>_<k>_frame` and its spin the joint `<shaft>_<k>_spin`; element `k` (from node
//! `k − 1` to node `k`) is the beam `<shaft>_e<k>`; the coupling, the force element
//! `<shaft>_coupling`. A tapered station's elements take the section at their midpoints
//! (a stepped shaft converging to the taper as elements are added).

use super::names::check_name;
use super::{Ctx, R};
use crate::model::schema::{
    BeamSchema, BodySchema, FileSchema, ForceSchema, JointSchema, Num, Nums, SNum, SNums, SVec,
    ShaftSchema, StationSchema,
};
use std::ops::Range;
use toml::Spanned;

/// Most elements in one station, and in all the shafts of a model together: a bound on what a
/// mistyped count can ask of memory and time (a 10 000-element model has 60 000 coordinates).
const MAX_ELEMENTS: i64 = 10_000;

/// Longest text of a node's arc length (an expression is at most 4096 bytes; the rest of a
/// position's text is the start and the axis).
const MAX_ARC_TEXT: usize = 3000;

/// Longest shaft name: the generated names add up to `_<k>_frame` to it.
const MAX_SHAFT_NAME: usize = 48;

/// Replaces the `[[shafts]]` tables of `raw` by the bodies, joints, force elements and beams
/// they stand for.
pub(super) fn expand(ctx: &Ctx, raw: &mut FileSchema) -> R<()> {
    let shafts = std::mem::take(&mut raw.shafts);
    // Counted before anything is generated, so a mistyped count costs nothing.
    let mut total = 0;
    for s in &shafts {
        let owner = format!("shaft '{}'", s.get_ref().name.get_ref());
        for (i, st) in s.get_ref().stations.get_ref().iter().enumerate() {
            total += elements(ctx, &owner, i, st)?;
            if total > MAX_ELEMENTS as usize {
                return Err(ctx.err(
                    st.span(),
                    format!(
                        "the shafts have more than {MAX_ELEMENTS} elements together (here {total})"
                    ),
                ));
            }
        }
    }
    for s in &shafts {
        mesh(ctx, s.get_ref(), raw)?;
    }
    Ok(())
}

/// An expression's text, parenthesised, to be composed with others.
fn text(n: &Num) -> String {
    match n {
        Num::Value(v) => format!("({v:e})"),
        Num::Expr(s) => format!("({s})"),
    }
}

fn expr(span: Range<usize>, s: String) -> SNum {
    Spanned::new(span, Num::Expr(s))
}

fn named(span: &Range<usize>, s: String) -> Spanned<String> {
    Spanned::new(span.clone(), s)
}

/// Writes out shaft `s` into `raw`; returns its number of elements.
fn mesh(ctx: &Ctx, s: &ShaftSchema, raw: &mut FileSchema) -> R<usize> {
    check_name(ctx, &s.name, "shaft")?;
    let name = s.name.get_ref();
    let here = s.name.span();
    if name.chars().count() > MAX_SHAFT_NAME {
        return Err(ctx.err(
            here,
            format!("shaft name '{name}' is longer than {MAX_SHAFT_NAME} characters (its nodes' names add to it)"),
        ));
    }
    let owner = format!("shaft '{name}'");
    let stations = s.stations.get_ref();
    if stations.is_empty() {
        return Err(ctx.err(
            s.stations.span(),
            format!("{owner}: no stations; give at least one [[shafts.stations]] with its length"),
        ));
    }
    ctx.vec3(&s.start, format!("{owner} start"))?;
    let axis = unit_axis(ctx, &owner, &s.axis)?;
    if let Some(spin) = &s.spin {
        ctx.field(spin, format!("{owner} spin"))?;
    }
    if let Some(c) = &s.coupling {
        if s.spin.is_none() {
            return Err(ctx.err(
                c.span(),
                format!("{owner}: a coupling holds a spinning shaft's twist; without `spin`, hold the nodes with force elements"),
            ));
        }
        ctx.field(c, format!("{owner} coupling"))?;
        if let Some(b) = &s.start_body {
            return Err(ctx.err(
                c.span(),
                format!("{owner}: the coupling holds the first generated node's frame, and `start_body` '{}' is the first node: hold the twist at that body instead", b.get_ref()),
            ));
        }
    }
    if s.spin.is_some() {
        for b in [&s.start_body, &s.end_body].into_iter().flatten() {
            if b.get_ref() == "ground" {
                return Err(ctx.err(
                    b.span(),
                    format!("{owner}: its nodes spin, and the ground does not: a spinning shaft ends on a body that turns with it (a driven hub), or on a generated node held by a bearing"),
                ));
            }
        }
    }
    if let (Some(a), Some(b)) = (&s.start_body, &s.end_body) {
        let count: i64 = (stations.iter())
            .map(|st| st.get_ref().elements.as_ref().map_or(1, |n| *n.get_ref()))
            .sum();
        if a.get_ref() == b.get_ref() && count == 1 {
            return Err(ctx.err(
                b.span(),
                format!(
                    "{owner}: its one element would join '{}' to itself; a beam joins two bodies",
                    b.get_ref()
                ),
            ));
        }
    }
    // Each node's arc length from `start`, and where it sits: station, element of it (from 1)
    // and the station's count.
    let mut arcs: Vec<(String, usize, usize, usize)> = vec![("0".into(), 0, 0, 1)];
    // The arc length before the station: the numbers summed, the expressions' text added.
    let (mut number, mut text_before) = (0.0, String::new());
    for (i, st) in stations.iter().enumerate() {
        let st_ref = st.get_ref();
        let n = elements(ctx, &owner, i, st)?;
        let length = ctx.field(&st_ref.length, format!("{owner} station {} length", i + 1))?;
        match ctx.nominal(&length)? {
            Some(l) if l > 0.0 => {}
            Some(l) => {
                return Err(ctx.err(
                    st_ref.length.span(),
                    format!(
                        "{owner} station {}: length {l} m; it must be positive",
                        i + 1
                    ),
                ));
            }
            None => {
                return Err(ctx.err(
                    st_ref.length.span(),
                    format!(
                        "{owner} station {}: its length must not depend on the speed",
                        i + 1
                    ),
                ));
            }
        }
        let l = text(st_ref.length.get_ref());
        for k in 1..=n {
            let arc = format!("{number:e}{text_before} + {l}*{k}/{n}");
            if arc.len() > MAX_ARC_TEXT {
                return Err(ctx.err(
                    st_ref.length.span(),
                    format!("{owner} station {}: the lengths given as expressions up to here add up to {} bytes of text, more than {MAX_ARC_TEXT}; give the stations' lengths as numbers, or fewer stations with expressions", i + 1, arc.len()),
                ));
            }
            arcs.push((arc, i, k, n));
        }
        match st_ref.length.get_ref() {
            Num::Value(v) => number += v,
            Num::Expr(_) => text_before = format!("{text_before} + {l}"),
        }
    }
    let start = s.start.get_ref();
    let point = |k: usize| -> SVec {
        let (arc, station, ..) = &arcs[k];
        let span = if k == 0 {
            s.start.span()
        } else {
            stations[*station].get_ref().length.span()
        };
        let c = [0, 1, 2].map(|c| {
            let p = text(start[c].get_ref());
            expr(span.clone(), format!("{p} + {}*({arc})", axis[c]))
        });
        Spanned::new(span, c.to_vec())
    };
    let last = arcs.len() - 1;
    let parent = s
        .parent
        .clone()
        .unwrap_or_else(|| named(&here, "ground".into()));
    let mut node_names = Vec::with_capacity(arcs.len());
    for k in 0..=last {
        let given = match k {
            0 => s.start_body.as_ref(),
            _ if k == last => s.end_body.as_ref(),
            _ => None,
        };
        if let Some(b) = given {
            node_names.push(b.clone());
            continue;
        }
        let node = format!("{name}_{k}");
        node_names.push(named(&here, node.clone()));
        let at = point(k);
        let body = |n: String| BodySchema {
            name: named(&here, n),
            mass: Spanned::new(here.clone(), Num::Value(0.0)),
            inertia: None,
            x_axis: None,
            y_axis: None,
            cm: at.clone(),
        };
        let joint = |n: String, kind: &str, parent: Spanned<String>, child: String| JointSchema {
            name: named(&here, n),
            kind: named(&here, kind.into()),
            parent,
            child: named(&here, child),
            at: Some(at.clone()),
            axis: None,
            axis2: None,
            initial: None,
            drive: None,
            stiffness: None,
            free: None,
            damping: None,
        };
        let Some(spin) = &s.spin else {
            raw.bodies
                .push(Spanned::new(here.clone(), body(node.clone())));
            let float = joint(node.clone(), "free", parent.clone(), node);
            raw.joints.push(Spanned::new(here.clone(), float));
            continue;
        };
        let frame = format!("{node}_frame");
        raw.bodies
            .push(Spanned::new(here.clone(), body(frame.clone())));
        raw.bodies
            .push(Spanned::new(here.clone(), body(node.clone())));
        let float = joint(node.clone(), "free", parent.clone(), frame.clone());
        raw.joints.push(Spanned::new(here.clone(), float));
        let mut turn = joint(
            format!("{node}_spin"),
            "revolute",
            named(&here, frame.clone()),
            node,
        );
        turn.axis = Some(s.axis.clone());
        turn.drive = Some(spin.clone());
        raw.joints.push(Spanned::new(here.clone(), turn));
        if let (0, Some(c)) = (k, &s.coupling) {
            raw.forces.push(Spanned::new(
                c.span(),
                ForceSchema {
                    name: named(&here, format!("{name}_coupling")),
                    kind: named(&here, "rotational_spring_damper".into()),
                    body1: parent.clone(),
                    point1: None,
                    body2: named(&here, frame),
                    point2: None,
                    axis: Some(s.axis.clone()),
                    axis2: None,
                    stiffness: Some(Spanned::new(c.span(), Nums::One(c.get_ref().clone()))),
                    damping: None,
                    free: None,
                    preload: None,
                },
            ));
        }
    }
    for k in 1..=last {
        let (_, station, m, n) = arcs[k];
        // The element's midpoint as a fraction of its station, for a taper.
        let beam = section(
            ctx,
            &owner,
            s,
            &stations[station],
            (m as f64 - 0.5) / n as f64,
            BeamSchema {
                name: named(&here, format!("{name}_e{k}")),
                body1: node_names[k - 1].clone(),
                point1: point(k - 1),
                body2: node_names[k].clone(),
                point2: point(k),
                reference: s.reference.clone(),
                outer_diameter: None,
                inner_diameter: None,
                youngs: None,
                shear_modulus: None,
                nu: None,
                density: None,
                shear_coefficient: None,
                ea: None,
                gj: None,
                ei: None,
                kga: None,
                rho_a: None,
                rho_i: None,
                beta: None,
            },
        )?;
        raw.beams.push(Spanned::new(stations[station].span(), beam));
    }
    Ok(last)
}

/// Station `i`'s number of elements: 1 by default, at most [`MAX_ELEMENTS`].
fn elements(ctx: &Ctx, owner: &str, i: usize, st: &Spanned<StationSchema>) -> R<usize> {
    let Some(n) = &st.get_ref().elements else {
        return Ok(1);
    };
    match *n.get_ref() {
        v @ 1..=MAX_ELEMENTS => Ok(v as usize),
        v => Err(ctx.err(
            n.span(),
            format!(
                "{owner} station {}: {v} elements; give a whole number from 1 to {MAX_ELEMENTS}",
                i + 1
            ),
        )),
    }
}

/// The axis as a unit vector's three component texts; an error for a zero or speed-dependent
/// axis.
fn unit_axis(ctx: &Ctx, owner: &str, axis: &SVec) -> R<[String; 3]> {
    let f = ctx.vec3(axis, format!("{owner} axis"))?;
    let mut v = [0.0; 3];
    for (x, f) in v.iter_mut().zip(&f) {
        *x = ctx.nominal(f)?.ok_or_else(|| {
            ctx.err(
                axis.span(),
                format!("{owner}: its axis must not depend on the speed"),
            )
        })?;
    }
    // Scaled first, so that an axis such as [1e200, 1e200, 0] does not overflow.
    let big = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let norm = big * v.iter().map(|x| (x / big).powi(2)).sum::<f64>().sqrt();
    if big == 0.0 || !norm.is_finite() {
        return Err(ctx.err(axis.span(), format!("{owner}: its axis is zero")));
    }
    let c = axis.get_ref();
    Ok(match [0, 1, 2].map(|i| c[i].get_ref()) {
        // Numbers are normalised here; expressions (a toleranced direction) in the text.
        [Num::Value(_), Num::Value(_), Num::Value(_)] => {
            v.map(|x| format!("({:e})", x / big / (norm / big)))
        }
        n => {
            let [a, b, d] = n.map(text);
            let norm = format!("sqrt({a}^2 + {b}^2 + {d}^2)");
            [a, b, d].map(|a| format!("{a}/{norm}"))
        }
    })
}

/// `beam` with the section of station `st` (its keys over the shaft's material), a tapered
/// diameter taken at `fraction` of the station's length.
fn section(
    ctx: &Ctx,
    owner: &str,
    s: &ShaftSchema,
    st: &Spanned<StationSchema>,
    fraction: f64,
    mut beam: BeamSchema,
) -> R<BeamSchema> {
    let t = st.get_ref();
    // A station given by section properties takes no material from the shaft.
    let properties = t.ea.is_some()
        || t.gj.is_some()
        || t.ei.is_some()
        || t.kga.is_some()
        || t.rho_a.is_some()
        || t.rho_i.is_some();
    let or = |a: &Option<SNum>, b: &Option<SNum>| match properties {
        true => a.clone(),
        false => a.clone().or_else(|| b.clone()),
    };
    taper_ends(ctx, owner, t)?;
    beam.outer_diameter = diameter(ctx, owner, &t.outer_diameter, fraction)?;
    beam.inner_diameter = diameter(ctx, owner, &t.inner_diameter, fraction)?;
    beam.youngs = or(&t.youngs, &s.youngs);
    // G and ν say one thing: a station that gives either takes neither from the shaft.
    if t.shear_modulus.is_some() || t.nu.is_some() {
        beam.shear_modulus = t.shear_modulus.clone();
        beam.nu = t.nu.clone();
    } else {
        beam.shear_modulus = or(&t.shear_modulus, &s.shear_modulus);
        beam.nu = or(&t.nu, &s.nu);
    }
    beam.density = or(&t.density, &s.density);
    beam.shear_coefficient = or(&t.shear_coefficient, &s.shear_coefficient);
    beam.ea = t.ea.clone();
    beam.gj = t.gj.clone();
    beam.ei = t.ei.clone();
    beam.kga = t.kga.clone();
    beam.rho_a = t.rho_a.clone();
    beam.rho_i = t.rho_i.clone();
    beam.beta = or(&t.beta, &s.beta);
    Ok(beam)
}

/// A diameter's values at the station's two ends (nominal; `None` where it depends on the
/// speed, or is not given).
fn ends(ctx: &Ctx, owner: &str, d: &Option<SNums>) -> R<Option<[f64; 2]>> {
    let Some(d) = d else { return Ok(None) };
    let value = |n: &SNum| -> R<Option<f64>> {
        let f = ctx.field(n, format!("{owner} diameter"))?;
        ctx.nominal(&f)
    };
    Ok(match d.get_ref() {
        Nums::One(n) => value(&Spanned::new(d.span(), n.clone()))?.map(|v| [v, v]),
        Nums::Many(e) if e.len() == 2 => value(&e[0])?.zip(value(&e[1])?).map(|(a, b)| [a, b]),
        Nums::Many(_) | Nums::Rows(_) => None,
    })
}

/// A taper is checked at both ends, not only at the elements' midpoints: the outer diameter
/// positive, the inner one not negative and below the outer.
fn taper_ends(ctx: &Ctx, owner: &str, t: &StationSchema) -> R<()> {
    let outer = ends(ctx, owner, &t.outer_diameter)?;
    let inner = ends(ctx, owner, &t.inner_diameter)?;
    for (k, side) in ["start", "end"].iter().enumerate() {
        let bad_outer = outer.is_some_and(|o| o[k].is_nan() || o[k] <= 0.0);
        let bad_inner = inner
            .is_some_and(|i| i[k].is_nan() || i[k] < 0.0 || outer.is_some_and(|o| i[k] >= o[k]));
        let (what, d, v) = match (bad_outer, bad_inner) {
            (true, _) => ("outer", &t.outer_diameter, outer.map(|o| o[k])),
            (_, true) => ("inner", &t.inner_diameter, inner.map(|i| i[k])),
            _ => continue,
        };
        let span = d.as_ref().map_or(0..0, |d| d.span());
        return Err(ctx.err(
            span,
            format!(
                "{owner}: {what} diameter {} at the station's {side}: the outer one must be positive, the inner one not negative and not below the outer one",
                v.unwrap_or(f64::NAN)
            ),
        ));
    }
    Ok(())
}

/// A diameter: one value, or `[start, end]` interpolated linearly at `fraction`.
fn diameter(ctx: &Ctx, owner: &str, d: &Option<SNums>, fraction: f64) -> R<Option<SNum>> {
    let Some(d) = d else { return Ok(None) };
    match d.get_ref() {
        Nums::One(n) => Ok(Some(Spanned::new(d.span(), n.clone()))),
        Nums::Many(ends) if ends.len() == 2 => {
            for e in ends {
                ctx.field(e, format!("{owner} diameter"))?;
            }
            let (a, b) = (text(ends[0].get_ref()), text(ends[1].get_ref()));
            Ok(Some(expr(d.span(), format!("{a} + ({b} - {a})*{fraction:e}"))))
        }
        Nums::Many(ends) => Err(ctx.err(
            d.span(),
            format!(
                "{owner}: a diameter is one value or a pair [start, end] for a taper, not {} values",
                ends.len()
            ),
        )),
        Nums::Rows(_) => Err(ctx.err(
            d.span(),
            format!("{owner}: a diameter is one value or a pair [start, end] for a taper, not a matrix"),
        )),
    }
}
