//! The `[[requirements]]` (what a design must meet over an operating range) and the
//! `[allocation]` table (the yield target and the cost of each tolerance). Their own stage, last,
//! because a requirement names modes and an allocation names parameters and cases.

use super::names::check_name;
use super::parameters::tolerance;
use super::{Ctx, R};
use crate::model::schema::{AllocationSchema, RequirementSchema};
use crate::model::{Allocation, Case, Cost, Parameter, Requirement};
use crate::requirements::{Fields, Kind, Reads};
use toml::Spanned;

/// What the outputs call every requirement together (`yield.csv`, `summary.json`).
const ALL: &str = "all";

/// The requirements in file order; `modes` is the number of modes of the mechanism, and a
/// `transfer` requirement needs the `[analysis] transfer` (`transfer`) it reads.
pub(super) fn requirements(
    ctx: &Ctx,
    raw: &[Spanned<RequirementSchema>],
    modes: usize,
    transfer: bool,
) -> R<Vec<Requirement>> {
    let mut out: Vec<Requirement> = Vec::new();
    for (i, r) in raw.iter().enumerate() {
        let at = r.span();
        let r = r.get_ref();
        let name = match &r.name {
            Some(n) => {
                check_name(ctx, n, "requirement")?;
                n.get_ref().clone()
            }
            None => format!("requirement{}", i + 1),
        };
        if out.iter().any(|x| x.name == name) {
            let span = r.name.as_ref().map_or(at.clone(), |n| n.span());
            return Err(ctx.err(span, format!("duplicate requirement name '{name}'")));
        }
        if name == ALL {
            let span = r.name.as_ref().map_or(at.clone(), |n| n.span());
            return Err(ctx.err(
                span,
                format!(
                    "requirement name '{ALL}' is taken: the outputs name every requirement \
                     together so"
                ),
            ));
        }
        let what = format!("requirement '{name}'");
        let kind = kind(ctx, r, &what)?;
        if kind.reads() == Reads::Transfer && !transfer {
            return Err(ctx.err(
                r.kind.span(),
                format!(
                    "{what}: a '{}' requirement needs [analysis] transfer (the |H| it bounds)",
                    kind.name()
                ),
            ));
        }
        let speeds = match &r.speeds {
            None => None,
            Some(s) => match s.get_ref().as_slice() {
                &[a, b] if a.is_finite() && b.is_finite() && 0.0 <= a && a <= b => Some((a, b)),
                _ => {
                    return Err(ctx.err(
                        s.span(),
                        format!("{what}: speeds must be [from, to] in rad/s, 0 ≤ from ≤ to"),
                    ));
                }
            },
        };
        let per_mode = kind.reads() == Reads::Mode;
        let mode = match &r.mode {
            None => None,
            Some(m) if !per_mode => {
                return Err(ctx.err(
                    m.span(),
                    format!(
                        "{what}: a '{}' requirement is not per mode",
                        r.kind.get_ref()
                    ),
                ));
            }
            Some(m) => {
                let k = *m.get_ref();
                if k < 1 || k as u64 > modes as u64 {
                    return Err(ctx.err(
                        m.span(),
                        format!("{what}: mode {k} does not exist (the mechanism has {modes} mode(s), numbered from 1)"),
                    ));
                }
                Some(k as usize - 1)
            }
        };
        out.push(Requirement {
            name,
            kind,
            speeds,
            mode,
        });
    }
    Ok(out)
}

/// The requirement's kind and its settings, read by the kind ([`crate::requirements`]); a
/// field the kind does not take is an error.
fn kind(ctx: &Ctx, r: &RequirementSchema, what: &str) -> R<Kind> {
    let fields = Fields {
        what,
        kind: &r.kind,
        orders: r.orders.as_ref(),
        margin: r.margin.as_ref(),
        band: r.band.as_ref(),
        min: r.min.as_ref(),
        max: r.max.as_ref(),
    };
    let k = r.kind.get_ref().as_str();
    let Some(index) = Kind::NAMES.iter().position(|n| *n == k) else {
        let (last, rest) = Kind::NAMES
            .split_last()
            .expect("requirement kinds are listed");
        return Err(ctx.err(
            r.kind.span(),
            format!(
                "{what}: unknown kind '{k}': expected {} or {last}",
                rest.join(", ")
            ),
        ));
    };
    for (field, span) in fields.given() {
        if let Some(span) = span
            && !Kind::FIELDS[index].contains(&field)
        {
            return Err(ctx.err(
                span,
                format!("{what}: a '{k}' requirement has no field '{field}'"),
            ));
        }
    }
    match Kind::read(k, &fields) {
        Some(Ok(kind)) => Ok(kind),
        Some(Err(e)) => Err(ctx.err(e.span, e.message)),
        None => unreachable!("'{k}' is a kind's name"),
    }
}

/// The `[allocation]` table (defaults where absent: a yield of 0.9973, the parameters' own
/// tolerances, reciprocal costs).
pub(super) fn allocation(
    ctx: &Ctx,
    raw: Option<&Spanned<AllocationSchema>>,
    params: &[Parameter],
    cases: &[Case],
) -> R<Allocation> {
    let mut out = Allocation {
        target_yield: 0.9973,
        case: None,
        costs: Vec::new(),
    };
    let Some(raw) = raw else { return Ok(out) };
    let a = raw.get_ref();
    if let Some(y) = &a.target_yield {
        let v = *y.get_ref();
        if !(v > 0.0 && v < 1.0) {
            return Err(ctx.err(
                y.span(),
                "allocation target_yield must be a probability strictly between 0 and 1",
            ));
        }
        out.target_yield = v;
    }
    if let Some(c) = &a.case {
        if !cases.iter().any(|x| &x.name == c.get_ref()) {
            return Err(ctx.err(
                c.span(),
                format!(
                    "allocation case '{}' is not a case of [analysis]",
                    c.get_ref()
                ),
            ));
        }
        out.case = Some(c.get_ref().clone());
    }
    let mut costs: Vec<_> = a.cost.iter().collect();
    costs.sort_by_key(|(k, _)| k.span().start);
    for (name, c) in costs {
        let Some(pi) = params.iter().position(|p| &p.name == name.get_ref()) else {
            return Err(ctx.err(
                name.span(),
                ctx.not_a_variable(name.get_ref(), "allocation cost"),
            ));
        };
        let s = c.get_ref();
        let d = Cost::default();
        let cost = Cost {
            a: s.a.unwrap_or(d.a),
            b: s.b.unwrap_or(d.b),
            k: s.k.unwrap_or(d.k),
            max: s
                .max
                .as_ref()
                .map(|m| tolerance(ctx, m.get_ref(), m.span(), "allocation cost max"))
                .transpose()?,
        };
        if let Some(m) = &s.max
            && cost
                .max
                .is_some_and(|t| t.absolute(params[pi].value) <= 0.0)
        {
            return Err(ctx.err(
                m.span(),
                format!(
                    "allocation cost of '{}': max must be a tolerance > 0 (the largest allowed)",
                    name.get_ref()
                ),
            ));
        }
        let toleranced = params[pi].tolerance.is_some()
            || cases.iter().any(|c| c.tolerances.iter().any(|t| t.0 == pi));
        if !toleranced {
            return Err(ctx.err(
                name.span(),
                format!(
                    "allocation cost of '{}': the parameter has no tolerance (neither its own \
                     nor in a case of [analysis]), so there is nothing to allocate",
                    name.get_ref()
                ),
            ));
        }
        if !(cost.a.is_finite()
            && cost.b.is_finite()
            && cost.b > 0.0
            && cost.k.is_finite()
            && cost.k > 0.0)
        {
            return Err(ctx.err(
                c.span(),
                format!(
                    "allocation cost of '{}': a must be finite, b and k finite and > 0",
                    name.get_ref()
                ),
            ));
        }
        out.costs.push((pi, cost));
    }
    Ok(out)
}
