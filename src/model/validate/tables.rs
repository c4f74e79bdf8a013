//! `[[tables]]`: tabulated functions of one argument ([`crate::model::table::Table`]), callable
//! by name in every expression after them (derived parameters included). A table's name is
//! well formed, unique, and neither a parameter's nor a built-in function's; its argument
//! strictly increases; both lists are finite numbers of the same length.

use super::names::check_name;
use super::{Ctx, R};
use crate::model::schema::TableSchema;
use crate::model::table::{Column, Table};
use std::sync::Arc;
use toml::Spanned;

/// The built-in functions and reserved names a table may not take.
const RESERVED: [&str; 13] = [
    "sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "exp", "ln", "abs", "speed", "pi",
];

/// Parses and checks the tables; `derived` are the derived parameters' names.
pub(super) fn tables(
    ctx: &Ctx,
    raw: &[Spanned<TableSchema>],
    derived: &[String],
) -> R<Vec<Arc<Table>>> {
    let mut out: Vec<Arc<Table>> = Vec::new();
    for t in raw {
        let s = t.get_ref();
        check_name(ctx, &s.name, "table")?;
        let name = s.name.get_ref();
        let clash = if RESERVED.contains(&name.as_str()) {
            Some("a built-in function or reserved name")
        } else if ctx.params.contains(name) || derived.contains(name) {
            Some("a parameter")
        } else if out.iter().any(|o| &o.name == name) {
            Some("another table")
        } else {
            None
        };
        if let Some(by) = clash {
            return Err(ctx.err(
                s.name.span(),
                format!("table name '{name}' is already taken by {by}"),
            ));
        }
        let table = Table::new(name, s.x.get_ref().clone(), s.y.get_ref().clone()).map_err(
            |(list, e)| {
                let span = if list == Column::X {
                    s.x.span()
                } else {
                    s.y.span()
                };
                ctx.err(span, format!("table '{name}': {e}"))
            },
        )?;
        out.push(Arc::new(table));
    }
    Ok(out)
}
