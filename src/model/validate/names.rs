//! Names in a model file: well formed, unique where they must be, and resolved to what they
//! name (a body, a joint, force or cut joint type). Every table names things the same way, so
//! these checks are shared by the stages rather than one of them.

use super::locate::abbreviate;
use super::{Ctx, R};
use std::collections::{HashMap, HashSet};
use toml::Spanned;

/// Longest name of a parameter, body, joint, force, constraint or case (characters): names
/// go into column headers, file names and plot titles.
const MAX_NAME: usize = 64;

/// Names must be non-empty, short, and not clash with reserved words.
pub(super) fn check_name(ctx: &Ctx, name: &Spanned<String>, kind: &str) -> R<()> {
    let n = name.get_ref();
    if n.chars().count() > MAX_NAME {
        return Err(ctx.err(
            name.span(),
            format!(
                "{kind} name '{}' has {} characters; at most {MAX_NAME} are allowed",
                abbreviate(n),
                n.chars().count()
            ),
        ));
    }
    if n.is_empty()
        || !n
            .chars()
            .all(|c| c.is_alphanumeric() || c == '_' || c == '-')
    {
        return Err(ctx.err(
            name.span(),
            format!("{kind} name '{n}' must be non-empty and use letters, digits, '_' or '-'"),
        ));
    }
    Ok(())
}

/// The name of a force element, cut joint or coupler (`what`): well formed and unique across
/// joints, force elements, cut joints and couplers (`elements` collects all but the joints),
/// which share one namespace (outputs and messages name them alike).
pub(super) fn element_name(
    ctx: &Ctx,
    name: &Spanned<String>,
    what: &str,
    joint_names: &HashMap<String, usize>,
    elements: &mut HashSet<String>,
) -> R<String> {
    check_name(ctx, name, what)?;
    let n = name.get_ref().clone();
    let taken = if joint_names.contains_key(&n) {
        Some("a joint")
    } else if !elements.insert(n.clone()) {
        Some("another force element, beam, cut joint or coupler")
    } else {
        None
    };
    if let Some(by) = taken {
        return Err(ctx.err(
            name.span(),
            format!("duplicate name '{n}': {by} has it (joints, force elements, beams, cut joints and couplers share names)"),
        ));
    }
    Ok(n)
}

/// The type named by `kind` among `all` (whose names `name` gives), or an error of `owner`
/// listing them.
pub(super) fn type_named<K: Copy>(
    ctx: &Ctx,
    kind: &Spanned<String>,
    owner: &str,
    all: &[K],
    name: impl Fn(K) -> &'static str,
) -> R<K> {
    all.iter()
        .copied()
        .find(|&k| name(k) == kind.get_ref())
        .ok_or_else(|| {
            ctx.err(
                kind.span(),
                format!(
                    "{owner}: unknown type '{}' (expected {})",
                    kind.get_ref(),
                    list(all.iter().map(|&k| name(k)))
                ),
            )
        })
}

/// `a, b or c`.
fn list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    match v.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => v.join(""),
    }
}

/// "a" or "an" before a type name.
pub(super) fn article(name: &str) -> String {
    if name.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an".into()
    } else {
        "a".into()
    }
}

/// Resolves a body name (`ground` → `None`).
pub(super) fn body_ref(
    ctx: &Ctx,
    names: &HashMap<String, usize>,
    s: &Spanned<String>,
) -> R<Option<usize>> {
    if s.get_ref() == "ground" {
        return Ok(None);
    }
    names.get(s.get_ref()).map(|&i| Some(i)).ok_or_else(|| {
        ctx.err(
            s.span(),
            format!("unknown body '{}' (bodies are declared in [[bodies]]; 'ground' is the fixed frame)", s.get_ref()),
        )
    })
}
