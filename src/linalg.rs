//! Small dense helpers over any [`Real`]: forward-mode Jacobians, a pivoted solve, Newton's LU
//! factorisation ([`Lu`], `f64`), the choice of independent columns of a constraint Jacobian,
//! and bounded forms of nalgebra's iterative factorisations.
//!
//! nalgebra's factorisations need a `ComplexField`, which nested dual numbers are not, so the
//! few solves that must carry derivatives (the independent-coordinate basis) use this
//! elimination, pivoting on real parts.
//!
//! **Every iterative factorisation goes through this module** ([`svd`], [`schur`], [`eigen_dense`],
//! [`symmetric_eigen`]). nalgebra's plain calls iterate without bound and panic on a NaN they
//! produce themselves: entries near `f64::MAX` overflow inside the QR sweeps, after which the
//! iteration never converges (a hang) or a singular value is NaN (a panic). Here the input must be
//! finite, is scaled by a power of two (exact) so that its largest entry lies in `[½, 1)`, and the
//! iteration count is bounded (LAPACK allows 30 QR sweeps per eigenvalue; we allow
//! [`SWEEPS_PER_ROW`]). The result is unscaled; a result that overflows on unscaling is not
//! finite and the caller reports it as a failure.

use crate::real::{D1, Real, cst, lift1};
use nalgebra::{ComplexField, DMatrix, DVector, Dyn, SVD, Schur, SymmetricEigen};
use num_dual::Dual;

/// QR or Jacobi sweeps allowed per row of the matrix (LAPACK's `dhseqr` allows 30 per
/// eigenvalue); beyond that the factorisation is reported as not converged.
pub const SWEEPS_PER_ROW: usize = 100;

/// Iteration bound of a factorisation of an `n`-row matrix (nalgebra counts all sweeps).
fn sweeps(n: usize) -> usize {
    SWEEPS_PER_ROW * n.max(1)
}

/// Power of two that brings the largest modulus of a finite matrix into `[½, 1)`, or `None`
/// when an entry is NaN or infinite. The exponent is clamped to ±1000 so that the factor itself
/// is finite and normal (a matrix of subnormals stays small, which is harmless).
fn balance<T: ComplexField<RealField = f64>>(a: &DMatrix<T>) -> Option<f64> {
    let mut amax = 0.0f64;
    for v in a.iter() {
        if !v.is_finite() {
            return None;
        }
        // |re| + |im| can overflow for a finite complex number; the larger part cannot.
        let (re, im) = (v.clone().real().abs(), v.clone().imaginary().abs());
        amax = amax.max(re.max(im));
    }
    if amax == 0.0 {
        return Some(1.0);
    }
    let e = (amax.log2().floor() as i32 + 1).clamp(-1000, 1000);
    Some(2f64.powi(-e))
}

/// `a` times the real factor `s`.
fn scaled<T: ComplexField<RealField = f64>>(mut a: DMatrix<T>, s: f64) -> DMatrix<T> {
    if s.to_bits() != 1f64.to_bits() {
        let f = T::from_real(s);
        a.iter_mut().for_each(|v| *v *= f.clone());
    }
    a
}

/// Singular value decomposition (sorted), or `None` when `a` is not finite or the iteration
/// does not converge. Singular values that overflow on unscaling are infinite.
pub fn svd<T: ComplexField<RealField = f64>>(
    a: DMatrix<T>,
    compute_u: bool,
    compute_v: bool,
) -> Option<SVD<T, Dyn, Dyn>> {
    let s = balance(&a)?;
    let n = a.nrows().max(a.ncols());
    let mut out = SVD::try_new(
        scaled(a, s),
        compute_u,
        compute_v,
        f64::EPSILON * 5.0,
        sweeps(n),
    )?;
    out.singular_values.unscale_mut(s);
    Some(out)
}

/// Real Schur form `s A = Q T Qᵀ` of a real square matrix as `(Q, T, s)`, `s` the power of
/// two that balances `A`; `None` when `a` is not finite or the QR iteration does not converge.
/// The `schur` module reads eigenvalues and eigenvectors from it.
pub fn schur(a: DMatrix<f64>) -> Option<(DMatrix<f64>, DMatrix<f64>, f64)> {
    let s = balance(&a)?;
    let n = a.nrows();
    let (q, t) = Schur::try_new(scaled(a, s), f64::EPSILON, sweeps(n))?.unpack();
    Some((q, t, s))
}

/// `(eigenvalues, left vectors, right vectors)` of [`eigen_dense`].
pub type DenseEigen = (Vec<nalgebra::Complex<f64>>, DMatrix<f64>, DMatrix<f64>);

/// Eigenvalues of a real square matrix with its left and right eigenvectors by faer's blocked
/// Hessenberg reduction, multishift QR and triangular eigenvector solves (LAPACK's `dgeev`
/// layout: a complex pair's vectors are the real and imaginary parts in two adjacent columns, the
/// one with positive imaginary part first), as `(eigenvalues, left, right)`. `None` when `a` is
/// not finite or the iteration does not converge.
pub fn eigen_dense(a: &DMatrix<f64>) -> Option<DenseEigen> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{ComputeEigenvectors, evd_real, evd_scratch};
    let s = balance(a)?;
    let n = a.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)] * s);
    let (mut re, mut im) = (
        faer::diag::Diag::<f64>::zeros(n),
        faer::diag::Diag::<f64>::zeros(n),
    );
    let (mut ul, mut ur) = (faer::Mat::<f64>::zeros(n, n), faer::Mat::<f64>::zeros(n, n));
    let par = faer::Par::Seq;
    let yes = ComputeEigenvectors::Yes;
    let mut buf = MemBuffer::new(evd_scratch::<f64>(n, yes, yes, par, Default::default()));
    evd_real(
        m.as_ref(),
        re.as_mut(),
        im.as_mut(),
        Some(ul.as_mut()),
        Some(ur.as_mut()),
        par,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .ok()?;
    let values = (0..n)
        .map(|k| nalgebra::Complex::new(re.column_vector()[k] / s, im.column_vector()[k] / s))
        .collect();
    let left = DMatrix::from_fn(n, n, |i, j| ul[(i, j)]);
    let right = DMatrix::from_fn(n, n, |i, j| ur[(i, j)]);
    Some((values, left, right))
}

/// Relative asymmetry (of the largest entry) below which a matrix counts as symmetric: rounding
/// in the assembly of `M̂`, `K̂` leaves a few ε (measured: 3e-16 on the blade's `M̂`).
const SYMMETRY: f64 = 1e-13;

/// The undamped pencil `K x = μ M x` with `M` and `K` symmetric and `M` positive definite.
#[derive(Debug, Clone)]
pub struct Definite {
    /// The eigenvalues `μ`, ascending.
    pub values: Vec<f64>,
    /// The eigenvectors, `M`-orthonormal columns.
    pub vectors: DMatrix<f64>,
    /// The spectral condition number of `M`.
    pub mass_condition: f64,
    /// Reduced by `K`'s Cholesky factor (`M` the worse conditioned), not by `M`'s.
    pub by_stiffness: bool,
}

/// Condition number of a mass matrix up to which the modal solves divide by it without
/// looking at the stiffness matrix's (see [`symmetric_definite`]).
pub const WELL_CONDITIONED: f64 = 1e4;

/// Solves `K x = μ M x` by LAPACK `dsygv`'s route (Golub & Van Loan, *Matrix Computations*,
/// 4th ed., 2013, §8.7.2) on faer's blocked kernels: Cholesky `M = LLᵀ`, the symmetric
/// standard problem `L⁻¹ K L⁻ᵀ z = μ z`, `x = L⁻ᵀ z`. An n×n symmetric problem instead of the
/// 2n×2n nonsymmetric first-order form: about twenty times fewer operations, real `μ` by
/// construction (no rounding can give an undamped mode a spurious real part), and vectors with
/// no overflow however stiff the spectrum. `None` when either matrix is not symmetric (to
/// 1e-13 of its largest entry), `M` is not positive definite, or the iteration fails: the
/// caller then takes the general route.
///
/// That route is backward stable only as far as `M` is well conditioned: forming `L⁻¹ K L⁻ᵀ`
/// commits errors of `ε cond(M) ‖K‖`, and every eigenvalue carries them (Golub & Van Loan,
/// §8.7.2). A chain of many segments in joint coordinates has `cond(M) ∝ n⁴` (3.9e12 at a
/// thousand segments) while its `K` (the joint springs) stays well conditioned: there the
/// lowest frequency came out 1e-4 off, in a noise that grew with `n`. So when `M` is
/// ill-conditioned and `K` is positive definite and better conditioned, the roles swap:
/// `M x = ν K x` by the Cholesky factor of `K`, `μ = 1/ν`, with the errors of `ε cond(K) ‖M‖`
/// (the same eigenpairs; the low modes then to a few ε).
pub fn symmetric_definite(m: &DMatrix<f64>, k: &DMatrix<f64>) -> Option<Definite> {
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
    use faer::{Mat, Par, Side};
    let n = m.nrows();
    if n == 0 || k.nrows() != n || m.iter().chain(k.iter()).any(|v| !v.is_finite()) {
        return None;
    }
    let symmetric = |a: &DMatrix<f64>| {
        let s = a.amax();
        (0..n).all(|j| (0..j).all(|i| (a[(i, j)] - a[(j, i)]).abs() <= SYMMETRY * s))
    };
    if !symmetric(m) || !symmetric(k) {
        return None;
    }
    let mean = |a: &DMatrix<f64>| Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let (fm, fk) = (mean(m), mean(k));
    let condition = |a: &Mat<f64>| {
        let s = a.self_adjoint_eigenvalues(Side::Lower).ok()?;
        (s[0] > 0.0 && s[n - 1].is_finite()).then(|| s[n - 1] / s[0])
    };
    let mass_condition = condition(&fm)?;
    let by_stiffness =
        mass_condition > WELL_CONDITIONED && condition(&fk).is_some_and(|c| c < mass_condition);
    // `a z = θ b z` by the Cholesky factor of `b`: θ = μ by M, θ = 1/μ by K.
    let (a, b) = if by_stiffness { (fm, fk) } else { (fk, fm) };
    let llt = b.llt(Side::Lower).ok()?;
    let l = llt.L();
    // L⁻¹ A, then L⁻¹ (L⁻¹ A)ᵀ = L⁻¹ A L⁻ᵀ.
    let mut c = a;
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    let mut c = c.transpose().to_owned();
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    let c = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c.self_adjoint_eigen(Side::Lower).ok()?;
    let mut z = evd.U().to_owned();
    solve_upper_triangular_in_place(l.transpose(), z.as_mut(), Par::Seq);
    let theta = evd.S().column_vector();
    let (values, vectors): (Vec<f64>, DMatrix<f64>) = if by_stiffness {
        // Ascending μ = 1/θ is descending θ; x = z/√θ is M-orthonormal (zᵀKz = 1, zᵀMz = θ).
        let order: Vec<usize> = (0..n).rev().collect();
        (
            order.iter().map(|&j| 1.0 / theta[j]).collect(),
            DMatrix::from_fn(n, n, |i, c| z[(i, order[c])] / theta[order[c]].sqrt()),
        )
    } else {
        (
            (0..n).map(|j| theta[j]).collect(),
            DMatrix::from_fn(n, n, |i, j| z[(i, j)]),
        )
    };
    (values.iter().chain(vectors.iter()).all(|v| v.is_finite())).then_some(Definite {
        values,
        vectors,
        mass_condition,
        by_stiffness,
    })
}

/// Eigen-decomposition of a real symmetric matrix (eigenvalues unsorted), or `None` when `a`
/// is not finite or the iteration does not converge.
pub fn symmetric_eigen(a: DMatrix<f64>) -> Option<SymmetricEigen<f64, Dyn>> {
    let s = balance(&a)?;
    let n = a.nrows();
    let mut out = SymmetricEigen::try_new(scaled(a, s), f64::EPSILON, sweeps(n))?;
    out.eigenvalues.unscale_mut(s);
    Some(out)
}

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

/// The largest magnitude of `a`'s entries, as nalgebra's `amax` (`if m > |v| { m } else
/// { |v| }` from the first entry's: a NaN entry is taken, and passed over by the next), over
/// the column-major slice: nalgebra's generic fold took about 2 % of the 12-arm governor's
/// point (`perf`).
pub fn amax(a: &DMatrix<f64>) -> f64 {
    let s = a.as_slice();
    let first = s.first().map_or(0.0, |v| v.abs());
    s.iter()
        .skip(1)
        .fold(first, |m, v| if m > v.abs() { m } else { v.abs() })
}

/// Chooses `m` linearly independent columns of the `m × n` matrix `a` by elimination with
/// complete pivoting. Returns them sorted, or `None` when `a` has rank below `m`.
pub fn pivot_columns(a: &DMatrix<f64>) -> Option<Vec<usize>> {
    let (m, n) = a.shape();
    let mut a = a.clone();
    let scale = amax(&a).max(f64::MIN_POSITIVE);
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
    let scale = amax(&a).max(f64::MIN_POSITIVE);
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
    match svd(a, true, true).map(|svd| svd.solve(&b, 1e-12)) {
        Some(Ok(l)) if l.iter().all(|v| v.is_finite()) => l.iter().copied().collect(),
        _ => vec![0.0; m],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    #[test]
    fn lu_gives_nalgebras_bits() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for n in [1, 2, 5, 13, 25] {
            for trial in 0..20 {
                let mut a = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
                match trial {
                    // A zero column (singular), a row of huge and tiny magnitudes, a NaN.
                    1 => a.column_mut(n / 2).fill(0.0),
                    2 => a.row_mut(0).iter_mut().for_each(|v| *v *= 1e200),
                    3 => a[(n - 1, 0)] = f64::NAN,
                    4 if n > 1 => {
                        let first = a.row(0).clone_owned();
                        a.row_mut(1).copy_from(&first);
                    }
                    _ => {}
                }
                let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
                let ours = Lu::new(a.clone()).solve(&b);
                let theirs = a.lu().solve(&DVector::from_column_slice(&b));
                match (ours, theirs) {
                    (Some(x), Some(y)) => assert!(
                        x.iter()
                            .zip(y.iter())
                            .all(|(u, v)| u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan())),
                        "n {n} trial {trial}: {x:?} vs {y:?}"
                    ),
                    (None, None) => assert!(trial == 1 || trial == 4, "n {n} trial {trial}"),
                    (x, y) => panic!("n {n} trial {trial}: {x:?} vs {y:?}"),
                }
            }
        }
    }

    #[test]
    fn amax_is_nalgebras() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for (r, c) in [(0, 0), (1, 1), (3, 7), (25, 25)] {
            for trial in 0..6 {
                let mut a = DMatrix::from_fn(r, c, |_, _| rng.random_range(-1e3..1e3));
                match trial {
                    // A NaN first (passed over), a NaN last (kept), an infinity, all NaN.
                    1 if r > 0 => a[(0, 0)] = f64::NAN,
                    2 if r > 1 => a[(r - 1, c - 1)] = f64::NAN,
                    3 if r > 0 => a[(r / 2, c / 2)] = f64::NEG_INFINITY,
                    4 => a.fill(f64::NAN),
                    _ => {}
                }
                let (ours, theirs) = (amax(&a), a.amax());
                assert!(
                    ours.to_bits() == theirs.to_bits() || (ours.is_nan() && theirs.is_nan()),
                    "{r}×{c} trial {trial}: {ours} vs {theirs}"
                );
            }
        }
    }

    #[test]
    fn least_squares_solves_the_normal_equations() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for (rows, cols) in [(1, 1), (5, 5), (13, 12), (40, 7)] {
            let a = DMatrix::from_fn(rows, cols, |_, _| rng.random_range(-1.0..1.0));
            let b = DVector::from_fn(rows, |_, _| rng.random_range(-1.0..1.0));
            let x = DVector::from_vec(least_squares(a.clone(), b.clone()));
            // Aᵀ(Ax − b) = 0, against the normal equations solved by Cholesky as a second route.
            let gradient = a.tr_mul(&(&a * &x - &b));
            assert!(gradient.amax() < 1e-12, "{rows}×{cols}: {gradient}");
            let normal = a.tr_mul(&a).cholesky().unwrap().solve(&a.tr_mul(&b));
            assert!((&x - &normal).amax() < 1e-9 * normal.amax().max(1.0));
        }
        // Rank deficient (two equal columns): the minimum-norm solution, by SVD.
        let mut a = DMatrix::from_fn(6, 3, |_, _| rng.random_range(-1.0..1.0));
        let first = a.column(0).clone_owned();
        a.column_mut(2).copy_from(&first);
        let b = DVector::from_fn(6, |_, _| rng.random_range(-1.0..1.0));
        let x = least_squares(a.clone(), b.clone());
        let pinv = a.clone().pseudo_inverse(1e-12).unwrap() * &b;
        assert!((DVector::from_vec(x) - pinv).amax() < 1e-12);
    }

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
    fn an_ill_conditioned_mass_matrix_keeps_the_low_modes_exact() {
        // A planted pencil: K = L Lᵀ (well conditioned), M = L Q diag(ν) Qᵀ Lᵀ with ν from 1
        // down to 1e-11, so cond(M) ≈ 1e11 and the eigenvalues are μ = 1/ν, the lowest (ν near
        // 1) known to the construction's rounding. Reducing by M's Cholesky factor carries
        // ε cond(M) ‖K‖ into every eigenvalue (1e-6 of the lowest here); by K's, a few ε.
        let n = 30;
        let l = DMatrix::from_fn(n, n, |i, j| match i.cmp(&j) {
            std::cmp::Ordering::Equal => 2.0 + (i as f64 * 0.37).sin(),
            std::cmp::Ordering::Greater => 0.3 * ((i * 7 + j * 3) as f64).cos(),
            std::cmp::Ordering::Less => 0.0,
        });
        let q = DMatrix::from_fn(n, n, |i, j| ((i * 13 + j * 5 + 1) as f64).sin())
            .qr()
            .q();
        let nu: Vec<f64> = (0..n)
            .map(|i| 10f64.powf(-11.0 * i as f64 / (n - 1) as f64))
            .collect();
        let k = &l * l.transpose();
        let m = &l
            * &q
            * DMatrix::from_diagonal(&DVector::from_vec(nu.clone()))
            * q.transpose()
            * l.transpose();
        let m = (&m + m.transpose()) * 0.5;
        let d = symmetric_definite(&m, &k).expect("a definite pencil");
        assert!(d.mass_condition > 1e10, "cond(M) {:e}", d.mass_condition);
        for (i, nu) in nu.iter().enumerate().take(8) {
            let (mu, x) = (d.values[i], d.vectors.column(i));
            assert!(
                (mu * nu - 1.0).abs() < 1e-12,
                "μ_{i} = {mu} vs {}",
                1.0 / nu
            );
            assert!(((x.transpose() * &m * x)[0] - 1.0).abs() < 1e-12);
            let r = &k * x - &m * x * mu;
            assert!(r.norm() < 1e-12 * (k.norm() + mu * m.norm()) * x.norm());
        }
        assert!(d.values.windows(2).all(|w| w[0] <= w[1]), "ascending");
    }

    #[test]
    fn factorisations_of_extreme_matrices_end_with_an_answer_or_none() {
        // Entries near f64::MAX overflow inside nalgebra's unscaled sweeps (a hang in Schur, a
        // NaN panic in the SVD); balanced, they are ordinary matrices.
        let big = DMatrix::from_row_slice(2, 2, &[1e308, -1e308, 1e308, 1e308]);
        // (The eigenvalues read from this Schur form: `schur::tests`.)
        let (q, t, _) = schur(big.clone()).unwrap();
        assert!(q.iter().chain(t.iter()).all(|v| v.is_finite()));
        let sv = svd(big.clone(), true, true).unwrap().singular_values;
        assert!(
            sv.iter()
                .all(|s| s.is_infinite() || (s / 1e308 - 2f64.sqrt()).abs() < 1e-12)
        );
        let c = big.map(|v| nalgebra::Complex::new(v, v));
        assert!(svd(c, false, true).is_some());
        let sym = DMatrix::from_row_slice(2, 2, &[1e-320, 5e-321, 5e-321, 1e-320]);
        assert!(symmetric_eigen(sym).is_some());
        let nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(schur(nan.clone()).is_none());
        assert!(svd(nan.clone(), false, false).is_none());
        assert!(symmetric_eigen(DMatrix::from_element(2, 2, f64::INFINITY)).is_none());
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
