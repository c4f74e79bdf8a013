//! A body's inertia: three principal values or a 3×3 matrix of numbers or expressions, in axes
//! that are neither zero nor parallel, symmetric and positive semi-definite at the nominal
//! values. Apart from the body's other fields because it is the one field with a shape of its
//! own and checks of its own.

use super::geometry::{known, parallel};
use super::{Ctx, R};
use crate::model::Field;
use crate::model::schema::Num;
use std::ops::Range;
use toml::Spanned;

/// Reads an inertia given as three principal values or a 3×3 matrix of numbers or expressions.
pub(super) fn inertia(ctx: &Ctx, v: &Spanned<toml::Value>, what: &str) -> R<[[Field; 3]; 3]> {
    let span = v.span();
    let bad = || {
        ctx.err(span.clone(), format!("{what}inertia: expected 3 principal values [Ixx, Iyy, Izz] or a 3×3 matrix of numbers or expressions"))
    };
    let num = |x: &toml::Value, i: usize, j: usize| -> R<Field> {
        let n = match x {
            toml::Value::Float(f) => Num::Value(*f),
            toml::Value::Integer(k) => Num::Value(*k as f64),
            toml::Value::String(s) => Num::Expr(s.clone()),
            _ => return Err(bad()),
        };
        // Entries carry the span of the whole array: errors point at its start.
        ctx.field(
            &Spanned::new(span.clone(), n),
            format!("{what}inertia[{i}][{j}]"),
        )
    };
    let toml::Value::Array(rows) = v.get_ref() else {
        return Err(bad());
    };
    if rows.len() != 3 {
        return Err(bad());
    }
    if rows.iter().all(|r| !r.is_array()) {
        let d = [
            num(&rows[0], 0, 0)?,
            num(&rows[1], 1, 1)?,
            num(&rows[2], 2, 2)?,
        ];
        return Ok(std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                if i == j {
                    d[i].clone()
                } else {
                    ctx.zero(&span, format!("{what}inertia[{i}][{j}]"))
                }
            })
        }));
    }
    let mut out: Vec<Vec<Field>> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let toml::Value::Array(r) = r else {
            return Err(bad());
        };
        if r.len() != 3 {
            return Err(bad());
        }
        out.push(
            r.iter()
                .enumerate()
                .map(|(j, x)| num(x, i, j))
                .collect::<R<Vec<_>>>()?,
        );
    }
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| out[i][j].clone())
    }))
}

/// The inertia at the nominal values, when no entry depends on the speed (every entry is
/// evaluated, so the first that fails is reported).
pub(super) fn nominal_inertia(ctx: &Ctx, inertia: &[[Field; 3]; 3]) -> R<Option<[[f64; 3]; 3]>> {
    let mut inom = [[0.0; 3]; 3];
    let mut all_known = true;
    for i in 0..3 {
        for j in 0..3 {
            match ctx.nominal(&inertia[i][j])? {
                Some(v) => inom[i][j] = v,
                None => all_known = false,
            }
        }
    }
    Ok(all_known.then_some(inom))
}

/// Inertia axes: neither zero nor parallel at the nominal values.
pub(super) fn inertia_axes(
    ctx: &Ctx,
    x: &[Field; 3],
    y: &[Field; 3],
    span: Range<usize>,
    name: &str,
) -> R<()> {
    let (Some(a), Some(b)) = (known(ctx, x)?, known(ctx, y)?) else {
        return Ok(());
    };
    let Some(parallel) = parallel(a, b) else {
        return Err(ctx.err(span, format!("body '{name}': x_axis or y_axis is zero")));
    };
    if parallel {
        return Err(ctx.err(
            span,
            format!("body '{name}': x_axis and y_axis are parallel"),
        ));
    }
    Ok(())
}

/// Symmetric and positive semi-definite (see [`crate::model::admissible::inertia_defect`]).
pub(super) fn check_inertia(ctx: &Ctx, i: &[[f64; 3]; 3], span: Range<usize>, name: &str) -> R<()> {
    match crate::model::admissible::inertia_defect(i) {
        Some((defect, value)) => {
            Err(ctx.err(span, format!("body '{name}': {defect}: {value:.6e}")))
        }
        None => Ok(()),
    }
}
