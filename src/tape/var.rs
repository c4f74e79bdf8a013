//! The recording scalar [`Var`] and the thread's recorder: running the generic mechanics over
//! [`Var`] records each operation it does (folded with constants and hash-consed) instead of
//! only computing it.
//!
//! Everything that makes a trace is here: the recorder a trace is written to, the arithmetic and
//! the `num-traits`/`num-dual` traits that write to it, the comparisons that mark it tainted,
//! and the start and end of a recording ([`record_with`]).

// Folding compares with exact constants (0, 1, −1) on purpose.
#![allow(clippy::float_cmp)]

use super::{Fun, Op, Tape};
use num_dual::{DualNum, DualStruct, Mappable};
use num_traits::{FromPrimitive, Inv, Num, One, Signed, Zero};
use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// A traced scalar: a constant, or the result of recorded operation `index` (with its value at
/// the tracing point, for [`DualStruct::re`]). Read it through [`Var::term`].
///
/// Two fields, an operation's index (`CONST` for a constant) and the value, so that it travels
/// in two registers: as an enum of three fields it was passed and returned through memory, and
/// the whole-value copies after its field-by-field writes stalled the trace and the replay.
#[derive(Clone, Copy)]
pub struct Var {
    node: u32,
    value: f64,
}

/// What a [`Var`] is.
#[derive(Debug, Clone, Copy)]
pub enum Term {
    Const(f64),
    Node(u32, f64),
}

/// [`Var::node`] of a constant.
const CONST: u32 = u32::MAX;

impl Var {
    /// A constant.
    #[allow(non_snake_case)]
    #[inline(always)]
    pub const fn Const(value: f64) -> Var {
        Var { node: CONST, value }
    }

    /// The result of recorded operation `index`, with its value at the tracing point.
    #[allow(non_snake_case)]
    #[inline(always)]
    pub const fn Node(index: u32, value: f64) -> Var {
        Var { node: index, value }
    }

    /// A constant or an operation's result.
    #[inline(always)]
    pub fn term(self) -> Term {
        if self.node == CONST {
            Term::Const(self.value)
        } else {
            Term::Node(self.node, self.value)
        }
    }

    /// Value at the tracing point.
    #[inline(always)]
    pub fn value(self) -> f64 {
        self.value
    }
}

impl fmt::Debug for Var {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.term().fmt(f)
    }
}

/// The operations recorded so far on this thread.
#[derive(Default)]
struct Recorder {
    ops: Vec<Op>,
    /// Hash-consing: the index of each distinct operation (foldhash: recording is hashing
    /// bound, and SipHash's resistance is not needed for keys made by the program itself).
    /// The [`Op::key`] is kept as two `u64` halves: a slot of 24 bytes where a `u128`'s
    /// alignment made it 32 (a 40-segment chain's trace 2–3 % faster, its table growing less).
    seen: HashMap<(u64, u64), u32, foldhash::fast::FixedState>,
    tainted: bool,
    /// Hash-consing on (off for a replay, see [`Tape::specialise`]).
    cse: bool,
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
}

/// Records `op` with value `value` (or returns the constant where nothing records).
fn push(op: Op, value: f64) -> Var {
    RECORDER.with(|r| match r.borrow_mut().as_mut() {
        Some(rec) => {
            let next = rec.ops.len() as u32;
            if !rec.cse {
                rec.ops.push(op);
                return Var::Node(next, value);
            }
            let k = op.key();
            let i = *rec.seen.entry(((k >> 64) as u64, k as u64)).or_insert(next);
            if i == next {
                rec.ops.push(op);
            }
            Var::Node(i, value)
        }
        None => Var::Const(value),
    })
}

/// Notes that the traced code looked at a value (a branch the trace cannot follow).
fn taint() {
    RECORDER.with(|r| {
        if let Some(rec) = r.borrow_mut().as_mut() {
            rec.tainted = true;
        }
    });
}

fn unary(a: Var, f: impl Fn(f64) -> f64, op: impl Fn(u32) -> Op) -> Var {
    match a.term() {
        Term::Const(x) => Var::Const(f(x)),
        Term::Node(i, x) => push(op(i), f(x)),
    }
}

impl Add for Var {
    type Output = Var;
    fn add(self, b: Var) -> Var {
        match (self.term(), b.term()) {
            (Term::Const(x), Term::Const(y)) => Var::Const(x + y),
            (Term::Node(..), Term::Const(c)) | (Term::Const(c), Term::Node(..)) if c == 0.0 => {
                if let Term::Node(..) = self.term() {
                    self
                } else {
                    b
                }
            }
            (Term::Node(i, x), Term::Const(c)) | (Term::Const(c), Term::Node(i, x)) => {
                push(Op::AddC(i, c), x + c)
            }
            (Term::Node(i, x), Term::Node(j, y)) => push(Op::Add(i, j), x + y),
        }
    }
}

impl Sub for Var {
    type Output = Var;
    fn sub(self, b: Var) -> Var {
        match (self.term(), b.term()) {
            (Term::Const(x), Term::Const(y)) => Var::Const(x - y),
            (Term::Node(..), Term::Const(0.0)) => self,
            (Term::Node(i, x), Term::Const(c)) => push(Op::AddC(i, -c), x - c),
            (Term::Const(0.0), Term::Node(..)) => -b,
            (Term::Const(c), Term::Node(i, y)) => push(Op::CSub(c, i), c - y),
            (Term::Node(i, x), Term::Node(j, y)) => push(Op::Sub(i, j), x - y),
        }
    }
}

impl Mul for Var {
    type Output = Var;
    fn mul(self, b: Var) -> Var {
        match (self.term(), b.term()) {
            (Term::Const(x), Term::Const(y)) => Var::Const(x * y),
            (Term::Node(i, x), Term::Const(c)) | (Term::Const(c), Term::Node(i, x)) => {
                if c == 0.0 {
                    Var::Const(0.0)
                } else if c == 1.0 {
                    Var::Node(i, x)
                } else if c == -1.0 {
                    -Var::Node(i, x)
                } else {
                    push(Op::MulC(i, c), x * c)
                }
            }
            (Term::Node(i, x), Term::Node(j, y)) => push(Op::Mul(i, j), x * y),
        }
    }
}

impl Div for Var {
    type Output = Var;
    fn div(self, b: Var) -> Var {
        match (self.term(), b.term()) {
            (Term::Const(x), Term::Const(y)) => Var::Const(x / y),
            (Term::Node(..), Term::Const(1.0)) => self,
            (Term::Node(i, x), Term::Const(c)) => push(Op::DivC(i, c), x / c),
            (Term::Const(0.0), Term::Node(_, y)) => Var::Const(0.0 / y),
            (Term::Const(c), Term::Node(i, y)) => push(Op::CDiv(c, i), c / y),
            (Term::Node(i, x), Term::Node(j, y)) => push(Op::Div(i, j), x / y),
        }
    }
}

impl Neg for Var {
    type Output = Var;
    fn neg(self) -> Var {
        unary(self, |x| -x, Op::Neg)
    }
}

impl Rem for Var {
    type Output = Var;
    /// Not part of the mechanics; a remainder is a branch the trace cannot follow.
    fn rem(self, b: Var) -> Var {
        taint();
        Var::Const(self.value() % b.value())
    }
}

macro_rules! by_ref_and_f64 {
    ($($tr:ident $f:ident $atr:ident $af:ident),*) => {$(
        impl<'a> $tr<&'a Var> for Var {
            type Output = Var;
            fn $f(self, b: &'a Var) -> Var {
                $tr::$f(self, *b)
            }
        }
        impl $tr<f64> for Var {
            type Output = Var;
            fn $f(self, b: f64) -> Var {
                $tr::$f(self, Var::Const(b))
            }
        }
        impl $atr for Var {
            fn $af(&mut self, b: Var) {
                *self = $tr::$f(*self, b);
            }
        }
        impl $atr<f64> for Var {
            fn $af(&mut self, b: f64) {
                *self = $tr::$f(*self, Var::Const(b));
            }
        }
    )*};
}
by_ref_and_f64!(
    Add add AddAssign add_assign,
    Sub sub SubAssign sub_assign,
    Mul mul MulAssign mul_assign,
    Div div DivAssign div_assign,
    Rem rem RemAssign rem_assign
);

impl PartialEq for Var {
    fn eq(&self, other: &Var) -> bool {
        taint();
        self.value() == other.value()
    }
}

impl PartialOrd for Var {
    fn partial_cmp(&self, other: &Var) -> Option<std::cmp::Ordering> {
        taint();
        self.value().partial_cmp(&other.value())
    }
}

impl PartialEq<f64> for Var {
    fn eq(&self, other: &f64) -> bool {
        taint();
        self.value() == *other
    }
}

impl PartialOrd<f64> for Var {
    fn partial_cmp(&self, other: &f64) -> Option<std::cmp::Ordering> {
        taint();
        self.value().partial_cmp(other)
    }
}

impl fmt::Display for Var {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.value())
    }
}

impl From<f64> for Var {
    fn from(c: f64) -> Var {
        Var::Const(c)
    }
}

impl Zero for Var {
    fn zero() -> Var {
        Var::Const(0.0)
    }
    fn is_zero(&self) -> bool {
        match self.term() {
            Term::Const(c) => c == 0.0,
            Term::Node(..) => {
                taint();
                self.value() == 0.0
            }
        }
    }
}

impl One for Var {
    fn one() -> Var {
        Var::Const(1.0)
    }
}

impl Num for Var {
    type FromStrRadixErr = <f64 as Num>::FromStrRadixErr;
    fn from_str_radix(s: &str, radix: u32) -> Result<Var, Self::FromStrRadixErr> {
        f64::from_str_radix(s, radix).map(Var::Const)
    }
}

impl Signed for Var {
    fn abs(&self) -> Var {
        unary(*self, f64::abs, |i| Op::Fun(Fun::Abs, i))
    }
    fn abs_sub(&self, other: &Var) -> Var {
        taint();
        Var::Const((self.value() - other.value()).max(0.0))
    }
    fn signum(&self) -> Var {
        if let Term::Node(..) = self.term() {
            taint();
        }
        Var::Const(self.value().signum())
    }
    fn is_positive(&self) -> bool {
        if let Term::Node(..) = self.term() {
            taint();
        }
        self.value().is_sign_positive()
    }
    fn is_negative(&self) -> bool {
        if let Term::Node(..) = self.term() {
            taint();
        }
        self.value().is_sign_negative()
    }
}

impl Inv for Var {
    type Output = Var;
    fn inv(self) -> Var {
        self.recip()
    }
}

impl std::iter::Sum for Var {
    fn sum<I: Iterator<Item = Var>>(iter: I) -> Var {
        iter.fold(Var::Const(0.0), |a, b| a + b)
    }
}

impl std::iter::Product for Var {
    fn product<I: Iterator<Item = Var>>(iter: I) -> Var {
        iter.fold(Var::Const(1.0), |a, b| a * b)
    }
}

impl FromPrimitive for Var {
    fn from_i64(n: i64) -> Option<Var> {
        Some(Var::Const(n as f64))
    }
    fn from_u64(n: u64) -> Option<Var> {
        Some(Var::Const(n as f64))
    }
    fn from_f64(n: f64) -> Option<Var> {
        Some(Var::Const(n))
    }
}

impl DualStruct for Var {
    type Real = f64;
    type Inner = f64;
    fn re(&self) -> f64 {
        self.value()
    }
    fn from_inner(inner: &f64) -> Var {
        Var::Const(*inner)
    }
}

impl Mappable<Var> for Var {
    type Output<O> = O;
    fn map_dual<M: Fn(Var) -> O, O>(self, f: M) -> O {
        f(self)
    }
}

macro_rules! funs {
    ($($name:ident $fun:ident),*) => {$(
        fn $name(&self) -> Var {
            unary(*self, f64::$name, |i| Op::Fun(Fun::$fun, i))
        }
    )*};
}

impl DualNum for Var {
    type Primitive = f64;
    const NDERIV: usize = 0;
    type InnerDual = f64;

    fn from_re(re: f64) -> Var {
        Var::Const(re)
    }
    fn scale(self, factor: &f64) -> Var {
        self * *factor
    }
    fn powi(&self, n: i32) -> Var {
        match n {
            0 => Var::Const(1.0),
            1 => *self,
            _ => unary(*self, |x| x.powi(n), |i| Op::Powi(i, n)),
        }
    }
    fn powf(&self, n: f64) -> Var {
        unary(*self, |x| x.powf(n), |i| Op::Powf(i, n))
    }
    fn log(&self, base: f64) -> Var {
        unary(*self, |x| x.log(base), |i| Op::Log(i, base))
    }
    fn sin_cos(&self) -> (Var, Var) {
        (self.sin(), self.cos())
    }
    fn atan2(&self, other: Var) -> Var {
        match (self.term(), other.term()) {
            (Term::Const(y), Term::Const(x)) => Var::Const(y.atan2(x)),
            _ => {
                let (i, j) = (node(*self), node(other));
                push(Op::Atan2(i, j), self.value().atan2(other.value()))
            }
        }
    }
    fn powd(&self, exp: Var) -> Var {
        match (self.term(), exp.term()) {
            (Term::Const(x), Term::Const(y)) => Var::Const(x.powf(y)),
            _ => {
                let (i, j) = (node(*self), node(exp));
                push(Op::Powd(i, j), self.value().powf(exp.value()))
            }
        }
    }
    fn recip(&self) -> Var {
        unary(*self, f64::recip, |i| Op::Fun(Fun::Recip, i))
    }
    fn sph_j0(&self) -> Var {
        unary(*self, |x| x.sph_j0(), |i| Op::Fun(Fun::SphJ0, i))
    }
    fn sph_j1(&self) -> Var {
        unary(*self, |x| x.sph_j1(), |i| Op::Fun(Fun::SphJ1, i))
    }
    fn sph_j2(&self) -> Var {
        unary(*self, |x| x.sph_j2(), |i| Op::Fun(Fun::SphJ2, i))
    }
    funs!(
        sqrt Sqrt, cbrt Cbrt, exp Exp, exp2 Exp2, exp_m1 ExpM1, ln Ln, log2 Log2, log10 Log10,
        ln_1p Ln1p, sin Sin, cos Cos, tan Tan, asin Asin, acos Acos, atan Atan, sinh Sinh,
        cosh Cosh, tanh Tanh, asinh Asinh, acosh Acosh, atanh Atanh
    );
}

/// The index of `v` as an operand (a constant gets a node of its own; only the rare
/// two-argument functions with one constant argument need that).
fn node(v: Var) -> u32 {
    match v.term() {
        Term::Node(i, _) => i,
        Term::Const(c) => match push(Op::Const(c), c).term() {
            Term::Node(i, _) => i,
            Term::Const(_) => 0,
        },
    }
}

/// The thread's recording, active while this guard lives. Dropping it ends the recording,
/// also when the traced code panics, so that no later computation on the thread records into
/// a recorder left behind.
struct Recording;

impl Recording {
    /// Starts recording on this thread, with hash-consing on or off.
    fn start(cse: bool) -> Recording {
        RECORDER.with(|r| {
            *r.borrow_mut() = Some(Recorder {
                cse,
                ..Recorder::default()
            });
        });
        Recording
    }

    /// Ends the recording and gives what it recorded.
    fn finish(self) -> Option<Recorder> {
        RECORDER.with(|r| r.borrow_mut().take())
    }
}

impl Drop for Recording {
    fn drop(&mut self) {
        // `try_with`: the thread's storage may already be gone when a thread exits.
        let _ = RECORDER.try_with(|r| r.borrow_mut().take());
    }
}

/// [`record`](super::record), with hash-consing on or off.
pub(super) fn record_with(
    x: &[f64],
    cse: bool,
    f: impl FnOnce(&[Var]) -> Option<Vec<Var>>,
) -> Option<Tape> {
    let recording = Recording::start(cse);
    let vars: Vec<Var> = x
        .iter()
        .enumerate()
        .map(|(k, &v)| push(Op::Input(k as u32), v))
        .collect();
    let outputs = f(&vars);
    let rec = recording.finish()?;
    let outputs = outputs?;
    if rec.tainted {
        return None;
    }
    Some(Tape {
        ops: rec.ops,
        outputs,
        n_static: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_in_traced_code_ends_the_recording() {
        let traced = std::panic::catch_unwind(|| {
            record_with(&[1.0, 2.0], true, |x| {
                let _ = x[0] * x[1];
                panic!("the traced code fails")
            })
        });
        assert!(traced.is_err());
        assert!(RECORDER.with(|r| r.borrow().is_none()));
        // The thread records afresh afterwards.
        let tape = record_with(&[3.0], true, |x| Some(vec![x[0] * 2.0])).expect("records");
        assert_eq!(tape.outputs.len(), 1);
    }
}
