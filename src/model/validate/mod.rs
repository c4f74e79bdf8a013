//! Turns the serde mirror of a model file into a checked [`Model`].
//!
//! Every check reports the first problem found, with the file, line, column and item:
//! unknown or duplicate names, bad expressions, unknown parameters, bodies not connected to
//! ground, cycles in the joint tree, zero axes, more constraints than coordinates, non-finite
//! values, negative mass and inertia that is not positive semi-definite. Expressions that do not
//! mention `speed` are evaluated at the nominal parameters here, so such errors surface at load
//! time; the rest are checked at each speed when the system is built.
//!
//! [`validate`] runs the stages in the order of the file's dependencies, each a submodule named
//! for what it validates: [`syntax`], [`parameters`], [`header`], [`bodies`], [`joints`],
//! [`tree`], [`forces`], [`beams`], [`cuts`], [`mobility`], [`ports`], [`loads`], [`analysis`],
//! [`requirements`]. The first error
//! stops validation, so this order is also the order in which errors are reported. Two stages
//! keep a part with checks of its own apart: [`inertia`] (of [`bodies`]) and [`cases`] (of
//! [`analysis`]). The checks several stages share are [`names`], [`geometry`],
//! [`per_coordinate::Each`] and [`locate`] (where a message points).

mod analysis;
mod beams;
mod bodies;
mod cases;
mod couplers;
mod cuts;
mod forces;
mod geometry;
mod header;
mod inertia;
mod joints;
mod loads;
mod locate;
mod mobility;
mod names;
mod parameters;
mod per_coordinate;
mod ports;
mod redundancy;
mod requirements;
mod shafts;
mod syntax;
mod tables;
mod tree;
mod unbalances;

pub(super) use locate::error_at;

use super::schema::{Num, SNum, SVec};
use super::table::Table;
use super::{Expr, Field, Model, ModelError, Parameter, Site};
use locate::{abbreviate, line_starts, locate_line};
use std::collections::HashSet;
use std::ops::Range;
use std::sync::Arc;

/// Validates the model `text` (named `file` in messages) with the nominal values of the
/// parameters in `overrides` replaced.
pub(super) fn validate(text: &str, file: &str, overrides: &[(String, f64)]) -> R<Model> {
    let mut raw = syntax::parse(text, file)?;
    let mut ctx = Ctx::new(text, file);
    let (parameters, derived) = parameters::parameters(&ctx, &raw.parameters, overrides)?;
    ctx.declare(&parameters);
    let derived_names: Vec<String> = derived.iter().map(|d| d.name.clone()).collect();
    ctx.tables = tables::tables(&ctx, &raw.tables, &derived_names)?;
    let derived = parameters::derived(&ctx, &derived)?;
    ctx.derive(&derived);
    shafts::expand(&ctx, &mut raw)?;
    let header = header::header(&ctx, &raw)?;
    let (body_names, bodies) = bodies::bodies(&ctx, &raw.bodies)?;
    let tree = joints::joints(&ctx, &raw.joints, &body_names, &bodies)?;
    let order = tree::order(&ctx, &raw, &bodies, &tree)?;
    // Force elements, cut joints and couplers share one namespace (with the joints).
    let mut elements = HashSet::new();
    let forces = forces::forces(&ctx, &raw.forces, &body_names, &tree.names, &mut elements)?;
    let beams = beams::beams(&ctx, &raw.beams, &body_names, &tree.names, &mut elements)?;
    let mut constraints = cuts::constraints(
        &ctx,
        &raw.constraints,
        &body_names,
        &tree.names,
        &mut elements,
    )?;
    let couplers = couplers::couplers(
        &ctx,
        &raw.couplers,
        &tree.coordinates,
        &tree.names,
        &mut elements,
    )?;
    let independent = mobility::mobility(
        &ctx,
        &raw,
        Mechanism {
            joints: &tree.joints,
            order: &order,
            bodies: bodies.len(),
            coordinates: &tree.coordinates,
        },
        &mut constraints,
        &couplers,
    )?;
    let ports = ports::ports(&ctx, &raw.ports, &body_names, &tree.coordinates)?;
    let loads = loads::loads(&ctx, &raw.loads, &body_names, &tree.coordinates)?;
    let unbalances = unbalances::unbalances(
        &ctx,
        &raw.unbalances,
        &unbalances::Known {
            body_names: &body_names,
            bodies: &bodies,
            coordinates: &tree.coordinates,
            ports: &ports,
            joints: &tree.joints,
        },
    )?;
    let analysis = analysis::analysis(
        &ctx,
        raw.analysis.as_ref(),
        analysis::Channels {
            coords: &tree.coordinates,
            ports: &ports,
            unbalances: &unbalances,
        },
        &parameters,
    )?;
    let equations: usize = constraints
        .iter()
        .map(|c| c.kind.equations() - c.dropped.len())
        .sum::<usize>()
        + couplers.len();
    let free = tree.coordinates.iter().filter(|c| !c.driven).count();
    let modes = free.saturating_sub(equations);
    let requirements =
        requirements::requirements(&ctx, &raw.requirements, modes, analysis.transfer.is_some())?;
    let allocation =
        requirements::allocation(&ctx, raw.allocation.as_ref(), &parameters, &analysis.cases)?;
    Ok(Model {
        name: header.name,
        file: file.to_string(),
        parameters,
        derived,
        gravity: header.gravity,
        bodies,
        joints: tree.joints,
        order,
        coordinates: tree.coordinates,
        forces,
        beams,
        constraints,
        ports,
        loads,
        unbalances,
        couplers,
        independent,
        analysis,
        requirements,
        allocation,
    })
}

/// What every stage needs: the file to point into, and the parameters its expressions refer to.
struct Ctx<'a> {
    text: &'a str,
    file: &'a str,
    /// The parameters' names, which expressions refer to by position (none until the
    /// parameters stage has run).
    params: Vec<String>,
    /// Their nominal values, at which every field that does not use the speed is evaluated.
    values: Vec<f64>,
    /// The derived parameters' names, expressions as written and expressions put in place of
    /// their names.
    derived: Vec<(String, String, Expr)>,
    /// The model's tables, which expressions may call (none until the tables stage has run).
    tables: Vec<Arc<Table>>,
    /// Byte offset of each line's start: every field's site is located by bisection (counting
    /// lines from the top for each of a large model's thousands of fields was quadratic).
    line_starts: Vec<usize>,
}

/// The result of a check: the first error found stops validation.
type R<T> = Result<T, ModelError>;

/// The tree the cut joints close: joints (parents before children in `order`), the number of
/// bodies and the coordinates.
#[derive(Clone, Copy)]
struct Mechanism<'a> {
    pub joints: &'a [crate::model::Joint],
    pub order: &'a [usize],
    pub bodies: usize,
    pub coordinates: &'a [crate::model::Coordinate],
}

impl<'a> Ctx<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        Ctx {
            text,
            file,
            params: Vec::new(),
            values: Vec::new(),
            derived: Vec::new(),
            tables: Vec::new(),
            line_starts: line_starts(text),
        }
    }

    /// From now on, expressions may refer to `parameters` and are evaluated at their values.
    fn declare(&mut self, parameters: &[Parameter]) {
        self.params = parameters.iter().map(|p| p.name.clone()).collect();
        self.values = parameters.iter().map(|p| p.value).collect();
    }

    /// The table named `name`, if the model has one.
    fn table(&self, name: &str) -> Option<Arc<Table>> {
        self.tables.iter().find(|t| t.name == name).cloned()
    }

    /// From now on, expressions may also refer to the `derived` parameters (their
    /// expressions are put in their place).
    fn derive(&mut self, derived: &[super::Derived]) {
        self.derived = derived
            .iter()
            .map(|d| (d.name.clone(), d.text.clone(), d.expr.clone()))
            .collect();
    }

    /// Why `name` is not a design variable: derived (and from what), or unknown (`what` says
    /// where it was named).
    fn not_a_variable(&self, name: &str, what: &str) -> String {
        match self.derived.iter().find(|d| d.0 == name) {
            Some(d) => format!(
                "{what}: parameter '{name}' is derived (= \"{}\") and carries no tolerance or cost of its own; give them to the parameters it is made of",
                d.1
            ),
            None => format!("{what}: unknown parameter '{name}'"),
        }
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
                let lookup = |name: &str| match self.params.iter().position(|p| p == name) {
                    Some(i) => Some(Expr::Param(i)),
                    None => self
                        .derived
                        .iter()
                        .find(|d| d.0 == name)
                        .map(|d| d.2.clone()),
                };
                Expr::parse_in(s, &lookup, &|name| self.table(name)).map_err(|e| {
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
