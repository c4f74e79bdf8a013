//! The first and second derivatives of one simple root of `P(λ) x = (λ²M̂ + λĈ + K̂) x = 0`
//! from the derivatives of the matrices, in closed form.
//!
//! With the right and left vectors `x`, `y` (`yᵀP(λ) = 0`), `P' = 2λM̂ + Ĉ`, and per design
//! variable `a` the matrices' derivatives `P_a = λ²M̂_a + λĈ_a + K̂_a` (at fixed λ), `P'_a =
//! 2λM̂_a + Ĉ_a`:
//!
//! ```text
//! λ_a  = −yᵀP_a x / yᵀP'x
//! [P  P'x; wᵀ 0] [x_a; λ_a] = [−P_a x; 0]                    (the bordered equations, wᵀx = 1)
//! λ_ab = −( yᵀP_ab x + α_a λ_b + α_b λ_a + 2λ_a λ_b yᵀM̂x + u_aᵀx_b + u_bᵀx_a ) / yᵀP'x
//!        α_a = yᵀP'_a x,   u_a = (P_a + λ_a P')ᵀ y
//! ```
//!
//! (twice differentiating `P(λ(b), b) x(b) = 0` and multiplying by `yᵀ`, which removes `x_ab`
//! and leaves `λ_ab`). So the bordered matrix is factorised once per root and point, each
//! variable costs one solve, and a pair of variables costs `O(n)` (the product `u_aᵀx_b`, taken
//! for all pairs at once as `UᵀX`) plus the contraction `yᵀP_ab x` of the matrices' own second
//! derivatives where those are not zero. The normalisation `w` of `x_a` drops out: `u_bᵀx = 0`.
//!
//! # Reference
//! Lancaster, *On eigenvalues of matrices dependent on a parameter*, Numer. Math. 6 (1964);
//! Andrew & Tan, *Computation of derivatives of repeated eigenvalues and the corresponding
//! eigenvectors of symmetric matrix pencils*, SIAM J. Matrix Anal. Appl. 20 (1998), for the
//! bordered equations.

use crate::modal::{C64, Root};
use nalgebra::{DMatrix, DVector};

/// A real matrix times a complex vector.
fn times(a: &DMatrix<f64>, x: &DVector<C64>) -> DVector<C64> {
    let (re, im) = (x.map(|z| z.re), x.map(|z| z.im));
    let (r, i) = (a * re, a * im);
    r.zip_map(&i, C64::new)
}

/// A real matrix transposed times a complex vector.
fn times_transposed(a: &DMatrix<f64>, x: &DVector<C64>) -> DVector<C64> {
    let (re, im) = (x.map(|z| z.re), x.map(|z| z.im));
    let (r, i) = (a.tr_mul(&re), a.tr_mul(&im));
    r.zip_map(&i, C64::new)
}

/// Three real matrices: `(M̂, Ĉ, K̂)` or their derivatives.
pub type Triple<'a> = (&'a DMatrix<f64>, &'a DMatrix<f64>, &'a DMatrix<f64>);

/// `P(λ) v = λ²(M v) + λ(C v) + K v` for one variable's matrices.
fn pencil(l: C64, (m, c, k): Triple<'_>, v: &DVector<C64>) -> DVector<C64> {
    times(m, v) * (l * l) + times(c, v) * l + times(k, v)
}

/// `P(λ)ᵀ v`.
fn pencil_transposed(l: C64, (m, c, k): Triple<'_>, v: &DVector<C64>) -> DVector<C64> {
    times_transposed(m, v) * (l * l) + times_transposed(c, v) * l + times_transposed(k, v)
}

/// `yᵀ v` without conjugation.
fn dot(y: &DVector<C64>, v: &DVector<C64>) -> C64 {
    y.iter().zip(v.iter()).map(|(a, b)| a * b).sum()
}

/// One simple root with its first derivatives along every variable and what the second
/// derivatives of every pair share (see the module documentation).
pub struct RootTerms {
    lambda: C64,
    right: DVector<C64>,
    left: DVector<C64>,
    /// `yᵀP'x`.
    den: C64,
    /// `yᵀM̂x`.
    ymx: C64,
    /// `λ_a` per variable.
    pub first: Vec<C64>,
    /// `λ_aa` per variable.
    pub diagonal: Vec<C64>,
    /// `α_a = yᵀP'_a x` per variable.
    alpha: Vec<C64>,
    /// `u_aᵀx_b + u_bᵀx_a` (symmetric, variables × variables).
    cross: DMatrix<C64>,
}

/// A variable's first and second derivatives of `(M̂, Ĉ, K̂)` along itself.
pub type Along<'a> = (Triple<'a>, Triple<'a>);

impl RootTerms {
    /// The terms of `root` of the nominal matrices `(m, c, k)`, with `along[a]` variable `a`'s
    /// derivatives of the matrices; `None` where the bordered equations are exactly singular.
    pub fn new(root: &Root, (m, c, k): Triple<'_>, along: &[Along<'_>]) -> Option<RootTerms> {
        let n = m.nrows();
        let (l, x, y) = (root.lambda, &root.right, &root.left);
        let cm = |a: &DMatrix<f64>| a.map(|v| C64::new(v, 0.0));
        let (mc, cc, kc) = (cm(m), cm(c), cm(k));
        let p0 = &mc * (l * l) + &cc * l + &kc;
        let dp = &mc * (l * 2.0) + &cc;
        let dpx = &dp * x;
        // w = x̄/|x|², so that wᵀx = 1.
        let w = x.map(|z| z.conj()) / C64::new(x.norm_squared(), 0.0);
        let mut j0 = DMatrix::zeros(n + 1, n + 1);
        j0.view_mut((0, 0), (n, n)).copy_from(&p0);
        j0.view_mut((0, n), (n, 1)).copy_from(&dpx);
        j0.view_mut((n, 0), (1, n)).copy_from(&w.transpose());
        let lu = j0.lu();
        if !lu.is_invertible() {
            return None;
        }
        let den = dot(y, &dpx);
        let ymx = dot(y, &times(m, x));
        // P'ᵀy, shared by every u_a.
        let dpty = dp.transpose() * y;
        let nv = along.len();
        let (mut first, mut diagonal, mut alpha) = (vec![], vec![], vec![]);
        let mut xs = DMatrix::<C64>::zeros(n, nv);
        let mut us = DMatrix::<C64>::zeros(n, nv);
        for (a, &((ma, ca, ka), second)) in along.iter().enumerate() {
            let pax = pencil(l, (ma, ca, ka), x);
            let la = -dot(y, &pax) / den;
            let rhs =
                DVector::from_iterator(n + 1, pax.iter().map(|v| -v).chain([C64::new(0.0, 0.0)]));
            let sol = lu.solve(&rhs)?;
            xs.column_mut(a).copy_from(&sol.rows(0, n));
            let al = dot(y, &(times(ma, x) * (l * 2.0) + times(ca, x)));
            let u = pencil_transposed(l, (ma, ca, ka), y) + &dpty * la;
            us.column_mut(a).copy_from(&u);
            let caa = dot(y, &pencil(l, second, x));
            let cross = dot(&u, &sol.rows(0, n).into_owned());
            diagonal.push(-(caa + al * la * 2.0 + la * la * ymx * 2.0 + cross * 2.0) / den);
            first.push(la);
            alpha.push(al);
        }
        let ux = us.transpose() * &xs;
        let cross = &ux + ux.transpose();
        Some(RootTerms {
            lambda: l,
            right: x.clone(),
            left: y.clone(),
            den,
            ymx,
            first,
            diagonal,
            alpha,
            cross,
        })
    }

    /// The root's value.
    pub fn lambda(&self) -> C64 {
        self.lambda
    }

    /// `λ_ab` for variables `a ≠ b`, with `second` the matrices' mixed derivatives `(M̂_ab,
    /// Ĉ_ab, K̂_ab)` (`None` where they are zero).
    pub fn mixed(&self, (a, b): (usize, usize), second: Option<Triple<'_>>) -> C64 {
        let cab = second.map_or(C64::new(0.0, 0.0), |s| {
            dot(&self.left, &pencil(self.lambda, s, &self.right))
        });
        let (la, lb) = (self.first[a], self.first[b]);
        -(cab
            + self.alpha[a] * lb
            + self.alpha[b] * la
            + la * lb * self.ymx * 2.0
            + self.cross[(a, b)])
            / self.den
    }
}
