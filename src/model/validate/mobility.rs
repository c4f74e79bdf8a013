//! The mechanism's mobility: the cut joints' redundant equations dropped ([`super::redundancy`]),
//! fewer independent constraint equations than free coordinates, at least one free
//! coordinate, and the `independent` coordinates that span the remaining degrees of freedom.
//! Its own stage because it weighs the joints against the cut joints, so it comes after both.

use super::{Ctx, Mechanism, R};
use crate::model::schema::FileSchema;
use crate::model::{Constraint, Coordinate, Coupler};
use toml::Spanned;

/// Drops the cut joints' redundant equations, checks that the mechanism can move, and returns
/// the `independent` coordinates (indices into `coordinates`) if the file lists them.
pub(super) fn mobility(
    ctx: &Ctx,
    raw: &FileSchema,
    mech: Mechanism,
    constraints: &mut [Constraint],
    couplers: &[Coupler],
) -> R<Option<Vec<usize>>> {
    let coordinates = mech.coordinates;
    let free: Vec<usize> = (0..coordinates.len())
        .filter(|&i| !coordinates[i].driven)
        .collect();
    if let Some(dropped) = super::redundancy::redundant(&mech, constraints, couplers, &ctx.values) {
        let (cuts, coupled) = dropped;
        if let Some(&k) = coupled.first() {
            let span = raw.couplers.get(k).map_or(ctx.whole(), |c| c.span());
            return Err(ctx.err(
                span,
                format!(
                    "coupler '{}': its equation is a combination of the cut joints' and the other couplers' at the reference configuration: a duplicate of what the loop imposes, or only tangent to it there (then the two lock the mechanism); remove it",
                    couplers[k].name
                ),
            ));
        }
        for (c, d) in constraints.iter_mut().zip(cuts) {
            c.dropped = d;
        }
    }
    let n_free = free.len();
    let written: usize = constraints
        .iter()
        .map(|c| c.kind.equations())
        .sum::<usize>()
        + couplers.len();
    let n_con: usize = constraints
        .iter()
        .map(|c| c.kind.equations() - c.dropped.len())
        .sum::<usize>()
        + couplers.len();
    if n_con > n_free || (n_con == n_free && n_con > 0) {
        let span = raw.constraints.last().map_or(ctx.whole(), |c| c.span());
        let independent = if n_con < written {
            format!(" ({written} written, {} redundant)", written - n_con)
        } else {
            String::new()
        };
        return Err(ctx.err(
            span,
            format!("{n_con} independent constraint equation(s){independent} for {n_free} free coordinate(s): the mechanism would have no degree of freedom"),
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
