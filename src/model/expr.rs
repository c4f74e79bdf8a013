//! Expressions in model files: parsed once into a small tree, evaluated over any [`Real`].
//!
//! Grammar (usual precedence, `^` right-associative and binding tighter than unary minus):
//!
//! ```text
//! expr  := term (('+' | '-') term)*
//! term  := unary (('*' | '/') unary)*
//! unary := ('-' | '+') unary | power
//! power := atom ('^' unary)?
//! atom  := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//!
//! Names are model parameters, the constant `pi`, or the reserved symbol `speed` (the operating
//! speed in rad/s). Functions: `sqrt sin cos tan asin acos atan atan2 exp ln abs`, and the
//! model's tables (`[[tables]]`, [`Table`]), each a function of one argument.

use super::table::Table;
use crate::real::{Real, cst, re};
use std::sync::Arc;

/// Deepest nesting the parser accepts (guards the stack against hostile input).
pub const MAX_DEPTH: usize = 64;
/// Longest expression accepted, in bytes.
pub const MAX_LEN: usize = 4096;

/// A parse error at a byte offset within the expression text.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    /// Byte offset of the offending token within the expression.
    pub offset: usize,
    /// What is wrong.
    pub message: String,
}

/// Built-in functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Func {
    Sqrt,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Exp,
    Ln,
    Abs,
}

impl Func {
    fn from_name(s: &str) -> Option<Func> {
        Some(match s {
            "sqrt" => Func::Sqrt,
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "asin" => Func::Asin,
            "acos" => Func::Acos,
            "atan" => Func::Atan,
            "atan2" => Func::Atan2,
            "exp" => Func::Exp,
            "ln" => Func::Ln,
            "abs" => Func::Abs,
            _ => return None,
        })
    }
    fn arity(self) -> usize {
        if self == Func::Atan2 { 2 } else { 1 }
    }
    fn name(self) -> &'static str {
        match self {
            Func::Sqrt => "sqrt",
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Atan2 => "atan2",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
        }
    }
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

/// A parsed expression. Names are resolved to parameter indices while parsing ([`Expr::parse`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub enum Expr {
    Num(f64),
    /// Parameter by index into the model's parameter list.
    Param(usize),
    /// The operating speed (rad/s).
    Speed,
    Neg(Box<Expr>),
    Bin(BinOp, Box<Expr>, Box<Expr>),
    Call(Func, Vec<Expr>),
    /// A table of the model called with an argument.
    Table(Arc<Table>, Box<Expr>),
}

/// Why an expression could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    #[error("division by zero")]
    DivisionByZero,
    #[error("{func} of {value} is outside its domain")]
    Domain { func: &'static str, value: f64 },
    #[error("result is not finite ({0})")]
    NotFinite(f64),
}

impl Expr {
    /// Parses `src`; `lookup` maps a name to a parameter index.
    pub fn parse(src: &str, lookup: &dyn Fn(&str) -> Option<usize>) -> Result<Expr, ParseError> {
        Expr::parse_with(src, &|name| lookup(name).map(Expr::Param))
    }

    /// Parses `src`; `lookup` maps a name to the expression it stands for (a parameter, or the
    /// expression of a derived parameter, put in its place as if written there in brackets).
    pub fn parse_with(
        src: &str,
        lookup: &dyn Fn(&str) -> Option<Expr>,
    ) -> Result<Expr, ParseError> {
        Expr::parse_in(src, lookup, &|_| None)
    }

    /// Parses `src` as [`Expr::parse_with`], with `tables` mapping a function's name to a
    /// table of the model.
    pub fn parse_in(
        src: &str,
        lookup: &dyn Fn(&str) -> Option<Expr>,
        tables: &dyn Fn(&str) -> Option<Arc<Table>>,
    ) -> Result<Expr, ParseError> {
        if src.len() > MAX_LEN {
            return Err(ParseError {
                offset: 0,
                message: format!(
                    "expression is {} bytes long; the limit is {MAX_LEN}",
                    src.len()
                ),
            });
        }
        let mut p = Parser {
            src,
            toks: tokenize(src)?,
            pos: 0,
            depth: 0,
            lookup,
            tables,
        };
        let e = p.expr()?;
        if p.pos < p.toks.len() {
            return Err(p.err_here("unexpected text after the end of the expression"));
        }
        Ok(e)
    }

    /// The number of terms: the numbers, parameters and speeds written, the leaves of the
    /// tree (what a chain of derived parameters could multiply; the tree has fewer than twice
    /// as many nodes).
    pub fn terms(&self) -> usize {
        match self {
            Expr::Num(_) | Expr::Param(_) | Expr::Speed => 1,
            Expr::Neg(a) => a.terms(),
            Expr::Bin(_, a, b) => a.terms() + b.terms(),
            Expr::Call(_, args) => args.iter().map(Expr::terms).sum(),
            Expr::Table(_, a) => a.terms(),
        }
    }

    /// The parameters (indices) the expression uses, each once, in increasing order.
    pub fn parameters(&self) -> Vec<usize> {
        fn walk(e: &Expr, out: &mut Vec<usize>) {
            match e {
                Expr::Param(i) => out.push(*i),
                Expr::Num(_) | Expr::Speed => {}
                Expr::Neg(a) => walk(a, out),
                Expr::Bin(_, a, b) => {
                    walk(a, out);
                    walk(b, out);
                }
                Expr::Call(_, args) => args.iter().for_each(|a| walk(a, out)),
                Expr::Table(_, a) => walk(a, out),
            }
        }
        let mut out = Vec::new();
        walk(self, &mut out);
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Does the expression mention the operating speed?
    pub fn uses_speed(&self) -> bool {
        match self {
            Expr::Speed => true,
            Expr::Num(_) | Expr::Param(_) => false,
            Expr::Neg(a) => a.uses_speed(),
            Expr::Bin(_, a, b) => a.uses_speed() || b.uses_speed(),
            Expr::Call(_, args) => args.iter().any(Expr::uses_speed),
            Expr::Table(_, a) => a.uses_speed(),
        }
    }

    /// Evaluates over `T` with parameter values `p` and operating speed `speed`.
    /// Domain errors are checked on the real part; the result must be finite.
    pub fn eval<T: Real>(&self, p: &[T], speed: T) -> Result<T, EvalError> {
        let v = self.eval_inner(p, speed)?;
        if re(v).is_finite() {
            Ok(v)
        } else {
            Err(EvalError::NotFinite(re(v)))
        }
    }

    fn eval_inner<T: Real>(&self, p: &[T], speed: T) -> Result<T, EvalError> {
        Ok(match self {
            Expr::Num(x) => cst(*x),
            Expr::Param(i) => p[*i],
            Expr::Speed => speed,
            Expr::Neg(a) => -a.eval_inner(p, speed)?,
            Expr::Bin(BinOp::Pow, a, b) if b.integer_literal().is_some() => {
                let n = b.integer_literal().unwrap_or(1);
                let a = a.eval_inner(p, speed)?;
                if n < 0 && re(a) == 0.0 {
                    return Err(EvalError::DivisionByZero);
                }
                a.powi(n)
            }
            Expr::Bin(op, a, b) => {
                let a = a.eval_inner(p, speed)?;
                let b = b.eval_inner(p, speed)?;
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => {
                        if re(b) == 0.0 {
                            return Err(EvalError::DivisionByZero);
                        }
                        a / b
                    }
                    BinOp::Pow => pow(a, b)?,
                }
            }
            Expr::Table(t, a) => t.eval(a.eval_inner(p, speed)?),
            Expr::Call(f, args) => {
                let x = args[0].eval_inner(p, speed)?;
                let dom = |ok: bool| {
                    if ok {
                        Ok(())
                    } else {
                        Err(EvalError::Domain {
                            func: f.name(),
                            value: re(x),
                        })
                    }
                };
                match f {
                    Func::Sqrt => {
                        dom(re(x) >= 0.0)?;
                        x.sqrt()
                    }
                    Func::Sin => x.sin(),
                    Func::Cos => x.cos(),
                    Func::Tan => x.tan(),
                    Func::Asin => {
                        dom(re(x).abs() <= 1.0)?;
                        x.asin()
                    }
                    Func::Acos => {
                        dom(re(x).abs() <= 1.0)?;
                        x.acos()
                    }
                    Func::Atan => x.atan(),
                    Func::Atan2 => {
                        let y = args[1].eval_inner(p, speed)?;
                        x.atan2(y)
                    }
                    Func::Exp => x.exp(),
                    Func::Ln => {
                        dom(re(x) > 0.0)?;
                        x.ln()
                    }
                    Func::Abs => x.abs(),
                }
            }
        })
    }
}

impl Expr {
    /// The value of a literal integer exponent such as `2` or `-1` (small magnitudes only).
    fn integer_literal(&self) -> Option<i32> {
        match self {
            Expr::Num(x) if x.fract() == 0.0 && x.abs() <= 64.0 => Some(*x as i32),
            Expr::Neg(a) => a.integer_literal().map(|n| -n),
            _ => None,
        }
    }
}

/// `a^b` for a non-literal exponent: `exp(b ln a)` for `a > 0`, `0` for `a = 0 < b`.
/// (Literal integer exponents such as `x^2` go through `powi` and accept any sign of `a`.)
fn pow<T: Real>(a: T, b: T) -> Result<T, EvalError> {
    let (ar, br) = (re(a), re(b));
    if ar > 0.0 {
        Ok((b * a.ln()).exp())
    } else if ar == 0.0 && br > 0.0 {
        Ok(cst(0.0))
    } else {
        Err(EvalError::Domain {
            func: "^ (non-integer power of a non-positive base)",
            value: ar,
        })
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(char),
}

fn tokenize(src: &str) -> Result<Vec<(Tok, usize)>, ParseError> {
    let b = src.as_bytes();
    let mut i = 0;
    let mut out = Vec::new();
    while i < b.len() {
        let c = b[i] as char;
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                let save = i;
                i += 1;
                if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
                    i += 1;
                }
                if i < b.len() && b[i].is_ascii_digit() {
                    while i < b.len() && b[i].is_ascii_digit() {
                        i += 1;
                    }
                } else {
                    i = save;
                }
            }
            let text = &src[start..i];
            let v: f64 = text.parse().map_err(|_| ParseError {
                offset: start,
                message: format!("'{text}' is not a number"),
            })?;
            out.push((Tok::Num(v), start));
        } else if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((Tok::Name(src[start..i].to_string()), start));
        } else if "+-*/^(),".contains(c) {
            out.push((Tok::Op(c), i));
            i += 1;
        } else {
            let ch = src[i..].chars().next().unwrap_or('?');
            return Err(ParseError {
                offset: i,
                message: format!("unexpected character '{ch}'"),
            });
        }
    }
    Ok(out)
}

struct Parser<'a> {
    src: &'a str,
    toks: Vec<(Tok, usize)>,
    pos: usize,
    depth: usize,
    lookup: &'a dyn Fn(&str) -> Option<Expr>,
    tables: &'a dyn Fn(&str) -> Option<Arc<Table>>,
}

impl Parser<'_> {
    fn err_here(&self, msg: &str) -> ParseError {
        let offset = self.toks.get(self.pos).map_or(self.src.len(), |t| t.1);
        ParseError {
            offset,
            message: msg.to_string(),
        }
    }
    fn peek_op(&self) -> Option<char> {
        match self.toks.get(self.pos) {
            Some((Tok::Op(c), _)) => Some(*c),
            _ => None,
        }
    }
    fn enter(&mut self) -> Result<(), ParseError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            Err(self.err_here(&format!("expression nested deeper than {MAX_DEPTH} levels")))
        } else {
            Ok(())
        }
    }
    fn expr(&mut self) -> Result<Expr, ParseError> {
        self.enter()?;
        let mut e = self.term()?;
        while let Some(c @ ('+' | '-')) = self.peek_op() {
            self.pos += 1;
            let r = self.term()?;
            let op = if c == '+' { BinOp::Add } else { BinOp::Sub };
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
        self.depth -= 1;
        Ok(e)
    }
    fn term(&mut self) -> Result<Expr, ParseError> {
        let mut e = self.unary()?;
        while let Some(c @ ('*' | '/')) = self.peek_op() {
            self.pos += 1;
            let r = self.unary()?;
            let op = if c == '*' { BinOp::Mul } else { BinOp::Div };
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
        Ok(e)
    }
    fn unary(&mut self) -> Result<Expr, ParseError> {
        self.enter()?;
        let e = match self.peek_op() {
            Some('-') => {
                self.pos += 1;
                Expr::Neg(Box::new(self.unary()?))
            }
            Some('+') => {
                self.pos += 1;
                self.unary()?
            }
            _ => {
                let base = self.atom()?;
                if self.peek_op() == Some('^') {
                    self.pos += 1;
                    let exp = self.unary()?;
                    Expr::Bin(BinOp::Pow, Box::new(base), Box::new(exp))
                } else {
                    base
                }
            }
        };
        self.depth -= 1;
        Ok(e)
    }
    fn atom(&mut self) -> Result<Expr, ParseError> {
        let Some((tok, off)) = self.toks.get(self.pos).cloned() else {
            return Err(self.err_here("expression ends where a value was expected"));
        };
        self.pos += 1;
        match tok {
            Tok::Num(v) => Ok(Expr::Num(v)),
            Tok::Op('(') => {
                let e = self.expr()?;
                self.expect(')')?;
                Ok(e)
            }
            Tok::Op(c) => {
                self.pos -= 1;
                Err(self.err_here(&format!("unexpected '{c}' where a value was expected")))
            }
            Tok::Name(name) => {
                if self.peek_op() == Some('(')
                    && let Some(table) = (self.tables)(&name)
                {
                    self.pos += 1;
                    let arg = self.expr()?;
                    if self.peek_op() == Some(',') {
                        return Err(ParseError {
                            offset: off,
                            message: format!("table '{name}' takes one argument"),
                        });
                    }
                    self.expect(')')?;
                    return Ok(Expr::Table(table, Box::new(arg)));
                }
                if self.peek_op() == Some('(') {
                    let Some(f) = Func::from_name(&name) else {
                        return Err(ParseError {
                            offset: off,
                            message: format!(
                                "unknown function '{name}' (known: sqrt sin cos tan asin acos atan atan2 exp ln abs, and the model's [[tables]])"
                            ),
                        });
                    };
                    self.pos += 1;
                    let mut args = vec![self.expr()?];
                    while self.peek_op() == Some(',') {
                        self.pos += 1;
                        args.push(self.expr()?);
                    }
                    self.expect(')')?;
                    if args.len() != f.arity() {
                        return Err(ParseError {
                            offset: off,
                            message: format!(
                                "{name} takes {} argument(s), got {}",
                                f.arity(),
                                args.len()
                            ),
                        });
                    }
                    return Ok(Expr::Call(f, args));
                }
                match name.as_str() {
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    "speed" => Ok(Expr::Speed),
                    _ => match (self.lookup)(&name) {
                        Some(e) => Ok(e),
                        None => Err(ParseError {
                            offset: off,
                            message: format!("unknown parameter '{name}'"),
                        }),
                    },
                }
            }
        }
    }
    fn expect(&mut self, c: char) -> Result<(), ParseError> {
        if self.peek_op() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err_here(&format!("expected '{c}'")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    fn lookup(s: &str) -> Option<usize> {
        ["L", "m"].iter().position(|n| *n == s)
    }
    fn ev(s: &str) -> f64 {
        Expr::parse(s, &lookup)
            .unwrap()
            .eval(&[2.0, 3.0], 5.0)
            .unwrap()
    }

    #[test]
    fn precedence_and_associativity() {
        assert!((ev("1 + 2 * 3") - 7.0).abs() < 1e-15);
        assert!((ev("-2^2") + 4.0).abs() < 1e-15);
        assert!((ev("2^3^2") - 512.0).abs() < 1e-12);
        assert!((ev("m*L^2/12") - 1.0).abs() < 1e-15);
        assert!((ev("2^-1") - 0.5).abs() < 1e-15);
        assert!((ev("(1+2)*speed") - 15.0).abs() < 1e-15);
        assert!((ev("atan2(1, 1) * 4 / pi") - 1.0).abs() < 1e-15);
        assert!((ev("sqrt(L)^2 - L") - 0.0).abs() < 1e-15);
        assert!((ev("1.5e-3 * 1e3") - 1.5).abs() < 1e-15);
    }

    #[test]
    fn derivative_through_expression_is_exact() {
        let e = Expr::parse("sin(L) * L^2 + ln(L)", &lookup).unwrap();
        let l = Dual64::from_re(2.0).derivative();
        let v = e
            .eval(&[l, Dual64::from_re(3.0)], Dual64::from_re(0.0))
            .unwrap();
        let exact = 2.0f64.cos() * 4.0 + 2.0f64.sin() * 4.0 + 0.5;
        assert!((v.eps - exact).abs() < 1e-14);
    }

    #[test]
    fn errors_point_at_the_offending_token() {
        let e = Expr::parse("1 + foo", &lookup).unwrap_err();
        assert_eq!(e.offset, 4);
        assert!(e.message.contains("unknown parameter 'foo'"));
        let e = Expr::parse("2 * (3 + 4", &lookup).unwrap_err();
        assert!(e.message.contains("expected ')'"));
        let e = Expr::parse("cosh(1)", &lookup).unwrap_err();
        assert!(e.message.contains("unknown function"));
        let e = Expr::parse("1 $ 2", &lookup).unwrap_err();
        assert_eq!(e.offset, 2);
        let deep = format!("{}1{}", "(".repeat(200), ")".repeat(200));
        assert!(
            Expr::parse(&deep, &lookup)
                .unwrap_err()
                .message
                .contains("nested")
        );
    }

    #[test]
    fn evaluation_errors_are_reported_not_nan() {
        let p = |s| Expr::parse(s, &lookup).unwrap().eval(&[2.0, 3.0], 0.0);
        assert_eq!(p("1 / (L - 2)"), Err(EvalError::DivisionByZero));
        assert!(matches!(p("sqrt(-L)"), Err(EvalError::Domain { .. })));
        assert!(matches!(p("ln(0)"), Err(EvalError::Domain { .. })));
        assert!(matches!(p("exp(1000)"), Err(EvalError::NotFinite(_))));
        assert!(matches!(p("1/speed"), Err(EvalError::DivisionByZero)));
    }
}
