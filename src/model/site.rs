//! Where a model item comes from, and the errors that name it.

use super::expr::{EvalError, Expr};
use std::fmt;

/// Where a model item comes from: file, 1-based line and column, and a description.
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub what: String,
}

impl fmt::Display for Site {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} ({}:{}:{})",
            self.what, self.file, self.line, self.column
        )
    }
}

/// An error in a model file, pointing at a line and column when it can.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct ModelError {
    pub file: String,
    /// 1-based line and column, when the error has a place in the file.
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
    /// The source line, for display under the message.
    pub snippet: Option<String>,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match (self.line, self.column) {
            (Some(l), Some(c)) => write!(f, "{}:{}:{}: {}", self.file, l, c, self.message)?,
            _ => write!(f, "{}: {}", self.file, self.message)?,
        }
        if let (Some(s), Some(c)) = (&self.snippet, self.column) {
            // A window of at most 160 characters around the column (hostile lines are long).
            let from = c
                .saturating_sub(80)
                .min(s.chars().count().saturating_sub(1));
            let shown: String = s.chars().skip(from).take(160).collect();
            write!(
                f,
                "\n    | {shown}\n    | {}^",
                " ".repeat(c.saturating_sub(1 + from))
            )?;
        }
        Ok(())
    }
}

/// A field of the model: an expression and where it was written (which is no part of what it
/// means: left out of its serialisation).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Field {
    pub expr: Expr,
    #[serde(skip)]
    pub site: Site,
}

/// A field evaluation failed (at some parameter values and speed).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{site}: {error}")]
pub struct FieldError {
    pub site: Site,
    pub error: EvalError,
}

impl Field {
    /// Evaluates the field over `T`; errors name the field and its place in the file.
    pub fn eval<T: crate::real::Real>(&self, p: &[T], speed: T) -> Result<T, FieldError> {
        self.expr.eval(p, speed).map_err(|error| FieldError {
            site: self.site.clone(),
            error,
        })
    }
}
