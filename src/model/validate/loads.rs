//! The `[[loads]]` tables: constant forces and torques on bodies (in ground axes, or turning with
//! the body), and generalised forces on joint coordinates. Its own stage because a load names a
//! body or a coordinate, so it is checked once the joints are known.

use super::geometry::{Item, vector};
use super::names::{body_ref, check_name};
use super::{Ctx, R};
use crate::joints::Use;
use crate::model::schema::LoadSchema;
use crate::model::{Coordinate, Load, LoadKind};
use std::collections::HashMap;
use toml::Spanned;

/// Parses and checks the `[[loads]]` tables.
pub(super) fn loads(
    ctx: &Ctx,
    raw: &[Spanned<LoadSchema>],
    body_names: &HashMap<String, usize>,
    coordinates: &[Coordinate],
) -> R<Vec<Load>> {
    let mut out: Vec<Load> = Vec::new();
    for item in raw {
        let s = item.get_ref();
        check_name(ctx, &s.name, "load")?;
        let name = s.name.get_ref().clone();
        if out.iter().any(|l| l.name == name) {
            return Err(ctx.err(s.name.span(), format!("duplicate load name '{name}'")));
        }
        let kind = load(ctx, item, body_names, coordinates, &name)?;
        out.push(Load { name, kind });
    }
    Ok(out)
}

/// One load, its name already checked.
fn load(
    ctx: &Ctx,
    item: &Spanned<LoadSchema>,
    body_names: &HashMap<String, usize>,
    coordinates: &[Coordinate],
    name: &str,
) -> R<LoadKind> {
    let s = item.get_ref();
    let owner = format!("load '{name}'");
    let kind = s.kind.get_ref().as_str();
    if !["force", "torque", "coordinate"].contains(&kind) {
        return Err(ctx.err(
            s.kind.span(),
            format!("{owner}: unknown type '{kind}' (expected force, torque or coordinate)"),
        ));
    }
    let table = Table {
        ctx,
        item,
        this: format!("a {kind} load"),
        owner,
    };
    if kind == "coordinate" {
        table.on_coordinate(coordinates)
    } else {
        table.on_body(body_names, kind == "force")
    }
}

/// One `[[loads]]` table of a known type: what its messages name it (`owner`, and `this`,
/// its type).
struct Table<'a> {
    ctx: &'a Ctx<'a>,
    item: &'a Spanned<LoadSchema>,
    owner: String,
    this: String,
}

impl Table<'_> {
    /// A key this type does not read, refused rather than ignored (`span` where it is given,
    /// the table where not known).
    fn unused(&self, present: bool, key: &str, span: Option<std::ops::Range<usize>>) -> R<()> {
        if present {
            let span = span.unwrap_or_else(|| self.item.span());
            Err(self.ctx.err(
                span,
                format!("{}: {} has no '{key}'", self.owner, self.this),
            ))
        } else {
            Ok(())
        }
    }

    /// A generalised force on a free joint coordinate.
    fn on_coordinate(&self, coordinates: &[Coordinate]) -> R<LoadKind> {
        let (ctx, item, owner, this) = (self.ctx, self.item, &self.owner, &self.this);
        let s = item.get_ref();
        self.unused(s.body.is_some(), "body", s.body.as_ref().map(|b| b.span()))?;
        self.unused(
            s.frame.is_some(),
            "frame",
            s.frame.as_ref().map(|b| b.span()),
        )?;
        for (v, key) in [
            (&s.point, "point"),
            (&s.force, "force"),
            (&s.torque, "torque"),
        ] {
            self.unused(v.is_some(), key, v.as_ref().map(|v| v.span()))?;
        }
        let Some(c) = &s.coordinate else {
            return Err(ctx.err(
                item.span(),
                format!("{owner}: {this} needs 'coordinate' (a joint coordinate's name)"),
            ));
        };
        let Some(k) = coordinates.iter().position(|x| &x.name == c.get_ref()) else {
            return Err(ctx.err(
                c.span(),
                format!("{owner}: no joint coordinate '{}'", c.get_ref()),
            ));
        };
        if coordinates[k].driven {
            return Err(ctx.err(
                c.span(),
                format!(
                    "{owner}: coordinate '{}' is driven (its drive supplies whatever force it takes)",
                    c.get_ref()
                ),
            ));
        }
        let Some(v) = &s.value else {
            return Err(ctx.err(
                item.span(),
                format!("{owner}: {this} needs 'value' (N·m on an angle, N on a length)"),
            ));
        };
        let value = ctx.field(v, format!("{owner} value"))?;
        ctx.nominal(&value)?;
        Ok(LoadKind::Coordinate {
            coordinate: k,
            value,
        })
    }

    /// A force (`force`) at a body's point or a torque on a body, in ground axes or turning
    /// with the body.
    fn on_body(&self, body_names: &HashMap<String, usize>, force: bool) -> R<LoadKind> {
        let (ctx, item, owner, this) = (self.ctx, self.item, &self.owner, &self.this);
        let s = item.get_ref();
        let c = s.coordinate.as_ref();
        self.unused(c.is_some(), "coordinate", c.map(|b| b.span()))?;
        let v = s.value.as_ref();
        self.unused(v.is_some(), "value", v.map(|b| b.span()))?;
        let Some(b) = &s.body else {
            return Err(ctx.err(item.span(), format!("{owner}: {this} needs 'body'")));
        };
        let Some(body) = body_ref(ctx, body_names, b)? else {
            return Err(ctx.err(
                b.span(),
                format!("{owner}: the ground takes any load; give a body"),
            ));
        };
        let follower = match s.frame.as_ref().map(|f| f.get_ref().as_str()) {
            None | Some("ground") => false,
            Some("body") => true,
            Some(other) => {
                let f = s.frame.as_ref().expect("given");
                return Err(ctx.err(
                    f.span(),
                    format!(
                        "{owner}: unknown frame '{other}' (expected ground: fixed axes, or body: turning with the body)"
                    ),
                ));
            }
        };
        let table = Item {
            owner,
            kind: this,
            span: item.span(),
        };
        let (point_use, force_use, torque_use) = if force {
            (Use::Required, Use::Required, Use::Unused)
        } else {
            (Use::Unused, Use::Unused, Use::Required)
        };
        let point = vector(ctx, &table, &s.point, point_use, "point")?;
        let force_v = vector(ctx, &table, &s.force, force_use, "force")?;
        let torque = vector(ctx, &table, &s.torque, torque_use, "torque")?;
        Ok(if force {
            LoadKind::Force {
                body,
                point: Box::new(point),
                force: Box::new(force_v),
                follower,
            }
        } else {
            LoadKind::Torque {
                body,
                torque: Box::new(torque),
                follower,
            }
        })
    }
}
