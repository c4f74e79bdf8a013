//! The `[[unbalances]]` tables: a mass's eccentricity on a spinning body, the rotating load of
//! an unbalance response. Its own stage because unbalances share their names with the ports
//! and the joint coordinates (all are channels of a transfer function), and a body spins only
//! below a driven joint, so both are checked once the joints and ports are known.

use super::geometry::{Item, vector};
use super::names::{body_ref, check_name};
use super::{Ctx, R};
use crate::joints::Use;
use crate::model::schema::UnbalanceSchema;
use crate::model::{Body, Coordinate, Joint, Port, Unbalance};
use std::collections::HashMap;
use toml::Spanned;

/// The names an unbalance may not take, and the joints that can spin its body.
pub(super) struct Known<'a> {
    pub body_names: &'a HashMap<String, usize>,
    pub bodies: &'a [Body],
    pub coordinates: &'a [Coordinate],
    pub ports: &'a [Port],
    pub joints: &'a [Joint],
}

/// Parses and checks the `[[unbalances]]` tables.
pub(super) fn unbalances(
    ctx: &Ctx,
    raw: &[Spanned<UnbalanceSchema>],
    known: &Known,
) -> R<Vec<Unbalance>> {
    let mut out: Vec<Unbalance> = Vec::new();
    for item in raw {
        let s = item.get_ref();
        check_name(ctx, &s.name, "unbalance")?;
        let name = s.name.get_ref().clone();
        if out.iter().any(|u| u.name == name)
            || known.ports.iter().any(|p| p.name == name)
            || known.coordinates.iter().any(|c| c.name == name)
        {
            return Err(ctx.err(
                s.name.span(),
                format!("duplicate name '{name}' (unbalances, ports and joint coordinates share the names a transfer function refers to)"),
            ));
        }
        out.push(unbalance(ctx, item, known, name)?);
    }
    Ok(out)
}

/// One unbalance, its name already checked.
fn unbalance(
    ctx: &Ctx,
    item: &Spanned<UnbalanceSchema>,
    known: &Known,
    name: String,
) -> R<Unbalance> {
    let s = item.get_ref();
    let owner = format!("unbalance '{name}'");
    let Some(body) = body_ref(ctx, known.body_names, &s.body)? else {
        return Err(ctx.err(
            s.body.span(),
            format!(
                "{owner}: the ground does not spin; give a spinning body (a disk, a shaft's node)"
            ),
        ));
    };
    if !spun(known.joints, body) {
        return Err(ctx.err(
            s.body.span(),
            format!(
                "{owner}: body '{}' does not spin: no driven joint carries it (an unbalance turns \
                 with a body spun by a `drive`, or a shaft's node with `spin`)",
                s.body.get_ref()
            ),
        ));
    }
    let table = Item {
        owner: &owner,
        kind: "an unbalance",
        span: item.span(),
    };
    // At the body's centre of mass where no point is given (a disk's centre).
    let point = match &s.point {
        Some(_) => vector(ctx, &table, &s.point, Use::Optional, "point")?,
        None => known.bodies[body].cm.clone(),
    };
    let magnitude = ctx.field(&s.magnitude, format!("{owner} magnitude"))?;
    ctx.nominal(&magnitude)?;
    let phase = match &s.phase {
        Some(f) => ctx.field(f, format!("{owner} phase"))?,
        None => ctx.zero(&item.span(), format!("{owner} phase")),
    };
    ctx.nominal(&phase)?;
    Ok(Unbalance {
        name,
        body,
        point,
        magnitude,
        phase,
    })
}

/// Is `body` carried by a driven joint (is it or an ancestor the child of one)?
fn spun(joints: &[Joint], body: usize) -> bool {
    let mut b = body;
    // A tree: at most one joint has `b` as its child, and the walk ends at the ground.
    for _ in 0..=joints.len() {
        let Some(j) = joints.iter().find(|j| j.child == b) else {
            return false;
        };
        if j.drive.is_some() {
            return true;
        }
        match j.parent {
            Some(p) => b = p,
            None => return false,
        }
    }
    false
}
