//! The `[parameters]` table and the tolerances written in it (and in the analysis cases): names,
//! nominal values, tolerances and distributions, then the overrides of the command line. Its own
//! stage because every later expression refers to these names and is checked at these values.

use super::names::check_name;
use super::{Ctx, R};
use crate::model::{Distribution, ModelError, Parameter, Tolerance};
use std::collections::BTreeMap;
use std::ops::Range;
use toml::Spanned;

/// The parameters in file order, with the `overrides` applied.
pub(super) fn parameters(
    ctx: &Ctx,
    raw: &BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    overrides: &[(String, f64)],
) -> R<Vec<Parameter>> {
    let mut praw: Vec<_> = raw.iter().collect();
    praw.sort_by_key(|(k, _)| k.span().start);
    let mut parameters = Vec::new();
    for (k, v) in praw {
        check_name(ctx, k, "parameter")?;
        if ["speed", "pi"].contains(&k.get_ref().as_str()) {
            return Err(ctx.err(
                k.span(),
                format!(
                    "'{}' is reserved and cannot be a parameter name",
                    k.get_ref()
                ),
            ));
        }
        parameters.push(parameter(ctx, k, v)?);
    }
    override_values(ctx, &mut parameters, overrides)?;
    Ok(parameters)
}

/// A tolerance: `"3%"` (relative) or a number (absolute), finite and not negative.
pub(super) fn tolerance(
    ctx: &Ctx,
    v: &toml::Value,
    span: Range<usize>,
    what: &str,
) -> R<Tolerance> {
    let bad = |m: &str| ctx.err(span.clone(), format!("{what}: {m}"));
    let t = match v {
        toml::Value::String(s) => {
            let s = s.trim();
            if let Some(p) = s.strip_suffix('%') {
                let f: f64 = p
                    .trim()
                    .parse()
                    .map_err(|_| bad(&format!("'{s}' is not a percentage such as \"3%\"")))?;
                Tolerance::Relative(f / 100.0)
            } else {
                let f: f64 = s.parse().map_err(|_| {
                    bad(&format!(
                        "'{s}' is neither a percentage (\"3%\") nor an absolute value"
                    ))
                })?;
                Tolerance::Absolute(f)
            }
        }
        toml::Value::Float(f) => Tolerance::Absolute(*f),
        toml::Value::Integer(i) => Tolerance::Absolute(*i as f64),
        _ => {
            return Err(bad(
                "a tolerance is \"3%\" (relative) or a number (absolute)",
            ));
        }
    };
    let x = match t {
        Tolerance::Relative(x) | Tolerance::Absolute(x) => x,
    };
    if !x.is_finite() || x < 0.0 {
        return Err(bad("a tolerance must be finite and not negative"));
    }
    Ok(t)
}

fn parameter(ctx: &Ctx, name: &Spanned<String>, v: &Spanned<toml::Value>) -> R<Parameter> {
    let n = name.get_ref().clone();
    let what = format!("parameter '{n}'");
    let span = v.span();
    let num = |x: &toml::Value| -> Option<f64> {
        match x {
            toml::Value::Float(f) => Some(*f),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        }
    };
    let (value, tol, dist) = match v.get_ref() {
        toml::Value::Table(t) => {
            for k in t.keys() {
                if !["value", "tolerance", "distribution"].contains(&k.as_str()) {
                    return Err(ctx.err(
                        span,
                        format!(
                            "{what}: unknown key '{k}' (expected value, tolerance, distribution)"
                        ),
                    ));
                }
            }
            let value = t
                .get("value")
                .ok_or_else(|| ctx.err(span.clone(), format!("{what}: missing 'value'")))?;
            let value = num(value).ok_or_else(|| {
                ctx.err(span.clone(), format!("{what}: 'value' must be a number"))
            })?;
            let tol = t
                .get("tolerance")
                .map(|x| tolerance(ctx, x, span.clone(), &what))
                .transpose()?;
            let dist = match t.get("distribution") {
                None => Distribution::Normal,
                Some(toml::Value::String(s)) if s == "normal" => Distribution::Normal,
                Some(toml::Value::String(s)) if s == "uniform" => Distribution::Uniform,
                Some(_) => {
                    return Err(ctx.err(
                        span,
                        format!("{what}: distribution must be \"normal\" or \"uniform\""),
                    ));
                }
            };
            (value, tol, dist)
        }
        other => {
            let value = num(other).ok_or_else(|| {
                ctx.err(
                    span.clone(),
                    format!("{what}: expected a number or {{ value = …, tolerance = \"3%\" }}"),
                )
            })?;
            (value, None, Distribution::Normal)
        }
    };
    if !value.is_finite() {
        return Err(ctx.err(span, format!("{what}: value {value} is not finite")));
    }
    Ok(Parameter {
        name: n,
        value,
        tolerance: tol,
        distribution: dist,
        site: ctx.site(&name.span(), what),
    })
}

/// Replaces the nominal values of the named parameters, before anything reads them: the
/// model is then validated exactly as if the file had said so. A name the model does not
/// declare, or a value that is not finite, is an error naming the override.
fn override_values(ctx: &Ctx, parameters: &mut [Parameter], overrides: &[(String, f64)]) -> R<()> {
    for (name, value) in overrides {
        let err = |message: String| ModelError {
            file: ctx.file.to_string(),
            line: None,
            column: None,
            message,
            snippet: None,
        };
        let Some(p) = parameters.iter().position(|p| &p.name == name) else {
            let names: Vec<&str> = parameters.iter().map(|p| p.name.as_str()).collect();
            return Err(err(format!(
                "override '{name}': the model has no such parameter (it has: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )));
        };
        if !value.is_finite() {
            return Err(err(format!("override '{name}' = {value}: not finite")));
        }
        parameters[p].value = *value;
    }
    Ok(())
}
