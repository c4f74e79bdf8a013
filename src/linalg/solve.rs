//! Solves: forward-mode Jacobians, the pivoted elimination over any [`Real`], Newton's LU
//! factorisation and least squares.

use super::svd_real;
use crate::real::{D1, Real, cst, lift1};
use nalgebra::{ComplexField, DMatrix, DVector};
use num_dual::Dual;

/// Value and Jacobian of `f` at `x`: one pass of `f` over `Dual<T>` per column.
pub fn jacobian<T: Real>(x: &[T], f: impl Fn(&[D1<T>]) -> Vec<D1<T>>) -> (Vec<T>, DMatrix<T>) {
    let base: Vec<D1<T>> = x.iter().map(|&v| lift1(v)).collect();
    let mut value = Vec::new();
    let mut jac = DMatrix::from_element(0, x.len(), cst::<T>(0.0));
    for j in 0..x.len() {
        let mut xj = base.clone();
        xj[j] = Dual::new(x[j], cst(1.0));
        let fj = f(&xj);
        if j == 0 {
            value = fj.iter().map(|v| v.re).collect();
            jac = DMatrix::from_element(fj.len(), x.len(), cst::<T>(0.0));
        }
        for (i, v) in fj.iter().enumerate() {
            jac[(i, j)] = v.eps;
        }
    }
    (value, jac)
}

/// Solves `A X = B` by Gaussian elimination with partial pivoting on real parts.
/// `None` when a pivot is below `1e-14 ×` the largest entry of `A`.
pub fn solve<T: Real>(a: &DMatrix<T>, b: &DMatrix<T>) -> Option<DMatrix<T>> {
    let n = a.nrows();
    assert_eq!(a.ncols(), n, "solve needs a square matrix");
    let mut a = a.clone();
    let mut b = b.clone();
    let scale = a.iter().fold(0.0f64, |s, x| s.max(x.re().abs()));
    for col in 0..n {
        let (p, best) = (col..n)
            .map(|r| (r, a[(r, col)].re().abs()))
            .fold((col, -1.0), |acc, x| if x.1 > acc.1 { x } else { acc });
        if best <= 1e-14 * scale || best == 0.0 {
            return None;
        }
        a.swap_rows(col, p);
        b.swap_rows(col, p);
        let piv = a[(col, col)];
        for r in col + 1..n {
            let f = a[(r, col)] / piv;
            for c in col..n {
                let v = a[(col, c)];
                a[(r, c)] -= f * v;
            }
            for c in 0..b.ncols() {
                let v = b[(col, c)];
                b[(r, c)] -= f * v;
            }
        }
    }
    for col in (0..n).rev() {
        let piv = a[(col, col)];
        for c in 0..b.ncols() {
            let mut s = b[(col, c)];
            for k in col + 1..n {
                s -= a[(col, k)] * b[(k, c)];
            }
            b[(col, c)] = s / piv;
        }
    }
    Some(b)
}

/// `P A = L U` with partial pivoting, for Newton's small dense systems. The arithmetic is
/// nalgebra's `LU` (Golub & Van Loan, *Matrix Computations*, 4th ed., Alg. 3.4.1) operation for
/// operation, so the results are its bits (tested); on a column-major slice, where nalgebra's
/// generic views cost a 25×25 factorisation about 2 of the 12-arm governor's 39 µs point
/// (`perf`).
#[derive(Debug, Clone)]
pub struct Lu {
    /// `U` on and above the diagonal, `L`'s multipliers below (unit diagonal implied).
    lu: DMatrix<f64>,
    /// The row interchanges, in order.
    swaps: Vec<(usize, usize)>,
}

impl Lu {
    /// Factorises the square matrix `a`. A column without a nonzero entry is left as it is
    /// (then [`Lu::solve`] fails).
    pub fn new(mut a: DMatrix<f64>) -> Lu {
        let n = a.nrows();
        assert_eq!(a.ncols(), n, "an LU factorisation of a square matrix");
        let mut swaps = Vec::new();
        let s = a.as_mut_slice();
        for i in 0..n {
            // The first entry of largest magnitude on or below the diagonal.
            let column = &s[i * n + i..(i + 1) * n];
            let (mut piv, mut best) = (0, column[0].abs());
            for (r, v) in column.iter().enumerate().skip(1) {
                if v.abs() > best {
                    (piv, best) = (r, v.abs());
                }
            }
            let piv = piv + i;
            let diag = s[i * n + piv];
            if diag == 0.0 {
                continue;
            }
            if piv != i {
                swaps.push((i, piv));
                for c in 0..n {
                    s.swap(c * n + i, c * n + piv);
                }
            }
            let inv = 1.0 / diag;
            for l in &mut s[i * n + i + 1..(i + 1) * n] {
                *l *= inv;
            }
            let (head, tail) = s.split_at_mut((i + 1) * n);
            let l = &head[i * n + i + 1..];
            for column in tail.chunks_exact_mut(n) {
                let p = -column[i];
                for (y, &x) in column[i + 1..].iter_mut().zip(l) {
                    *y += p * x;
                }
            }
        }
        Lu { lu: a, swaps }
    }

    /// The smallest magnitude on `U`'s diagonal over the largest (0 for a zero matrix or a
    /// zero pivot): a cheap sign of (near) singularity.
    pub fn pivot_ratio(&self) -> f64 {
        let n = self.lu.nrows();
        let (lo, hi) = (0..n)
            .map(|i| self.lu[(i, i)].abs())
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if n == 0 {
            1.0
        } else if hi > 0.0 {
            lo / hi
        } else {
            0.0
        }
    }

    /// `x` with `A x = b`, or `None` where `U` has a zero on its diagonal.
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let n = self.lu.nrows();
        assert_eq!(
            b.len(),
            n,
            "a right-hand side of the factorised matrix's size"
        );
        let s = self.lu.as_slice();
        let mut x = b.to_vec();
        for &(i, p) in &self.swaps {
            x.swap(i, p);
        }
        for i in 0..n.saturating_sub(1) {
            let c = -x[i];
            for (y, &l) in x[i + 1..].iter_mut().zip(&s[i * n + i + 1..(i + 1) * n]) {
                *y += c * l;
            }
        }
        for i in (0..n).rev() {
            let d = s[i * n + i];
            if d == 0.0 {
                return None;
            }
            let coeff = x[i] / d;
            x[i] = coeff;
            for (y, &u) in x[..i].iter_mut().zip(&s[i * n..i * n + i]) {
                *y += -coeff * u;
            }
        }
        Some(x)
    }
}

/// The least-squares solution of `a λ = b` (zero if that fails; empty when `a` has no
/// columns): by QR where `a` has full column rank, the usual case, else by SVD (the
/// minimum-norm solution).
pub fn least_squares(a: DMatrix<f64>, b: DVector<f64>) -> Vec<f64> {
    let m = a.ncols();
    if m == 0 {
        return Vec::new();
    }
    if a.nrows() >= m {
        let qr = a.clone().qr();
        let r = qr.r();
        let d = r.diagonal().map(f64::abs);
        if d.min() > 1e-12 * d.max() {
            let qtb = qr.q().tr_mul(&b);
            if let Some(l) = r.solve_upper_triangular(&qtb)
                && l.iter().all(|v| v.is_finite())
            {
                return l.iter().copied().collect();
            }
        }
    }
    match svd_real(a, true, true).map(|svd| svd.solve(&b, 1e-12)) {
        Some(Ok(l)) if l.iter().all(|v| v.is_finite()) => l.iter().copied().collect(),
        _ => vec![0.0; m],
    }
}
