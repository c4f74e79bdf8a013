//! Which pairs of a program's leading inputs can have a mixed second derivative: the
//! **nonlinear interaction domains** of Walther, *Computing sparse Hessians with automatic
//! differentiation*, ACM TOMS 34 (2008).
//!
//! By the second-order chain rule the Hessian of any weighted sum of the outputs is a sum over
//! the operations of (the operation's adjoint) × (its second partial derivatives in its
//! operands) × (the operands' gradients). An entry `(a, b)` can therefore be nonzero only where
//! some operation has a nonzero second partial in two operands `j`, `k` (the same one for a
//! function of one argument) with `a` reaching `j` and `b` reaching `k`. Forward propagation of
//! each value's index domain (the inputs it depends on) and, at each nonlinear operation, the
//! union of those products gives a pattern that holds for **every** value of the inputs: an
//! entry outside it is zero identically, so its derivatives along any further input (a
//! coordinate, a rate, a root's lane) are zero too. A product `x·y` adds the pairs of `x`'s
//! domain with `y`'s only (its second partials in `x` alone and in `y` alone vanish), so
//! parameters that enter as factors of coordinate functions (a mass times a kinematic term)
//! stay uncoupled.

use super::{Op, Tape};

/// A symmetric pattern over `n` inputs, as rows of bits.
#[derive(Debug, Clone)]
pub struct Pattern {
    n: usize,
    words: usize,
    bits: Vec<u64>,
}

impl Pattern {
    fn empty(n: usize) -> Pattern {
        let words = n.div_ceil(64);
        Pattern {
            n,
            words,
            bits: vec![0; n * words],
        }
    }

    /// Number of inputs the pattern is over.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Is the pattern over no inputs?
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// May entry `(a, b)` be nonzero?
    pub fn contains(&self, a: usize, b: usize) -> bool {
        self.bits[a * self.words + b / 64] >> (b % 64) & 1 == 1
    }

    /// Adds the pairs `A × B` and `B × A` for the index domains `A`, `B` (`words` words each).
    fn cross(&mut self, a: &[u64], b: &[u64]) {
        for (from, to) in [(a, b), (b, a)] {
            for (w, &word) in from.iter().enumerate() {
                let mut rest = word;
                while rest != 0 {
                    let row = 64 * w + rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let dst = &mut self.bits[row * self.words..(row + 1) * self.words];
                    for (d, s) in dst.iter_mut().zip(to) {
                        *d |= s;
                    }
                }
            }
        }
    }
}

impl Tape {
    /// The pattern of the Hessian, in the first `n` inputs, of every weighted sum of the
    /// outputs and of its derivatives along any inputs (see the module documentation).
    pub fn hessian_pattern(&self, n: usize) -> Pattern {
        let mut pattern = Pattern::empty(n);
        let words = pattern.words;
        if words == 0 {
            return pattern;
        }
        // Each operation's index domain in the first `n` inputs.
        let mut domains = vec![0u64; self.ops.len() * words];
        let mut union = vec![0u64; words];
        for (i, op) in self.ops.iter().enumerate() {
            let (done, rest) = domains.split_at_mut(i * words);
            let here = &mut rest[..words];
            let domain = |j: u32| &done[j as usize * words..(j as usize + 1) * words];
            let (operands, count) = op.operands();
            match *op {
                Op::Input(k) if (k as usize) < n => here[k as usize / 64] |= 1 << (k % 64),
                _ => {
                    for &j in &operands[..count] {
                        for (h, d) in here.iter_mut().zip(domain(j)) {
                            *h |= d;
                        }
                    }
                }
            }
            match *op {
                // Linear in every operand.
                Op::Input(_)
                | Op::Const(_)
                | Op::Add(..)
                | Op::Sub(..)
                | Op::Neg(_)
                | Op::AddC(..)
                | Op::MulC(..)
                | Op::DivC(..)
                | Op::CSub(..) => {}
                // Bilinear in the two factors.
                Op::Mul(x, y) | Op::MulAdd(x, y, _) | Op::MulSub(x, y, _) | Op::SubMul(x, y, _) => {
                    pattern.cross(domain(x), domain(y));
                }
                // `x / y`: bilinear in `x` and `1/y`, nonlinear in `y`.
                Op::Div(x, y) => {
                    pattern.cross(domain(x), domain(y));
                    pattern.cross(domain(y), domain(y));
                }
                // Nonlinear in each operand and across them.
                _ => {
                    union.iter_mut().for_each(|u| *u = 0);
                    for &j in &operands[..count] {
                        for (u, d) in union.iter_mut().zip(domain(j)) {
                            *u |= d;
                        }
                    }
                    pattern.cross(&union, &union);
                }
            }
        }
        pattern
    }
}

#[cfg(test)]
mod tests {
    use crate::tape::record;

    /// The pattern against the Hessian's own nonzeros (by hyper-dual numbers at a point) on a
    /// program with products, quotients, functions and inputs beyond the pattern's: every
    /// nonzero is in it, and the pairs that never interact are not.
    #[test]
    fn the_pattern_holds_every_nonzero_and_leaves_out_what_never_interacts() {
        use num_dual::{DualNum, HyperDual64};
        // Inputs: a0..a4 in the pattern, q (index 5) beyond it.
        let f = |x: &[HyperDual64]| -> HyperDual64 {
            let q = x[5];
            // a0·sin(q) + a1·q² (linear in a0, a1), a2/a3 (a2 with a3, a3 with itself),
            // (a4 + a0)·q·a4 (a4 with a4 and a0), exp(a1·q)·… only through a product with q.
            x[0] * q.sin() + x[1] * q * q + x[2] / x[3] + (x[4] + x[0]) * q * x[4]
        };
        let x0 = [0.3, -1.1, 0.7, 1.9, 0.4, 0.8];
        let tape = record(&x0, |v| {
            let q = v[5];
            Some(vec![
                v[0] * q.sin() + v[1] * q * q + v[2] / v[3] + (v[4] + v[0]) * q * v[4],
            ])
        })
        .expect("records")
        .finish(&[0]);
        let pattern = tape.hessian_pattern(5);
        assert_eq!(pattern.len(), 5);
        for a in 0..5 {
            for b in 0..5 {
                let x: Vec<HyperDual64> = (0..x0.len())
                    .map(|k| {
                        let (e1, e2) = (f64::from(u8::from(k == a)), f64::from(u8::from(k == b)));
                        HyperDual64::new(x0[k], e1, e2, 0.0)
                    })
                    .collect();
                let h = f(&x).eps1eps2;
                if h != 0.0 {
                    assert!(pattern.contains(a, b), "({a}, {b}) = {h} left out");
                }
            }
        }
        let expected = [(2, 3), (3, 3), (4, 4), (0, 4)];
        for a in 0..5 {
            for b in 0..5 {
                let want = expected.contains(&(a, b)) || expected.contains(&(b, a));
                assert_eq!(pattern.contains(a, b), want, "({a}, {b})");
            }
        }
    }
}
