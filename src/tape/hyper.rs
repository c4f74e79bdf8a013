//! Forward over reverse with hyper-dual values in a lean form: the kernel of
//! [`crate::program::Program::pencil_hessian`].
//!
//! [`Tape::gradients`] over `num_dual`'s hyper-dual vectors spends most of its time moving and
//! testing their optional parts (measured: 2.5 ms a sweep of the 40-segment blade's 8800
//! operations, a third in `memmove`). [`Hyper`] keeps every part as a plain array, the common
//! operations are written out over them, and the adjoints of two weightings are swept
//! together; the other operations go through `num_dual` ([`Op::partials`]).

use super::{Op, Tape, Term};
use num_dual::{Derivative, HyperDualSVec64};

/// A value, its derivatives along two lanes (`e1`) and `N` directions (`e2`), and the mixed
/// ones (`e12[k][j]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hyper<const N: usize> {
    pub re: f64,
    pub e1: [f64; 2],
    pub e2: [f64; N],
    pub e12: [[f64; N]; 2],
}

impl<const N: usize> Hyper<N> {
    /// A constant.
    pub const fn constant(re: f64) -> Self {
        Hyper {
            re,
            e1: [0.0; 2],
            e2: [0.0; N],
            e12: [[0.0; N]; 2],
        }
    }

    #[inline(always)]
    fn add(&self, b: &Self, sign: f64) -> Self {
        let mut c = *self;
        c.re += sign * b.re;
        for k in 0..2 {
            c.e1[k] += sign * b.e1[k];
            for j in 0..N {
                c.e12[k][j] += sign * b.e12[k][j];
            }
        }
        for j in 0..N {
            c.e2[j] += sign * b.e2[j];
        }
        c
    }

    #[inline(always)]
    fn scale(&self, s: f64) -> Self {
        let mut c = *self;
        c.re *= s;
        for k in 0..2 {
            c.e1[k] *= s;
            for j in 0..N {
                c.e12[k][j] *= s;
            }
        }
        for j in 0..N {
            c.e2[j] *= s;
        }
        c
    }

    /// `self + a·b`.
    #[inline(always)]
    fn fma(&mut self, a: &Self, b: &Self) {
        for k in 0..2 {
            for j in 0..N {
                self.e12[k][j] +=
                    a.re * b.e12[k][j] + a.e12[k][j] * b.re + a.e1[k] * b.e2[j] + a.e2[j] * b.e1[k];
            }
            self.e1[k] += a.re * b.e1[k] + a.e1[k] * b.re;
        }
        for j in 0..N {
            self.e2[j] += a.re * b.e2[j] + a.e2[j] * b.re;
        }
        self.re += a.re * b.re;
    }

    #[inline(always)]
    fn mul(&self, b: &Self) -> Self {
        let mut c = Self::constant(0.0);
        c.fma(self, b);
        c
    }

    fn to_dual(self) -> HyperDualSVec64<2, N> {
        HyperDualSVec64::new(
            self.re,
            Derivative::some(self.e1.into()),
            Derivative::some(nalgebra::SMatrix::<f64, 1, N>::from_row_slice(&self.e2)),
            Derivative::some(nalgebra::SMatrix::<f64, 2, N>::from_fn(|k, j| {
                self.e12[k][j]
            })),
        )
    }

    fn from_dual(d: HyperDualSVec64<2, N>) -> Self {
        let mut h = Self::constant(d.re);
        if let Some(e) = d.eps1.0 {
            h.e1 = [e[0], e[1]];
        }
        if let Some(e) = d.eps2.0 {
            h.e2 = std::array::from_fn(|j| e[j]);
        }
        if let Some(e) = d.eps1eps2.0 {
            h.e12 = std::array::from_fn(|k| std::array::from_fn(|j| e[(k, j)]));
        }
        h
    }
}

/// Value and partial derivatives of an operation that is not written out, through `num_dual`
/// (its operands renumbered onto a local slice).
fn through_dual<const N: usize>(op: Op, v: &[Hyper<N>]) -> (Hyper<N>, [Hyper<N>; 2]) {
    let (operands, count) = op.operands();
    let local: Vec<HyperDualSVec64<2, N>> = operands[..count]
        .iter()
        .map(|&j| v[j as usize].to_dual())
        .collect();
    let first = operands[0];
    let renumbered = op.map(|j| u32::from(count > 1 && j != first));
    let (value, da, db) = renumbered.partials(&local);
    let zero = Hyper::constant(0.0);
    (
        Hyper::from_dual(value),
        [
            da.map_or(zero, Hyper::from_dual),
            db.map_or(zero, Hyper::from_dual),
        ],
    )
}

/// The value of operation `op` from the values `v`.
#[inline]
fn value<const N: usize>(op: Op, v: &[Hyper<N>], x: &[Hyper<N>]) -> Hyper<N> {
    let g = |a: u32| &v[a as usize];
    match op {
        Op::Input(k) => x[k as usize],
        Op::Const(c) => Hyper::constant(c),
        Op::Add(a, b) => g(a).add(g(b), 1.0),
        Op::Sub(a, b) => g(a).add(g(b), -1.0),
        Op::Mul(a, b) => g(a).mul(g(b)),
        Op::Neg(a) => g(a).scale(-1.0),
        Op::AddC(a, c) => {
            let mut r = *g(a);
            r.re += c;
            r
        }
        Op::MulC(a, c) => g(a).scale(c),
        Op::DivC(a, c) => g(a).scale(c.recip()),
        Op::CSub(c, a) => {
            let mut r = g(a).scale(-1.0);
            r.re += c;
            r
        }
        Op::MulAdd(a, b, c) => {
            let mut r = *g(c);
            r.fma(g(a), g(b));
            r
        }
        Op::MulSub(a, b, c) => {
            let mut r = g(c).scale(-1.0);
            r.fma(g(a), g(b));
            r
        }
        Op::SubMul(a, b, c) => {
            let mut r = *g(c);
            r.fma(&g(a).scale(-1.0), g(b));
            r
        }
        op => through_dual(op, v).0,
    }
}

/// `adjoint[j] += ∂ · a` for one operand.
#[inline(always)]
fn accumulate<const N: usize>(
    adjoint: &mut [Hyper<N>],
    j: u32,
    d: Option<&Hyper<N>>,
    sign: f64,
    a: &Hyper<N>,
) {
    let t = &mut adjoint[j as usize];
    match d {
        None => *t = t.add(a, sign),
        Some(d) => t.fma(d, a),
    }
}

impl Tape {
    /// The adjoints of every input (`x.len()` entries each) of two weightings of the outputs
    /// (pairs of an output's index and its weight), swept together over [`Hyper`] values: the
    /// lean form of [`Tape::gradients`] (see the module documentation).
    pub fn hyper_gradients<const N: usize>(
        &self,
        x: &[Hyper<N>],
        weights: [&[(usize, Hyper<N>)]; 2],
        values: &mut Vec<Hyper<N>>,
        adjoints: &mut [Vec<Hyper<N>>; 2],
    ) -> [Vec<Hyper<N>>; 2] {
        let n = self.ops.len();
        let zero = Hyper::constant(0.0);
        values.clear();
        for op in &self.ops {
            let v = value(*op, values, x);
            values.push(v);
        }
        let mut reached = vec![false; n];
        for (w, adjoint) in weights.iter().zip(adjoints.iter_mut()) {
            adjoint.clear();
            adjoint.resize(n, zero);
            for &(o, wo) in *w {
                if let Term::Node(i, _) = self.outputs[o].term() {
                    adjoint[i as usize] = adjoint[i as usize].add(&wo, 1.0);
                    reached[i as usize] = true;
                }
            }
        }
        let mut gradients = [vec![zero; x.len()], vec![zero; x.len()]];
        let v = &values[..];
        for i in (0..n).rev() {
            if !reached[i] {
                continue;
            }
            let op = self.ops[i];
            let a = [adjoints[0][i], adjoints[1][i]];
            let (operands, count) = op.operands();
            for &j in &operands[..count] {
                reached[j as usize] = true;
            }
            let g = |k: u32| &v[k as usize];
            let written = matches!(
                op,
                Op::Input(_)
                    | Op::Const(_)
                    | Op::Add(..)
                    | Op::Sub(..)
                    | Op::Neg(_)
                    | Op::CSub(..)
                    | Op::AddC(..)
                    | Op::MulC(..)
                    | Op::DivC(..)
                    | Op::Mul(..)
                    | Op::MulAdd(..)
                    | Op::MulSub(..)
                    | Op::SubMul(..)
            );
            let fallback = (!written).then(|| through_dual(op, v).1);
            for (s, a) in a.iter().enumerate() {
                let adjoint = &mut adjoints[s];
                match op {
                    Op::Input(k) => {
                        gradients[s][k as usize] = gradients[s][k as usize].add(a, 1.0);
                    }
                    Op::Const(_) => {}
                    Op::Add(x, y) => {
                        accumulate(adjoint, x, None, 1.0, a);
                        accumulate(adjoint, y, None, 1.0, a);
                    }
                    Op::Sub(x, y) => {
                        accumulate(adjoint, x, None, 1.0, a);
                        accumulate(adjoint, y, None, -1.0, a);
                    }
                    Op::Neg(x) | Op::CSub(_, x) => accumulate(adjoint, x, None, -1.0, a),
                    Op::AddC(x, _) => accumulate(adjoint, x, None, 1.0, a),
                    Op::MulC(x, c) => accumulate(adjoint, x, None, c, a),
                    Op::DivC(x, c) => accumulate(adjoint, x, None, c.recip(), a),
                    Op::Mul(x, y) | Op::MulAdd(x, y, _) | Op::MulSub(x, y, _) => {
                        accumulate(adjoint, x, Some(g(y)), 1.0, a);
                        accumulate(adjoint, y, Some(g(x)), 1.0, a);
                        match op {
                            Op::MulAdd(.., z) => accumulate(adjoint, z, None, 1.0, a),
                            Op::MulSub(.., z) => accumulate(adjoint, z, None, -1.0, a),
                            _ => {}
                        }
                    }
                    Op::SubMul(x, y, z) => {
                        let na = a.scale(-1.0);
                        accumulate(adjoint, x, Some(g(y)), 1.0, &na);
                        accumulate(adjoint, y, Some(g(x)), 1.0, &na);
                        accumulate(adjoint, z, None, 1.0, a);
                    }
                    _ => {
                        let d = fallback.as_ref().expect("an operation not written out");
                        for (&j, d) in operands[..count].iter().zip(d) {
                            accumulate(adjoint, j, Some(d), 1.0, a);
                        }
                    }
                }
            }
        }
        gradients
    }
}
