//! Forward over reverse with hyper-dual values in a lean form: the kernel of
//! [`crate::program::Program::pencil_hessian`].
//!
//! [`Tape::gradients`] over `num_dual`'s hyper-dual vectors spends most of its time moving and
//! testing their optional parts (measured: 2.5 ms a sweep of the 40-segment blade's 8800
//! operations, a third in `memmove`). [`Hyper`] keeps every part as a plain array and the
//! common operations are written out over them; the other operations go through `num_dual`
//! ([`Op::partials`]).
//!
//! The values carry one complex lane `ε₁` (a root's vector, as its real and imaginary parts)
//! and `N` real directions `ε₂`. The adjoints are complex ([`Adjoint`]): the weighting of the
//! outputs (a root's left vector) is complex, and everything the sweep computes is linear in
//! the lane and in the weighting, so one complex adjoint does the work of the four real
//! products of two real lanes with two real weightings, with a fifth fewer multiplications and
//! a third less adjoint memory. The sweep is compiled twice, for the baseline instruction set
//! and for AVX2, and the second is used where the processor has it: the same operations in the
//! same order on the same operands, so the results are the same to the bit; only the registers
//! are wider. On the 40-segment blade's point with 81 variables (40 roots, four directions a
//! sweep) the roots' mixed terms took 0.94 s with the real form, 0.55 s with the complex one
//! (0.65 ms a sweep) and about 0.40 s with AVX2 besides (`scale_chain local 40 40 --family
//! moving`, best of 3).

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
#[inline(always)]
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

/// The adjoint of a value: complex parts (real and imaginary rows) of the value, of its
/// derivative along the lane `ε₁`, along the `N` directions `ε₂` and of the mixed ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adjoint<const N: usize> {
    pub re: [f64; 2],
    pub e1: [f64; 2],
    pub e2: [[f64; N]; 2],
    pub e12: [[f64; N]; 2],
}

impl<const N: usize> Adjoint<N> {
    /// Zero.
    pub const ZERO: Self = Adjoint {
        re: [0.0; 2],
        e1: [0.0; 2],
        e2: [[0.0; N]; 2],
        e12: [[0.0; N]; 2],
    };

    /// `self += sign · a`.
    #[inline(always)]
    fn add(&mut self, a: &Self, sign: f64) {
        for c in 0..2 {
            self.re[c] += sign * a.re[c];
            self.e1[c] += sign * a.e1[c];
            for j in 0..N {
                self.e2[c][j] += sign * a.e2[c][j];
                self.e12[c][j] += sign * a.e12[c][j];
            }
        }
    }

    /// `self += d · a` for a value `d` (a partial derivative).
    #[inline(always)]
    fn fma(&mut self, d: &Hyper<N>, a: &Self) {
        let [dr, di] = d.e1;
        let [ar, ai] = a.re;
        let [br, bi] = a.e1;
        for j in 0..N {
            self.e12[0][j] += d.re * a.e12[0][j] + d.e12[0][j] * ar - d.e12[1][j] * ai
                + dr * a.e2[0][j]
                - di * a.e2[1][j]
                + d.e2[j] * br;
            self.e12[1][j] += d.re * a.e12[1][j]
                + d.e12[0][j] * ai
                + d.e12[1][j] * ar
                + dr * a.e2[1][j]
                + di * a.e2[0][j]
                + d.e2[j] * bi;
            self.e2[0][j] += d.re * a.e2[0][j] + d.e2[j] * ar;
            self.e2[1][j] += d.re * a.e2[1][j] + d.e2[j] * ai;
        }
        self.e1[0] += d.re * br + dr * ar - di * ai;
        self.e1[1] += d.re * bi + dr * ai + di * ar;
        self.re[0] += d.re * ar;
        self.re[1] += d.re * ai;
    }

    /// `−self`.
    #[inline(always)]
    fn negated(&self) -> Self {
        let mut z = Self::ZERO;
        z.add(self, -1.0);
        z
    }
}

/// One reverse step: the adjoint `a` of operation `op` passed on to its operands.
#[inline(always)]
fn step<const N: usize>(op: Op, a: &Adjoint<N>, v: &[Hyper<N>], adjoint: &mut [Adjoint<N>]) {
    let g = |k: u32| &v[k as usize];
    let mut linear = |j: u32, c: f64| adjoint[j as usize].add(a, c);
    match op {
        Op::Input(_) | Op::Const(_) => {}
        Op::Add(x, y) => {
            linear(x, 1.0);
            linear(y, 1.0);
        }
        Op::Sub(x, y) => {
            linear(x, 1.0);
            linear(y, -1.0);
        }
        Op::Neg(x) | Op::CSub(_, x) => linear(x, -1.0),
        Op::AddC(x, _) => linear(x, 1.0),
        Op::MulC(x, c) => linear(x, c),
        Op::DivC(x, c) => linear(x, c.recip()),
        Op::Mul(x, y) => {
            adjoint[x as usize].fma(g(y), a);
            adjoint[y as usize].fma(g(x), a);
        }
        Op::MulAdd(x, y, z) | Op::MulSub(x, y, z) => {
            adjoint[x as usize].fma(g(y), a);
            adjoint[y as usize].fma(g(x), a);
            let sign = if matches!(op, Op::MulAdd(..)) {
                1.0
            } else {
                -1.0
            };
            adjoint[z as usize].add(a, sign);
        }
        Op::SubMul(x, y, z) => {
            let na = a.negated();
            adjoint[x as usize].fma(g(y), &na);
            adjoint[y as usize].fma(g(x), &na);
            adjoint[z as usize].add(a, 1.0);
        }
        _ => {
            let (operands, count) = op.operands();
            let (_, d) = through_dual(op, v);
            for (&j, d) in operands[..count].iter().zip(&d) {
                adjoint[j as usize].fma(d, a);
            }
        }
    }
}

/// The sweep of [`Tape::hyper_gradients`] (see there), inlined into each instruction set's
/// copy.
#[inline(always)]
fn sweep<const N: usize>(
    tape: &Tape,
    x: &[Hyper<N>],
    seeds: &[(usize, Adjoint<N>)],
    values: &mut Vec<Hyper<N>>,
    adjoint: &mut Vec<Adjoint<N>>,
) -> Vec<Adjoint<N>> {
    let n = tape.ops.len();
    values.clear();
    for op in &tape.ops {
        let v = value(*op, values, x);
        values.push(v);
    }
    adjoint.clear();
    adjoint.resize(n, Adjoint::ZERO);
    let mut reached = vec![false; n];
    for (o, seed) in seeds {
        if let Term::Node(i, _) = tape.outputs[*o].term() {
            adjoint[i as usize].add(seed, 1.0);
            reached[i as usize] = true;
        }
    }
    let mut gradients = vec![Adjoint::ZERO; x.len()];
    for i in (0..n).rev() {
        if !reached[i] {
            continue;
        }
        let op = tape.ops[i];
        let a = adjoint[i];
        let (operands, count) = op.operands();
        for &j in &operands[..count] {
            reached[j as usize] = true;
        }
        match op {
            Op::Input(k) => gradients[k as usize].add(&a, 1.0),
            _ => step(op, &a, values, adjoint),
        }
    }
    gradients
}

/// [`sweep`] compiled for AVX2.
///
/// # Safety
/// The processor must have AVX2 (checked by the caller).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sweep_avx2<const N: usize>(
    tape: &Tape,
    x: &[Hyper<N>],
    seeds: &[(usize, Adjoint<N>)],
    values: &mut Vec<Hyper<N>>,
    adjoint: &mut Vec<Adjoint<N>>,
) -> Vec<Adjoint<N>> {
    sweep(tape, x, seeds, values, adjoint)
}

impl Tape {
    /// The adjoints of every input (`x.len()` entries) of the outputs weighted by `seeds`
    /// (pairs of an output's index and its complex weight, with its part along the lane), swept
    /// over [`Hyper`] values: the lean form of [`Tape::gradients`] (see the module
    /// documentation). `values` and `adjoint` are working memory.
    pub fn hyper_gradients<const N: usize>(
        &self,
        x: &[Hyper<N>],
        seeds: &[(usize, Adjoint<N>)],
        values: &mut Vec<Hyper<N>>,
        adjoint: &mut Vec<Adjoint<N>>,
    ) -> Vec<Adjoint<N>> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, just checked.
            return unsafe { sweep_avx2(self, x, seeds, values, adjoint) };
        }
        sweep(self, x, seeds, values, adjoint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tape::{Reverse, record};
    use num_dual::{DualNum, HyperDualSVec64};

    /// A program with every kind of operation the sweep writes out (fused ones included) and
    /// some it takes through `num_dual`.
    fn program() -> Tape {
        let x0 = [0.7, -1.3, 2.1, 0.4];
        let raw = record(&x0, |x| {
            let s = x[0] * x[1] + x[2];
            let t = (x[0] * x[2]).sin() / x[1] - x[3] * x[2];
            let u = -(x[3] * s) + 3.0 + (-t) * 0.5 + s / 4.0 + (x[0] + 1.5);
            Some(vec![s * t, u.sqrt() * x[3] - x[1], (u * t).powi(3)])
        })
        .expect("records");
        raw.finish(&[0, 1, 2])
    }

    fn inputs(x0: &[f64]) -> Vec<Hyper<2>> {
        (0..x0.len())
            .map(|k| {
                let mut h = Hyper::constant(x0[k]);
                h.e1 = [0.3 * k as f64 - 0.2, 0.1 + 0.05 * k as f64];
                h.e2 = [(k as f64).cos(), 1.0 / (1.0 + k as f64)];
                h
            })
            .collect()
    }

    fn seeds() -> Vec<(usize, Adjoint<2>)> {
        (0..3)
            .map(|o| {
                let mut a = Adjoint::ZERO;
                a.re = [1.0 + o as f64, -0.5 * o as f64];
                a.e1 = [0.25, -0.125 * o as f64];
                (o, a)
            })
            .collect()
    }

    /// The complex sweep against `num_dual`'s hyper-dual numbers through [`Tape::gradients`]:
    /// two real lanes and two real weightings, recombined as complex numbers.
    #[test]
    fn the_complex_sweep_is_four_real_ones() {
        let tape = program();
        let x0 = [0.7, -1.3, 2.1, 0.4];
        let x = inputs(&x0);
        let g = tape.hyper_gradients(&x, &seeds(), &mut Vec::new(), &mut Vec::new());
        let dual = |h: &Hyper<2>| {
            let mut d = HyperDualSVec64::<2, 2>::from_re(h.re);
            d.eps1 = num_dual::Derivative::some(h.e1.into());
            d.eps2 =
                num_dual::Derivative::some(nalgebra::SMatrix::<f64, 1, 2>::from_row_slice(&h.e2));
            d
        };
        let xd: Vec<_> = x.iter().map(dual).collect();
        // Weighting `re` part `k` of the seed, with its lane part as an ε₁ coefficient.
        let weighting = |k: usize| -> Vec<(usize, HyperDualSVec64<2, 2>)> {
            seeds()
                .iter()
                .map(|(o, a)| {
                    let mut w = HyperDualSVec64::<2, 2>::from_re(a.re[k]);
                    let lane = if k == 0 {
                        [a.e1[0], a.e1[1]]
                    } else {
                        [0.0, 0.0]
                    };
                    w.eps1 = num_dual::Derivative::some(lane.into());
                    (*o, w)
                })
                .collect()
        };
        let r = tape.gradients(&xd, &[weighting(0), weighting(1)], &mut Reverse::default());
        for (i, gi) in g.iter().enumerate() {
            let part =
                |w: usize, lane: usize, j: usize| r[w][i].eps1eps2.0.map_or(0.0, |e| e[(lane, j)]);
            for j in 0..2 {
                // The seeds' lane parts `ε₁ (−μ̄)` enter the real weighting's two lanes
                // as written in `pencil_hessian`: here as `a.e1` on weighting 0's lanes.
                let re = part(0, 0, j) - part(1, 1, j);
                let im = part(0, 1, j) + part(1, 0, j);
                let scale = 1.0 + re.abs().max(im.abs());
                assert!((gi.e12[0][j] - re).abs() < 1e-13 * scale, "{i} {j}");
                assert!((gi.e12[1][j] - im).abs() < 1e-13 * scale, "{i} {j}");
            }
        }
        assert!(g.iter().any(|a| a.e12[0].iter().any(|&v| v != 0.0)));
    }

    /// The AVX2 copy of the sweep gives the baseline copy's bits.
    #[test]
    fn every_instruction_set_sweeps_to_the_same_bits() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let tape = program();
            let x = inputs(&[0.7, -1.3, 2.1, 0.4]);
            let base = sweep(&tape, &x, &seeds(), &mut Vec::new(), &mut Vec::new());
            // SAFETY: the processor has AVX2, just checked.
            let wide = unsafe { sweep_avx2(&tape, &x, &seeds(), &mut Vec::new(), &mut Vec::new()) };
            let bits = |g: &[Adjoint<2>]| -> Vec<u64> {
                g.iter()
                    .flat_map(|a| {
                        a.re.iter()
                            .chain(&a.e1)
                            .chain(a.e2.iter().flatten())
                            .chain(a.e12.iter().flatten())
                            .map(|v| v.to_bits())
                            .collect::<Vec<_>>()
                    })
                    .collect()
            };
            assert_eq!(bits(&base), bits(&wide));
        }
    }
}
