//! The `[[couplers]]` tables: a linear relation `a q₁ + b q₂ = c` between two free joint
//! coordinates (a gear pair `r₁ q₁ + r₂ q₂ = 0`, a rack and pinion `r θ − x = 0`, a belt). Its own
//! stage because it names coordinates, so it comes after the joints; its equation joins the cut
//! joints' in the mobility count.

use super::names::element_name;
use super::{Ctx, R};
use crate::model::schema::CouplerSchema;
use crate::model::{Coordinate, Coupler};
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// Parses and checks the `[[couplers]]` tables (names shared with the joints, `joint_names`,
/// and the force elements and cut joints, `elements`).
pub(super) fn couplers(
    ctx: &Ctx,
    raw: &[Spanned<CouplerSchema>],
    coordinates: &[Coordinate],
    joint_names: &HashMap<String, usize>,
    elements: &mut HashSet<String>,
) -> R<Vec<Coupler>> {
    let mut out = Vec::new();
    for item in raw {
        let s = item.get_ref();
        let name = element_name(ctx, &s.name, "coupler", joint_names, elements)?;
        let owner = format!("coupler '{name}'");
        let list = s.coordinates.get_ref();
        if list.len() != 2 {
            return Err(ctx.err(
                s.coordinates.span(),
                format!(
                    "{owner}: 'coordinates' lists two joint coordinates, got {}",
                    list.len()
                ),
            ));
        }
        let mut idx = [0; 2];
        for (k, c) in list.iter().enumerate() {
            let Some(i) = coordinates.iter().position(|x| &x.name == c.get_ref()) else {
                return Err(ctx.err(
                    c.span(),
                    format!("{owner}: no joint coordinate '{}'", c.get_ref()),
                ));
            };
            if coordinates[i].driven {
                return Err(ctx.err(
                    c.span(),
                    format!(
                        "{owner}: coordinate '{}' is driven; a coupler joins two free coordinates",
                        c.get_ref()
                    ),
                ));
            }
            idx[k] = i;
        }
        if idx[0] == idx[1] {
            return Err(ctx.err(
                s.coordinates.span(),
                format!("{owner}: the two coordinates are the same"),
            ));
        }
        let coef = s.coefficients.get_ref();
        if coef.len() != 2 {
            return Err(ctx.err(
                s.coefficients.span(),
                format!(
                    "{owner}: 'coefficients' are [a, b] of a q₁ + b q₂ = c, got {} entries",
                    coef.len()
                ),
            ));
        }
        let a = ctx.field(&coef[0], format!("{owner} coefficients[0]"))?;
        let b = ctx.field(&coef[1], format!("{owner} coefficients[1]"))?;
        let (na, nb) = (ctx.nominal(&a)?, ctx.nominal(&b)?);
        if na.is_some_and(|x| x == 0.0) && nb.is_some_and(|x| x == 0.0) {
            return Err(ctx.err(
                s.coefficients.span(),
                format!("{owner}: both coefficients are zero"),
            ));
        }
        let value = match &s.value {
            Some(v) => {
                let f = ctx.field(v, format!("{owner} value"))?;
                ctx.nominal(&f)?;
                f
            }
            None => ctx.zero(&item.span(), format!("{owner} value")),
        };
        out.push(Coupler {
            name,
            coordinates: idx,
            coefficients: [a, b],
            value,
        });
    }
    Ok(out)
}
