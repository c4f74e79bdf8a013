//! The `[[requirements]]` (what a design must meet over an operating range) and the
//! `[allocation]` table (the yield target and the cost of each tolerance). Their own stage, last,
//! because a requirement names modes and an allocation names parameters and cases.

use super::names::check_name;
use super::parameters::tolerance;
use super::{Ctx, R};
use crate::model::schema::{AllocationSchema, RequirementSchema};
use crate::model::{
    Allocation, Case, Cost, Parameter, Requirement, RequirementKind, SeparationMargin,
};
use toml::Spanned;

/// What the outputs call every requirement together (`yield.csv`, `summary.json`).
const ALL: &str = "all";

/// The kinds of requirement, as written.
const KINDS: &str =
    "separation, frequency, avoid, damping, underdamped, stable, branch or transfer";

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
        if matches!(kind, RequirementKind::Transfer { .. }) && !transfer {
            return Err(ctx.err(
                r.kind.span(),
                format!(
                    "{what}: a 'transfer' requirement needs [analysis] transfer (the |H| it bounds)"
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
        let per_mode = !matches!(
            kind,
            RequirementKind::Stable
                | RequirementKind::SameBranch
                | RequirementKind::Transfer { .. }
        );
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

/// The requirement's kind and its fields; a field the kind does not use is an error.
fn kind(ctx: &Ctx, r: &RequirementSchema, what: &str) -> R<RequirementKind> {
    let k = r.kind.get_ref().as_str();
    let used: &[&str] = match k {
        "separation" => &["orders", "margin"],
        "frequency" => &["min", "max"],
        "avoid" => &["band"],
        "damping" => &["min"],
        "transfer" => &["max"],
        "underdamped" | "stable" | "branch" => &[],
        _ => {
            return Err(ctx.err(
                r.kind.span(),
                format!("{what}: unknown kind '{k}': expected {KINDS}"),
            ));
        }
    };
    let given = [
        ("orders", r.orders.as_ref().map(|x| x.span())),
        ("margin", r.margin.as_ref().map(|x| x.span())),
        ("band", r.band.as_ref().map(|x| x.span())),
        ("min", r.min.as_ref().map(|x| x.span())),
        ("max", r.max.as_ref().map(|x| x.span())),
    ];
    for (field, span) in given {
        if let Some(span) = span
            && !used.contains(&field)
        {
            return Err(ctx.err(
                span,
                format!("{what}: a '{k}' requirement has no field '{field}'"),
            ));
        }
    }
    let missing = |field: &str| {
        ctx.err(
            r.kind.span(),
            format!("{what}: a '{k}' requirement needs '{field}'"),
        )
    };
    let finite = |v: &Spanned<f64>, field: &str, positive: bool| -> R<f64> {
        let x = *v.get_ref();
        if !x.is_finite() || (positive && x <= 0.0) {
            let need = if positive { "finite and > 0" } else { "finite" };
            return Err(ctx.err(v.span(), format!("{what}: {field} must be {need}")));
        }
        Ok(x)
    };
    Ok(match k {
        "separation" => {
            let orders = r.orders.as_ref().ok_or_else(|| missing("orders"))?;
            if orders.get_ref().is_empty()
                || orders.get_ref().iter().any(|o| !o.is_finite() || *o <= 0.0)
            {
                return Err(ctx.err(
                    orders.span(),
                    format!("{what}: orders must be a non-empty list of numbers > 0"),
                ));
            }
            let m = r.margin.as_ref().ok_or_else(|| missing("margin"))?;
            let text = m.get_ref().trim();
            let margin = if text.eq_ignore_ascii_case("api684") {
                SeparationMargin::Api684
            } else {
                match text.strip_suffix('%').map(|p| p.trim().parse::<f64>()) {
                    Some(Ok(p)) if p.is_finite() && (0.0..100.0).contains(&p) => {
                        SeparationMargin::Fraction(p / 100.0)
                    }
                    _ => {
                        return Err(ctx.err(
                            m.span(),
                            format!("{what}: margin must be \"P%\" (0 ≤ P < 100) or \"api684\""),
                        ));
                    }
                }
            };
            RequirementKind::Separation {
                orders: orders.get_ref().clone(),
                margin,
            }
        }
        "frequency" => {
            let min = r
                .min
                .as_ref()
                .map(|v| finite(v, "min", false))
                .transpose()?;
            let max = r
                .max
                .as_ref()
                .map(|v| finite(v, "max", false))
                .transpose()?;
            match (min, max) {
                (None, None) => return Err(missing("min' or 'max")),
                (Some(a), Some(b)) if a > b => {
                    return Err(ctx.err(
                        r.kind.span(),
                        format!("{what}: min ({a}) is above max ({b})"),
                    ));
                }
                _ => {}
            }
            RequirementKind::Frequency { min, max }
        }
        "avoid" => {
            let band = r.band.as_ref().ok_or_else(|| missing("band"))?;
            match band.get_ref().as_slice() {
                &[low, high] if low.is_finite() && high.is_finite() && low < high => {
                    RequirementKind::Avoid { low, high }
                }
                _ => {
                    return Err(ctx.err(
                        band.span(),
                        format!("{what}: band must be [low, high] in rad/s, low < high"),
                    ));
                }
            }
        }
        "damping" => RequirementKind::Damping {
            min: finite(r.min.as_ref().ok_or_else(|| missing("min"))?, "min", false)?,
        },
        "transfer" => RequirementKind::Transfer {
            max: finite(r.max.as_ref().ok_or_else(|| missing("max"))?, "max", true)?,
        },
        "underdamped" => RequirementKind::Underdamped,
        "stable" => RequirementKind::Stable,
        _ => RequirementKind::SameBranch,
    })
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
