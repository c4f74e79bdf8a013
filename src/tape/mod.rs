//! Recorded programs: the generic mechanics traced once into a flat list of scalar operations,
//! then evaluated over any [`Real`].
//!
//! The mechanics is written once over [`Real`] and differentiated by nesting dual numbers: a
//! Jacobian of the equations of motion runs the tree kinematics once per coordinate over
//! `Dual<Dual2<f64>>`, most of whose parts are structurally zero, and repeats the same pose
//! products in every pass. Tracing that very code with [`Var`] (a scalar that records each
//! operation instead of only computing it) gives a straight-line program in which
//!
//! * operations on constants are folded (`x·0`, `x·1`, `x+0`, the zero parts of the duals),
//! * identical operations on identical operands are recorded once (hash-consing), so the pose
//!   products shared by all the dual passes appear once,
//! * operations that no output needs are dropped, and products used once by a sum are fused
//!   with it ([`Tape::finish`]).
//!
//! The program is then evaluated over `f64` for values, or over any dual number for exact
//! derivatives: no derivative is written by hand here either, the dual numbers differentiate the
//! recorded operations. A trace is only valid where the traced code does not branch on the
//! values: any comparison of a [`Var`] marks the trace as tainted, and [`record`] then returns
//! `None` so that the caller keeps to the direct route.
//!
//! This is operator-overloading tracing in the sense of Griewank & Walther, *Evaluating
//! Derivatives* (2nd ed., SIAM 2008), §3 and §5.

// Folding compares with exact constants (0, 1, −1) on purpose.
#![allow(clippy::float_cmp)]

mod native;
pub use native::NativePass;

use crate::real::Real;
use num_dual::{Dual, DualNum, DualStruct, Mappable};
use num_traits::{FromPrimitive, Inv, Num, One, Signed, Zero};
use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// Elementary functions of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fun {
    Recip,
    Sqrt,
    Cbrt,
    Exp,
    Exp2,
    ExpM1,
    Ln,
    Log2,
    Log10,
    Ln1p,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    SphJ0,
    SphJ1,
    SphJ2,
    Abs,
}

impl Fun {
    fn apply<S: Real>(self, x: S) -> S {
        match self {
            Fun::Recip => x.recip(),
            Fun::Sqrt => x.sqrt(),
            Fun::Cbrt => x.cbrt(),
            Fun::Exp => x.exp(),
            Fun::Exp2 => x.exp2(),
            Fun::ExpM1 => x.exp_m1(),
            Fun::Ln => x.ln(),
            Fun::Log2 => x.log2(),
            Fun::Log10 => x.log10(),
            Fun::Ln1p => x.ln_1p(),
            Fun::Sin => x.sin(),
            Fun::Cos => x.cos(),
            Fun::Tan => x.tan(),
            Fun::Asin => x.asin(),
            Fun::Acos => x.acos(),
            Fun::Atan => x.atan(),
            Fun::Sinh => x.sinh(),
            Fun::Cosh => x.cosh(),
            Fun::Tanh => x.tanh(),
            Fun::Asinh => x.asinh(),
            Fun::Acosh => x.acosh(),
            Fun::Atanh => x.atanh(),
            Fun::SphJ0 => x.sph_j0(),
            Fun::SphJ1 => x.sph_j1(),
            Fun::SphJ2 => x.sph_j2(),
            Fun::Abs => x.abs(),
        }
    }
}

/// One recorded operation; operands are indices of earlier operations.
#[derive(Debug, Clone, Copy)]
pub enum Op {
    /// Input number `k`.
    Input(u32),
    Const(f64),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    /// `a + c`.
    AddC(u32, f64),
    /// `a · c`.
    MulC(u32, f64),
    /// `a / c`.
    DivC(u32, f64),
    /// `c − a`.
    CSub(f64, u32),
    /// `c / a`.
    CDiv(f64, u32),
    Fun(Fun, u32),
    Powi(u32, i32),
    Powf(u32, f64),
    Log(u32, f64),
    Atan2(u32, u32),
    Powd(u32, u32),
    /// `a · b + c` (a product used once, fused with its sum when the program is recorded; rounded as
    /// the two operations it replaces).
    MulAdd(u32, u32, u32),
    /// `a · b − c`.
    MulSub(u32, u32, u32),
    /// `c − a · b`.
    SubMul(u32, u32, u32),
}

impl Op {
    /// Hash key of an operation: a code for its kind in the top byte, its first operand and
    /// its other operand or constant (by its bits) below; the operands of `+` and `·` in
    /// order. One `u128` is hashed in one step.
    fn key(self) -> u128 {
        let pack =
            |code: u128, a: u32, rest: u64| (code << 120) | ((a as u128) << 64) | rest as u128;
        let sorted = |code, a: u32, b: u32| pack(code, a.min(b), a.max(b) as u64);
        let three = |code, a, b: u32, c: u32| pack(code, a, ((b as u64) << 32) | c as u64);
        match self {
            Op::Input(k) => pack(0, 0, k as u64),
            Op::Const(c) => pack(1, 0, c.to_bits()),
            Op::Add(a, b) => sorted(2, a, b),
            Op::Mul(a, b) => sorted(3, a, b),
            Op::Sub(a, b) => pack(4, a, b as u64),
            Op::Div(a, b) => pack(5, a, b as u64),
            Op::Atan2(a, b) => pack(6, a, b as u64),
            Op::Powd(a, b) => pack(7, a, b as u64),
            Op::Neg(a) => pack(8, a, 0),
            Op::Powi(a, n) => pack(9, a, n as u32 as u64),
            Op::AddC(a, c) => pack(10, a, c.to_bits()),
            Op::MulC(a, c) => pack(11, a, c.to_bits()),
            Op::DivC(a, c) => pack(12, a, c.to_bits()),
            Op::CSub(c, a) => pack(13, a, c.to_bits()),
            Op::CDiv(c, a) => pack(14, a, c.to_bits()),
            Op::Powf(a, c) => pack(15, a, c.to_bits()),
            Op::Log(a, c) => pack(16, a, c.to_bits()),
            Op::Fun(f, a) => pack(17, a, f as u64),
            Op::MulAdd(a, b, c) => three(18, a, b, c),
            Op::MulSub(a, b, c) => three(19, a, b, c),
            Op::SubMul(a, b, c) => three(20, a, b, c),
        }
    }

    /// The operation with its operands renumbered by `f` (inlined: returned through memory,
    /// the copy that follows stalled on its pieces, a third of a recording's pruning).
    #[inline(always)]
    fn map(self, f: impl Fn(u32) -> u32) -> Op {
        match self {
            Op::Input(k) => Op::Input(k),
            Op::Const(c) => Op::Const(c),
            Op::Add(a, b) => Op::Add(f(a), f(b)),
            Op::Sub(a, b) => Op::Sub(f(a), f(b)),
            Op::Mul(a, b) => Op::Mul(f(a), f(b)),
            Op::Div(a, b) => Op::Div(f(a), f(b)),
            Op::Atan2(a, b) => Op::Atan2(f(a), f(b)),
            Op::Powd(a, b) => Op::Powd(f(a), f(b)),
            Op::Neg(a) => Op::Neg(f(a)),
            Op::AddC(a, c) => Op::AddC(f(a), c),
            Op::MulC(a, c) => Op::MulC(f(a), c),
            Op::DivC(a, c) => Op::DivC(f(a), c),
            Op::CSub(c, a) => Op::CSub(c, f(a)),
            Op::CDiv(c, a) => Op::CDiv(c, f(a)),
            Op::Fun(g, a) => Op::Fun(g, f(a)),
            Op::Powi(a, n) => Op::Powi(f(a), n),
            Op::Powf(a, c) => Op::Powf(f(a), c),
            Op::Log(a, c) => Op::Log(f(a), c),
            Op::MulAdd(a, b, c) => Op::MulAdd(f(a), f(b), f(c)),
            Op::MulSub(a, b, c) => Op::MulSub(f(a), f(b), f(c)),
            Op::SubMul(a, b, c) => Op::SubMul(f(a), f(b), f(c)),
        }
    }

    /// Operands, and how many there are (the rest of the array is zero): the passes over a
    /// program loop over these without testing each for presence.
    #[inline(always)]
    fn operands(self) -> ([u32; 3], usize) {
        match self {
            Op::Input(_) | Op::Const(_) => ([0; 3], 0),
            Op::MulAdd(a, b, c) | Op::MulSub(a, b, c) | Op::SubMul(a, b, c) => ([a, b, c], 3),
            Op::Add(a, b)
            | Op::Sub(a, b)
            | Op::Mul(a, b)
            | Op::Div(a, b)
            | Op::Atan2(a, b)
            | Op::Powd(a, b) => ([a, b, 0], 2),
            Op::Neg(a)
            | Op::AddC(a, _)
            | Op::MulC(a, _)
            | Op::DivC(a, _)
            | Op::CSub(_, a)
            | Op::CDiv(_, a)
            | Op::Fun(_, a)
            | Op::Powi(a, _)
            | Op::Powf(a, _)
            | Op::Log(a, _) => ([a, 0, 0], 1),
        }
    }

    /// Operands.
    #[inline(always)]
    fn args(self) -> [Option<u32>; 3] {
        let (a, k) = self.operands();
        std::array::from_fn(|i| (i < k).then_some(a[i]))
    }

    /// The operation applied to operand values `a` and `b` (`b` unused by the one-operand
    /// operations).
    #[inline]
    fn apply<S: Real>(self, a: S, b: S) -> S {
        match self {
            Op::Input(_) => unreachable_input(),
            Op::Const(c) => S::from(c),
            Op::Add(..) => a + b,
            Op::Sub(..) => a - b,
            Op::Mul(..) => a * b,
            Op::Div(..) => a / b,
            Op::Neg(_) => -a,
            Op::AddC(_, c) => a + c,
            Op::MulC(_, c) => a * c,
            Op::DivC(_, c) => a / c,
            Op::CSub(c, _) => S::from(c) - a,
            Op::CDiv(c, _) => S::from(c) / a,
            Op::Fun(f, _) => f.apply(a),
            Op::Powi(_, n) => a.powi(n),
            Op::Powf(_, c) => a.powf(c),
            Op::Log(_, c) => a.log(c),
            Op::Atan2(..) => a.atan2(b),
            Op::Powd(..) => a.powd(b),
            // Three operands: evaluated in [`Op::eval`] and [`Tape::forward`] directly.
            Op::MulAdd(..) | Op::MulSub(..) | Op::SubMul(..) => unreachable_input(),
        }
    }

    /// Value from the operation values `v`.
    #[inline(always)]
    fn eval<S: Real>(self, v: &[S]) -> S {
        self.eval_with(|i| v[i as usize])
    }

    /// Value from the operand values `g(index)`.
    #[inline(always)]
    fn eval_with<S: Real>(self, g: impl Fn(u32) -> S) -> S {
        match self {
            Op::Add(a, b) => g(a) + g(b),
            Op::Sub(a, b) => g(a) - g(b),
            Op::Mul(a, b) => g(a) * g(b),
            Op::Neg(a) => -g(a),
            Op::AddC(a, c) => g(a) + c,
            Op::MulC(a, c) => g(a) * c,
            Op::MulAdd(a, b, c) => g(a) * g(b) + g(c),
            Op::MulSub(a, b, c) => g(a) * g(b) - g(c),
            Op::SubMul(a, b, c) => g(c) - g(a) * g(b),
            op => {
                let [a, b, _] = op.args();
                let a = a.map_or(S::from(0.0), &g);
                let b = b.map_or(a, &g);
                op.apply(a, b)
            }
        }
    }

    /// Value and the partial derivatives with respect to each operand, from dual evaluations.
    fn partials<S: Real>(self, v: &[S]) -> (S, Option<S>, Option<S>) {
        let [a, b, _] = self.args();
        let a = a.map_or(S::from(0.0), |a| v[a as usize]);
        let one = S::from(1.0);
        match b {
            None => {
                let f = self.apply(Dual::new(a, one), Dual::from_re(a));
                (f.re, Some(f.eps), None)
            }
            Some(b) => {
                let b = v[b as usize];
                let fa = self.apply(Dual::new(a, one), Dual::from_re(b));
                let fb = self.apply(Dual::from_re(a), Dual::new(b, one));
                (fa.re, Some(fa.eps), Some(fb.eps))
            }
        }
    }
}

/// Inputs are placed before evaluation; the evaluator never reaches this.
#[inline]
fn unreachable_input<S: Real>() -> S {
    S::from(f64::NAN)
}

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

/// A recorded straight-line program with inputs and outputs.
#[derive(Debug, Clone)]
pub struct Tape {
    ops: Vec<Op>,
    outputs: Vec<Var>,
    /// The first `n_static` operations depend on the static inputs only (see
    /// [`Tape::split`]).
    n_static: usize,
}

/// Traces `f` at the input values `x`: returns the raw trace (operations hash-consed and
/// folded with constants, none dropped or fused: [`Tape::finish`] makes the program of some of
/// its outputs), or `None` when `f` failed or the trace branched on a value (then it is not
/// valid away from `x`).
pub fn record(x: &[f64], f: impl FnOnce(&[Var]) -> Option<Vec<Var>>) -> Option<Tape> {
    record_with(x, true, f)
}

/// [`record`], with hash-consing on or off.
fn record_with(x: &[f64], cse: bool, f: impl FnOnce(&[Var]) -> Option<Vec<Var>>) -> Option<Tape> {
    RECORDER.with(|r| {
        *r.borrow_mut() = Some(Recorder {
            cse,
            ..Recorder::default()
        });
    });
    let vars: Vec<Var> = x
        .iter()
        .enumerate()
        .map(|(k, &v)| push(Op::Input(k as u32), v))
        .collect();
    let outputs = f(&vars);
    let rec = RECORDER.with(|r| r.borrow_mut().take())?;
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

impl Tape {
    /// Number of recorded operations (inputs included).
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Is the program empty?
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The program of the outputs `keep` of a raw trace (in that order): without the
    /// operations they do not need, and with the products used once fused into their sums.
    pub fn finish(&self, keep: &[usize]) -> Tape {
        self.finished(keep, None)
    }

    /// [`Tape::finish`] and then [`Tape::split`] by the inputs `fixed`, in three passes over
    /// the trace instead of one pass each for the pruning, the fusing and the ordering: a
    /// recording makes two programs from a trace of tens of thousands of operations, and each
    /// pass costs a few nanoseconds an operation.
    pub fn finish_split(&self, keep: &[usize], fixed: &[usize]) -> Tape {
        self.finished(keep, Some(fixed))
    }

    /// [`Tape::finish`], split by `fixed` where given.
    ///
    /// Backwards from the outputs, each operation's uses by the live operations are counted;
    /// a product is visited after all its users, so where it has one, a sum or a difference,
    /// that user becomes the fused operation and the product goes (its operands are then the
    /// fused operation's). Forwards, the live operations are renumbered: with `fixed`, those
    /// that depend on the fixed inputs only first, each group in the trace's order. A fused
    /// operation rounds as the two it replaces, so which product a sum of two takes changes
    /// the program's length, never a value.
    fn finished(&self, keep: &[usize], fixed: Option<&[usize]>) -> Tape {
        let n = self.ops.len();
        // Uses by the live operations and the kept outputs (0: not needed), and the last user
        // counted (the only one where there is one; `u32::MAX`: an output).
        let mut uses = vec![0u32; n];
        let mut user = vec![u32::MAX; n];
        for &o in keep {
            if let Term::Node(i, _) = self.outputs[o].term() {
                uses[i as usize] += 1;
            }
        }
        let mut ops = self.ops.clone();
        for i in (0..n).rev() {
            if uses[i] == 0 {
                continue;
            }
            let mut by = i as u32;
            if let Op::Mul(x, y) = ops[i]
                && uses[i] == 1
                && user[i] != u32::MAX
            {
                let u = user[i] as usize;
                let j = i as u32;
                let fused = match ops[u] {
                    Op::Add(a, b) if a == j => Some(Op::MulAdd(x, y, b)),
                    Op::Add(a, b) if b == j => Some(Op::MulAdd(x, y, a)),
                    Op::Sub(a, b) if a == j => Some(Op::MulSub(x, y, b)),
                    Op::Sub(a, b) if b == j => Some(Op::SubMul(x, y, a)),
                    _ => None,
                };
                if let Some(f) = fused {
                    ops[u] = f;
                    uses[i] = 0;
                    by = u as u32;
                }
            }
            let (args, k) = ops[i].operands();
            for &a in &args[..k] {
                uses[a as usize] += 1;
                user[a as usize] = by;
            }
        }
        drop(user);
        // Renumbered: a fixed operation by its place among the fixed ones, the others by
        // theirs among the others, marked, until the number of fixed ones is known.
        const OTHER: u32 = 1 << 31;
        let mut new_index = vec![0u32; n];
        let mut first: Vec<Op> = Vec::with_capacity(n);
        let mut rest: Vec<Op> = Vec::new();
        for i in 0..n {
            if uses[i] == 0 {
                continue;
            }
            let op = ops[i];
            let is_fixed = fixed.is_some_and(|fixed| match op {
                Op::Input(k) => fixed.contains(&(k as usize)),
                op => {
                    let (args, k) = op.operands();
                    args[..k]
                        .iter()
                        .all(|&a| new_index[a as usize] & OTHER == 0)
                }
            });
            let op = op.map(|a| new_index[a as usize]);
            if is_fixed {
                new_index[i] = first.len() as u32;
                first.push(op);
            } else {
                new_index[i] = OTHER | rest.len() as u32;
                rest.push(op);
            }
        }
        let n_static = if fixed.is_some() { first.len() } else { 0 };
        let renumber = |a: u32| {
            if a & OTHER != 0 {
                first.len() as u32 + (a & !OTHER)
            } else {
                a
            }
        };
        let rest: Vec<Op> = rest.into_iter().map(|op| op.map(renumber)).collect();
        let outputs = keep
            .iter()
            .map(|&o| match self.outputs[o].term() {
                Term::Node(i, v) => Var::Node(renumber(new_index[i as usize]), v),
                Term::Const(c) => Var::Const(c),
            })
            .collect();
        first.extend(rest);
        Tape {
            ops: first,
            outputs,
            n_static,
        }
    }

    /// The raw trace of the outputs `keep` with the inputs `constants` (index, value) made
    /// constants: traced again from its own operations at the inputs `x`, so that everything
    /// that folds with those constants folds (`x·0`, `x+0`, ...) as if `f` had been recorded
    /// with them. One recording thus serves several programs: a trace of the mechanics costs
    /// many times its length in hashed operations, a replay one appended operation each. The
    /// replay does not hash-cons: the trace's operations are distinct, and only folding could
    /// make two of them equal (`a·(b+0)` and `a·b`), which would cost a duplicate operation,
    /// never a wrong value (none in the residuals of the shipped examples and the chains of
    /// `scale_chain`; the replay's hashing was 0.6 of the 4.8 ms that recording a 40-segment
    /// chain takes). Only the operations the outputs need are replayed. (`None` where the
    /// replay branched, which a straight-line program does not.)
    pub fn specialise(
        &self,
        x: &[f64],
        constants: &[(usize, f64)],
        keep: &[usize],
    ) -> Option<Tape> {
        let live = self.live(keep);
        record_with(x, false, |v| {
            let mut v = v.to_vec();
            for &(k, c) in constants {
                v[k] = Var::Const(c);
            }
            // Every live operation's operands are live, and written before it.
            let mut work = vec![Var::Const(0.0); self.ops.len()];
            for (i, op) in self.ops.iter().enumerate() {
                if live[i] {
                    work[i] = match *op {
                        Op::Input(k) => v[k as usize],
                        op => op.eval(&work),
                    };
                }
            }
            Some(
                keep.iter()
                    .map(|&o| match self.outputs[o].term() {
                        Term::Node(i, _) => work[i as usize],
                        Term::Const(c) => Var::Const(c),
                    })
                    .collect(),
            )
        })
    }

    /// The operations the outputs `keep` need.
    fn live(&self, keep: &[usize]) -> Vec<bool> {
        let mut live = vec![false; self.ops.len()];
        for &o in keep {
            if let Term::Node(i, _) = self.outputs[o].term() {
                live[i as usize] = true;
            }
        }
        for i in (0..self.ops.len()).rev() {
            if live[i] {
                let (args, k) = self.ops[i].operands();
                for &a in &args[..k] {
                    live[a as usize] = true;
                }
            }
        }
        live
    }

    /// The same program with the operations that depend on the inputs `fixed` only (and on
    /// constants) placed first: [`Tape::eval_static`] computes them once, and every later
    /// evaluation at new values of the other inputs starts from there. Topological order is
    /// kept, as static operations never depend on the others.
    pub fn split(&self, fixed: &[usize]) -> Tape {
        self.finished(&(0..self.outputs.len()).collect::<Vec<_>>(), Some(fixed))
    }

    /// Values of the static operations at `x` (only the static inputs of `x` are read).
    pub fn eval_static<S: Real>(&self, x: &[S]) -> Vec<S> {
        let mut work = Vec::with_capacity(self.n_static);
        for op in &self.ops[..self.n_static] {
            let v = match *op {
                Op::Input(k) => x[k as usize],
                op => op.eval(&work),
            };
            work.push(v);
        }
        work
    }

    /// Evaluates the program at `x` over any [`Real`], with the static values `fixed` from
    /// [`Tape::eval_static`] (at the same static inputs); `work` is scratch space reused
    /// between calls.
    pub fn eval<S: Real>(&self, fixed: &[S], x: &[S], work: &mut Vec<S>) -> Vec<S> {
        let ns = self.n_static;
        // Every entry is written below, in order, before it is read.
        work.resize(self.ops.len(), S::from(0.0));
        work[..ns].copy_from_slice(&fixed[..ns]);
        for (i, op) in self.ops.iter().enumerate().skip(ns) {
            work[i] = match *op {
                Op::Input(k) => x[k as usize],
                op => op.eval(work),
            };
        }
        self.outputs
            .iter()
            .map(|o| match o.term() {
                Term::Const(c) => S::from(c),
                Term::Node(i, _) => work[i as usize],
            })
            .collect()
    }

    /// The program's outputs at `L` points that differ in the inputs seeded by `varied` only
    /// (each of its seeds, any lane, takes the values `values`, one per point), in one pass:
    /// an operation that does not depend on those inputs is evaluated once for all points, the
    /// others once per point with a single dispatch. Returns each output at each point.
    pub fn eval_varied<const L: usize>(
        &self,
        fixed: &[f64],
        x: &[f64],
        varied: &Seeding,
        values: [f64; L],
        work: &mut Vec<[f64; L]>,
    ) -> Vec<[f64; L]> {
        let ns = self.n_static;
        work.clear();
        work.extend(fixed[..ns].iter().map(|&v| [v; L]));
        for (i, op) in self.ops.iter().enumerate().skip(ns) {
            let w = &work[..];
            let g = |a: u32| w[a as usize];
            let v = match *op {
                Op::Input(k) if varied.seeds.iter().any(|s| s.0 == k as usize) => values,
                Op::Input(k) => [x[k as usize]; L],
                // Not moved by the varied inputs: once, from the first point's operands.
                _ if varied.range[i].1 == 0 => [op.eval_with(|a| w[a as usize][0]); L],
                Op::Add(a, b) => {
                    let (a, b) = (g(a), g(b));
                    std::array::from_fn(|l| a[l] + b[l])
                }
                Op::Sub(a, b) => {
                    let (a, b) = (g(a), g(b));
                    std::array::from_fn(|l| a[l] - b[l])
                }
                Op::Mul(a, b) => {
                    let (a, b) = (g(a), g(b));
                    std::array::from_fn(|l| a[l] * b[l])
                }
                Op::MulAdd(a, b, c) => {
                    let (a, b, c) = (g(a), g(b), g(c));
                    std::array::from_fn(|l| a[l] * b[l] + c[l])
                }
                Op::MulSub(a, b, c) => {
                    let (a, b, c) = (g(a), g(b), g(c));
                    std::array::from_fn(|l| a[l] * b[l] - c[l])
                }
                Op::SubMul(a, b, c) => {
                    let (a, b, c) = (g(a), g(b), g(c));
                    std::array::from_fn(|l| c[l] - a[l] * b[l])
                }
                Op::Neg(a) => g(a).map(|x| -x),
                Op::AddC(a, c) => g(a).map(|x| x + c),
                Op::MulC(a, c) => g(a).map(|x| x * c),
                Op::Div(a, b) => {
                    let (a, b) = (g(a), g(b));
                    std::array::from_fn(|l| a[l] / b[l])
                }
                op => {
                    let [a, b, _] = op.args();
                    let a = a.map_or([0.0; L], g);
                    let b = b.map_or(a, g);
                    std::array::from_fn(|l| op.apply(a[l], b[l]))
                }
            };
            work.push(v);
        }
        self.outputs
            .iter()
            .map(|o| match o.term() {
                Term::Const(c) => [c; L],
                Term::Node(i, _) => work[i as usize],
            })
            .collect()
    }

    /// Which lanes of [`Tape::forward`] each operation can move: input `k` moves along lane
    /// `l` for each `(k, l)` in `seeds` (static inputs must not be seeded). Computed once per
    /// choice of seeds; an operation's derivative is only propagated over its lane range.
    /// Derivatives are wanted for the first `differentiated` outputs only: the operations that
    /// only the others need are evaluated without them.
    ///
    /// More than [`BLOCK`] lanes are split into blocks of that many, each a seeding of its own
    /// that [`Tape::forward`] runs in turn: the tangent buffer then holds `BLOCK` lanes of the
    /// operations alive at once, not all the lanes. (A chain's pass keeps every body's pose alive
    /// until the wrenches come back from the tip, and a lane per coordinate: one buffer over
    /// all lanes grows with the square of the number of bodies, about 1 GB at a thousand.) The
    /// values are evaluated once per block; the lane work is the same.
    pub fn seeding(
        &self,
        seeds: &[(usize, usize)],
        lanes: usize,
        differentiated: usize,
    ) -> Seeding {
        let mut whole = self.seeding_of(seeds, lanes, differentiated, lanes <= BLOCK);
        if lanes > BLOCK {
            whole.blocks = (0..lanes.div_ceil(BLOCK))
                .map(|b| {
                    let (lo, hi) = (b * BLOCK, (b * BLOCK + BLOCK).min(lanes));
                    let within: Vec<(usize, usize)> = seeds
                        .iter()
                        .filter(|s| (lo..hi).contains(&s.1))
                        .map(|&(k, l)| (k, l - lo))
                        .collect();
                    self.seeding_of(&within, hi - lo, differentiated, true)
                })
                .collect();
        }
        whole
    }

    /// One block of [`Tape::seeding`] (its tangent rows allocated when `rows`).
    fn seeding_of(
        &self,
        seeds: &[(usize, usize)],
        lanes: usize,
        differentiated: usize,
        rows: bool,
    ) -> Seeding {
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(1);
        let inputs = seeds.iter().map(|s| s.0 + 1).max().unwrap_or(0);
        let mut input_lanes = vec![Vec::new(); inputs];
        for &(k, l) in seeds {
            assert!(l < lanes, "a seed's lane is one of the seeding's lanes");
            input_lanes[k].push(l as u32);
        }
        let mut range = vec![(0u32, 0u32); self.ops.len()];
        for (i, op) in self.ops.iter().enumerate().skip(self.n_static) {
            range[i] = match *op {
                Op::Input(k) => input_lanes
                    .get(k as usize)
                    .map_or(&[][..], |v| &v[..])
                    .iter()
                    .fold((u32::MAX, 0), |(lo, hi), &l| (lo.min(l), hi.max(l + 1))),
                op => {
                    let (args, k) = op.operands();
                    // The forward pass reads operands unchecked on this (see `forward_with`).
                    assert!(
                        args[..k].iter().all(|&a| (a as usize) < i),
                        "every operand precedes its operation"
                    );
                    args[..k].iter().fold((u32::MAX, 0), |(lo, hi), &a| {
                        let (l, h) = range[a as usize];
                        if l >= h {
                            (lo, hi)
                        } else {
                            (lo.min(l), hi.max(h))
                        }
                    })
                }
            };
            if range[i].0 >= range[i].1 {
                range[i] = (0, 0);
            }
        }
        // The operations the differentiated outputs need.
        let live = self.live(&(0..differentiated).collect::<Vec<_>>());
        // As (first lane, width).
        for (r, &live) in range.iter_mut().zip(&live) {
            *r = if live { (r.0, r.1 - r.0) } else { (0, 0) };
        }
        let slots = if rows {
            self.slots(&range, lanes, differentiated)
        } else {
            Slots {
                slot: Vec::new(),
                rows: 0,
                reuse: false,
            }
        };
        Seeding {
            id: NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            seeds: seeds.to_vec(),
            input_lanes,
            lanes,
            range,
            differentiated,
            slots,
            blocks: Vec::new(),
        }
    }

    /// A row of the tangent buffer for every operation with lanes, reused once its last reader
    /// has run (linear-scan allocation; the differentiated outputs keep theirs to the end): the
    /// buffer holds the operations alive at once, not all of them. A chain's pass keeps a few
    /// bodies' operations alive where it records all of them. Returns the rows and their number.
    fn slots(&self, range: &[(u32, u32)], lanes: usize, differentiated: usize) -> Slots {
        let n = self.ops.len();
        // A buffer of one row per operation is kept when small: no clearing on takeover.
        if n * (lanes + CHUNK - 1) <= SMALL_BUFFER {
            return Slots {
                slot: (0..n as u32).collect(),
                rows: n,
                reuse: false,
            };
        }
        // The last reader with lanes of each operation (`usize::MAX`: kept to the end).
        let mut last: Vec<Option<usize>> = vec![None; n];
        for (i, op) in self.ops.iter().enumerate() {
            if range[i].1 > 0 {
                let (args, k) = op.operands();
                for &a in &args[..k] {
                    last[a as usize] = Some(i);
                }
            }
        }
        for o in &self.outputs[..differentiated] {
            if let Term::Node(i, _) = o.term() {
                last[i as usize] = Some(usize::MAX);
            }
        }
        // The operation after which each row is free again (read by nothing: at once).
        let end = |i: usize| match last[i] {
            Some(l) if range[i].1 > 0 && l < n => Some(l),
            None if range[i].1 > 0 => Some(i),
            _ => None,
        };
        // For each operation, the operations whose last reader it is: `ended[start[i]..
        // start[i + 1]]` in increasing order (grouped by a counting sort, not a list each).
        let mut start = vec![0usize; n + 1];
        for i in 0..n {
            if let Some(l) = end(i) {
                start[l + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut ended = vec![0u32; start[n]];
        let mut fill = start.clone();
        for i in 0..n {
            if let Some(l) = end(i) {
                ended[fill[l]] = i as u32;
                fill[l] += 1;
            }
        }
        let mut slot = vec![u32::MAX; n];
        let mut free: Vec<u32> = Vec::new();
        let mut count = 0u32;
        for i in 0..n {
            if range[i].1 > 0 {
                slot[i] = free.pop().unwrap_or_else(|| {
                    count += 1;
                    count - 1
                });
            }
            for &a in &ended[start[i]..start[i + 1]] {
                free.push(slot[a as usize]);
            }
        }
        // The operations without lanes read the zero row after the last.
        for s in &mut slot {
            if *s == u32::MAX {
                *s = count;
            }
        }
        Slots {
            slot,
            rows: count as usize,
            reuse: true,
        }
    }

    /// Forward mode with several directions (lanes) at once: values of every output and first
    /// derivatives of the seeding's differentiated outputs along its directions. Returns the
    /// outputs' values and those derivatives (`differentiated × lanes`, row-major). The local
    /// derivative of each elementary function comes from evaluating it over a dual number; the
    /// lanes carry the chain rule.
    pub fn forward<S: Real>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &mut Forward<S>,
    ) -> (Vec<S>, Vec<S>) {
        let (values, rows) = self.forward_rows(fixed, x, seeding, work);
        let mut derivs = Vec::with_capacity(rows.len() * seeding.lanes);
        for k in 0..rows.len() {
            derivs.extend_from_slice(rows.row(k));
        }
        (values, derivs)
    }

    /// [`Tape::forward`], the derivatives read where the pass left them (copying them out
    /// took about 2 of the 30 µs of the 12-arm governor's exact evaluation, `perf`).
    pub fn forward_rows<'w, S: Real>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &'w mut Forward<S>,
    ) -> (Vec<S>, Rows<'w, S>) {
        if !seeding.blocks.is_empty() {
            let (nd, lanes) = (seeding.differentiated, seeding.lanes);
            let mut derivs = vec![S::from(0.0); nd * lanes];
            let mut values = Vec::new();
            for (b, block) in seeding.blocks.iter().enumerate() {
                let (v, d) = self.forward(fixed, x, block, work);
                let (lo, w) = (b * BLOCK, block.lanes);
                for r in 0..nd {
                    derivs[r * lanes + lo..r * lanes + lo + w]
                        .copy_from_slice(&d[r * w..(r + 1) * w]);
                }
                values = v;
            }
            return (
                values,
                Rows {
                    start: (0..nd).map(|r| r * lanes).collect(),
                    lanes,
                    tan: Cow::Owned(derivs),
                },
            );
        }
        let stride = seeding.lanes + CHUNK - 1;
        if seeding.slots.reuse {
            self.forward_with::<S, true>(fixed, x, seeding, work, stride);
        } else {
            self.forward_with::<S, false>(fixed, x, seeding, work, stride);
        }
        self.read_outputs(&work.val, &work.tan, seeding, stride)
    }

    /// [`Tape::forward`] with rows shared or not (two compiled loops: the small programs'
    /// one keeps no bookkeeping of shared rows).
    fn forward_with<S: Real, const REUSE: bool>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &mut Forward<S>,
        stride: usize,
    ) {
        let ns = self.n_static;
        let zero = S::from(0.0);
        // Every operation writes its value below: no clearing.
        work.val.resize(self.ops.len(), zero);
        work.val[..ns].copy_from_slice(&fixed[..ns]);
        // A row holds zeros outside what its operation wrote (`dirty`); a row taken over by
        // another operation is cleared where the new one does not write.
        let rows = seeding.slots.rows + 1;
        if work.seeding != seeding.id || work.tan.len() != rows * stride {
            work.tan.clear();
            work.tan.resize(rows * stride, zero);
            work.dirty.clear();
            work.dirty.resize(rows, (0, 0));
            work.seeding = seeding.id;
        }
        // What the unchecked reads and writes below rely on, besides every operand preceding its
        // operation (kept by the tape's constructors, asserted when a seeding is made) and the
        // lanes' ranges lying within the lanes (asserted there too).
        assert!(
            seeding.range.len() == self.ops.len()
                && (REUSE || seeding.slots.rows == self.ops.len())
                && stride == seeding.lanes + CHUNK - 1,
            "a seeding of this program"
        );
        let (val, tan, dirty) = (&mut work.val, &mut work.tan, &mut work.dirty);
        // An operand's value. SAFETY: `val` holds a value for every operation (resized above)
        // and an operand precedes its operation, so it is in bounds and written already.
        macro_rules! v {
            ($a:expr) => {
                unsafe { *val.get_unchecked($a as usize) }
            };
        }
        for (i, op) in self.ops.iter().enumerate().skip(ns) {
            let (lo, w) = seeding.range[i];
            let at = if REUSE {
                seeding.slots.slot[i]
            } else {
                i as u32
            };
            if REUSE && w > 0 {
                let (lo, w) = (lo as usize, w as usize);
                let written = if w == 1 {
                    (lo, lo + 1)
                } else {
                    (lo, lo + w.div_ceil(CHUNK) * CHUNK)
                };
                let d = &mut dirty[at as usize];
                if d.0 < written.0 || d.1 > written.1 {
                    let row = at as usize * stride;
                    tan[row + d.0..row + d.1].fill(zero);
                }
                *d = written;
            }
            let lanes = Lanes::<REUSE> {
                stride,
                at: at as usize,
                lo: lo as usize,
                width: w as usize,
                slot: &seeding.slots.slot,
            };
            let v = match *op {
                Op::Input(k) => {
                    lanes.map(tan, [], |[]| zero);
                    if lanes.width > 0 {
                        for &l in &seeding.input_lanes[k as usize] {
                            tan[lanes.at * stride + l as usize] = S::from(1.0);
                        }
                    }
                    x[k as usize]
                }
                Op::Const(c) => {
                    lanes.map(tan, [], |[]| zero);
                    S::from(c)
                }
                Op::Add(a, b) => {
                    lanes.map(tan, [a, b], |[x, y]| x + y);
                    v!(a) + v!(b)
                }
                Op::Sub(a, b) => {
                    lanes.map(tan, [a, b], |[x, y]| x - y);
                    v!(a) - v!(b)
                }
                Op::Mul(a, b) => {
                    let (va, vb) = (v!(a), v!(b));
                    lanes.map(tan, [a, b], |[x, y]| x * vb + va * y);
                    va * vb
                }
                Op::Neg(a) => {
                    lanes.map(tan, [a], |[x]| -x);
                    -v!(a)
                }
                Op::AddC(a, c) => {
                    lanes.map(tan, [a], |[x]| x);
                    v!(a) + c
                }
                Op::MulC(a, c) => {
                    lanes.map(tan, [a], |[x]| x * c);
                    v!(a) * c
                }
                Op::MulAdd(a, b, c) => {
                    let (va, vb, vc) = (v!(a), v!(b), v!(c));
                    lanes.map(tan, [a, b, c], |[x, y, z]| x * vb + va * y + z);
                    va * vb + vc
                }
                Op::MulSub(a, b, c) => {
                    let (va, vb, vc) = (v!(a), v!(b), v!(c));
                    lanes.map(tan, [a, b, c], |[x, y, z]| x * vb + va * y - z);
                    va * vb - vc
                }
                Op::SubMul(a, b, c) => {
                    let (va, vb, vc) = (v!(a), v!(b), v!(c));
                    lanes.map(tan, [a, b, c], |[x, y, z]| z - (x * vb + va * y));
                    vc - va * vb
                }
                op => {
                    // Division and the functions: local partials from a dual evaluation.
                    let (v, da, db) = op.partials(val);
                    match (op.args(), da, db) {
                        ([Some(a), Some(b), _], Some(da), Some(db)) => {
                            lanes.map(tan, [a, b], |[x, y]| da * x + db * y)
                        }
                        ([Some(a), _, _], Some(da), _) => lanes.map(tan, [a], |[x]| da * x),
                        _ => lanes.map(tan, [], |[]| zero),
                    }
                    v
                }
            };
            // SAFETY: `i` is an operation's index and `val` holds one value for each.
            unsafe { *val.get_unchecked_mut(i) = v };
        }
    }

    /// The outputs' values and where the differentiated outputs' lanes are after a forward
    /// pass (a constant output's in the zero row after the last).
    fn read_outputs<'w, S: Real>(
        &self,
        val: &[S],
        tan: &'w [S],
        seeding: &Seeding,
        stride: usize,
    ) -> (Vec<S>, Rows<'w, S>) {
        let zero_row = seeding.slots.rows * stride;
        let mut start = Vec::with_capacity(seeding.differentiated);
        let values = (self.outputs.iter().enumerate())
            .map(|(k, o)| {
                let (value, row) = match o.term() {
                    Term::Const(c) => (S::from(c), zero_row),
                    Term::Node(i, _) => {
                        let i = i as usize;
                        (val[i], seeding.slots.slot[i] as usize * stride)
                    }
                };
                if k < seeding.differentiated {
                    start.push(row);
                }
                value
            })
            .collect();
        (
            values,
            Rows {
                start,
                lanes: seeding.lanes,
                tan: Cow::Borrowed(tan),
            },
        )
    }
}

/// The derivatives of a forward pass's differentiated outputs (see [`Tape::forward_rows`]):
/// output `k`'s lanes are `row(k)`.
pub struct Rows<'w, S: Clone> {
    /// Where each output's lanes start in `tan`.
    start: Vec<usize>,
    lanes: usize,
    tan: Cow<'w, [S]>,
}

impl<S: Clone> Rows<'_, S> {
    /// Number of differentiated outputs.
    pub fn len(&self) -> usize {
        self.start.len()
    }

    /// Are there none?
    pub fn is_empty(&self) -> bool {
        self.start.is_empty()
    }

    /// The lanes of output `k`.
    pub fn row(&self, k: usize) -> &[S] {
        &self.tan[self.start[k]..self.start[k] + self.lanes]
    }
}

/// Lanes are processed in chunks of this many (fixed-size loops the compiler unrolls and
/// vectorises; the lane ranges are mostly 1 to 4 wide).
const CHUNK: usize = 4;

/// Scalars too wide to move a chunk of lanes as one array ([`crate::dual4::Dual4`], 40 bytes:
/// three operands' chunks are 480 bytes, which the compiler copies through memory, eight times
/// the time of the pass lane by lane). `f64` and `Dual64` keep their chunks.
const fn wide<S>() -> bool {
    std::mem::size_of::<S>() > 16
}

/// The lanes one operation of [`Tape::forward`] writes: `width` lanes from `lo` of tangent row
/// `at`, in rows of `stride` (the lanes plus room for the last chunk); `slot` gives each
/// operation's row.
struct Lanes<'a, const REUSE: bool> {
    stride: usize,
    at: usize,
    lo: usize,
    width: usize,
    slot: &'a [u32],
}

impl<const REUSE: bool> Lanes<'_, REUSE> {
    /// `out[l] = f([arg[l] for arg in args])` over the operation's lanes, a single lane alone
    /// and wider ranges in whole chunks. A chunk's lanes beyond the range are outside every
    /// operand's range too, so they are written with zeros (the derivatives there) and the
    /// zero invariant of [`Forward`] holds. An operand's row is never the operation's own (it
    /// is freed after the operation's row is taken).
    #[inline(always)]
    fn map<S: Copy, const K: usize>(&self, tan: &mut [S], args: [u32; K], f: impl Fn([S; K]) -> S) {
        let chunks = self.width.div_ceil(CHUNK) * CHUNK;
        let (base, out) = if REUSE {
            let base = args.map(|a| self.slot[a as usize] as usize * self.stride + self.lo);
            let out = self.at * self.stride + self.lo;
            // Raw reads and writes: this loop indexed through slices spends twice the time
            // (the 12-arm governor's exact evaluation with shared rows 95–113 µs, with these
            // 65–68 µs). One check per operation keeps it in bounds.
            assert!(
                out + chunks <= tan.len() && base.iter().all(|&b| b + chunks <= tan.len()),
                "a forward pass's lanes stay in their rows"
            );
            (base, out)
        } else {
            // One row per operation: an operand's row is its index, below the operation's own.
            // In bounds without a check: `forward_with` asserted a row per operation and one
            // zero row, every operand precedes its operation, and a range of lanes rounded up
            // to whole chunks ends within the row's `stride = lanes + CHUNK − 1`.
            (
                args.map(|a| a as usize * self.stride + self.lo),
                self.at * self.stride + self.lo,
            )
        };
        let p = tan.as_mut_ptr();
        if self.width == 1 {
            // SAFETY: in bounds as said above; no reference into `tan` is alive.
            unsafe { std::ptr::write(p.add(out), f(base.map(|b| std::ptr::read(p.add(b))))) };
            return;
        }
        let mut k = 0;
        if wide::<S>() {
            // Lane by lane (see [`wide`]): lane `j` of the output is written after lane `j` of
            // every operand is read, so an operand sharing the output's row is still read
            // before it changes.
            while k < self.width {
                for j in k..k + CHUNK {
                    // SAFETY: as for the chunks below, one element at a time.
                    let value = f(base.map(|b| unsafe { std::ptr::read(p.add(b + j)) }));
                    unsafe { std::ptr::write(p.add(out + j), value) };
                }
                k += CHUNK;
            }
            return;
        }
        while k < self.width {
            // SAFETY: every chunk read and written lies in `tan` (as said above) and is
            // aligned as `S` is (an array has its element's alignment); no reference into
            // `tan` is alive meanwhile, and each chunk is copied out before the output's is
            // written, so an operand sharing the output's row would still read its old values.
            let chunk: [[S; CHUNK]; K] =
                base.map(|b| unsafe { std::ptr::read(p.add(b + k).cast::<[S; CHUNK]>()) });
            let value: [S; CHUNK] = std::array::from_fn(|j| f(chunk.map(|c| c[j])));
            unsafe { std::ptr::write(p.add(out + k).cast::<[S; CHUNK]>(), value) };
            k += CHUNK;
        }
    }
}

/// Scratch space of [`Tape::forward`].
#[derive(Debug, Clone)]
pub struct Forward<S> {
    val: Vec<S>,
    tan: Vec<S>,
    /// The lanes each tangent row's last operation wrote (zeros elsewhere).
    dirty: Vec<(usize, usize)>,
    /// The [`Seeding`] the buffer was last used with.
    seeding: usize,
}

impl Seeding {
    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// The seeds `(input, lane)`.
    pub fn seeds(&self) -> &[(usize, usize)] {
        &self.seeds
    }

    /// Do operations alive at different times share tangent rows (in some block)? Big
    /// programs' passes do, small ones keep a row per operation.
    pub fn shares_rows(&self) -> bool {
        self.slots.reuse || self.blocks.iter().any(|b| b.slots.reuse)
    }
}

impl<S> Default for Forward<S> {
    fn default() -> Self {
        Forward {
            val: Vec::new(),
            tan: Vec::new(),
            dirty: Vec::new(),
            seeding: 0,
        }
    }
}

/// Seeds of [`Tape::forward`] with the lane range of every operation.
#[derive(Debug, Clone)]
pub struct Seeding {
    id: usize,
    seeds: Vec<(usize, usize)>,
    /// The lanes of each input (by input index; the seeds regrouped).
    input_lanes: Vec<Vec<u32>>,
    lanes: usize,
    /// First lane and number of lanes of each operation.
    range: Vec<(u32, u32)>,
    /// Outputs with derivatives (the first ones).
    differentiated: usize,
    slots: Slots,
    /// The blocks of at most [`BLOCK`] lanes the lanes are split into (none when they are
    /// that few; then `slots` are this seeding's own rows).
    blocks: Vec<Seeding>,
}

/// Most lanes one pass of [`Tape::forward`] carries (see [`Tape::seeding`]).
pub const BLOCK: usize = 256;

/// The tangent rows of a [`Seeding`]'s operations.
#[derive(Debug, Clone)]
struct Slots {
    /// Row of each operation; the operations without lanes read row `rows`, which stays zero.
    slot: Vec<u32>,
    rows: usize,
    /// Rows are shared by operations alive at different times.
    reuse: bool,
}

/// Tangent buffers up to this many numbers (8 MB of `f64`) keep one row per operation.
const SMALL_BUFFER: usize = 1 << 20;
