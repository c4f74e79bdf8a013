//! Reverse mode: the gradients of weighted sums of a program's outputs with respect to all its
//! inputs, in one forward sweep of values and one backward sweep of adjoints per sum.
//!
//! Over any [`Real`]: evaluated over a dual number seeded along a direction, the adjoints carry
//! the derivative of the gradient along it (forward over reverse, a Hessian-vector product);
//! over a hyper-dual number with a second direction inside the program's inputs, the derivative
//! of a directional derivative's gradient. The local partial derivatives of the common
//! operations are written out (a sum's are ±1, a product's the other factor); the others come
//! from a dual evaluation ([`Op::partials`]).
//!
//! Griewank & Walther, *Evaluating Derivatives* (2nd ed., SIAM 2008), §3.2 (the incremental
//! reverse mode) and §5.4 (second-order adjoints by forward over reverse).

use super::{Op, Tape, Term};
use crate::real::Real;

/// A local partial derivative: the common constants kept apart from a value.
#[derive(Clone, Copy)]
enum Partial<S> {
    One,
    MinusOne,
    Value(S),
}

impl<S: Real> Partial<S> {
    /// `adjoint · ∂`.
    #[inline(always)]
    fn times(self, adjoint: S) -> S {
        match self {
            Partial::One => adjoint,
            Partial::MinusOne => -adjoint,
            Partial::Value(d) => adjoint * d,
        }
    }
}

/// The partial derivatives of operation `op` with respect to its operands (in the order of
/// [`Op::operands`]), from the values `v` of the operations.
#[inline]
fn partials<S: Real>(op: Op, v: &[S], at: usize) -> [Partial<S>; 3] {
    use Partial::{MinusOne, One, Value};
    let g = |a: u32| v[a as usize];
    match op {
        Op::Add(..) | Op::AddC(..) => [One, One, One],
        Op::Sub(..) => [One, MinusOne, One],
        Op::Neg(_) | Op::CSub(..) => [MinusOne, One, One],
        Op::Mul(a, b) => [Value(g(b)), Value(g(a)), One],
        Op::MulC(_, c) => [Value(S::from(c)), One, One],
        Op::DivC(_, c) => [Value(S::from(c.recip())), One, One],
        Op::MulAdd(a, b, _) => [Value(g(b)), Value(g(a)), One],
        Op::MulSub(a, b, _) => [Value(g(b)), Value(g(a)), MinusOne],
        Op::SubMul(a, b, _) => [Value(-g(b)), Value(-g(a)), One],
        Op::Div(_, b) => {
            let r = g(b).recip();
            [Value(r), Value(-v[at] * r), One]
        }
        op => {
            let (_, da, db) = op.partials(v);
            let z = S::from(0.0);
            [Value(da.unwrap_or(z)), Value(db.unwrap_or(z)), One]
        }
    }
}

/// Working memory of [`Tape::gradients`], reused between calls (a sweep over hyper-dual
/// numbers holds megabytes: allocated afresh, their pages cost as much as the sweep).
#[derive(Debug)]
pub struct Reverse<S> {
    values: Vec<S>,
    adjoint: Vec<S>,
    reached: Vec<bool>,
}

impl<S> Default for Reverse<S> {
    fn default() -> Self {
        Reverse {
            values: Vec::new(),
            adjoint: Vec::new(),
            reached: Vec::new(),
        }
    }
}

impl Tape {
    /// The gradients with respect to every input (`x.len()` entries each) of `Σ_o w_o y_o` for
    /// each weighting `w` of `weights` (pairs of an output's index and its weight; the other
    /// outputs weigh nothing), at the inputs `x`, over any [`Real`]. The values are swept once
    /// for all the weightings, the adjoints once each, in `work`.
    pub fn gradients<S: Real>(
        &self,
        x: &[S],
        weights: &[Vec<(usize, S)>],
        work: &mut Reverse<S>,
    ) -> Vec<Vec<S>> {
        let n = self.ops.len();
        let zero = S::from(0.0);
        let Reverse {
            values: v,
            adjoint,
            reached,
        } = work;
        v.clear();
        for op in &self.ops {
            let value = match *op {
                Op::Input(k) => x[k as usize],
                op => op.eval(v),
            };
            v.push(value);
        }
        weights
            .iter()
            .map(|w| {
                adjoint.clear();
                adjoint.resize(n, zero);
                reached.clear();
                reached.resize(n, false);
                for &(o, wo) in w {
                    if let Term::Node(i, _) = self.outputs[o].term() {
                        adjoint[i as usize] += wo;
                        reached[i as usize] = true;
                    }
                }
                let mut gradient = vec![zero; x.len()];
                for i in (0..n).rev() {
                    if !reached[i] {
                        continue;
                    }
                    let op = self.ops[i];
                    let a = adjoint[i];
                    if let Op::Input(k) = op {
                        gradient[k as usize] += a;
                        continue;
                    }
                    let (operands, count) = op.operands();
                    let d = partials(op, v, i);
                    for (&j, d) in operands[..count].iter().zip(d) {
                        let j = j as usize;
                        adjoint[j] += d.times(a);
                        reached[j] = true;
                    }
                }
                gradient
            })
            .collect()
    }
}
