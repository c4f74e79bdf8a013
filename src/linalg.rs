//! Small dense helpers over any [`Real`]: forward-mode Jacobians, a pivoted solve, and the
//! choice of independent columns of a constraint Jacobian.
//!
//! nalgebra's factorisations need a `ComplexField`, which nested dual numbers are not, so the
//! few solves that must carry derivatives (the independent-coordinate basis) use this
//! elimination, pivoting on real parts.

use crate::real::{D1, Real, cst, lift1};
use nalgebra::DMatrix;
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

/// Chooses `m` linearly independent columns of the `m × n` matrix `a` by elimination with
/// complete pivoting. Returns them sorted, or `None` when `a` has rank below `m`.
pub fn pivot_columns(a: &DMatrix<f64>) -> Option<Vec<usize>> {
    let (m, n) = a.shape();
    let mut a = a.clone();
    let scale = a.amax().max(f64::MIN_POSITIVE);
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut chosen = Vec::new();
    for _ in 0..m {
        let mut best = (0, 0, -1.0);
        for &r in &rows {
            for &c in &cols {
                if a[(r, c)].abs() > best.2 {
                    best = (r, c, a[(r, c)].abs());
                }
            }
        }
        let (pr, pc, v) = best;
        if v <= 1e-10 * scale {
            return None;
        }
        chosen.push(pc);
        rows.retain(|&r| r != pr);
        cols.retain(|&c| c != pc);
        for &r in &rows {
            let f = a[(r, pc)] / a[(pr, pc)];
            for c in 0..n {
                let v = a[(pr, c)];
                a[(r, c)] -= f * v;
            }
        }
    }
    chosen.sort_unstable();
    Some(chosen)
}

/// Rows of `a` that are linear combinations of the others (elimination with complete pivoting,
/// relative tolerance 1e-10): the redundant equations of a rank-deficient system.
pub fn dependent_rows(a: &DMatrix<f64>) -> Vec<usize> {
    let (m, n) = a.shape();
    let mut a = a.clone();
    let scale = a.amax().max(f64::MIN_POSITIVE);
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    while !rows.is_empty() && !cols.is_empty() {
        let mut best = (0, 0, -1.0);
        for &r in &rows {
            for &c in &cols {
                if a[(r, c)].abs() > best.2 {
                    best = (r, c, a[(r, c)].abs());
                }
            }
        }
        let (pr, pc, v) = best;
        if v <= 1e-10 * scale {
            break;
        }
        rows.retain(|&r| r != pr);
        cols.retain(|&c| c != pc);
        for &r in &rows {
            let f = a[(r, pc)] / a[(pr, pc)];
            for c in 0..n {
                let x = a[(pr, c)];
                a[(r, c)] -= f * x;
            }
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    #[test]
    fn solve_carries_derivatives() {
        // A(t) = [[2+t, 1], [1, 3]], b = [1, 2]; d/dt of A⁻¹b at t=0 against the formula
        // dx = −A⁻¹ (dA) x.
        let t = Dual64::from_re(0.0).derivative();
        let one = Dual64::from_re(1.0);
        let a = DMatrix::from_row_slice(2, 2, &[one * 2.0 + t, one, one, one * 3.0]);
        let b = DMatrix::from_row_slice(2, 1, &[one, one * 2.0]);
        let x = solve(&a, &b).unwrap();
        let a0 = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 3.0]);
        let x0 = a0
            .clone()
            .lu()
            .solve(&DMatrix::from_row_slice(2, 1, &[1.0, 2.0]))
            .unwrap();
        let da = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        let dx = -a0.lu().solve(&(da * &x0)).unwrap();
        for i in 0..2 {
            assert!((x[(i, 0)].re - x0[(i, 0)]).abs() < 1e-15);
            assert!((x[(i, 0)].eps - dx[(i, 0)]).abs() < 1e-15);
        }
    }

    #[test]
    fn dependent_rows_finds_the_duplicate_equation() {
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 2.0, 0.0, 1.0, 0.0, 2.0, 0.0, 4.0]);
        assert_eq!(dependent_rows(&a), vec![0]);
        assert!(dependent_rows(&DMatrix::identity(2, 3)).is_empty());
    }

    #[test]
    fn pivot_columns_detects_rank_deficiency() {
        let a = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 0.0, 2.0, 4.0, 0.0]);
        assert!(pivot_columns(&a).is_none());
        let a = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.1, 0.0, 0.0, 3.0]);
        assert_eq!(pivot_columns(&a), Some(vec![0, 2]));
    }
}
