//! The line direction: the active subspace of the exact gradients of every output (Constantine
//! 2015), and an orthonormal basis of its complement.

use crate::model::Distribution;
use crate::tolerance::{LocalModel, Spread};
use nalgebra::{DMatrix, DVector};

/// `∂b/∂z` at `z = 0` of the design map ([`crate::sampling::DesignMap::parameters`]) of the
/// spread `s` (of the active variables) with the correlation factor `chol`.
pub(super) fn design_jacobian(s: &Spread, chol: &DMatrix<f64>) -> DMatrix<f64> {
    let d = s.sigma.len();
    let phi0 = 1.0 / (2.0 * std::f64::consts::PI).sqrt();
    DMatrix::from_fn(d, d, |i, k| match s.distribution[i] {
        Distribution::Normal => s.sigma[i] * chol[(i, k)],
        Distribution::Uniform if i == k => s.sigma[i] * 3f64.sqrt() * 2.0 * phi0,
        Distribution::Uniform => 0.0,
    })
}

/// The line direction first, then an orthonormal basis of its complement (columns, in `z`).
pub(super) fn directions(
    locals: &[Option<LocalModel>],
    active: &[usize],
    s: &Spread,
    chol: &DMatrix<f64>,
) -> DMatrix<f64> {
    let d = active.len();
    if d == 1 {
        return DMatrix::identity(1, 1);
    }
    let jac = design_jacobian(s, chol);
    let mut c = DMatrix::<f64>::zeros(d, d);
    for lm in locals.iter().flatten() {
        let grads = lm
            .grad
            .iter()
            .flatten()
            .chain(lm.disc.iter().filter_map(|(_, g, _)| g.as_ref().ok()));
        for g in grads {
            let gb = DVector::from_iterator(d, active.iter().map(|&k| g[k]));
            let gz = jac.transpose() * gb;
            let n = gz.norm();
            if n.is_finite() && n > 0.0 {
                let u = gz / n;
                c += &u * u.transpose();
            }
        }
    }
    if c.iter().all(|v| *v == 0.0) {
        c = DMatrix::identity(d, d);
    }
    let Some(eig) = crate::linalg::symmetric_eigen(c) else {
        return DMatrix::identity(d, d);
    };
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    DMatrix::from_fn(d, d, |i, j| {
        let col = eig.eigenvectors.column(order[j]);
        // A fixed sign: the largest component positive.
        let big = col
            .iter()
            .fold(0.0f64, |m, &v| if v.abs() > m.abs() { v } else { m });
        col[i] * big.signum()
    })
}
