//! The `[[ports]]` tables: points and directions on a body where a transfer function excites or
//! measures. Its own stage because ports share their names with the joint coordinates (both are
//! channels of a transfer function), so they are checked once the coordinates are known.

use super::geometry::{Item, known, vector};
use super::names::{body_ref, check_name};
use super::{Ctx, R};
use crate::joints::Use;
use crate::model::schema::PortSchema;
use crate::model::{Coordinate, Port};
use std::collections::HashMap;
use toml::Spanned;

/// Parses and checks the `[[ports]]` tables.
pub(super) fn ports(
    ctx: &Ctx,
    raw: &[Spanned<PortSchema>],
    body_names: &HashMap<String, usize>,
    coordinates: &[Coordinate],
) -> R<Vec<Port>> {
    let mut out: Vec<Port> = Vec::new();
    for item in raw {
        let s = item.get_ref();
        check_name(ctx, &s.name, "port")?;
        let name = s.name.get_ref().clone();
        if out.iter().any(|p| p.name == name) || coordinates.iter().any(|c| c.name == name) {
            return Err(ctx.err(
                s.name.span(),
                format!("duplicate name '{name}' (ports and joint coordinates share the names a transfer function refers to)"),
            ));
        }
        out.push(port(ctx, item, body_names, name)?);
    }
    Ok(out)
}

/// One port, its name already checked.
fn port(
    ctx: &Ctx,
    item: &Spanned<PortSchema>,
    body_names: &HashMap<String, usize>,
    name: String,
) -> R<Port> {
    let s = item.get_ref();
    let owner = format!("port '{name}'");
    let rotation = match s.kind.get_ref().as_str() {
        "translation" => false,
        "rotation" => true,
        other => {
            return Err(ctx.err(
                s.kind.span(),
                format!("{owner}: unknown type '{other}' (expected translation or rotation)"),
            ));
        }
    };
    let Some(body) = body_ref(ctx, body_names, &s.body)? else {
        return Err(ctx.err(
            s.body.span(),
            format!("{owner}: ground does not move; give a body"),
        ));
    };
    let usage = if rotation { Use::Unused } else { Use::Required };
    let this = format!("a {} port", s.kind.get_ref());
    let table = Item {
        owner: &owner,
        kind: &this,
        span: item.span(),
    };
    let point = vector(ctx, &table, &s.point, usage, "point")?;
    let direction = ctx.vec3(&s.direction, format!("{owner} direction"))?;
    if let Some(d) = known(ctx, &direction)?
        && d.iter().all(|x| x.abs() <= 0.0)
    {
        return Err(ctx.err(s.direction.span(), format!("{owner}: direction is zero")));
    }
    Ok(Port {
        name,
        body,
        point,
        direction,
        rotation,
    })
}
