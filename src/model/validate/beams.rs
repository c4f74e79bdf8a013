//! The `[[beams]]` tables: the two bodies (distinct), the node points (distinct), the direction
//! the section's axes are taken from, and the section, given either as a circular tube's
//! geometry and material or as section properties, never both. Every stiffness, density and
//! diameter is checked at the nominal values: positive (a rotary inertia may be zero), an
//! inner diameter below the outer one, Poisson's ratio in (−1, ½).

use super::geometry::{Item, coincident, known, least_aligned, parallel};
use super::names::{body_ref, element_name};
use super::per_coordinate::Each;
use super::{Ctx, R};
use crate::model::schema::{BeamSchema, SNum};
use crate::model::{Beam, BeamSection, Field, SectionProperties, TubeSection};
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// Parses and checks the `[[beams]]` tables; `elements` collects their names (one namespace
/// with joints, force elements, cut joints and couplers).
pub(super) fn beams(
    ctx: &Ctx,
    raw: &[Spanned<BeamSchema>],
    body_names: &HashMap<String, usize>,
    joint_names: &HashMap<String, usize>,
    elements: &mut HashSet<String>,
) -> R<Vec<Beam>> {
    let mut out = Vec::new();
    for b in raw {
        let s = b.get_ref();
        let name = element_name(ctx, &s.name, "beam", joint_names, elements)?;
        let owner = format!("beam '{name}'");
        let item = Item {
            owner: &owner,
            kind: "a beam",
            span: b.span(),
        };
        let body1 = body_ref(ctx, body_names, &s.body1)?;
        let body2 = body_ref(ctx, body_names, &s.body2)?;
        if body1 == body2 {
            return Err(ctx.err(
                s.body2.span(),
                format!("{owner}: both nodes are on the same body; a beam joins two"),
            ));
        }
        let point1 = ctx.vec3(&s.point1, format!("{owner} point1"))?;
        let point2 = ctx.vec3(&s.point2, format!("{owner} point2"))?;
        if coincident(ctx, &point1, &point2)? {
            return Err(ctx.err(
                s.point2.span(),
                format!(
                    "{owner}: its two nodes coincide, so it has zero length; give distinct points"
                ),
            ));
        }
        let (Some(a), Some(c)) = (known(ctx, &point1)?, known(ctx, &point2)?) else {
            return Err(ctx.err(
                item.span,
                format!("{owner}: its points must not depend on the speed"),
            ));
        };
        let chord = [0, 1, 2].map(|i| c[i] - a[i]);
        let reference = reference(ctx, &item, s, chord)?;
        out.push(Beam {
            name,
            body1,
            point1,
            body2,
            point2,
            reference,
            section: section(ctx, &item, s)?,
            damping: (s.beta.as_ref())
                .map(|b| sized(ctx, b, format!("{owner} beta"), true))
                .transpose()?,
        });
    }
    Ok(out)
}

/// The direction the section's second axis comes from: as given (not zero, not along the
/// chord), or the coordinate axis least aligned with the chord.
fn reference(ctx: &Ctx, item: &Item, s: &BeamSchema, chord: [f64; 3]) -> R<[Field; 3]> {
    let Some(v) = &s.reference else {
        let chord = chord.map(|x| Field {
            expr: crate::model::Expr::Num(x),
            site: ctx.site(&item.span, String::new()),
        });
        return least_aligned(ctx, item, &chord);
    };
    let r = ctx.vec3(v, format!("{} reference", item.owner))?;
    let Some(n) = known(ctx, &r)? else {
        return Err(ctx.err(
            v.span(),
            format!("{}: its reference must not depend on the speed", item.owner),
        ));
    };
    match parallel(n, chord) {
        None => Err(ctx.err(v.span(), format!("{}: reference is zero", item.owner))),
        Some(true) => Err(ctx.err(
            v.span(),
            format!(
                "{}: reference is along the beam; give a direction across it",
                item.owner
            ),
        )),
        Some(false) => Ok(r),
    }
}

/// A field that must be positive (or, where `zero` allows, not negative) at the nominal values.
fn sized(ctx: &Ctx, n: &SNum, what: String, zero: bool) -> R<Field> {
    let f = ctx.field(n, what)?;
    positive(ctx, &f, zero)?;
    Ok(f)
}

/// The section: a tube or section properties, whichever fields are given (not a mix).
fn section(ctx: &Ctx, item: &Item, s: &BeamSchema) -> R<BeamSection> {
    let owner = item.owner;
    let tube = [
        ("outer_diameter", &s.outer_diameter),
        ("inner_diameter", &s.inner_diameter),
        ("E", &s.youngs),
        ("G", &s.shear_modulus),
        ("nu", &s.nu),
        ("density", &s.density),
        ("shear_coefficient", &s.shear_coefficient),
    ];
    let props = [
        ("EA", s.ea.is_some()),
        ("GJ", s.gj.is_some()),
        ("EI", s.ei.is_some()),
    ]
    .into_iter()
    .chain([("kGA", s.kga.is_some()), ("rhoA", s.rho_a.is_some())])
    .chain([("rhoI", s.rho_i.is_some())]);
    let given_tube: Vec<&str> = tube.iter().filter(|t| t.1.is_some()).map(|t| t.0).collect();
    let given_props: Vec<&str> = props.filter(|p| p.1).map(|p| p.0).collect();
    let what = |f: &str| format!("{owner} {f}");
    let need = |f: &str, v: &Option<SNum>| -> R<SNum> {
        v.clone().ok_or_else(|| {
            ctx.err(
                item.span.clone(),
                format!("{owner}: its section needs '{f}'"),
            )
        })
    };
    match (given_tube.is_empty(), given_props.is_empty()) {
        (true, true) => Err(ctx.err(
            item.span.clone(),
            format!(
                "{owner}: give its section, either as a tube (outer_diameter, inner_diameter, E, G or nu, density) or as properties (EA, GJ, EI, kGA, rhoA, rhoI)"
            ),
        )),
        (false, false) => Err(ctx.err(
            item.span.clone(),
            format!(
                "{owner}: its section is given both as a tube ({}) and as properties ({}); give one",
                given_tube.join(", "),
                given_props.join(", ")
            ),
        )),
        (false, true) => {
            let outer = sized(ctx, &need("outer_diameter", &s.outer_diameter)?, what("outer_diameter"), false)?;
            let inner = match &s.inner_diameter {
                Some(n) => {
                    let f = sized(ctx, n, what("inner_diameter"), true)?;
                    if let (Some(i), Some(o)) = (ctx.nominal(&f)?, ctx.nominal(&outer)?)
                        && i >= o
                    {
                        return Err(ctx.err(
                            n.span(),
                            format!("{owner}: inner diameter {i} m is not below the outer diameter {o} m"),
                        ));
                    }
                    Some(f)
                }
                None => None,
            };
            let youngs = sized(ctx, &need("E", &s.youngs)?, what("E"), false)?;
            let (shear_modulus, poisson) = match (&s.shear_modulus, &s.nu) {
                (Some(g), None) => (Some(sized(ctx, g, what("G"), false)?), None),
                (None, Some(nu)) => {
                    let f = ctx.field(nu, what("nu"))?;
                    if let Some(v) = ctx.nominal(&f)?
                        && !(v > -1.0 && v < 0.5)
                    {
                        return Err(ctx.err(
                            nu.span(),
                            format!("{owner} nu is {v}; Poisson's ratio must lie in (-1, 0.5)"),
                        ));
                    }
                    (None, Some(f))
                }
                (Some(g), Some(_)) => {
                    return Err(ctx.err(
                        g.span(),
                        format!("{owner}: give the shear modulus G or Poisson's ratio nu, not both"),
                    ));
                }
                (None, None) => {
                    return Err(ctx.err(
                        item.span.clone(),
                        format!("{owner}: its section needs the shear modulus 'G' or Poisson's ratio 'nu'"),
                    ));
                }
            };
            let density = sized(ctx, &need("density", &s.density)?, what("density"), false)?;
            let coefficient = (s.shear_coefficient.as_ref())
                .map(|k| sized(ctx, k, what("shear_coefficient"), false))
                .transpose()?;
            Ok(BeamSection::Tube(Box::new(TubeSection {
                outer,
                inner,
                youngs,
                shear_modulus,
                poisson,
                density,
                coefficient,
            })))
        }
        (true, false) => {
            let pair = |v: &Option<crate::model::schema::SNums>, f: &str, zero: bool| -> R<Option<Vec<Field>>> {
                let per = Each { k: 2, per: "bending axis (e2, e3)", what: &what };
                let Some(fields) = per.read(ctx, v, f, true)?.into_iter().collect::<Option<Vec<_>>>() else {
                    return Ok(None);
                };
                for x in &fields {
                    positive(ctx, x, zero)?;
                }
                Ok(Some(fields))
            };
            let ei = pair(&s.ei, "EI", false)?.ok_or_else(|| {
                ctx.err(item.span.clone(), format!("{owner}: its section needs 'EI'"))
            })?;
            let kga = pair(&s.kga, "kGA", false)?;
            let three = Each { k: 3, per: "axis (e1, e2, e3)", what: &what };
            let rho_i = three
                .read(ctx, &s.rho_i, "rhoI", false)?
                .into_iter()
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| {
                    ctx.err(item.span.clone(), format!("{owner}: its section needs 'rhoI' = [rhoJ, rhoI2, rhoI3] (kg·m)"))
                })?;
            for x in &rho_i {
                positive(ctx, x, true)?;
            }
            Ok(BeamSection::Properties(Box::new(SectionProperties {
                ea: sized(ctx, &need("EA", &s.ea)?, what("EA"), false)?,
                gj: sized(ctx, &need("GJ", &s.gj)?, what("GJ"), false)?,
                ei: [ei[0].clone(), ei[1].clone()],
                kga: kga.map(|k| [k[0].clone(), k[1].clone()]),
                rho_a: sized(ctx, &need("rhoA", &s.rho_a)?, what("rhoA"), false)?,
                rho_i: [rho_i[0].clone(), rho_i[1].clone(), rho_i[2].clone()],
            })))
        }
    }
}

/// A parsed field positive (or not negative, where `zero`) at the nominal values, the error
/// at its site.
fn positive(ctx: &Ctx, f: &Field, zero: bool) -> R<()> {
    if let Some(v) = ctx.nominal(f)?
        && !(v > 0.0 || zero && v == 0.0)
    {
        let need = if zero { "zero or positive" } else { "positive" };
        return Err(crate::model::ModelError {
            file: ctx.file.to_string(),
            line: Some(f.site.line),
            column: Some(f.site.column),
            message: format!("{} is {v}; it must be {need}", f.site.what),
            snippet: Some(super::locate::locate_line(ctx.text, f.site.line)),
        });
    }
    Ok(())
}
