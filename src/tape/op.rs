//! The instruction set of a recorded program: the elementary functions [`Fun`], the operations
//! [`Op`], and how one operation is hashed, renumbered and evaluated over any [`Real`].
//!
//! Every other part of the tape speaks in these operations: the recorder makes them, the passes
//! rewrite them, the evaluators and the compiler run them.

use crate::real::Real;
use num_dual::Dual;

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
    #[inline]
    pub(super) fn key(self) -> u128 {
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
    pub(super) fn map(self, f: impl Fn(u32) -> u32) -> Op {
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
    pub(super) fn operands(self) -> ([u32; 3], usize) {
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
    pub(super) fn args(self) -> [Option<u32>; 3] {
        let (a, k) = self.operands();
        std::array::from_fn(|i| (i < k).then_some(a[i]))
    }

    /// The operation applied to operand values `a` and `b` (`b` unused by the one-operand
    /// operations).
    #[inline]
    pub(super) fn apply<S: Real>(self, a: S, b: S) -> S {
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
    pub(super) fn eval<S: Real>(self, v: &[S]) -> S {
        self.eval_with(|i| v[i as usize])
    }

    /// Value from the operand values `g(index)`.
    #[inline(always)]
    pub(super) fn eval_with<S: Real>(self, g: impl Fn(u32) -> S) -> S {
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
    pub(super) fn partials<S: Real>(self, v: &[S]) -> (S, Option<S>, Option<S>) {
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
