//! The roots' derivatives along a direction of the matrices: `dλ = −yᵀ(λ²M' + λC' + K')x /
//! yᵀ(2λM + C)x` for every root of a point at once, and a mode's derivatives from its roots'.

use super::{ModeSensitivity, Status};
use crate::modal::{C64, Mode, Root, Smoothness};
use crate::pair;
use nalgebra::{DMatrix, DVector};

/// Derivatives of a mode from the derivatives of its two roots; `invariants`, when given, are
/// the exact derivatives of `λ₁ + λ₂` and `λ₁ λ₂` (used instead of the roots' sums). `Ok` only
/// where the mode's roots are simple ([`Smoothness::Simple`]: not coalescing, not repeated in
/// another mode, not a rigid-body mode) and the derivatives finite.
pub(super) fn mode_derivative(
    m: &Mode,
    smooth: Smoothness,
    (d1, d2): (C64, C64),
    invariants: Option<(f64, f64)>,
) -> ModeSensitivity {
    let (l1, l2) = (m.root.lambda, m.partner.lambda);
    let status = if smooth != Smoothness::Simple || !d1.re.is_finite() || !d2.re.is_finite() {
        Status::NotDifferentiable
    } else {
        Status::Ok
    };
    let p = (l1 * l2).re;
    let s = (l1 + l2).re;
    let (ds, dp) = invariants.unwrap_or(((d1 + d2).re, (d1 * l2 + l1 * d2).re));
    let wn = m.natural_frequency;
    let dwn = pair::d_natural_frequency(p, wn, dp);
    let dzeta = pair::d_damping_ratio(s, wn, ds, dwn);
    ModeSensitivity {
        status,
        d_eigen_re: d1.re,
        d_eigen_im: d1.im,
        d_damped_frequency: if l1.im > 0.0 { d1.im } else { 0.0 },
        d_natural_frequency: dwn,
        d_damping_ratio: dzeta,
        d_sum: ds,
        d_product: dp,
    }
}

/// `dλ = −yᵀ(λ²M' + λC' + K')x / yᵀ(2λM + C)x` for one root.
pub fn eigenvalue_derivative(
    lambda: C64,
    x: &DVector<C64>,
    y: &DVector<C64>,
    (m, c): (&DMatrix<f64>, &DMatrix<f64>),
    (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
) -> C64 {
    let b = |a: &DMatrix<f64>| bilinear(y, a, x);
    -(lambda * lambda * b(dm) + lambda * b(dc) + b(dk)) / (lambda * 2.0 * b(m) + b(c))
}

/// `yᵀ A x` for a real `A` (no complex matrix formed).
fn bilinear(y: &DVector<C64>, a: &DMatrix<f64>, x: &DVector<C64>) -> C64 {
    a.column_iter()
        .zip(x.iter())
        .map(|(col, &xj)| {
            col.iter()
                .zip(y.iter())
                .map(|(&v, &yi)| yi * v)
                .sum::<C64>()
                * xj
        })
        .sum()
}

/// [`eigenvalue_derivative`] for all the roots of a point at once. The roots' right vectors
/// are the columns of one matrix, so that a design variable costs three real matrix products
/// (`M'X`, `C'X`, `K'X`, blocked) and O(n) per root, where a root at a time is a pass over
/// three matrices each (memory-bound, and 2n roots); the denominators `yᵀ(2λM + C)x` do not
/// depend on the variable and are computed once. A conjugate partner's derivative is the
/// conjugate, bitwise.
pub(super) struct RootDerivatives<'a> {
    /// Per mode, its root and the partner (`None` when it is the root's conjugate).
    roots: Vec<(&'a Root, Option<&'a Root>)>,
    /// Real and imaginary parts of the distinct roots' right vectors, as columns.
    xr: DMatrix<f64>,
    xi: DMatrix<f64>,
    /// `yᵀ(2λM + C)x` per distinct root.
    den: Vec<C64>,
}

impl<'a> RootDerivatives<'a> {
    pub(super) fn new(modes: &'a [Mode], m: &DMatrix<f64>, c: &DMatrix<f64>) -> Self {
        let roots: Vec<(&Root, Option<&Root>)> = modes
            .iter()
            .map(|md| {
                let (r, p) = (&md.root, &md.partner);
                let conjugate = p.lambda == r.lambda.conj()
                    && p.right.iter().zip(&r.right).all(|(a, b)| *a == b.conj())
                    && p.left.iter().zip(&r.left).all(|(a, b)| *a == b.conj());
                (r, (!conjugate).then_some(p))
            })
            .collect();
        let distinct: Vec<&Root> = roots
            .iter()
            .flat_map(|&(r, p)| std::iter::once(r).chain(p))
            .collect();
        let n = m.nrows();
        let xr = DMatrix::from_fn(n, distinct.len(), |i, k| distinct[k].right[i].re);
        let xi = DMatrix::from_fn(n, distinct.len(), |i, k| distinct[k].right[i].im);
        let (mr, mi, cr, ci) = (m * &xr, m * &xi, c * &xr, c * &xi);
        let den = distinct
            .iter()
            .enumerate()
            .map(|(k, r)| {
                (0..n)
                    .map(|i| {
                        let mx = C64::new(mr[(i, k)], mi[(i, k)]);
                        let cx = C64::new(cr[(i, k)], ci[(i, k)]);
                        r.left[i] * (r.lambda * 2.0 * mx + cx)
                    })
                    .sum()
            })
            .collect();
        RootDerivatives { roots, xr, xi, den }
    }

    /// `(dλ_root, dλ_partner)` per mode along `(M', C', K')`.
    pub(super) fn along(
        &self,
        (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Vec<(C64, C64)> {
        let prod = |a: &DMatrix<f64>| (a * &self.xr, a * &self.xi);
        let ((mr, mi), (cr, ci), (kr, ki)) = (prod(dm), prod(dc), prod(dk));
        let n = dm.nrows();
        let mut k = 0;
        let mut next = |r: &Root| {
            let l = r.lambda;
            let num: C64 = (0..n)
                .map(|i| {
                    let at =
                        |re: &DMatrix<f64>, im: &DMatrix<f64>| C64::new(re[(i, k)], im[(i, k)]);
                    r.left[i] * (l * l * at(&mr, &mi) + l * at(&cr, &ci) + at(&kr, &ki))
                })
                .sum();
            let d = -num / self.den[k];
            k += 1;
            d
        };
        self.roots
            .iter()
            .map(|&(r, p)| {
                let d1 = next(r);
                (d1, p.map_or(d1.conj(), &mut next))
            })
            .collect()
    }
}
