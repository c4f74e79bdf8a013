//! Tree joints of a model file: type, bodies, geometry and the per-coordinate fields, checked
//! against what the joint type ([`crate::joints::JointType`]) declares.

use super::geometry::{Item, least_aligned, not_parallel, vector};
use super::names::{article, body_ref, check_name, type_named};
use super::per_coordinate::{Each, indexed};
use super::{Ctx, R};
use crate::joints::{Geometry, Kind, Use};
use crate::model::schema::JointSchema;
use crate::model::{Body, Coordinate, Field};
use std::collections::HashMap;
use toml::Spanned;

/// The joints, their coordinates, and for each body the joint whose child it is.
pub(super) struct Tree {
    pub joints: Vec<crate::model::Joint>,
    pub coordinates: Vec<Coordinate>,
    pub child_of: Vec<Option<usize>>,
    pub names: HashMap<String, usize>,
}

/// The fields a joint gives per coordinate, and its drive.
struct CoordinateFields {
    initial: Vec<Field>,
    free: Vec<Field>,
    stiffness: Vec<Option<Field>>,
    damping: Vec<Option<Field>>,
    drive: Option<Field>,
}

/// Parses and checks the `[[joints]]` tables.
pub(super) fn joints(
    ctx: &Ctx,
    raw: &[Spanned<JointSchema>],
    body_names: &HashMap<String, usize>,
    bodies: &[Body],
) -> R<Tree> {
    let mut tree = Tree {
        joints: Vec::new(),
        coordinates: Vec::new(),
        child_of: vec![None; bodies.len()],
        names: HashMap::new(),
    };
    for j in raw {
        let s = j.get_ref();
        check_name(ctx, &s.name, "joint")?;
        let name = s.name.get_ref().clone();
        if tree.names.insert(name.clone(), tree.joints.len()).is_some() {
            return Err(ctx.err(s.name.span(), format!("duplicate joint name '{name}'")));
        }
        let owner = format!("joint '{name}'");
        let kind = type_named(ctx, &s.kind, &owner, Kind::ALL, Kind::name)?;
        let (parent, child) = ends(ctx, s, body_names, bodies, &tree)?;
        tree.child_of[child] = Some(tree.joints.len());

        let this = format!("{} {} joint", article(kind.name()), kind.name());
        let item = Item {
            owner: &owner,
            kind: &this,
            span: j.span(),
        };
        let geometry = geometry(ctx, &item, s, kind)?;
        let fields = coordinate_fields(ctx, &item, s, kind)?;
        let first = tree.coordinates.len();
        let k = kind.coordinates().len();
        for spec in kind.coordinates() {
            tree.coordinates.push(Coordinate {
                joint: tree.joints.len(),
                name: if k == 1 {
                    name.clone()
                } else {
                    format!("{name}.{}", spec.suffix)
                },
                unit: spec.unit,
                driven: fields.drive.is_some(),
            });
        }
        tree.joints.push(crate::model::Joint {
            name,
            kind,
            parent,
            child,
            geometry,
            initial: fields.initial,
            drive: fields.drive,
            stiffness: fields.stiffness,
            free: fields.free,
            damping: fields.damping,
            coords: first..tree.coordinates.len(),
        });
    }
    Ok(tree)
}

/// The joint's parent (`None`: ground) and child: distinct, and the child not yet the child of
/// another joint of `tree`.
fn ends(
    ctx: &Ctx,
    s: &JointSchema,
    body_names: &HashMap<String, usize>,
    bodies: &[Body],
    tree: &Tree,
) -> R<(Option<usize>, usize)> {
    let name = s.name.get_ref();
    let parent = body_ref(ctx, body_names, &s.parent)?;
    let child = body_ref(ctx, body_names, &s.child)?.ok_or_else(|| {
        ctx.err(
            s.child.span(),
            format!("joint '{name}': ground cannot be a child"),
        )
    })?;
    if parent == Some(child) {
        return Err(ctx.err(
            s.child.span(),
            format!(
                "joint '{name}' connects body '{}' to itself",
                bodies[child].name
            ),
        ));
    }
    if let Some(prev) = tree.child_of[child] {
        return Err(ctx.err(
            s.child.span(),
            format!(
                "body '{}' is the child of two joints ('{}' and '{name}'); a body has one parent joint, close loops with [[constraints]]",
                bodies[child].name, tree.joints[prev].name
            ),
        ));
    }
    Ok((parent, child))
}

/// The joint's point and axes, as its type uses them; a second axis it may omit defaults to the
/// coordinate axis least aligned with the first.
fn geometry(ctx: &Ctx, item: &Item, s: &JointSchema, kind: Kind) -> R<Geometry<[Field; 3]>> {
    let [use_at, use_axis, use_axis2] = kind.uses();
    let at = vector(ctx, item, &s.at, use_at, "at")?;
    let axis = vector(ctx, item, &s.axis, use_axis, "axis")?;
    let axis2 = match (&s.axis2, use_axis2) {
        (None, Use::Optional) => least_aligned(ctx, item, &axis)?,
        _ => vector(ctx, item, &s.axis2, use_axis2, "axis2")?,
    };
    if use_axis2 != Use::Unused {
        not_parallel(ctx, item, &axis, &axis2, &s.axis2)?;
    }
    Ok(Geometry { at, axis, axis2 })
}

/// Initial value, free value, stiffness and damping per coordinate, and the drive: refused
/// where the type has no coordinate (the drive also where it has more than one), and checked
/// at the nominal values.
fn coordinate_fields(ctx: &Ctx, item: &Item, s: &JointSchema, kind: Kind) -> R<CoordinateFields> {
    let k = kind.coordinates().len();
    refuse_fields(ctx, item, s, k)?;
    let what = |f: &str| format!("{} {f}", item.owner);
    let each = Each {
        k,
        per: "coordinate",
        what: &what,
    };
    let zero = |f: &str, v: Vec<Option<Field>>| -> Vec<Field> {
        v.into_iter()
            .enumerate()
            .map(|(i, x)| x.unwrap_or_else(|| ctx.zero(&item.span, what(&indexed(f, i, k)))))
            .collect()
    };
    let initial = zero("initial", each.read(ctx, &s.initial, "initial", false)?);
    let free = zero("free", each.read(ctx, &s.free, "free", false)?);
    let stiffness = each.read(ctx, &s.stiffness, "stiffness", true)?;
    let damping = each.read(ctx, &s.damping, "damping", true)?;
    let drive = ctx.opt_field(&s.drive, what("drive"))?;
    for f in initial
        .iter()
        .chain(&free)
        .chain(drive.iter())
        .chain(stiffness.iter().flatten())
        .chain(damping.iter().flatten())
    {
        ctx.nominal(f)?;
    }
    Ok(CoordinateFields {
        initial,
        free,
        stiffness,
        damping,
        drive,
    })
}

/// Refuses the per-coordinate fields and the drive of a type with no coordinate (`k` = 0), and
/// the drive of one with more than one.
fn refuse_fields(ctx: &Ctx, item: &Item, s: &JointSchema, k: usize) -> R<()> {
    let Item { owner, kind, .. } = item;
    if k == 0 {
        for (f, n) in [
            (&s.stiffness, "stiffness"),
            (&s.damping, "damping"),
            (&s.initial, "initial"),
        ] {
            if let Some(x) = f {
                return Err(ctx.err(
                    x.span(),
                    format!("{owner}: {kind} has no coordinate, so no '{n}'"),
                ));
            }
        }
        if let Some(x) = &s.drive {
            return Err(ctx.err(
                x.span(),
                format!("{owner}: {kind} has no coordinate, so no 'drive'"),
            ));
        }
    }
    if k > 1
        && let Some(x) = &s.drive
    {
        return Err(ctx.err(
            x.span(),
            format!(
                "{owner}: {kind} has {k} coordinates and only one-coordinate joints can be driven; drive a revolute or prismatic joint"
            ),
        ));
    }
    Ok(())
}
