//! The `[[bodies]]` tables: unique names (not `ground`), mass, centre of mass, inertia and the
//! axes it is given in, checked at the nominal values (mass not negative, inertia positive
//! semi-definite). Its own stage because joints, forces, cut joints and ports all refer to the
//! bodies by the names declared here.

use super::inertia::{check_inertia, inertia, inertia_axes, nominal_inertia};
use super::names::check_name;
use super::{Ctx, R};
use crate::model::schema::BodySchema;
use crate::model::{Body, Field, ModelError};
use std::collections::HashMap;
use toml::Spanned;

/// The bodies in file order, and the index of each by name.
pub(super) fn bodies(
    ctx: &Ctx,
    raw: &[Spanned<BodySchema>],
) -> R<(HashMap<String, usize>, Vec<Body>)> {
    let mut body_names: HashMap<String, usize> = HashMap::new();
    let mut bodies = Vec::new();
    for b in raw {
        let s = b.get_ref();
        check_name(ctx, &s.name, "body")?;
        let name = s.name.get_ref().clone();
        if name == "ground" {
            return Err(ctx.err(
                s.name.span(),
                "'ground' is the fixed frame and cannot be declared as a body",
            ));
        }
        if body_names.insert(name.clone(), bodies.len()).is_some() {
            return Err(ctx.err(s.name.span(), format!("duplicate body name '{name}'")));
        }
        bodies.push(body(ctx, b, name)?);
    }
    if bodies.is_empty() {
        return Err(ModelError {
            file: ctx.file.to_string(),
            line: None,
            column: None,
            message: "the model declares no bodies ([[bodies]])".into(),
            snippet: None,
        });
    }
    Ok((body_names, bodies))
}

/// One body, its name already checked.
fn body(ctx: &Ctx, b: &Spanned<BodySchema>, name: String) -> R<Body> {
    let s = b.get_ref();
    let what = |f: &str| format!("body '{name}' {f}");
    let mass = ctx.field(&s.mass, what("mass"))?;
    let inertia = match &s.inertia {
        None => std::array::from_fn(|i| {
            std::array::from_fn(|j| ctx.zero(&b.span(), what(&format!("inertia[{i}][{j}]"))))
        }),
        Some(sp) => inertia(ctx, sp, &what(""))?,
    };
    let cm = ctx.vec3(&s.cm, what("cm"))?;
    // Nominal checks: mass ≥ 0, inertia symmetric positive semi-definite.
    if let Some(m) = ctx.nominal(&mass)?
        && m < 0.0
    {
        return Err(ctx.err(
            s.mass.span(),
            format!("body '{name}': negative mass {m} kg"),
        ));
    }
    let inom = nominal_inertia(ctx, &inertia)?;
    for f in &cm {
        ctx.nominal(f)?;
    }
    if let Some(inom) = inom {
        let span = s.inertia.as_ref().map_or(b.span(), |x| x.span());
        check_inertia(ctx, &inom, span, &name)?;
    }
    let axes = axes(ctx, b, &name)?;
    Ok(Body {
        name,
        mass,
        inertia,
        axes,
        cm,
    })
}

/// The axes the inertia is given in: both or neither, not zero, not parallel.
fn axes(ctx: &Ctx, b: &Spanned<BodySchema>, name: &str) -> R<Option<[[Field; 3]; 2]>> {
    let s = b.get_ref();
    let what = |f: &str| format!("body '{name}' {f}");
    match (&s.x_axis, &s.y_axis) {
        (None, None) => Ok(None),
        (Some(x), Some(y)) => {
            let (x, y) = (ctx.vec3(x, what("x_axis"))?, ctx.vec3(y, what("y_axis"))?);
            inertia_axes(ctx, &x, &y, b.span(), name)?;
            Ok(Some([x, y]))
        }
        (Some(a), None) | (None, Some(a)) => Err(ctx.err(
            a.span(),
            format!(
                "body '{name}': give both 'x_axis' and 'y_axis' (the axes its inertia is given in)"
            ),
        )),
    }
}
