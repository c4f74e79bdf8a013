//! The `[parameters]` table and the tolerances written in it (and in the analysis cases): names,
//! nominal values, tolerances and distributions, then the overrides of the command line, then the
//! derived parameters (`h = "L/10"`: an expression of other parameters, resolved in the order of
//! their dependencies, a cycle refused). Its own stage because every later expression refers to
//! these names and is checked at these values.
//!
//! A derived parameter is put in place of its name wherever it is used, as if its expression
//! were written there in brackets: a model written with `h = "L/10"` is the model with `(L/10)`
//! written in every field, to the bit, and a tolerance on `L` reaches everything made from it.
//! It is not a design variable of its own: it carries no tolerance, and `--set` and the
//! tolerance cases refuse it, naming what it is made of.

use super::names::check_name;
use super::{Ctx, R};
use crate::model::{Derived, Distribution, Expr, ModelError, Parameter, Tolerance};
use std::collections::BTreeMap;
use std::ops::Range;
use toml::Spanned;

/// A derived parameter as written: its name, its expression and where that is.
pub(super) struct RawDerived {
    pub(super) name: String,
    text: String,
    span: Range<usize>,
}

/// Derived parameters may expand to at most this many terms ([`Expr::terms`]: a chain of
/// parameters each using the previous one twice doubles them at every link).
const MAX_TERMS: usize = 100_000;

/// The parameters in file order, with the `overrides` applied, and the derived ones as written.
pub(super) fn parameters(
    ctx: &Ctx,
    raw: &BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    overrides: &[(String, f64)],
) -> R<(Vec<Parameter>, Vec<RawDerived>)> {
    let mut praw: Vec<_> = raw.iter().collect();
    praw.sort_by_key(|(k, _)| k.span().start);
    let mut parameters = Vec::new();
    let mut derived = Vec::new();
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
        match v.get_ref() {
            toml::Value::String(text) => derived.push(RawDerived {
                name: k.get_ref().clone(),
                text: text.clone(),
                span: v.span(),
            }),
            _ => parameters.push(parameter(ctx, k, v)?),
        }
    }
    override_values(ctx, &mut parameters, &derived, overrides)?;
    Ok((parameters, derived))
}

/// Resolves the derived parameters over the declared ones, in the order of their
/// dependencies: each expression with the derived parameters it uses put in place, and its
/// nominal value. Refuses an unknown name, the speed, a cycle and an expansion beyond
/// [`MAX_TERMS`], each at its place.
pub(super) fn derived(ctx: &Ctx, raw: &[RawDerived]) -> R<Vec<Derived>> {
    let mut done: Vec<Option<Expr>> = vec![None; raw.len()];
    loop {
        let mut progress = false;
        for k in 0..raw.len() {
            if done[k].is_some() {
                continue;
            }
            let d = &raw[k];
            let waiting = std::cell::Cell::new(false);
            let lookup = |name: &str| {
                if let Some(i) = ctx.params.iter().position(|p| p == name) {
                    return Some(Expr::Param(i));
                }
                let j = raw.iter().position(|r| r.name == name)?;
                match &done[j] {
                    Some(e) => Some(e.clone()),
                    None => {
                        waiting.set(true);
                        Some(Expr::Num(0.0))
                    }
                }
            };
            let what = format!("parameter '{}'", d.name);
            let e = Expr::parse_in(&d.text, &lookup, &|name| ctx.table(name)).map_err(|e| {
                ctx.err(
                    d.span.start + 1 + e.offset..d.span.end,
                    format!("{what}: bad expression \"{}\": {}", d.text, e.message),
                )
            })?;
            if waiting.get() {
                continue;
            }
            if e.uses_speed() {
                return Err(ctx.err(
                    d.span.clone(),
                    format!(
                        "{what}: a parameter cannot depend on the speed (write `speed` in the fields that do)"
                    ),
                ));
            }
            if e.terms() > MAX_TERMS {
                return Err(ctx.err(
                    d.span.clone(),
                    format!(
                        "{what}: its expression expands to more than {MAX_TERMS} terms through the derived parameters it uses"
                    ),
                ));
            }
            done[k] = Some(e);
            progress = true;
        }
        if done.iter().all(Option::is_some) {
            break;
        }
        if !progress {
            let members = cycle(ctx, raw, &done);
            let mut names: Vec<&str> = members.iter().map(|&k| raw[k].name.as_str()).collect();
            names.push(names[0]);
            let first = &raw[members[0]];
            return Err(ctx.err(
                first.span.clone(),
                format!(
                    "parameter '{}': derived parameters defined through each other in a cycle ({})",
                    first.name,
                    names.join(" → ")
                ),
            ));
        }
    }
    raw.iter()
        .zip(done)
        .map(|(d, e)| {
            let expr = e.expect("every one resolved");
            let what = format!("parameter '{}'", d.name);
            let value = expr
                .eval(&ctx.values, 0.0)
                .map_err(|e| ctx.err(d.span.clone(), format!("{what}: {e}")))?;
            Ok(Derived {
                name: d.name.clone(),
                text: d.text.clone(),
                expr,
                value,
                site: ctx.site(&d.span, what),
            })
        })
        .collect()
}

/// A cycle among the derived parameters left unresolved (`done[k]` is `None`), as indices into
/// `raw` in the order each uses the next, starting at the one written first. Every unresolved
/// parameter uses another unresolved one (else it would have resolved), so a walk along such
/// uses from any of them comes back to a parameter it has passed: the walk from there on is a
/// cycle, and the parameters that merely use it are not in it.
fn cycle(ctx: &Ctx, raw: &[RawDerived], done: &[Option<Expr>]) -> Vec<usize> {
    let waiting_on = |k: usize| {
        let used = std::cell::RefCell::new(Vec::new());
        let lookup = |name: &str| {
            if let Some(j) = raw.iter().position(|r| r.name == name) {
                used.borrow_mut().push(j);
            } else if !ctx.params.iter().any(|p| p == name) {
                return None;
            }
            Some(Expr::Num(0.0))
        };
        // Parsed once before without an error, so only the uses matter.
        let _ = Expr::parse_in(&raw[k].text, &lookup, &|name| ctx.table(name));
        used.into_inner().into_iter().find(|&j| done[j].is_none())
    };
    let Some(start) = done.iter().position(Option::is_none) else {
        return Vec::new();
    };
    let mut path = vec![start];
    while let Some(next) = waiting_on(*path.last().unwrap_or(&start)) {
        if let Some(at) = path.iter().position(|&p| p == next) {
            let mut members = path.split_off(at);
            let first = (0..members.len()).min_by_key(|&i| members[i]).unwrap_or(0);
            members.rotate_left(first);
            return members;
        }
        path.push(next);
    }
    path
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
            if let toml::Value::String(text) = value {
                return Err(ctx.err(
                    span,
                    format!(
                        "{what}: a parameter defined by an expression is written {n} = \"{text}\" (no table): it carries no tolerance or distribution of its own; tolerance the parameters it is made of"
                    ),
                ));
            }
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
fn override_values(
    ctx: &Ctx,
    parameters: &mut [Parameter],
    derived: &[RawDerived],
    overrides: &[(String, f64)],
) -> R<()> {
    for (name, value) in overrides {
        let err = |message: String| ModelError {
            file: ctx.file.to_string(),
            line: None,
            column: None,
            message,
            snippet: None,
        };
        if let Some(d) = derived.iter().find(|d| &d.name == name) {
            return Err(err(format!(
                "override '{name}': '{name}' is derived (= \"{}\"); set the parameters it is made of",
                d.text
            )));
        }
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
