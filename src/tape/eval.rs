//! Value evaluation of a program: its outputs over any [`Real`] at one point, and over `f64`
//! at several points that differ in some inputs only ([`Tape::eval_varied`]).
//!
//! No derivatives are propagated here beyond what the scalar type carries (a dual number
//! differentiates the operations it is evaluated over); forward mode over many lanes is in
//! [`forward`](super::forward).

use super::{Op, Seeding, Tape, Term};
use crate::real::Real;

impl Tape {
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
}
