//! nalgebra's iterative factorisations bounded: the input checked finite and scaled by a
//! power of two, the sweeps counted (see the module above).

use nalgebra::{ComplexField, DMatrix, Dyn, SVD, Schur, SymmetricEigen};

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

/// Size (the smaller dimension) from which [`svd_real`] takes faer's blocked SVD: below it
/// nalgebra's is as fast, and the small models' results stay as they were.
pub(super) const BLOCKED_SVD_FROM: usize = 64;

/// Largest `‖A − U Σ Vᵀ‖_F / ‖A‖_F` accepted from the blocked SVD (a backward stable one
/// leaves a few `n ε`).
const SVD_RESIDUAL: f64 = 1e-11;

/// [`svd`] of a real matrix, from `BLOCKED_SVD_FROM` (64) rows and columns by faer's blocked
/// bidiagonalisation and divide and conquer (the unblocked Householder sweeps of nalgebra's
/// took a fifth of a 96-element shaft's modal point), checked, not trusted: where its factors
/// do not reproduce the matrix to `SVD_RESIDUAL` or its singular values are not finite,
/// non-negative and sorted, nalgebra's decomposition is taken instead.
pub fn svd_real(a: DMatrix<f64>, compute_u: bool, compute_v: bool) -> Option<SVD<f64, Dyn, Dyn>> {
    let (m, n) = a.shape();
    if m.min(n) >= BLOCKED_SVD_FROM
        && let Some(out) = blocked_svd(&a, compute_u, compute_v)
    {
        return Some(out);
    }
    svd(a, compute_u, compute_v)
}

/// [`svd_real`]'s blocked decomposition, `None` where it fails or its check does.
pub(super) fn blocked_svd(
    a: &DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
) -> Option<SVD<f64, Dyn, Dyn>> {
    let s = balance(a)?;
    let (m, n) = a.shape();
    let f = faer::Mat::<f64>::from_fn(m, n, |i, j| a[(i, j)] * s);
    let d = f.thin_svd().ok()?;
    let (u, v) = (d.U(), d.V());
    let sv: Vec<f64> = d.S().column_vector().iter().copied().collect();
    let ordered =
        sv.iter().all(|v| v.is_finite() && *v >= 0.0) && sv.windows(2).all(|w| w[0] >= w[1]);
    let us = faer::Mat::<f64>::from_fn(m, sv.len(), |i, j| u[(i, j)] * sv[j]);
    let residual = (&us * v.transpose() - &f).norm_l2();
    let reproduces = residual <= SVD_RESIDUAL * f.norm_l2();
    if !(ordered && reproduces) {
        return None;
    }
    let k = sv.len();
    Some(SVD {
        u: compute_u.then(|| DMatrix::from_fn(m, k, |i, j| u[(i, j)])),
        v_t: compute_v.then(|| DMatrix::from_fn(k, n, |i, j| v[(j, i)])),
        singular_values: nalgebra::DVector::from_iterator(k, sv.iter().map(|v| v / s)),
    })
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

/// Does `a` equal `sign` times its transpose (1: symmetric, −1: skew-symmetric) to
/// [`SYMMETRY`] of its largest entry?
pub(super) fn structured(a: &DMatrix<f64>, sign: f64) -> bool {
    let s = a.amax();
    let n = a.nrows();
    (0..n).all(|j| (0..=j).all(|i| (a[(i, j)] - sign * a[(j, i)]).abs() <= SYMMETRY * s))
}

/// The part of `a` with that symmetry, `(a + sign·aᵀ)/2`, for faer.
pub(super) fn part(a: &DMatrix<f64>, sign: f64) -> faer::Mat<f64> {
    faer::Mat::from_fn(a.nrows(), a.ncols(), |i, j| {
        0.5 * (a[(i, j)] + sign * a[(j, i)])
    })
}

/// The spectral condition number of the symmetric `a`; `None` where `a` is not positive
/// definite or the decomposition fails.
pub(super) fn spectral_condition(a: &faer::Mat<f64>) -> Option<f64> {
    let s = a.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    let n = s.len();
    (n > 0 && s[0] > 0.0 && s[n - 1].is_finite()).then(|| s[n - 1] / s[0])
}

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
    if !structured(m, 1.0) || !structured(k, 1.0) {
        return None;
    }
    let (fm, fk) = (part(m, 1.0), part(k, 1.0));
    let mass_condition = spectral_condition(&fm)?;
    let by_stiffness = mass_condition > WELL_CONDITIONED
        && spectral_condition(&fk).is_some_and(|c| c < mass_condition);
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
    let (theta, mut z) = checked_eigen(&c)?;
    solve_upper_triangular_in_place(l.transpose(), z.as_mut(), Par::Seq);
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

/// Largest backward error `‖C u − θ u‖ / ‖C‖` (unit `u`) accepted from a symmetric
/// eigensolver: a backward stable one leaves a few `n ε` (1e-13 at n = 500).
const EIGEN_RESIDUAL: f64 = 1e-10;

/// The eigenvalues (ascending) and orthonormal eigenvectors of the symmetric `c`, each pair
/// checked by its residual: faer's `self_adjoint_eigen` (0.23) returned, for a 480×480 graded
/// matrix (a cantilever of 80 beam elements reduced by `M`'s Cholesky factor, eigenvalues from
/// 1e4 to 9e11), eigenvalues thousands of units off with vectors that did not belong to
/// them (its eigenvalues alone were right): a clamped beam read as diverging. Where a pair
/// fails, the decomposition is redone by nalgebra's implicit QR; `None` where that fails too.
fn checked_eigen(c: &faer::Mat<f64>) -> Option<(Vec<f64>, faer::Mat<f64>)> {
    let n = c.nrows();
    let norm = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max(c[(i, j)].abs()))
        * n as f64;
    let holds = |theta: &[f64], u: &faer::Mat<f64>| {
        let cu = c * u;
        (0..n).all(|j| {
            let r = (0..n)
                .map(|i| (cu[(i, j)] - theta[j] * u[(i, j)]).powi(2))
                .sum::<f64>()
                .sqrt();
            r <= EIGEN_RESIDUAL * norm.max(f64::MIN_POSITIVE)
        })
    };
    if let Ok(evd) = c.self_adjoint_eigen(faer::Side::Lower) {
        let theta: Vec<f64> = (0..n).map(|j| evd.S().column_vector()[j]).collect();
        let u = evd.U().to_owned();
        if holds(&theta, &u) {
            return Some((theta, u));
        }
    }
    let e = symmetric_eigen(DMatrix::from_fn(n, n, |i, j| c[(i, j)]))?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    let theta: Vec<f64> = order.iter().map(|&j| e.eigenvalues[j]).collect();
    let u = faer::Mat::<f64>::from_fn(n, n, |i, j| e.eigenvectors[(i, order[j])]);
    holds(&theta, &u).then_some((theta, u))
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
