//! Rank by elimination with complete pivoting: independent columns, dependent rows.

use super::amax;
use nalgebra::DMatrix;

/// Gaussian elimination of `a` with complete pivoting until the largest remaining entry is
/// below `1e-10 ×` the largest entry of `a` (or no row or column is left): the pivot columns
/// in the order chosen, and the rows never pivoted on. The rows before `first` are pivoted on
/// first, as long as one of them has an entry above the tolerance; then all of them.
fn eliminate(a: &DMatrix<f64>, first: usize) -> (Vec<usize>, Vec<usize>) {
    let (m, n) = a.shape();
    let mut a = a.clone();
    let scale = amax(&a).max(f64::MIN_POSITIVE);
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut chosen = Vec::new();
    let mut group = first;
    while !rows.is_empty() && !cols.is_empty() {
        let mut best = (0, 0, -1.0);
        for &r in rows.iter().filter(|&&r| r < group) {
            for &c in &cols {
                if a[(r, c)].abs() > best.2 {
                    best = (r, c, a[(r, c)].abs());
                }
            }
        }
        let (pr, pc, v) = best;
        if v <= 1e-10 * scale {
            if group < m {
                group = m;
                continue;
            }
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
    let (mut chosen, _) = eliminate(a, a.nrows());
    if chosen.len() < a.nrows() {
        return None;
    }
    chosen.sort_unstable();
    Some(chosen)
}

/// Rows of `a` that are linear combinations of the others (elimination with complete pivoting,
/// relative tolerance 1e-10): the redundant equations of a rank-deficient system.
pub fn dependent_rows(a: &DMatrix<f64>) -> Vec<usize> {
    eliminate(a, a.nrows()).1
}

/// [`dependent_rows`] with the rows before `first` weighed first: of those, the ones that are
/// combinations of the others; of the rows from `first` on, the ones that are combinations of
/// the rows before `first` and the other rows from `first` on. So a later row that repeats an
/// earlier one is the one reported, whatever their sizes.
pub fn dependent_rows_after(a: &DMatrix<f64>, first: usize) -> Vec<usize> {
    let mut rows = eliminate(a, first).1;
    rows.sort_unstable();
    rows
}
