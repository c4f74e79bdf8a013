//! Eigenvalues of a real matrix with their right and left eigenvectors, from its real Schur form.
//!
//! `A = Q T Qᵀ` with `T` quasi-upper-triangular (1×1 blocks for real eigenvalues, 2×2 blocks
//! for complex pairs). An eigenvector of `T` for the eigenvalue of a diagonal block is zero
//! below the block, the block's own null vector in it, and follows by back substitution above
//! it; a left eigenvector is zero above the block and follows by forward substitution below it.
//! Each costs O(N²) where a singular value decomposition of the shifted matrix costs O(N³), so
//! all of them cost as much as the Schur form itself. This is LAPACK's `dtrevc` (Anderson et al.,
//! *LAPACK Users' Guide*, 3rd ed., SIAM 1999, §2.4.5), with its safeguard: a pivot of the
//! substitution smaller than `ε‖T‖` (a repeated eigenvalue) is replaced by `ε‖T‖`, so that
//! the vector stays finite and is an exact eigenvector of a matrix within `ε‖T‖` of `T`.

use crate::linalg;
use nalgebra::{Complex, DMatrix, DVector};

/// Complex scalar.
type C64 = Complex<f64>;

/// The real Schur form `A = Q T Qᵀ` of a square matrix (scaled by a power of two).
#[derive(Debug, Clone)]
pub struct RealSchur {
    q: DMatrix<f64>,
    t: DMatrix<f64>,
    /// `T` is the Schur form of `scale · A`.
    scale: f64,
    /// `ε ‖T‖`: the smallest pivot of a substitution.
    small: f64,
}

/// An eigenvalue of `A` and the diagonal block of `T` it belongs to.
#[derive(Debug, Clone, Copy)]
pub struct Eigenvalue {
    pub lambda: C64,
    /// First row of the block.
    start: usize,
    /// 1 or 2.
    size: usize,
}

impl RealSchur {
    /// The Schur form, or `None` when `a` is not finite or the QR iteration does not converge
    /// (see [`linalg::schur`]).
    pub fn new(a: DMatrix<f64>) -> Option<RealSchur> {
        let (q, t, scale) = linalg::schur(a)?;
        let small = f64::EPSILON * t.amax().max(f64::MIN_POSITIVE);
        Some(RealSchur { q, t, scale, small })
    }

    /// Every eigenvalue of `A` with its block, in the order of the diagonal.
    pub fn eigenvalues(&self) -> Vec<Eigenvalue> {
        let t = &self.t;
        let n = t.nrows();
        let mut out = Vec::with_capacity(n);
        let mut i = 0;
        while i < n {
            if i + 1 < n && t[(i + 1, i)] != 0.0 {
                let (a, b, c, d) = (t[(i, i)], t[(i, i + 1)], t[(i + 1, i)], t[(i + 1, i + 1)]);
                let half = 0.5 * (a + d);
                let disc = 0.25 * (a - d) * (a - d) + b * c;
                let root = C64::new(disc, 0.0).sqrt();
                for l in [half + root, half - root] {
                    out.push(Eigenvalue {
                        lambda: l / self.scale,
                        start: i,
                        size: 2,
                    });
                }
                i += 2;
            } else {
                out.push(Eigenvalue {
                    lambda: C64::new(t[(i, i)] / self.scale, 0.0),
                    start: i,
                    size: 1,
                });
                i += 1;
            }
        }
        out
    }

    /// `T − λ` on the diagonal: a pivot no smaller than `ε‖T‖`.
    fn pivot(&self, p: C64) -> C64 {
        if p.norm() < self.small {
            C64::new(self.small, 0.0)
        } else {
            p
        }
    }

    /// Solves the 2×2 system `[a b; c d] x = r`, the determinant kept away from zero.
    fn solve2(&self, [a, b, c, d]: [C64; 4], r: [C64; 2]) -> [C64; 2] {
        let det = self.pivot(a * d - b * c);
        [(r[0] * d - b * r[1]) / det, (a * r[1] - c * r[0]) / det]
    }

    /// Null vector of the 2×2 block `B − λ` at `s` (or of its transpose): the larger of the
    /// two candidates its rows give.
    fn block_null(&self, s: usize, l: C64, transpose: bool) -> [C64; 2] {
        let t = &self.t;
        let (a, mut b, mut c, d) = (t[(s, s)], t[(s, s + 1)], t[(s + 1, s)], t[(s + 1, s + 1)]);
        if transpose {
            std::mem::swap(&mut b, &mut c);
        }
        let one = [C64::new(b, 0.0), l - a];
        let two = [l - d, C64::new(c, 0.0)];
        let norm = |v: &[C64; 2]| v[0].norm() + v[1].norm();
        if norm(&one) >= norm(&two) { one } else { two }
    }

    /// Right eigenvector `x` of `A` (`A x = λ x`) for `e` evaluated at `λ = lambda` (`e`'s own
    /// eigenvalue, or a value rounded from it), rows `rows` of it only; not normalised.
    pub fn right(&self, e: &Eigenvalue, lambda: C64, rows: std::ops::Range<usize>) -> DVector<C64> {
        let t = &self.t;
        let l = lambda * self.scale;
        let end = e.start + e.size;
        let mut z = vec![C64::new(0.0, 0.0); end];
        if e.size == 1 {
            z[e.start] = C64::new(1.0, 0.0);
        } else {
            let v = self.block_null(e.start, l, false);
            z[e.start] = v[0];
            z[e.start + 1] = v[1];
        }
        let sum = |i: usize, z: &[C64]| -> C64 {
            let mut s = C64::new(0.0, 0.0);
            for (k, zk) in z.iter().enumerate().take(end).skip(i + 1) {
                s -= zk * t[(i, k)];
            }
            s
        };
        let mut i = e.start;
        while i > 0 {
            let r = i - 1;
            if r > 0 && t[(r, r - 1)] != 0.0 {
                let (a, b, c, d) = (
                    C64::new(t[(r - 1, r - 1)], 0.0) - l,
                    C64::new(t[(r - 1, r)], 0.0),
                    C64::new(t[(r, r - 1)], 0.0),
                    C64::new(t[(r, r)], 0.0) - l,
                );
                let rhs = [sum(r - 1, &z), sum(r, &z)];
                let [x0, x1] = self.solve2([a, b, c, d], rhs);
                z[r - 1] = x0;
                z[r] = x1;
                i -= 2;
            } else {
                z[r] = sum(r, &z) / self.pivot(C64::new(t[(r, r)], 0.0) - l);
                i -= 1;
            }
            rescale(&mut z);
        }
        self.times_q(&z, 0, rows)
    }

    /// Left eigenvector `y` of `A` (`yᵀ A = λ yᵀ`) for `e` at `λ = lambda`, rows `rows` of it
    /// only; not normalised.
    pub fn left(&self, e: &Eigenvalue, lambda: C64, rows: std::ops::Range<usize>) -> DVector<C64> {
        let t = &self.t;
        let n = t.nrows();
        let l = lambda * self.scale;
        let s = e.start;
        let mut u = vec![C64::new(0.0, 0.0); n - s];
        if e.size == 1 {
            u[0] = C64::new(1.0, 0.0);
        } else {
            let v = self.block_null(s, l, true);
            u[0] = v[0];
            u[1] = v[1];
        }
        // `−Σ_k T[k, i] u_k` over the rows computed so far (u is offset by `s`).
        let sum = |i: usize, u: &[C64], upto: usize| -> C64 {
            let mut acc = C64::new(0.0, 0.0);
            for (k, uk) in u.iter().enumerate().take(upto) {
                acc -= uk * t[(s + k, i)];
            }
            acc
        };
        let mut i = s + e.size;
        while i < n {
            let done = i - s;
            if i + 1 < n && t[(i + 1, i)] != 0.0 {
                // (Bᵀ − λ) [u_i; u_{i+1}] = rhs
                let (a, b, c, d) = (
                    C64::new(t[(i, i)], 0.0) - l,
                    C64::new(t[(i + 1, i)], 0.0),
                    C64::new(t[(i, i + 1)], 0.0),
                    C64::new(t[(i + 1, i + 1)], 0.0) - l,
                );
                let rhs = [sum(i, &u, done), sum(i + 1, &u, done)];
                let [x0, x1] = self.solve2([a, b, c, d], rhs);
                u[done] = x0;
                u[done + 1] = x1;
                i += 2;
            } else {
                u[done] = sum(i, &u, done) / self.pivot(C64::new(t[(i, i)], 0.0) - l);
                i += 1;
            }
            rescale(&mut u);
        }
        self.times_q(&u, s, rows)
    }

    /// Rows `rows` of `Q v`, `v` given from row `offset` on (zero before).
    fn times_q(&self, v: &[C64], offset: usize, rows: std::ops::Range<usize>) -> DVector<C64> {
        DVector::from_iterator(
            rows.len(),
            rows.map(|r| {
                let mut s = C64::new(0.0, 0.0);
                for (k, vk) in v.iter().enumerate() {
                    s += vk * self.q[(r, offset + k)];
                }
                s
            }),
        )
    }
}

/// Matrices from this size on take faer's blocked `dgeev` ([`linalg::eigen_dense`]), all
/// vectors at once; smaller ones nalgebra's Schur form with vectors by substitution for the
/// roots asked for (less set-up: the governor's 4×4 form is solved in a fraction of the time).
pub const DENSE_FROM: usize = 16;

/// Eigenvalues of a real matrix with right and left eigenvectors, by the route that is faster
/// at its size (see [`DENSE_FROM`]), of the matrix balanced first (see [`balancing`]).
#[derive(Debug, Clone)]
pub struct Eigen {
    route: Route,
    /// The balancing `D`: the route solved `D⁻¹ A D`.
    scale: Vec<f64>,
}

#[derive(Debug, Clone)]
enum Route {
    Schur(RealSchur, Vec<Eigenvalue>),
    /// `dgeev`'s layout (see [`linalg::eigen_dense`]).
    Dense {
        values: Vec<C64>,
        left: DMatrix<f64>,
        right: DMatrix<f64>,
    },
}

impl Eigen {
    /// `None` when `a` is not finite or the iteration does not converge.
    pub fn new(mut a: DMatrix<f64>) -> Option<Eigen> {
        if !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        let scale = balancing(&mut a);
        // faer's vector solves do not guard against growth: a stiff spectrum (a long chain's
        // highest modes next to its lowest) can overflow them, and the substitution here,
        // which keeps every vector finite, takes over.
        let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
        let route = if a.nrows() >= DENSE_FROM
            && let Some((values, left, right)) = linalg::eigen_dense(&a)
            && finite(&left)
            && finite(&right)
            && pairs_hold(&a, &values, &right)
        {
            Route::Dense {
                values,
                left,
                right,
            }
        } else {
            let s = RealSchur::new(a)?;
            let e = s.eigenvalues();
            Route::Schur(s, e)
        };
        Some(Eigen { route, scale })
    }

    /// The eigenvalues; a complex pair's two adjacent.
    pub fn values(&self) -> Vec<C64> {
        match &self.route {
            Route::Schur(_, e) => e.iter().map(|e| e.lambda).collect(),
            Route::Dense { values, .. } => values.clone(),
        }
    }

    /// Rows `rows` of the right eigenvector of eigenvalue `k` (`A x = λ x`), computed at
    /// `lambda` (its value, or one rounded from it) where the route computes per root.
    pub fn right(&self, k: usize, lambda: C64, rows: std::ops::Range<usize>) -> DVector<C64> {
        let d = &self.scale[rows.clone()];
        let v = match &self.route {
            Route::Schur(s, e) => s.right(&e[k], lambda, rows),
            Route::Dense { values, right, .. } => packed(right, values, k, rows, false),
        };
        DVector::from_iterator(v.len(), v.iter().zip(d).map(|(z, d)| z * *d))
    }

    /// Rows `rows` of the left eigenvector of eigenvalue `k` (`yᵀ A = λ yᵀ`).
    pub fn left(&self, k: usize, lambda: C64, rows: std::ops::Range<usize>) -> DVector<C64> {
        let d = &self.scale[rows.clone()];
        let v = match &self.route {
            Route::Schur(s, e) => s.left(&e[k], lambda, rows),
            // dgeev's left vectors are `uᴴ A = λ uᴴ`: `y = ū`.
            Route::Dense { values, left, .. } => packed(left, values, k, rows, true),
        };
        DVector::from_iterator(v.len(), v.iter().zip(d).map(|(z, d)| z / *d))
    }
}

/// Largest backward error `‖A x − λ x‖ / (‖A‖_F ‖x‖)` accepted from the dense eigensolver: a
/// backward stable one leaves a few `n ε`.
const PAIR_RESIDUAL: f64 = 1e-10;

/// Does every pair of the dense route (`dgeev`'s layout) satisfy `A x = λ x` to
/// [`PAIR_RESIDUAL`]? A library's eigensolver is checked, not trusted: faer's symmetric one
/// returned pairs that did not belong together on a graded matrix (see
/// [`linalg::symmetric_definite`]); where this fails, the Schur substitution takes over.
fn pairs_hold(a: &DMatrix<f64>, values: &[C64], right: &DMatrix<f64>) -> bool {
    let n = a.nrows();
    let norm = a.norm();
    let ar = a * right;
    let mut k = 0;
    while k < n {
        let l = values[k];
        // A real root's vector is column k; a complex pair's, columns k (real) and k + 1 (imag).
        let (re, im) = if l.im == 0.0 {
            (k, None)
        } else {
            (k, Some(k + 1))
        };
        let mut r2 = 0.0;
        let mut x2 = 0.0;
        for i in 0..n {
            let x = C64::new(right[(i, re)], im.map_or(0.0, |j| right[(i, j)]));
            let ax = C64::new(ar[(i, re)], im.map_or(0.0, |j| ar[(i, j)]));
            r2 += (ax - l * x).norm_sqr();
            x2 += x.norm_sqr();
        }
        let r = r2.sqrt();
        if r.is_nan() || r > PAIR_RESIDUAL * norm * x2.sqrt() {
            return false;
        }
        k += if im.is_some() { 2 } else { 1 };
    }
    true
}

/// Balances `a` in place by a diagonal similarity `D⁻¹ A D` of powers of two (exact), making
/// each row's and column's off-diagonal norms alike, and returns `D` (Parlett & Reinsch 1969,
/// Numer. Math. 13:293; LAPACK's `dgebal` scaling). The eigenvalues are unchanged; the vectors
/// of `A` are `D x` (right) and `D⁻¹ y` (left). The first-order form of a model whose
/// coordinates differ in scale by decades (a beam's axial and torsional coordinates beside its
/// bending ones) has rows decades apart, and unbalanced, the rounding of its largest rows
/// swamped the low modes' vectors (a spinning blade's first flap mode came out as a twist).
pub fn balancing(a: &mut DMatrix<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut d = vec![1.0; n];
    for _ in 0..100 {
        let mut done = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0f64, 0.0f64);
            for j in (0..n).filter(|&j| j != i) {
                c += a[(j, i)].abs();
                r += a[(i, j)].abs();
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let (total, mut f) = (c + r, 1.0f64);
            while c < r / 2.0 && f < 2f64.powi(500) {
                c *= 2.0;
                r /= 2.0;
                f *= 2.0;
            }
            while c >= r * 2.0 && f > 2f64.powi(-500) {
                c /= 2.0;
                r *= 2.0;
                f /= 2.0;
            }
            if c + r < 0.95 * total {
                done = false;
                d[i] *= f;
                for j in 0..n {
                    a[(i, j)] /= f;
                    a[(j, i)] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
    d
}

/// The vector of eigenvalue `k` from `dgeev`'s real layout, conjugated with `conj`.
fn packed(
    v: &DMatrix<f64>,
    values: &[C64],
    k: usize,
    rows: std::ops::Range<usize>,
    conj: bool,
) -> DVector<C64> {
    let im = values[k].im;
    let (re_col, im_col, sign) = if im > 0.0 {
        (k, Some(k + 1), 1.0)
    } else if im < 0.0 {
        (k - 1, Some(k), -1.0)
    } else {
        (k, None, 1.0)
    };
    let sign = if conj { -sign } else { sign };
    DVector::from_iterator(
        rows.len(),
        rows.map(|r| C64::new(v[(r, re_col)], im_col.map_or(0.0, |c| sign * v[(r, c)]))),
    )
}

/// Scales `v` down by a power of two when an entry grows past `2^500` (a nearly repeated
/// eigenvalue makes the substitution grow), keeping it finite; the direction is unchanged.
fn rescale(v: &mut [C64]) {
    let big = v
        .iter()
        .fold(0.0f64, |m, z| m.max(z.re.abs()).max(z.im.abs()));
    if big > 2f64.powi(500) {
        let f = 2f64.powi(-500);
        v.iter_mut().for_each(|z| *z *= f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `‖A x − λ x‖ / ‖x‖` and `‖yᵀ A − λ yᵀ‖ / ‖y‖` for every eigenvalue of `a`.
    fn residuals(a: &DMatrix<f64>) -> f64 {
        let n = a.nrows();
        let e = Eigen::new(a.clone()).unwrap();
        let ac = a.map(|v| C64::new(v, 0.0));
        let mut worst = 0.0f64;
        for (k, l) in e.values().into_iter().enumerate() {
            let x = e.right(k, l, 0..n);
            let y = e.left(k, l, 0..n);
            let rx = (&ac * &x - &x * l).norm() / x.norm();
            let ry = (ac.transpose() * &y - &y * l).norm() / y.norm();
            worst = worst.max(rx).max(ry);
        }
        worst / a.amax()
    }

    fn pseudo_random(n: usize) -> DMatrix<f64> {
        let mut x = 0.3f64;
        DMatrix::from_fn(n, n, |_, _| {
            x = (x * 3.7 + 0.11).fract();
            x - 0.5
        })
    }

    #[test]
    fn vectors_of_a_random_matrix_satisfy_their_equations_on_both_routes() {
        // Fixed pseudo-random matrices, one below and one above DENSE_FROM: complex pairs and
        // real eigenvalues.
        assert!(matches!(
            Eigen::new(pseudo_random(12)).map(|e| e.route),
            Some(Route::Schur(..))
        ));
        assert!(matches!(
            Eigen::new(pseudo_random(40)).map(|e| e.route),
            Some(Route::Dense { .. })
        ));
        for n in [12, 40] {
            let a = pseudo_random(n);
            assert!(residuals(&a) < 1e-13, "{n}: {}", residuals(&a));
        }
    }

    #[test]
    fn vectors_of_a_badly_scaled_matrix_hold_row_by_row() {
        // `S R S⁻¹` with `S` spanning twelve decades: each row of `A x − λ x` is at rounding of
        // that row's own terms, `(|A| |x| + |λ| |x|)_i`, on both routes, as the balanced form
        // gives (unbalanced, the large rows' rounding swamped the small rows' entries).
        for n in [12, 40] {
            let s: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 13) as i32 - 6)).collect();
            let r = pseudo_random(n);
            let a = DMatrix::from_fn(n, n, |i, j| s[i] * r[(i, j)] / s[j]);
            let e = Eigen::new(a.clone()).unwrap();
            let ac = a.map(|v| C64::new(v, 0.0));
            let abs = a.abs();
            for (k, l) in e.values().into_iter().enumerate() {
                let x = e.right(k, l, 0..n);
                let residual = &ac * &x - &x * l;
                let size = &abs * x.map(|z| z.norm()) + x.map(|z| z.norm() * l.norm());
                for i in 0..n {
                    assert!(
                        residual[i].norm() <= 1e-12 * size[i],
                        "{n}: eigenvalue {k}, row {i}: {:e} of {:e}",
                        residual[i].norm(),
                        size[i]
                    );
                }
            }
        }
    }

    #[test]
    fn vectors_of_a_repeated_eigenvalue_stay_finite_and_exact_to_rounding() {
        // A Jordan block (defective) and a repeated diagonal (not).
        let mut j = DMatrix::identity(4, 4) * 2.0;
        for i in 0..3 {
            j[(i, i + 1)] = 1.0;
        }
        assert!(residuals(&j) < 1e-12, "{}", residuals(&j));
        let d = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 3.0, 3.0]));
        assert!(residuals(&d) < 1e-14);
        // The same on the dense route: a 20×20 Jordan block beside a repeated pair.
        let mut j = DMatrix::identity(20, 20) * 2.0;
        for i in 0..9 {
            j[(i, i + 1)] = 1.0;
        }
        j[(18, 18)] = 5.0;
        j[(19, 19)] = 5.0;
        let r = residuals(&j);
        assert!(r.is_finite() && r < 1e-12, "{r}");
    }

    #[test]
    fn eigenvalues_near_the_largest_double_are_found_from_the_balanced_form() {
        // Entries near f64::MAX overflow inside nalgebra's unscaled sweeps; balanced by a power
        // of two, λ = 1e308 (1 ± i) comes out exact to rounding.
        let big = DMatrix::from_row_slice(2, 2, &[1e308, -1e308, 1e308, 1e308]);
        for e in RealSchur::new(big).unwrap().eigenvalues() {
            let l = e.lambda;
            assert!((l.re / 1e308 - 1.0).abs() < 1e-12 && (l.im.abs() / 1e308 - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_eigenvalues_of_a_rotation_block_are_its_complex_pair() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, -2.0, 2.0, 0.0]);
        let s = RealSchur::new(a.clone()).unwrap();
        let mut ims: Vec<f64> = s.eigenvalues().iter().map(|e| e.lambda.im).collect();
        ims.sort_by(f64::total_cmp);
        assert!((ims[0] + 2.0).abs() < 1e-14 && (ims[1] - 2.0).abs() < 1e-14);
        assert!(residuals(&a) < 1e-15);
    }
}
