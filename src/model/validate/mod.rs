//! Turns the serde mirror of a model file into a checked [`Model`].
//!
//! Every check reports the first problem found, with the file, line, column and item:
//! unknown or duplicate names, bad expressions, unknown parameters, bodies not connected to
//! ground, cycles in the joint tree, zero axes, more constraints than coordinates, non-finite
//! values, negative mass and inertia that is not positive semi-definite. Expressions that do not
//! mention `speed` are evaluated at the nominal parameters here, so such errors surface at load
//! time; the rest are checked at each speed when the system is built.

mod cuts;
mod forces;
mod geometry;
mod joints;
mod locate;
mod names;
mod per_coordinate;

pub(super) use locate::error_at;

use super::schema::{self, FileSchema, Num, SNum, SVec};
use super::*;
use geometry::{Item, known, vector};
use locate::{abbreviate, line_starts, locate_line};
use names::{body_ref, check_name};
use std::collections::{HashMap, HashSet};
use std::ops::Range;
use toml::Spanned;

/// Byte offset of the start of the line with the most dots and opening brackets (the deepest
/// nesting of keys, tables and arrays), roughly: quotes are not tracked.
fn most_nested_line(text: &str) -> usize {
    let mut best = (0, 0);
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let depth = line
            .chars()
            .filter(|c| matches!(c, '.' | '[' | '{'))
            .count();
        if depth > best.0 {
            best = (depth, start);
        }
        start += line.len();
    }
    best.1
}

struct Ctx<'a> {
    text: &'a str,
    file: &'a str,
    /// The parameters' names, which expressions refer to by position (none until the
    /// parameters stage has run).
    params: Vec<String>,
    /// Their nominal values, at which every field that does not use the speed is evaluated.
    values: Vec<f64>,
    /// Byte offset of each line's start: every field's site is located by bisection (counting
    /// lines from the top for each of a large model's thousands of fields was quadratic).
    line_starts: Vec<usize>,
}

/// The result of a check: the first error found stops validation.
type R<T> = Result<T, ModelError>;

impl<'a> Ctx<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        Ctx {
            text,
            file,
            params: Vec::new(),
            values: Vec::new(),
            line_starts: line_starts(text),
        }
    }

    /// From now on, expressions may refer to `parameters` and are evaluated at their values.
    fn declare(&mut self, parameters: &[Parameter]) {
        self.params = parameters.iter().map(|p| p.name.clone()).collect();
        self.values = parameters.iter().map(|p| p.value).collect();
    }

    /// Where errors about the file as a whole point: its first character.
    fn whole(&self) -> Range<usize> {
        0..self.text.len().min(1)
    }

    fn err(&self, span: Range<usize>, msg: impl AsRef<str>) -> ModelError {
        error_at(self.file, self.text, span.start, msg.as_ref())
    }

    fn site(&self, span: &Range<usize>, what: String) -> Site {
        let mut off = span.start.min(self.text.len());
        while !self.text.is_char_boundary(off) {
            off -= 1;
        }
        let line = self.line_starts.partition_point(|&s| s <= off);
        let column = self.text[self.line_starts[line - 1]..off].chars().count() + 1;
        Site {
            file: self.file.to_string(),
            line,
            column,
            what,
        }
    }

    /// Parses a number-or-expression field; `what` names it in messages.
    fn field(&self, n: &SNum, what: String) -> R<Field> {
        let span = n.span();
        let expr = match n.get_ref() {
            Num::Value(v) => {
                if !v.is_finite() {
                    return Err(self.err(span, format!("{what}: value {v} is not finite")));
                }
                Expr::Num(*v)
            }
            Num::Expr(s) => {
                let lookup = |name: &str| self.params.iter().position(|p| p == name);
                Expr::parse(s, &lookup).map_err(|e| {
                    // The string starts one byte after its opening quote.
                    let off = span.start + 1 + e.offset;
                    error_at(
                        self.file,
                        self.text,
                        off,
                        &format!(
                            "{what}: bad expression \"{}\": {}",
                            abbreviate(s),
                            e.message
                        ),
                    )
                })?
            }
        };
        let field = Field {
            expr,
            site: self.site(&span, what.clone()),
        };
        Ok(field)
    }

    fn opt_field(&self, n: &Option<SNum>, what: String) -> R<Option<Field>> {
        n.as_ref().map(|n| self.field(n, what)).transpose()
    }

    fn vec3(&self, v: &SVec, what: String) -> R<[Field; 3]> {
        let items = v.get_ref();
        if items.len() != 3 {
            return Err(self.err(
                v.span(),
                format!(
                    "{what}: expected 3 components [x, y, z], got {}",
                    items.len()
                ),
            ));
        }
        Ok([
            self.field(&items[0], format!("{what}[0]"))?,
            self.field(&items[1], format!("{what}[1]"))?,
            self.field(&items[2], format!("{what}[2]"))?,
        ])
    }

    fn zero(&self, span: &Range<usize>, what: String) -> Field {
        Field {
            expr: Expr::Num(0.0),
            site: self.site(span, what),
        }
    }

    /// Evaluates a field at the nominal parameters (if it does not use `speed`).
    fn nominal(&self, f: &Field) -> R<Option<f64>> {
        if f.expr.uses_speed() {
            return Ok(None);
        }
        f.expr
            .eval(&self.values, 0.0)
            .map(Some)
            .map_err(|e| ModelError {
                file: self.file.to_string(),
                line: Some(f.site.line),
                column: Some(f.site.column),
                message: format!("{}: {e}", f.site.what),
                snippet: Some(locate_line(self.text, f.site.line)),
            })
    }
}

/// Longest model name and description (characters).
const MAX_TITLE: usize = 200;
const MAX_DESCRIPTION: usize = 4000;

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

fn tolerance(ctx: &Ctx, v: &toml::Value, span: Range<usize>, what: &str) -> R<Tolerance> {
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

pub(super) fn validate(text: &str, file: &str, overrides: &[(String, f64)]) -> R<Model> {
    let raw: FileSchema = toml::from_str(text).map_err(|e| {
        let off = e.span().map_or(0, |s| s.start);
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(_) => error_at(file, text, off, &msg),
            // The parser gives no place for some errors (its nesting limit): point at the
            // most deeply nested line, the likely culprit.
            None => error_at(file, text, most_nested_line(text), &msg),
        }
    })?;

    // Parameters, in file order.
    let mut praw: Vec<_> = raw.parameters.iter().collect();
    praw.sort_by_key(|(k, _)| k.span().start);
    let mut ctx = Ctx::new(text, file);
    let mut parameters = Vec::new();
    for (k, v) in praw {
        check_name(&ctx, k, "parameter")?;
        if ["speed", "pi"].contains(&k.get_ref().as_str()) {
            return Err(ctx.err(
                k.span(),
                format!(
                    "'{}' is reserved and cannot be a parameter name",
                    k.get_ref()
                ),
            ));
        }
        parameters.push(parameter(&ctx, k, v)?);
    }
    override_values(&ctx, &mut parameters, overrides)?;
    ctx.declare(&parameters);
    check_text(&ctx, &raw.name, "model name", MAX_TITLE)?;
    check_text(&ctx, &raw.description, "description", MAX_DESCRIPTION)?;

    let gravity = match &raw.gravity {
        Some(g) => ctx.vec3(g, "gravity".into())?,
        None => [0, 1, 2].map(|i| ctx.zero(&ctx.whole(), format!("gravity[{i}]"))),
    };
    for f in &gravity {
        ctx.nominal(f)?;
    }

    // Bodies.
    let mut body_names: HashMap<String, usize> = HashMap::new();
    let mut bodies = Vec::new();
    for b in &raw.bodies {
        let s = b.get_ref();
        check_name(&ctx, &s.name, "body")?;
        let name = s.name.get_ref().clone();
        if name == "ground" {
            return Err(ctx.err(
                s.name.span(),
                "'ground' is the fixed frame and cannot be declared as a body",
            ));
        }
        if body_names.insert(name.clone(), bodies.len()).is_some() {
            return Err(ctx.err(s.name.span(), format!("duplicate body name '{name}'")));
        }
        let what = |f: &str| format!("body '{name}' {f}");
        let mass = ctx.field(&s.mass, what("mass"))?;
        let inertia = match &s.inertia {
            None => std::array::from_fn(|i| {
                std::array::from_fn(|j| ctx.zero(&b.span(), what(&format!("inertia[{i}][{j}]"))))
            }),
            Some(sp) => inertia(&ctx, sp, &what(""))?,
        };
        let cm = ctx.vec3(&s.cm, what("cm"))?;
        // Nominal checks: mass ≥ 0, inertia symmetric positive semi-definite.
        if let Some(m) = ctx.nominal(&mass)?
            && m < 0.0
        {
            return Err(ctx.err(
                s.mass.span(),
                format!("body '{name}': negative mass {m} kg"),
            ));
        }
        let mut inom = [[0.0; 3]; 3];
        let mut all_known = true;
        for i in 0..3 {
            for j in 0..3 {
                match ctx.nominal(&inertia[i][j])? {
                    Some(v) => inom[i][j] = v,
                    None => all_known = false,
                }
            }
        }
        for f in &cm {
            ctx.nominal(f)?;
        }
        if all_known {
            let span = s.inertia.as_ref().map_or(b.span(), |x| x.span());
            check_inertia(&ctx, &inom, span, &name)?;
        }
        let axes = match (&s.x_axis, &s.y_axis) {
            (None, None) => None,
            (Some(x), Some(y)) => {
                let (x, y) = (ctx.vec3(x, what("x_axis"))?, ctx.vec3(y, what("y_axis"))?);
                inertia_axes(&ctx, &x, &y, b.span(), &name)?;
                Some([x, y])
            }
            (Some(a), None) | (None, Some(a)) => {
                return Err(ctx.err(
                    a.span(),
                    format!(
                        "body '{name}': give both 'x_axis' and 'y_axis' (the axes its inertia is given in)"
                    ),
                ));
            }
        };
        bodies.push(Body {
            name,
            mass,
            inertia,
            axes,
            cm,
        });
    }
    if bodies.is_empty() {
        return Err(ModelError {
            file: file.to_string(),
            line: None,
            column: None,
            message: "the model declares no bodies ([[bodies]])".into(),
            snippet: None,
        });
    }

    // Joints.
    let joints::Tree {
        joints,
        coordinates,
        child_of,
        names: joint_names,
    } = joints::joints(&ctx, &raw.joints, &body_names, &bodies)?;

    // Tree: every body is reached from ground; no cycles.
    for (b, c) in child_of.iter().enumerate() {
        if c.is_none() {
            let span = raw.bodies[b].get_ref().name.span();
            return Err(ctx.err(
                span,
                format!(
                    "body '{}' is not connected to ground: no joint has it as child",
                    bodies[b].name
                ),
            ));
        }
    }
    let mut order = Vec::new();
    let mut placed = vec![false; joints.len()];
    let mut frontier: Vec<Option<usize>> = vec![None];
    while let Some(parent) = frontier.pop() {
        for (ji, j) in joints.iter().enumerate() {
            if j.parent == parent && !placed[ji] {
                placed[ji] = true;
                order.push(ji);
                frontier.push(Some(j.child));
            }
        }
    }
    if let Some(ji) = placed.iter().position(|p| !p) {
        // Walk up from this joint until a joint repeats: that is the cycle.
        let mut path = vec![ji];
        let mut cur = ji;
        loop {
            let parent_body = joints[cur]
                .parent
                .expect("unplaced joints have a body parent");
            let up = child_of[parent_body].expect("every body has a parent joint");
            if let Some(pos) = path.iter().position(|&x| x == up) {
                let names: Vec<&str> = path[pos..]
                    .iter()
                    .rev()
                    .map(|&k| joints[k].name.as_str())
                    .collect();
                let span = raw.joints[up].get_ref().name.span();
                return Err(ctx.err(
                    span,
                    format!(
                        "the joints form a cycle not connected to ground: {} → {}",
                        names.join(" → "),
                        names[0]
                    ),
                ));
            }
            path.push(up);
            cur = up;
        }
    }

    // Force elements.
    let mut element_names: HashSet<String> = HashSet::new();
    let forces = forces::forces(
        &ctx,
        &raw.forces,
        &body_names,
        &joint_names,
        &mut element_names,
    )?;

    // Cut joints.
    let constraints = cuts::constraints(
        &ctx,
        &raw.constraints,
        &body_names,
        &joint_names,
        &mut element_names,
    )?;
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

    // Independent coordinates.
    let independent = match &raw.independent {
        None => None,
        Some(list) => {
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
            if out.len() != n_free - n_con {
                return Err(ctx.err(
                    list.span(),
                    format!("independent lists {} coordinate(s) but the mechanism has {} degree(s) of freedom", out.len(), n_free - n_con),
                ));
            }
            Some(out)
        }
    };

    let ports = ports(&ctx, &raw.ports, &body_names, &coordinates)?;
    let analysis = analysis(
        &ctx,
        raw.analysis.as_ref(),
        &coordinates,
        &ports,
        &parameters,
    )?;

    Ok(Model {
        name: raw
            .name
            .as_ref()
            .map(|n| n.get_ref().clone())
            .unwrap_or_else(|| {
                std::path::Path::new(file)
                    .file_stem()
                    .map_or("model".into(), |s| s.to_string_lossy().into_owned())
            }),
        file: file.to_string(),
        parameters,
        gravity,
        bodies,
        joints,
        order,
        coordinates,
        forces,
        constraints,
        ports,
        independent,
        analysis,
    })
}

/// Parses and checks the `[[ports]]` tables.
fn ports(
    ctx: &Ctx,
    raw: &[Spanned<schema::PortSchema>],
    body_names: &HashMap<String, usize>,
    coordinates: &[Coordinate],
) -> R<Vec<Port>> {
    let mut out: Vec<Port> = Vec::new();
    for item in raw {
        let s = item.get_ref();
        check_name(ctx, &s.name, "port")?;
        let name = s.name.get_ref().clone();
        if out.iter().any(|p| p.name == name) || coordinates.iter().any(|c| c.name == name) {
            return Err(ctx.err(
                s.name.span(),
                format!("duplicate name '{name}' (ports and joint coordinates share the names a transfer function refers to)"),
            ));
        }
        let owner = format!("port '{name}'");
        let rotation = match s.kind.get_ref().as_str() {
            "translation" => false,
            "rotation" => true,
            other => {
                return Err(ctx.err(
                    s.kind.span(),
                    format!("{owner}: unknown type '{other}' (expected translation or rotation)"),
                ));
            }
        };
        let Some(body) = body_ref(ctx, body_names, &s.body)? else {
            return Err(ctx.err(
                s.body.span(),
                format!("{owner}: ground does not move; give a body"),
            ));
        };
        let usage = if rotation {
            crate::joints::Use::Unused
        } else {
            crate::joints::Use::Required
        };
        let this = format!("a {} port", s.kind.get_ref());
        let table = Item {
            owner: &owner,
            kind: &this,
            span: item.span(),
        };
        let point = vector(ctx, &table, &s.point, usage, "point")?;
        let direction = ctx.vec3(&s.direction, format!("{owner} direction"))?;
        if let Some(d) = known(ctx, &direction)?
            && d.iter().all(|x| x.abs() <= 0.0)
        {
            return Err(ctx.err(s.direction.span(), format!("{owner}: direction is zero")));
        }
        out.push(Port {
            name,
            body,
            point,
            direction,
            rotation,
        });
    }
    Ok(out)
}

/// Reads an inertia given as three principal values or a 3×3 matrix of numbers or expressions.
fn inertia(ctx: &Ctx, v: &Spanned<toml::Value>, what: &str) -> R<[[Field; 3]; 3]> {
    let span = v.span();
    let bad = || {
        ctx.err(span.clone(), format!("{what}inertia: expected 3 principal values [Ixx, Iyy, Izz] or a 3×3 matrix of numbers or expressions"))
    };
    let num = |x: &toml::Value, i: usize, j: usize| -> R<Field> {
        let n = match x {
            toml::Value::Float(f) => Num::Value(*f),
            toml::Value::Integer(k) => Num::Value(*k as f64),
            toml::Value::String(s) => Num::Expr(s.clone()),
            _ => return Err(bad()),
        };
        // Entries carry the span of the whole array: errors point at its start.
        ctx.field(
            &Spanned::new(span.clone(), n),
            format!("{what}inertia[{i}][{j}]"),
        )
    };
    let toml::Value::Array(rows) = v.get_ref() else {
        return Err(bad());
    };
    if rows.len() != 3 {
        return Err(bad());
    }
    if rows.iter().all(|r| !r.is_array()) {
        let d = [
            num(&rows[0], 0, 0)?,
            num(&rows[1], 1, 1)?,
            num(&rows[2], 2, 2)?,
        ];
        return Ok(std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                if i == j {
                    d[i].clone()
                } else {
                    ctx.zero(&span, format!("{what}inertia[{i}][{j}]"))
                }
            })
        }));
    }
    let mut out: Vec<Vec<Field>> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let toml::Value::Array(r) = r else {
            return Err(bad());
        };
        if r.len() != 3 {
            return Err(bad());
        }
        out.push(
            r.iter()
                .enumerate()
                .map(|(j, x)| num(x, i, j))
                .collect::<R<Vec<_>>>()?,
        );
    }
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| out[i][j].clone())
    }))
}

/// Inertia axes: neither zero nor parallel at the nominal values.
fn inertia_axes(
    ctx: &Ctx,
    x: &[Field; 3],
    y: &[Field; 3],
    span: Range<usize>,
    name: &str,
) -> R<()> {
    let (Some(a), Some(b)) = (known(ctx, x)?, known(ctx, y)?) else {
        return Ok(());
    };
    let scale = |v: [f64; 3]| {
        let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        (m > 0.0).then(|| v.map(|x| x / m))
    };
    let (Some(a), Some(b)) = (scale(a), scale(b)) else {
        return Err(ctx.err(span, format!("body '{name}': x_axis or y_axis is zero")));
    };
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm(c) <= 1e-9 * norm(a) * norm(b) {
        return Err(ctx.err(
            span,
            format!("body '{name}': x_axis and y_axis are parallel"),
        ));
    }
    Ok(())
}

/// Symmetric and positive semi-definite (see [`super::admissible::inertia_defect`]).
fn check_inertia(ctx: &Ctx, i: &[[f64; 3]; 3], span: Range<usize>, name: &str) -> R<()> {
    match super::admissible::inertia_defect(i) {
        Some((defect, value)) => {
            Err(ctx.err(span, format!("body '{name}': {defect}: {value:.6e}")))
        }
        None => Ok(()),
    }
}

fn analysis(
    ctx: &Ctx,
    raw: Option<&Spanned<schema::AnalysisSchema>>,
    coords: &[Coordinate],
    ports: &[Port],
    params: &[Parameter],
) -> R<Analysis> {
    let mut a = Analysis {
        speed: None,
        transfer: None,
        samples: 3000,
        seed: 1,
        sampling: Sampling::Random,
        cases: Vec::new(),
    };
    let Some(raw) = raw else { return Ok(a) };
    let s = raw.get_ref();
    if let Some(sp) = &s.speed {
        a.speed = Some(
            SpeedRange::parse(sp.get_ref())
                .map_err(|e| ctx.err(sp.span(), format!("analysis speed: {e}")))?,
        );
    }
    if let Some(t) = &s.transfer {
        let t = t.get_ref();
        let coord = |n: &Spanned<String>| {
            let name = n.get_ref();
            match coords.iter().position(|c| &c.name == name) {
                Some(c) if !coords[c].driven => Ok(Channel::Coordinate(c)),
                _ => ports
                    .iter()
                    .position(|p| &p.name == name)
                    .map(Channel::Port)
                    .ok_or_else(|| {
                        ctx.err(
                            n.span(),
                            format!(
                                "analysis transfer: '{name}' is neither a free joint coordinate nor a port"
                            ),
                        )
                    }),
            }
        };
        let order = t.order.as_ref().map_or(1.0, |o| *o.get_ref());
        if !order.is_finite() || order < 0.0 {
            return Err(ctx.err(
                t.order.as_ref().map_or(raw.span(), |o| o.span()),
                "analysis transfer: order must be finite and ≥ 0",
            ));
        }
        a.transfer = Some(Transfer {
            input: coord(&t.input)?,
            output: coord(&t.output)?,
            order,
        });
    }
    if let Some(n) = &s.samples {
        if let Err(e) = crate::settings::samples(*n.get_ref()) {
            return Err(ctx.err(n.span(), format!("analysis samples {e}")));
        }
        a.samples = *n.get_ref() as usize;
    }
    if let Some(seed) = s.seed {
        a.seed = seed;
    }
    if let Some(m) = &s.sampling {
        a.sampling = match m.get_ref().as_str() {
            "random" => Sampling::Random,
            "lhs" => Sampling::Lhs,
            "sobol" => Sampling::Sobol,
            x => {
                return Err(ctx.err(
                    m.span(),
                    format!("analysis sampling '{x}': expected random, lhs or sobol"),
                ));
            }
        };
    }
    for c in &s.cases {
        let c = c.get_ref();
        check_name(ctx, &c.name, "case")?;
        if a.cases.iter().any(|x: &Case| &x.name == c.name.get_ref()) {
            return Err(ctx.err(
                c.name.span(),
                format!("duplicate case name '{}'", c.name.get_ref()),
            ));
        }
        let mut tl: Vec<_> = c.tolerances.iter().collect();
        tl.sort_by_key(|(k, _)| k.span().start);
        let mut tolerances = Vec::new();
        for (k, v) in tl {
            let Some(pi) = params.iter().position(|p| &p.name == k.get_ref()) else {
                return Err(ctx.err(
                    k.span(),
                    format!(
                        "case '{}': unknown parameter '{}'",
                        c.name.get_ref(),
                        k.get_ref()
                    ),
                ));
            };
            tolerances.push((
                pi,
                tolerance(
                    ctx,
                    v.get_ref(),
                    v.span(),
                    &format!("case '{}'", c.name.get_ref()),
                )?,
            ));
        }
        let correlation = match &c.correlation {
            None => None,
            Some(m) => {
                let rows = m.get_ref();
                let n = tolerances.len();
                let bad = |msg: &str| {
                    ctx.err(
                        m.span(),
                        format!("case '{}' correlation: {msg}", c.name.get_ref()),
                    )
                };
                if rows.len() != n || rows.iter().any(|r| r.len() != n) {
                    return Err(bad(&format!(
                        "expected a {n}×{n} matrix (one row per tolerance, in the order written)"
                    )));
                }
                let mat = nalgebra::DMatrix::from_fn(n, n, |i, j| rows[i][j]);
                if mat.iter().any(|v| !v.is_finite() || v.abs() > 1.0)
                    || (0..n).any(|i| (mat[(i, i)] - 1.0).abs() > 1e-12)
                {
                    return Err(bad("entries must lie in [−1, 1] with a unit diagonal"));
                }
                if (&mat - mat.transpose()).amax() > 1e-12 {
                    return Err(bad("the matrix is not symmetric"));
                }
                if crate::linalg::symmetric_eigen(mat.clone())
                    .is_none_or(|e| e.eigenvalues.min() < -1e-12)
                {
                    return Err(bad("the matrix is not positive semi-definite"));
                }
                Some(Correlation {
                    params: tolerances.iter().map(|t| t.0).collect(),
                    matrix: rows.clone(),
                })
            }
        };
        a.cases.push(Case {
            name: c.name.get_ref().clone(),
            tolerances,
            correlation,
        });
    }
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::locate::locate;
    use super::*;

    /// Sites located by bisection over the line starts agree with counting from the top, at
    /// every byte (inside multi-byte characters too, on empty lines, after the last newline).
    #[test]
    fn sites_by_bisection_agree_with_counting_lines() {
        let text = "a = 1\n\nλ = \"x·2\"\r\n  [[bodies]]\nω\n";
        let ctx = Ctx::new(text, "f.toml");
        for off in 0..=text.len() + 2 {
            let site = ctx.site(&(off..off + 1), String::new());
            let (line, column, _) = locate(text, off);
            assert_eq!((site.line, site.column), (line, column), "offset {off}");
        }
    }
}
