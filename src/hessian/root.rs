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

/// Three real matrices: `(M̂, Ĉ, K̂)` or their derivatives.
pub type Triple<'a> = (&'a DMatrix<f64>, &'a DMatrix<f64>, &'a DMatrix<f64>);

/// `P(λ) v = λ²(M v) + λ(C v) + K v` for one variable's matrices.
fn pencil(l: C64, (m, c, k): Triple<'_>, v: &DVector<C64>) -> DVector<C64> {
    times(m, v) * (l * l) + times(c, v) * l + times(k, v)
}

/// A real matrix as a complex one.
pub(super) fn complex(a: &DMatrix<f64>) -> DMatrix<C64> {
    a.map(|v| C64::new(v, 0.0))
}

/// The pencil `P(λ) = λ²M + λC + K` of the matrices `(m, c, k)`.
pub(super) fn pencil_matrix(l: C64, (m, c, k): Triple<'_>) -> DMatrix<C64> {
    complex(m) * (l * l) + complex(c) * l + complex(k)
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
    /// `yᵀP_ab x` for every pair, where reverse mode gave them all (`mixed.rs`).
    pub pairs: Option<DMatrix<C64>>,
}

/// A variable's first and second derivatives of `(M̂, Ĉ, K̂)` along itself (the second where
/// taken: otherwise every root's [`RootTerms::pairs`] holds the diagonal).
pub type Along<'a> = (Triple<'a>, Option<Triple<'a>>);

/// A root's terms while the variables are added (see [`RootTerms::all`]).
struct Partial {
    lambda: C64,
    left: DVector<C64>,
    lu: nalgebra::LU<C64, nalgebra::Dyn, nalgebra::Dyn>,
    den: C64,
    ymx: C64,
    /// `P'ᵀy`, shared by every `u_a`.
    dpty: DVector<C64>,
    first: Vec<C64>,
    diagonal: Vec<C64>,
    alpha: Vec<C64>,
    /// `x_a` and `u_a` as columns.
    xs: DMatrix<C64>,
    us: DMatrix<C64>,
    /// A solve with the bordered matrix failed.
    failed: bool,
}

impl Partial {
    /// The bordered equations of `root` factorised, with what every variable shares; `None`
    /// where they are exactly singular.
    fn new(root: &Root, (m, c, k): Triple<'_>, nv: usize) -> Option<Partial> {
        let n = m.nrows();
        let (l, x, y) = (root.lambda, &root.right, &root.left);
        let (mc, cc, kc) = (complex(m), complex(c), complex(k));
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
        Some(Partial {
            lambda: l,
            left: y.clone(),
            lu,
            den: dot(y, &dpx),
            ymx: dot(y, &(&mc * x)),
            dpty: dp.transpose() * y,
            first: Vec::with_capacity(nv),
            diagonal: Vec::with_capacity(nv),
            alpha: Vec::with_capacity(nv),
            xs: DMatrix::zeros(n, nv),
            us: DMatrix::zeros(n, nv),
            failed: false,
        })
    }

    /// The root's terms, the cross products `u_aᵀx_b + u_bᵀx_a` of every pair taken at once.
    fn finish(self, root: &Root, pairs: Option<DMatrix<C64>>) -> RootTerms {
        let ux = self.us.transpose() * &self.xs;
        RootTerms {
            lambda: self.lambda,
            right: root.right.clone(),
            left: self.left,
            den: self.den,
            ymx: self.ymx,
            first: self.first,
            diagonal: self.diagonal,
            alpha: self.alpha,
            cross: &ux + ux.transpose(),
            pairs,
        }
    }
}

impl RootTerms {
    /// The terms of each of `roots` of the nominal matrices `(m, c, k)`, with `along[a]`
    /// variable `a`'s derivatives of the matrices; `None` for a root whose bordered equations
    /// are exactly singular; `pairs`, where given, each root's `yᵀP_ab x` for every pair (the
    /// diagonal read from there where `along` has no second derivatives). The matrices'
    /// products with the roots' vectors are taken for all the roots at once (one matrix product
    /// per variable and matrix, not one matrix–vector product per root).
    pub fn all(
        roots: &[&Root],
        (m, c, k): Triple<'_>,
        along: &[Along<'_>],
        pairs: Option<Vec<DMatrix<C64>>>,
    ) -> Vec<Option<RootTerms>> {
        let n = m.nrows();
        let nv = along.len();
        // The roots' right (or left) vectors as the columns of a real and an imaginary part.
        let split = |left: bool| {
            let v = |j: usize| {
                if left {
                    &roots[j].left
                } else {
                    &roots[j].right
                }
            };
            (
                DMatrix::from_fn(n, roots.len(), |i, j| v(j)[i].re),
                DMatrix::from_fn(n, roots.len(), |i, j| v(j)[i].im),
            )
        };
        let (xs_all, ys_all) = (split(false), split(true));
        // `a Z` (or `aᵀ Z`) for the complex matrix `Z` given by its parts.
        let product = |a: &DMatrix<f64>, (re, im): &(DMatrix<f64>, DMatrix<f64>), t: bool| {
            let (r, i) = if t {
                (a.tr_mul(re), a.tr_mul(im))
            } else {
                (a * re, a * im)
            };
            r.zip_map(&i, C64::new)
        };
        let mut terms: Vec<Option<Partial>> = roots
            .iter()
            .map(|root| Partial::new(root, (m, c, k), nv))
            .collect();
        for (a, &((ma, ca, ka), second)) in along.iter().enumerate() {
            let [mx, cx, kx] = [ma, ca, ka].map(|mat| product(mat, &xs_all, false));
            let second_x =
                second.map(|(m2, c2, k2)| [m2, c2, k2].map(|mat| product(mat, &xs_all, false)));
            let [mty, cty, kty] = [ma, ca, ka].map(|mat| product(mat, &ys_all, true));
            for (j, t) in terms.iter_mut().enumerate() {
                let Some(t) = t.as_mut().filter(|t| !t.failed) else {
                    continue;
                };
                let col = |z: &DMatrix<C64>| z.column(j).into_owned();
                let pencil = |l: C64, (m, c, k): (&DMatrix<C64>, &DMatrix<C64>, &DMatrix<C64>)| {
                    col(m) * (l * l) + col(c) * l + col(k)
                };
                let l = t.lambda;
                let pax = pencil(l, (&mx, &cx, &kx));
                let la = -dot(&t.left, &pax) / t.den;
                let rhs = DVector::from_iterator(
                    n + 1,
                    pax.iter().map(|v| -v).chain([C64::new(0.0, 0.0)]),
                );
                let Some(sol) = t.lu.solve(&rhs) else {
                    t.failed = true;
                    continue;
                };
                let xa = sol.rows(0, n).into_owned();
                let al = dot(&t.left, &(col(&mx) * (l * 2.0) + col(&cx)));
                let u = pencil(l, (&mty, &cty, &kty)) + &t.dpty * la;
                let caa = match (&second_x, &pairs) {
                    (Some([m2x, c2x, k2x]), _) => dot(&t.left, &pencil(l, (m2x, c2x, k2x))),
                    (None, Some(pairs)) => pairs[j][(a, a)],
                    (None, None) => C64::new(0.0, 0.0),
                };
                let cross = dot(&u, &xa);
                t.diagonal
                    .push(-(caa + al * la * 2.0 + la * la * t.ymx * 2.0 + cross * 2.0) / t.den);
                t.first.push(la);
                t.alpha.push(al);
                t.xs.column_mut(a).copy_from(&xa);
                t.us.column_mut(a).copy_from(&u);
            }
        }
        let mut pairs = pairs.map(Vec::into_iter);
        terms
            .into_iter()
            .zip(roots)
            .map(|(t, root)| {
                let own = pairs.as_mut().and_then(Iterator::next);
                t.filter(|t| !t.failed).map(|t| t.finish(root, own))
            })
            .collect()
    }

    /// The root's value.
    pub fn lambda(&self) -> C64 {
        self.lambda
    }

    /// `λ_ab` for variables `a < b`, with `second` the matrices' mixed derivatives `(M̂_ab,
    /// Ĉ_ab, K̂_ab)` (`None` where they are zero or the root has [`RootTerms::pairs`]).
    pub fn mixed(&self, (a, b): (usize, usize), second: Option<Triple<'_>>) -> C64 {
        let cab = match (second, &self.pairs) {
            (Some(s), _) => dot(&self.left, &pencil(self.lambda, s, &self.right)),
            (None, Some(pairs)) => pairs[(a, b)],
            (None, None) => C64::new(0.0, 0.0),
        };
        let (la, lb) = (self.first[a], self.first[b]);
        -(cab
            + self.alpha[a] * lb
            + self.alpha[b] * la
            + la * lb * self.ymx * 2.0
            + self.cross[(a, b)])
            / self.den
    }
}
