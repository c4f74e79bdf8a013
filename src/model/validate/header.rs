//! The file's own keys, outside any table: the model's name and description (free texts of
//! bounded length) and gravity. They describe the model as a whole, so they form one stage,
//! checked once the parameters that gravity may use are known.

use super::{Ctx, R};
use crate::model::Field;
use crate::model::schema::FileSchema;
use toml::Spanned;

/// Longest model name and description (characters).
const MAX_TITLE: usize = 200;
const MAX_DESCRIPTION: usize = 4000;

/// What the file's own keys give the model.
pub(super) struct Header {
    /// The `name` written, or the file's stem.
    pub name: String,
    pub gravity: [Field; 3],
}

/// Checks the name and description and reads gravity (zero when not given), which must
/// evaluate at the nominal values.
pub(super) fn header(ctx: &Ctx, raw: &FileSchema) -> R<Header> {
    check_text(ctx, &raw.name, "model name", MAX_TITLE)?;
    check_text(ctx, &raw.description, "description", MAX_DESCRIPTION)?;
    let gravity = match &raw.gravity {
        Some(g) => ctx.vec3(g, "gravity".into())?,
        None => [0, 1, 2].map(|i| ctx.zero(&ctx.whole(), format!("gravity[{i}]"))),
    };
    for f in &gravity {
        ctx.nominal(f)?;
    }
    let name = raw
        .name
        .as_ref()
        .map(|n| n.get_ref().clone())
        .unwrap_or_else(|| {
            std::path::Path::new(ctx.file)
                .file_stem()
                .map_or("model".into(), |s| s.to_string_lossy().into_owned())
        });
    Ok(Header { name, gravity })
}

/// A free text no longer than `max` characters.
fn check_text(ctx: &Ctx, text: &Option<Spanned<String>>, what: &str, max: usize) -> R<()> {
    if let Some(t) = text
        && t.get_ref().chars().count() > max
    {
        return Err(ctx.err(
            t.span(),
            format!(
                "the {what} has {} characters; at most {max} are allowed",
                t.get_ref().chars().count()
            ),
        ));
    }
    Ok(())
}
