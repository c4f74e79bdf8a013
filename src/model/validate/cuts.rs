//! Cut joints of a model file: type, bodies, points and the fields the type
//! ([`crate::cuts::CutType`]) declares.

use super::geometry::{Item, coincident, least_aligned, not_parallel, vector};
use super::names::{article, body_ref, element_name, type_named};
use super::{Ctx, R};
use crate::cuts::{Geometry, Kind};
use crate::joints::Use;
use crate::model::Constraint;
use crate::model::schema::ConstraintSchema;
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// Parses and checks the `[[constraints]]` tables; `elements` holds the force elements' names
/// (names are unique across joints, force elements and cut joints).
pub(super) fn constraints(
    ctx: &Ctx,
    raw: &[Spanned<ConstraintSchema>],
    body_names: &HashMap<String, usize>,
    joint_names: &HashMap<String, usize>,
    elements: &mut HashSet<String>,
) -> R<Vec<Constraint>> {
    let mut out = Vec::new();
    for c in raw {
        let s = c.get_ref();
        let name = element_name(ctx, &s.name, "constraint", joint_names, elements)?;
        let owner = format!("constraint '{name}'");
        let kind = type_named(ctx, &s.kind, &owner, Kind::ALL, Kind::name)?;
        let this = format!("{} {} cut joint", article(kind.name()), kind.name());
        let body1 = body_ref(ctx, body_names, &s.body1)?;
        let body2 = body_ref(ctx, body_names, &s.body2)?;
        if body1 == body2 {
            return Err(ctx.err(
                s.body2.span(),
                format!("{owner}: both points are on the same body"),
            ));
        }
        let [use_point2, use_axis, use_axis2, use_length] = kind.uses();
        let item = Item {
            owner: &owner,
            kind: &this,
            span: c.span(),
        };
        let point1 = ctx.vec3(&s.point1, format!("{owner} point1"))?;
        for f in &point1 {
            ctx.nominal(f)?;
        }
        let point2 = match (&s.point2, use_point2) {
            (None, Use::Optional) => point1.clone(),
            _ => vector(ctx, &item, &s.point2, use_point2, "point2")?,
        };
        let axis = vector(ctx, &item, &s.axis, use_axis, "axis")?;
        let axis2 = match (&s.axis2, use_axis2) {
            (None, Use::Optional) => least_aligned(ctx, &item, &axis)?,
            _ => vector(ctx, &item, &s.axis2, use_axis2, "axis2")?,
        };
        if use_axis2 != Use::Unused {
            not_parallel(ctx, &item, &axis, &axis2, &s.axis2)?;
        }
        if let (Some(l), Use::Unused) = (&s.length, use_length) {
            return Err(ctx.err(l.span(), format!("{owner}: {this} has no 'length'")));
        }
        let length = ctx.opt_field(&s.length, format!("{owner} length"))?;
        for f in length.iter() {
            ctx.nominal(f)?;
        }
        if kind.distinct_points() && coincident(ctx, &point1, &point2)? {
            return Err(ctx.err(
                item.span,
                format!(
                    "{owner}: its two points coincide in the reference configuration, so the distance has no direction there; give distinct points"
                ),
            ));
        }
        out.push(Constraint {
            name,
            kind,
            geometry: Geometry {
                body1,
                point1,
                body2,
                point2,
                axis,
                axis2,
                length,
            },
            dropped: Vec::new(),
        });
    }
    Ok(out)
}
