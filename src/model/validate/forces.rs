//! Force elements of a model file: type, bodies, points, axis and the per-component fields the
//! type ([`crate::forces::ForceType`]) declares.

use super::geometry::{Item, coincident, known, least_aligned, parallel, vector};
use super::names::{article, body_ref, element_name, type_named};
use super::per_coordinate::{Each, indexed};
use super::{Ctx, R};
use crate::forces::{Geometry, Kind};
use crate::joints::Use;
use crate::model::schema::ForceSchema;
use crate::model::{CrossField, Field, ForceElement};
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// The fields an element gives per component (`None`: not given).
struct ComponentFields {
    stiffness: Vec<Option<Field>>,
    damping: Vec<Option<Field>>,
    free: Vec<Option<Field>>,
    preload: Vec<Option<Field>>,
    cross: Vec<CrossField>,
}

/// Parses and checks the `[[forces]]` tables; `elements` collects their names (names are
/// unique across joints, force elements and cut joints).
pub(super) fn forces(
    ctx: &Ctx,
    raw: &[Spanned<ForceSchema>],
    body_names: &HashMap<String, usize>,
    joint_names: &HashMap<String, usize>,
    elements: &mut HashSet<String>,
) -> R<Vec<ForceElement>> {
    let mut out = Vec::new();
    for f in raw {
        let s = f.get_ref();
        let name = element_name(ctx, &s.name, "force", joint_names, elements)?;
        let owner = format!("force '{name}'");
        let kind = type_named(ctx, &s.kind, &owner, Kind::ALL, Kind::name)?;
        let this = format!("{} {}", article(kind.name()), kind.name());
        let item = Item {
            owner: &owner,
            kind: &this,
            span: f.span(),
        };
        let geometry = geometry(ctx, &item, s, kind, body_names)?;
        let fields = component_fields(ctx, &item, s, kind)?;
        if kind.distinct_points()
            && fields.free.iter().any(Option::is_none)
            && coincident(ctx, &geometry.point1, &geometry.point2)?
        {
            return Err(ctx.err(
                item.span,
                format!(
                    "{owner}: its two points coincide in the reference configuration, so its free {} is zero and its line of action undefined there; give distinct points",
                    indexed(kind.components()[0].suffix, 0, 1)
                ),
            ));
        }
        out.push(ForceElement {
            name,
            kind,
            geometry,
            stiffness: fields.stiffness,
            damping: fields.damping,
            free: fields.free,
            preload: fields.preload,
            cross: fields.cross,
        });
    }
    Ok(out)
}

/// The element's bodies (distinct) and its points and axis as its type uses them; the
/// reference direction angles about the axis are measured from, which needs an axis that does
/// not depend on the speed.
fn geometry(
    ctx: &Ctx,
    item: &Item,
    s: &ForceSchema,
    kind: Kind,
    body_names: &HashMap<String, usize>,
) -> R<Geometry<[Field; 3]>> {
    let body1 = body_ref(ctx, body_names, &s.body1)?;
    let body2 = body_ref(ctx, body_names, &s.body2)?;
    if body1 == body2 {
        return Err(ctx.err(
            s.body2.span(),
            format!("{}: both ends are on the same body", item.owner),
        ));
    }
    let [use_point1, use_point2, use_axis] = kind.uses();
    let point1 = vector(ctx, item, &s.point1, use_point1, "point1")?;
    let point2 = match (&s.point2, use_point2) {
        (None, Use::Optional) => point1.clone(),
        _ => vector(ctx, item, &s.point2, use_point2, "point2")?,
    };
    let axis = vector(ctx, item, &s.axis, use_axis, "axis")?;
    let reference = if use_axis == Use::Unused {
        axis.clone()
    } else {
        if known(ctx, &axis)?.is_none() {
            let span = s.axis.as_ref().map_or(item.span.clone(), |a| a.span());
            return Err(ctx.err(
                span,
                format!("{}: its axis must not depend on the speed", item.owner),
            ));
        }
        match &s.axis2 {
            Some(_) => second_axis(ctx, item, s, &axis)?,
            None => least_aligned(ctx, item, &axis)?,
        }
    };
    if use_axis == Use::Unused
        && let Some(a2) = &s.axis2
    {
        return Err(ctx.err(
            a2.span(),
            format!("{}: {} has no axis, so no 'axis2'", item.owner, item.kind),
        ));
    }
    Ok(Geometry {
        body1,
        point1,
        body2,
        point2,
        axis,
        reference,
    })
}

/// The element's `axis2`: the direction its type measures from about `axis` (a bearing's `x`),
/// not depending on the speed and not parallel to the axis.
fn second_axis(ctx: &Ctx, item: &Item, s: &ForceSchema, axis: &[Field; 3]) -> R<[Field; 3]> {
    let a2 = vector(ctx, item, &s.axis2, Use::Required, "axis2")?;
    let span = s.axis2.as_ref().map_or(item.span.clone(), |a| a.span());
    let (Some(a), Some(b)) = (known(ctx, axis)?, known(ctx, &a2)?) else {
        return Err(ctx.err(
            span,
            format!("{}: its axis2 must not depend on the speed", item.owner),
        ));
    };
    if parallel(a, b) != Some(false) {
        return Err(ctx.err(
            span,
            format!(
                "{}: its axis2 {b:?} is zero or parallel to its axis {a:?}; give a direction across the axis",
                item.owner
            ),
        ));
    }
    Ok(a2)
}

/// Stiffness, damping, free value and preload per component, checked at the nominal values.
fn component_fields(ctx: &Ctx, item: &Item, s: &ForceSchema, kind: Kind) -> R<ComponentFields> {
    let k = kind.components().len();
    let what = |x: &str| format!("{} {x}", item.owner);
    let each = Each {
        k,
        per: "component",
        what: &what,
    };
    let (stiffness, cross_k) = each.read_matrix(ctx, &s.stiffness, "stiffness")?;
    let (damping, cross_c) = each.read_matrix(ctx, &s.damping, "damping")?;
    let free = each.read(ctx, &s.free, "free", false)?;
    let preload = each.read(ctx, &s.preload, "preload", false)?;
    let mut cross: Vec<CrossField> = Vec::new();
    for (is_damping, (row, col, f)) in
        (cross_k.into_iter().map(|x| (false, x))).chain(cross_c.into_iter().map(|x| (true, x)))
    {
        let at = match cross.iter().position(|x| (x.row, x.col) == (row, col)) {
            Some(at) => at,
            None => {
                cross.push(CrossField {
                    row,
                    col,
                    stiffness: None,
                    damping: None,
                });
                cross.len() - 1
            }
        };
        let slot = if is_damping {
            &mut cross[at].damping
        } else {
            &mut cross[at].stiffness
        };
        *slot = Some(f);
    }
    for x in stiffness
        .iter()
        .chain(&damping)
        .chain(&free)
        .chain(&preload)
        .chain(cross.iter().flat_map(|x| [&x.stiffness, &x.damping]))
        .flatten()
    {
        ctx.nominal(x)?;
    }
    Ok(ComponentFields {
        stiffness,
        damping,
        free,
        preload,
        cross,
    })
}
