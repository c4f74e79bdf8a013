//! Geometry vectors of joints, force elements, cut joints and ports: a point or direction is
//! required, optional or refused as the item's type declares, a direction is not zero, a
//! second direction is not parallel to the first, two points coincide or not. The four tables
//! check their vectors alike, so the checks live here rather than with one of them.

use super::{Ctx, R};
use crate::joints::Use;
use crate::model::schema::SVec;
use crate::model::{Expr, Field};
use std::ops::Range;

/// The table a vector belongs to, as messages name it.
pub(super) struct Item<'a> {
    /// The item itself: `joint 'hinge'`.
    pub owner: &'a str,
    /// Its type with an article: `a revolute joint`.
    pub kind: &'a str,
    /// The whole table, where a missing field is reported.
    pub span: Range<usize>,
}

/// A geometry vector as the type uses it: required, optional (default zero), ignored or
/// refused. A direction (`axis`, `axis2`) that is used must not be zero.
pub(super) fn vector(
    ctx: &Ctx,
    item: &Item,
    v: &Option<SVec>,
    usage: Use,
    field: &str,
) -> R<[Field; 3]> {
    let Item { owner, kind, span } = item;
    let out = match (v, usage) {
        (None, Use::Required) => {
            return Err(ctx.err(
                span.clone(),
                format!("{owner}: {kind} needs '{field}'{}", hint(field)),
            ));
        }
        (Some(v), Use::Unused) => {
            return Err(ctx.err(v.span(), format!("{owner}: {kind} has no '{field}'")));
        }
        (Some(v), _) => ctx.vec3(v, format!("{owner} {field}"))?,
        (None, _) => [0, 1, 2].map(|i| ctx.zero(span, format!("{owner} {field}[{i}]"))),
    };
    for f in &out {
        ctx.nominal(f)?;
    }
    let direction = field.starts_with("axis") && matches!(usage, Use::Required | Use::Optional);
    if direction && let Some(n) = known(ctx, &out)? {
        // Any non-zero direction is an axis (the mechanics scales it before normalising).
        if n.iter().all(|x| x.abs() <= 0.0) {
            let span = v.as_ref().map_or(span.clone(), |a| a.span());
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
pub(super) fn known(ctx: &Ctx, v: &[Field; 3]) -> R<Option<[f64; 3]>> {
    let mut out = [0.0; 3];
    for (o, f) in out.iter_mut().zip(v) {
        match ctx.nominal(f)? {
            Some(x) => *o = x,
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// The coordinate axis least aligned with `axis` at the nominal values, as constant fields: the
/// default second direction.
pub(super) fn least_aligned(ctx: &Ctx, item: &Item, axis: &[Field; 3]) -> R<[Field; 3]> {
    let Item { owner, span, .. } = item;
    let Some(a) = known(ctx, axis)? else {
        return Err(ctx.err(
            span.clone(),
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
        site: ctx.site(span, format!("{owner} axis2[{i}] (default)")),
    }))
}

/// Are `a` and `b` parallel (|a × b| ≤ 10⁻⁹ |a| |b|, each scaled to a largest entry of 1 first,
/// so that the test does not depend on their lengths)? `None` where either is zero.
pub(super) fn parallel(a: [f64; 3], b: [f64; 3]) -> Option<bool> {
    let scale = |v: [f64; 3]| {
        let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        (m > 0.0).then(|| v.map(|x| x / m))
    };
    let (a, b) = (scale(a)?, scale(b)?);
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    Some(norm(c) <= 1e-9 * norm(a) * norm(b))
}

/// Refuses (nominally) parallel `axis` and `axis2`, pointing at `axis2` as `written` (or, when
/// it was not, at the item).
pub(super) fn not_parallel(
    ctx: &Ctx,
    item: &Item,
    axis: &[Field; 3],
    axis2: &[Field; 3],
    written: &Option<SVec>,
) -> R<()> {
    let span = written.as_ref().map_or(item.span.clone(), |a| a.span());
    if let (Some(a), Some(b)) = (known(ctx, axis)?, known(ctx, axis2)?) {
        // A zero axis is refused where it is read; here it is not parallel to anything.
        if parallel(a, b) == Some(true) {
            return Err(ctx.err(span, format!("{}: axis2 is parallel to axis", item.owner)));
        }
    }
    Ok(())
}

/// Do two points (known at nominal, not depending on the speed) coincide?
pub(super) fn coincident(ctx: &Ctx, a: &[Field; 3], b: &[Field; 3]) -> R<bool> {
    for (x, y) in a.iter().zip(b) {
        match (ctx.nominal(x)?, ctx.nominal(y)?) {
            (Some(u), Some(v)) if (u - v).abs() <= 0.0 => {}
            _ => return Ok(false),
        }
    }
    Ok(true)
}
