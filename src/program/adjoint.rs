//! The linearisation's second derivatives contracted with one root's vectors, by reverse mode
//! over the recorded equations: what the Hessians need of the matrices' mixed derivatives,
//! without a pass per pair of variables.
//!
//! For a root `λ` of the pencil with right and left vectors `x̃`, `ỹ` (over the free
//! coordinates and the multipliers, and over `F`'s rows), `Ψ(w) = ỹᵀ F'(w)[ṽ]` is the pencil
//! `ỹᵀ(λ²M + λC + J)x̃` at the program's inputs `w`, `ṽ` being the lane that moves the free
//! coordinates by `x̃`, their rates by `λx̃` and `λ²x̃` and the multipliers by `x̃`'s multiplier
//! part. [`Program::pencil_gradient`] gives `∇_w Ψ` (a dual number along `ṽ` in the values,
//! reverse in the adjoints); [`Program::pencil_hessian`] gives `∇²_w ℒ · d` along directions
//! `d` for `ℒ = Ψ − μ̄ᵀF` (hyper-dual numbers: `ṽ` and the directions in the values, a batch of
//! [`BATCH`] directions at once). Complex vectors are carried as two real lanes and two
//! weightings of the outputs in the gradient, as one complex lane and one complex weighting
//! in the Hessian's sweep ([`Adjoint`]).

use super::Program;
use super::instance::inputs;
/// A complex number (a root, an entry of its vectors).
type C64 = nalgebra::Complex<f64>;
use crate::tape::{Adjoint, Hyper, Reverse};
use nalgebra::Vector2;
use num_dual::{Derivative, DualSVec64};

/// Directions per reverse sweep of [`Program::pencil_hessian`].
pub const BATCH: usize = 8;

/// One root of the pencil as the program's inputs and outputs see it.
#[derive(Debug, Clone)]
pub struct Contraction {
    pub lambda: C64,
    /// `x̃`: the free coordinates' entries, then the multipliers'.
    pub right: Vec<C64>,
    /// `ỹ`: one entry per row of `F`.
    pub left: Vec<C64>,
}

impl Program {
    /// The input vector at parameters `p`, `speed`, coordinates `q` and multipliers `lambda`
    /// (rates zero), the order of [`Program::pencil_gradient`]'s entries.
    pub fn input_vector(&self, p: &[f64], speed: f64, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        inputs(p, speed, q, lambda, self.free.len())
    }

    /// Where the input vector holds coordinate `i` (parameter `k` is at `k`).
    pub fn coordinate_input(&self, i: usize) -> usize {
        self.np + 1 + i
    }

    /// Where the input vector holds multiplier `k`.
    pub fn multiplier_input(&self, k: usize) -> usize {
        self.np + 1 + self.n + 2 * self.free.len() + k
    }

    /// The lane `ṽ` of a root as its real and imaginary parts over the inputs.
    fn lane(&self, c: &Contraction, len: usize) -> (Vec<f64>, Vec<f64>) {
        let (np, n, nf) = (self.np, self.n, self.free.len());
        let mut v = vec![C64::new(0.0, 0.0); len];
        let l = c.lambda;
        for (k, &i) in self.free.iter().enumerate() {
            let x = c.right[k];
            v[np + 1 + i] = x;
            v[np + 1 + n + k] = l * x;
            v[np + 1 + n + nf + k] = l * l * x;
        }
        for k in 0..self.m {
            v[np + 1 + n + 2 * nf + k] = c.right[nf + k];
        }
        (
            v.iter().map(|z| z.re).collect(),
            v.iter().map(|z| z.im).collect(),
        )
    }

    /// `∇_w Ψ` at the inputs `w` (see the module documentation), one entry per input.
    pub fn pencil_gradient(&self, w: &[f64], c: &Contraction) -> Vec<C64> {
        let (vr, vi) = self.lane(c, w.len());
        let x: Vec<DualSVec64<2>> = (0..w.len())
            .map(|k| {
                let eps = (vr[k] != 0.0 || vi[k] != 0.0).then(|| Vector2::new(vr[k], vi[k]));
                DualSVec64::new(w[k], Derivative::new(eps))
            })
            .collect();
        let weights = |part: fn(&C64) -> f64| {
            c.left
                .iter()
                .enumerate()
                .map(|(o, y)| (o, DualSVec64::from_re(part(y))))
                .collect::<Vec<_>>()
        };
        let g = self.full.gradients(
            &x,
            &[weights(|y| y.re), weights(|y| y.im)],
            &mut Reverse::default(),
        );
        let eps = |d: &DualSVec64<2>| d.eps.0.map_or([0.0; 2], |e| [e[0], e[1]]);
        g[0].iter()
            .zip(&g[1])
            .map(|(a, b)| {
                let ([ar, ai], [br, bi]) = (eps(a), eps(b));
                C64::new(ar - bi, ai + br)
            })
            .collect()
    }

    /// `∇²_w ℒ · d` for each direction `d` of `directions` (over the inputs), with
    /// `ℒ = Ψ − μ̄ᵀF` and `mu` the weights `μ̄` of `F`'s rows (see the module documentation).
    pub fn pencil_hessian(
        &self,
        w: &[f64],
        c: &Contraction,
        mu: &[C64],
        directions: &[Vec<f64>],
    ) -> Vec<Vec<C64>> {
        type H = Hyper<BATCH>;
        let (vr, vi) = self.lane(c, w.len());
        // The weighting `ỹ − ε₁ μ̄`.
        let seeds: Vec<(usize, Adjoint<BATCH>)> = (c.left.iter().zip(mu).enumerate())
            .map(|(o, (y, m))| {
                let mut a = Adjoint::ZERO;
                a.re = [y.re, y.im];
                a.e1 = [-m.re, -m.im];
                (o, a)
            })
            .collect();
        let mut out = Vec::with_capacity(directions.len());
        let (mut values, mut adjoint) = (Vec::new(), Vec::new());
        for batch in directions.chunks(BATCH) {
            let x: Vec<H> = (0..w.len())
                .map(|k| {
                    let mut h = H::constant(w[k]);
                    h.e1 = [vr[k], vi[k]];
                    for (j, d) in batch.iter().enumerate() {
                        h.e2[j] = d[k];
                    }
                    h
                })
                .collect();
            let g = self
                .full
                .hyper_gradients(&x, &seeds, &mut values, &mut adjoint);
            for j in 0..batch.len() {
                out.push(
                    g.iter()
                        .map(|a| C64::new(a.e12[0][j], a.e12[1][j]))
                        .collect(),
                );
            }
        }
        out
    }
}
