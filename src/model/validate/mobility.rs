//! The mechanism's mobility: fewer constraint equations than free coordinates, at least one
//! free coordinate, and the `independent` coordinates that span the remaining degrees of
//! freedom. Its own stage because it weighs the joints against the cut joints, so it comes
//! after both.

use super::{Ctx, R};
use crate::model::schema::FileSchema;
use crate::model::{Constraint, Coordinate};
use toml::Spanned;

/// Checks that the mechanism can move, and returns the `independent` coordinates (indices
/// into `coordinates`) if the file lists them.
pub(super) fn mobility(
    ctx: &Ctx,
    raw: &FileSchema,
    coordinates: &[Coordinate],
    constraints: &[Constraint],
) -> R<Option<Vec<usize>>> {
    let n_free = coordinates.iter().filter(|c| !c.driven).count();
    let n_con: usize = constraints.iter().map(|c| c.kind.equations()).sum();
    if n_con > n_free || (n_con == n_free && !constraints.is_empty()) {
        let span = raw.constraints.last().map_or(ctx.whole(), |c| c.span());
        return Err(ctx.err(
            span,
            format!("{n_con} constraint equation(s) for {n_free} free coordinate(s): the mechanism would have no degree of freedom"),
        ));
    }
    if n_free == 0 {
        let span = raw.joints.first().map_or(ctx.whole(), |c| c.span());
        return Err(ctx.err(
            span,
            "the mechanism has no free coordinate (every joint is fixed or driven)",
        ));
    }
    raw.independent
        .as_ref()
        .map(|list| independent(ctx, list, coordinates, n_free - n_con))
        .transpose()
}

/// The listed coordinates: free, each once, as many as the degrees of freedom.
fn independent(
    ctx: &Ctx,
    list: &Spanned<Vec<Spanned<String>>>,
    coordinates: &[Coordinate],
    dof: usize,
) -> R<Vec<usize>> {
    let mut out = Vec::new();
    for n in list.get_ref() {
        let Some(ci) = coordinates.iter().position(|c| &c.name == n.get_ref()) else {
            return Err(ctx.err(
                n.span(),
                format!(
                    "independent: '{}' is not a joint with a coordinate",
                    n.get_ref()
                ),
            ));
        };
        if coordinates[ci].driven {
            return Err(ctx.err(
                n.span(),
                format!("independent: joint '{}' is driven", n.get_ref()),
            ));
        }
        if out.contains(&ci) {
            return Err(ctx.err(
                n.span(),
                format!("independent: '{}' is listed twice", n.get_ref()),
            ));
        }
        out.push(ci);
    }
    if out.len() != dof {
        return Err(ctx.err(
            list.span(),
            format!(
                "independent lists {} coordinate(s) but the mechanism has {dof} degree(s) of freedom",
                out.len()
            ),
        ));
    }
    Ok(out)
}
