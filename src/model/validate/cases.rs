//! The tolerance cases of `[analysis]` (`[[analysis.cases]]`): unique names, tolerances of
//! declared parameters, and a correlation matrix that is a valid correlation (unit diagonal,
//! symmetric, positive semi-definite). Apart from the other analysis settings because a case is
//! a statistical model of the parameters, with checks of its own.

use super::names::check_name;
use super::parameters::tolerance;
use super::{Ctx, R};
use crate::model::schema::CaseSchema;
use crate::model::{Case, Correlation, Parameter, Tolerance};
use toml::Spanned;

/// The cases in file order.
pub(super) fn cases(ctx: &Ctx, raw: &[Spanned<CaseSchema>], params: &[Parameter]) -> R<Vec<Case>> {
    let mut out: Vec<Case> = Vec::new();
    for c in raw {
        let c = c.get_ref();
        check_name(ctx, &c.name, "case")?;
        if out.iter().any(|x: &Case| &x.name == c.name.get_ref()) {
            return Err(ctx.err(
                c.name.span(),
                format!("duplicate case name '{}'", c.name.get_ref()),
            ));
        }
        let tolerances = tolerances(ctx, c, params)?;
        let correlation = c
            .correlation
            .as_ref()
            .map(|m| correlation(ctx, c, m, &tolerances))
            .transpose()?;
        out.push(Case {
            name: c.name.get_ref().clone(),
            tolerances,
            correlation,
        });
    }
    Ok(out)
}

/// The case's tolerances in the order written, as (parameter index, tolerance).
fn tolerances(ctx: &Ctx, c: &CaseSchema, params: &[Parameter]) -> R<Vec<(usize, Tolerance)>> {
    let mut tl: Vec<_> = c.tolerances.iter().collect();
    tl.sort_by_key(|(k, _)| k.span().start);
    let mut tolerances = Vec::new();
    for (k, v) in tl {
        let Some(pi) = params.iter().position(|p| &p.name == k.get_ref()) else {
            return Err(ctx.err(
                k.span(),
                ctx.not_a_variable(k.get_ref(), &format!("case '{}'", c.name.get_ref())),
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
    Ok(tolerances)
}

/// The correlation matrix `m` of the case's `tolerances`: one row and column per tolerance,
/// entries in [−1, 1] with a unit diagonal, symmetric and positive semi-definite.
fn correlation(
    ctx: &Ctx,
    c: &CaseSchema,
    m: &Spanned<Vec<Vec<f64>>>,
    tolerances: &[(usize, Tolerance)],
) -> R<Correlation> {
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
    if crate::linalg::symmetric_eigen(mat.clone()).is_none_or(|e| e.eigenvalues.min() < -1e-12) {
        return Err(bad("the matrix is not positive semi-definite"));
    }
    Ok(Correlation {
        params: tolerances.iter().map(|t| t.0).collect(),
        matrix: rows.clone(),
    })
}
