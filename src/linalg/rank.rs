//! Rank by elimination with complete pivoting: independent columns, dependent rows.

use super::amax;
use nalgebra::DMatrix;

/// Gaussian elimination of `a` with complete pivoting until the largest remaining entry is
/// below `1e-10 ×` the largest entry of `a` (or no row or column is left): the pivot columns
/// in the order chosen, and the rows never pivoted on.
fn eliminate(a: &DMatrix<f64>) -> (Vec<usize>, Vec<usize>) {
    let (m, n) = a.shape();
    let mut a = a.clone();
    let scale = amax(&a).max(f64::MIN_POSITIVE);
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut chosen = Vec::new();
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
        chosen.push(pc);
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
    (chosen, rows)
}

/// Chooses `m` linearly independent columns of the `m × n` matrix `a` by elimination with
/// complete pivoting. Returns them sorted, or `None` when `a` has rank below `m`.
pub fn pivot_columns(a: &DMatrix<f64>) -> Option<Vec<usize>> {
    let (mut chosen, _) = eliminate(a);
    if chosen.len() < a.nrows() {
        return None;
    }
    chosen.sort_unstable();
    Some(chosen)
}

/// Rows of `a` that are linear combinations of the others (elimination with complete pivoting,
/// relative tolerance 1e-10): the redundant equations of a rank-deficient system.
pub fn dependent_rows(a: &DMatrix<f64>) -> Vec<usize> {
    eliminate(a).1
}
