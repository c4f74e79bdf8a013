//! Fields given once per coordinate of a joint or per component of a force element: a list of
//! one value each, or a single value where that is unambiguous. Joints and force elements both
//! take them, so the rule lives in one place.

use super::{Ctx, R};
use crate::model::Field;
use crate::model::schema::{Num, Nums, SNums};
use toml::Spanned;

/// `field` or `field[i]` for coordinate `i` of `k`.
pub(super) fn indexed(field: &str, i: usize, k: usize) -> String {
    if k == 1 {
        field.into()
    } else {
        format!("{field}[{i}]")
    }
}

/// The `k` coordinates of a joint or components of a force element (`per` names which) whose
/// fields are read, and how a field of the element is named in messages (`what`).
pub(super) struct Each<'a, W> {
    pub k: usize,
    pub per: &'static str,
    pub what: &'a W,
}

impl<W: Fn(&str) -> String> Each<'_, W> {
    /// The values of `field` (given as `v`) per coordinate or component: a list of `k`, or one
    /// value where `k` is one (or, when `broadcast`, for every one).
    pub(super) fn read(
        &self,
        ctx: &Ctx,
        v: &Option<SNums>,
        field: &str,
        broadcast: bool,
    ) -> R<Vec<Option<Field>>> {
        let Each { k, per, what } = *self;
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
            Nums::Rows(_) => Err(ctx.err(
                v.span(),
                format!(
                    "{}: a matrix is taken by a force element's stiffness and damping only; give one value per {per}",
                    what(field)
                ),
            )),
        }
    }

    /// The values of `field` as a matrix over the components: its diagonal (as [`Each::read`]
    /// reads a number or a list) and, where it is given as `k` rows of `k`, its off-diagonal
    /// entries `(row, column, value)` that are not written as a plain zero.
    pub(super) fn read_matrix(&self, ctx: &Ctx, v: &Option<SNums>, field: &str) -> R<Matrix> {
        let Some(Nums::Rows(rows)) = v.as_ref().map(Spanned::get_ref) else {
            return Ok((self.read(ctx, v, field, true)?, Vec::new()));
        };
        let Each { k, per, what } = *self;
        let span = v.as_ref().map_or(0..0, Spanned::span);
        if rows.len() != k {
            return Err(ctx.err(
                span,
                format!(
                    "{}: a matrix over the {k} {per}s needs {k} rows of {k}, got {} rows",
                    what(field),
                    rows.len()
                ),
            ));
        }
        let (mut diagonal, mut cross) = (Vec::new(), Vec::new());
        for (i, row) in rows.iter().enumerate() {
            if row.get_ref().len() != k {
                return Err(ctx.err(
                    row.span(),
                    format!(
                        "{}: row {} of the matrix has {} entries, not {k} (one per {per})",
                        what(field),
                        i + 1,
                        row.get_ref().len()
                    ),
                ));
            }
            for (j, n) in row.get_ref().iter().enumerate() {
                let entry = ctx.field(n, what(&format!("{field}[{i}][{j}]")))?;
                if i == j {
                    diagonal.push(Some(entry));
                } else if !matches!(n.get_ref(), Num::Value(x) if *x == 0.0) {
                    cross.push((i, j, entry));
                }
            }
        }
        Ok((diagonal, cross))
    }
}

/// A matrix field over an element's components: the diagonal (`None`: not given) and the
/// off-diagonal entries given, `(row, column, value)`.
pub(super) type Matrix = (Vec<Option<Field>>, Vec<(usize, usize, Field)>);
