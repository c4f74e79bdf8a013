//! Tree joints of a model file: type, bodies, geometry and the per-coordinate fields, checked
//! against what the joint type ([`crate::joints::JointType`]) declares.

use super::{Ctx, R, body_ref, check_name, type_named};
use crate::joints::{Kind, Use};
use crate::model::schema::{JointSchema, Nums, SNums, SVec};
use crate::model::{Body, Coordinate, Expr, Field};
use std::collections::HashMap;
use std::ops::Range;
use toml::Spanned;

/// The joints, their coordinates, and for each body the joint whose child it is.
pub(super) struct Tree {
    pub joints: Vec<crate::model::Joint>,
    pub coordinates: Vec<Coordinate>,
    pub child_of: Vec<Option<usize>>,
    pub names: HashMap<String, usize>,
}

/// Parses and checks the `[[joints]]` tables.
pub(super) fn joints(
    ctx: &Ctx,
    raw: &[Spanned<JointSchema>],
    body_names: &HashMap<String, usize>,
    bodies: &[Body],
    nominal: &[f64],
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
        let what = |f: &str| format!("joint '{name}' {f}");
        let kind = type_named(
            ctx,
            &s.kind,
            &format!("joint '{name}'"),
            Kind::ALL,
            Kind::name,
        )?;
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
        tree.child_of[child] = Some(tree.joints.len());

        let [use_at, use_axis, use_axis2] = kind.uses();
        let owner = format!("joint '{name}'");
        let article = article(kind.name());
        let this = format!("{article} {} joint", kind.name());
        let at = vector(ctx, &s.at, use_at, "at", &owner, &this, &j.span(), nominal)?;
        let axis = vector(
            ctx,
            &s.axis,
            use_axis,
            "axis",
            &owner,
            &this,
            &j.span(),
            nominal,
        )?;
        let axis2 = match (&s.axis2, use_axis2) {
            (None, Use::Optional) => least_aligned(ctx, &axis, &owner, &j.span(), nominal)?,
            _ => vector(
                ctx,
                &s.axis2,
                use_axis2,
                "axis2",
                &owner,
                &this,
                &j.span(),
                nominal,
            )?,
        };
        if use_axis2 != Use::Unused {
            not_parallel(
                ctx,
                &axis,
                &axis2,
                &owner,
                s.axis2.as_ref().map_or(j.span(), |a| a.span()),
                nominal,
            )?;
        }

        let specs = kind.coordinates();
        let k = specs.len();
        if k == 0 {
            for (f, n) in [
                (&s.stiffness, "stiffness"),
                (&s.damping, "damping"),
                (&s.initial, "initial"),
            ] {
                if let Some(x) = f {
                    return Err(ctx.err(
                        x.span(),
                        format!("{owner}: {this} has no coordinate, so no '{n}'"),
                    ));
                }
            }
            if let Some(x) = &s.drive {
                return Err(ctx.err(
                    x.span(),
                    format!("{owner}: {this} has no coordinate, so no 'drive'"),
                ));
            }
        }
        if k > 1
            && let Some(x) = &s.drive
        {
            return Err(ctx.err(
                x.span(),
                format!(
                        "{owner}: {this} has {k} coordinates and only one-coordinate joints can be driven; drive a revolute or prismatic joint"
                ),
            ));
        }
        let zero = |f: &str, v: Vec<Option<Field>>| -> Vec<Field> {
            v.into_iter()
                .enumerate()
                .map(|(i, x)| x.unwrap_or_else(|| ctx.zero(&j.span(), what(&indexed(f, i, k)))))
                .collect()
        };
        let initial = zero(
            "initial",
            per_coordinate(ctx, &s.initial, k, "initial", false, "coordinate", &what)?,
        );
        let free = zero(
            "free",
            per_coordinate(ctx, &s.free, k, "free", false, "coordinate", &what)?,
        );
        let stiffness =
            per_coordinate(ctx, &s.stiffness, k, "stiffness", true, "coordinate", &what)?;
        let damping = per_coordinate(ctx, &s.damping, k, "damping", true, "coordinate", &what)?;
        let drive = ctx.opt_field(&s.drive, what("drive"))?;
        for f in initial
            .iter()
            .chain(&free)
            .chain(drive.iter())
            .chain(stiffness.iter().flatten())
            .chain(damping.iter().flatten())
        {
            ctx.nominal(f, nominal)?;
        }
        let first = tree.coordinates.len();
        for spec in specs {
            tree.coordinates.push(Coordinate {
                joint: tree.joints.len(),
                name: if k == 1 {
                    name.clone()
                } else {
                    format!("{name}.{}", spec.suffix)
                },
                unit: spec.unit,
                driven: drive.is_some(),
            });
        }
        tree.joints.push(crate::model::Joint {
            name,
            kind,
            parent,
            child,
            geometry: crate::joints::Geometry { at, axis, axis2 },
            initial,
            drive,
            stiffness,
            free,
            damping,
            coords: first..tree.coordinates.len(),
        });
    }
    Ok(tree)
}

/// "a" or "an" before a type name.
pub(super) fn article(name: &str) -> String {
    if name.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an".into()
    } else {
        "a".into()
    }
}

/// `a, b or c`.
pub(super) fn list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    match v.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => v.join(""),
    }
}

/// `field` or `field[i]` for coordinate `i` of `k`.
pub(super) fn indexed(field: &str, i: usize, k: usize) -> String {
    if k == 1 {
        field.into()
    } else {
        format!("{field}[{i}]")
    }
}

/// A geometry vector as the type uses it: required, optional (default zero), ignored or
/// refused. A direction (`axis`, `axis2`) that is used must not be zero.
#[allow(clippy::too_many_arguments)]
pub(super) fn vector(
    ctx: &Ctx,
    v: &Option<SVec>,
    usage: Use,
    field: &str,
    owner: &str,
    kind: &str,
    item: &Range<usize>,
    nominal: &[f64],
) -> R<[Field; 3]> {
    let out = match (v, usage) {
        (None, Use::Required) => {
            return Err(ctx.err(
                item.clone(),
                format!("{owner}: {kind} needs '{field}'{}", hint(field)),
            ));
        }
        (Some(v), Use::Unused) => {
            return Err(ctx.err(v.span(), format!("{owner}: {kind} has no '{field}'")));
        }
        (Some(v), _) => ctx.vec3(v, format!("{owner} {field}"))?,
        (None, _) => [0, 1, 2].map(|i| ctx.zero(item, format!("{owner} {field}[{i}]"))),
    };
    for f in &out {
        ctx.nominal(f, nominal)?;
    }
    let direction = field.starts_with("axis") && matches!(usage, Use::Required | Use::Optional);
    if direction && let Some(n) = known(ctx, &out, nominal)? {
        // Any non-zero direction is an axis (the mechanics scales it before normalising).
        if n.iter().all(|x| x.abs() <= 0.0) {
            let span = v.as_ref().map_or(item.clone(), |a| a.span());
            return Err(ctx.err(span, format!("{owner}: {field} is zero")));
        }
    }
    Ok(out)
}

fn hint(field: &str) -> &'static str {
    match field {
        "at" => " (a point on its axis or its centre)",
        "axis2" => " (a second direction, not parallel to 'axis')",
        _ => "",
    }
}

/// Nominal values of a vector, when none depends on the speed.
pub(super) fn known(ctx: &Ctx, v: &[Field; 3], nominal: &[f64]) -> R<Option<[f64; 3]>> {
    let mut out = [0.0; 3];
    for (o, f) in out.iter_mut().zip(v) {
        match ctx.nominal(f, nominal)? {
            Some(x) => *o = x,
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// The coordinate axis least aligned with `axis` at the nominal values, as constant fields: the
/// default second direction.
pub(super) fn least_aligned(
    ctx: &Ctx,
    axis: &[Field; 3],
    owner: &str,
    item: &Range<usize>,
    nominal: &[f64],
) -> R<[Field; 3]> {
    let Some(a) = known(ctx, axis, nominal)? else {
        return Err(ctx.err(
            item.clone(),
            format!("{owner}: its axis depends on the speed, so give 'axis2' (a second direction)"),
        ));
    };
    let mut best = 0;
    for i in 1..3 {
        if a[i].abs() < a[best].abs() {
            best = i;
        }
    }
    Ok([0, 1, 2].map(|i| Field {
        expr: Expr::Num(if i == best { 1.0 } else { 0.0 }),
        site: ctx.site(item, format!("{owner} axis2[{i}] (default)")),
    }))
}

/// Refuses (nominally) parallel `axis` and `axis2`.
pub(super) fn not_parallel(
    ctx: &Ctx,
    axis: &[Field; 3],
    axis2: &[Field; 3],
    owner: &str,
    span: Range<usize>,
    nominal: &[f64],
) -> R<()> {
    if let (Some(a), Some(b)) = (known(ctx, axis, nominal)?, known(ctx, axis2, nominal)?) {
        let scale = |v: [f64; 3]| {
            let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            v.map(|x| x / m)
        };
        let (a, b) = (scale(a), scale(b));
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm(c) <= 1e-9 * norm(a) * norm(b) {
            return Err(ctx.err(span, format!("{owner}: axis2 is parallel to axis")));
        }
    }
    Ok(())
}

/// Values given per coordinate (or, for a force element, per component: `per` names which): a
/// list of `k`, or one value where `k` is one (or, when `broadcast`, for every one).
pub(super) fn per_coordinate(
    ctx: &Ctx,
    v: &Option<SNums>,
    k: usize,
    field: &str,
    broadcast: bool,
    per: &str,
    what: &impl Fn(&str) -> String,
) -> R<Vec<Option<Field>>> {
    let Some(v) = v else {
        return Ok(vec![None; k]);
    };
    match v.get_ref() {
        Nums::One(n) if k == 1 || broadcast => {
            let sn = Spanned::new(v.span(), n.clone());
            (0..k)
                .map(|i| ctx.field(&sn, what(&indexed(field, i, k))).map(Some))
                .collect()
        }
        Nums::One(_) => Err(ctx.err(
            v.span(),
            format!("{}: give one value per {per}, a list of {k}", what(field)),
        )),
        Nums::Many(items) if items.len() == k => items
            .iter()
            .enumerate()
            .map(|(i, n)| ctx.field(n, what(&indexed(field, i, k))).map(Some))
            .collect(),
        Nums::Many(items) => Err(ctx.err(
            v.span(),
            format!(
                "{}: expected {k} value(s), one per {per}, got {}",
                what(field),
                items.len()
            ),
        )),
    }
}
