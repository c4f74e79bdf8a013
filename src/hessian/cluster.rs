//! The first and second derivatives of a repeated root's cluster from the derivatives of the
//! matrices, in closed form: the block form of `root.rs` (see [`crate::modal::cluster`] for the
//! cluster and its bases).
//!
//! With the right basis `X` (n×k) and the left basis `Y` (`YᵀP(λ) = 0`, `YᵀP'X = I`), the
//! cluster is the block `T` of `M X T² + C X T + K X = 0` (`T = λI` at the point, its
//! eigenvalues the members), smooth in the variables where no other root joins it. Twice
//! differentiating and multiplying by `Yᵀ`, which removes `X_ab`:
//!
//! ```text
//! [P  P'X; Wᵀ 0] [X_a; T_a] = [−P_a X; 0]                       (the bordered equations)
//! T_ab = −( YᵀP_ab X + U_aᵀX_b + U_bᵀX_a + α_a T_b + α_b T_a
//!           + (YᵀP'X_a) T_b + (YᵀP'X_b) T_a + YᵀM̂X (T_a T_b + T_b T_a) )
//!        α_a = YᵀP'_a X,   U_a = P_aᵀ Y
//! ```
//!
//! with `P_a`, `P'_a` as in `root.rs` (for k = 1 these are its formulas). Where every `T_a` and
//! `T_ab` is a multiple of the identity, the members move as one to second order: each member's
//! derivatives are the traces over k. The bordered matrix is regular where the root is
//! semisimple (`YᵀP'X` regular) and `WᵀX` is (`W = X̄`), whatever the members' multiplicity.
//!
//! # Reference
//! Andrew & Tan, SIAM J. Matrix Anal. Appl. 20 (1998); Seyranian & Mailybaev (2003), ch. 2.

use super::root::{Along, Triple, complex};
use crate::modal::C64;
use crate::modal::cluster::as_one;
use nalgebra::DMatrix;

/// A repeated root's cluster with its first derivatives along every variable and what the
/// second derivatives of every pair share.
pub struct ClusterTerms {
    lambda: C64,
    right: DMatrix<C64>,
    /// `Y`, normalised: `YᵀP'X = I`.
    left: DMatrix<C64>,
    /// `YᵀM̂X`.
    ymx: DMatrix<C64>,
    /// `T_a` per variable.
    first: Vec<DMatrix<C64>>,
    /// `T_aa` per variable.
    diagonal: Vec<DMatrix<C64>>,
    /// `α_a` per variable.
    alpha: Vec<DMatrix<C64>>,
    /// `YᵀP'X_a` per variable.
    moved: Vec<DMatrix<C64>>,
    /// `X_a` and `U_a` per variable.
    xs: Vec<DMatrix<C64>>,
    us: Vec<DMatrix<C64>>,
    /// `YᵀP_ab X` for every pair (entry `(i, j)` of the k×k blocks: `pairs[i·k + j][(a, b)]`),
    /// where reverse mode gave them.
    pairs: Option<Vec<DMatrix<C64>>>,
}

impl ClusterTerms {
    /// The cluster at `lambda` with bases `right` (X) and `left` (Y) of the pencil `(m, c, k)`,
    /// `along[a]` variable `a`'s derivatives of the matrices; `pairs`, where given, `y_iᵀP_ab x_j`
    /// for every pair, in the order `i·k + j` (the left basis as given, before normalising);
    /// `None` where the bordered equations are singular (a defective root).
    pub fn new(
        lambda: C64,
        (right, left): (DMatrix<C64>, DMatrix<C64>),
        (m, c, k): Triple<'_>,
        along: &[Along<'_>],
        pairs: Option<Vec<DMatrix<C64>>>,
    ) -> Option<ClusterTerms> {
        let (n, size) = right.shape();
        let l = lambda;
        let (mc, cc, kc) = (complex(m), complex(c), complex(k));
        let p0 = &mc * (l * l) + &cc * l + &kc;
        let dp = &mc * (l * 2.0) + &cc;
        let dpx = &dp * &right;
        // Normalise the left basis so that `YᵀP'X = I`; the pairs' blocks likewise.
        let inverse = (left.transpose() * &dpx).try_inverse()?;
        let left = left * inverse.transpose();
        let pairs = pairs.map(|raw| {
            (0..size * size)
                .map(|ij| {
                    let (i, j) = (ij / size, ij % size);
                    let mut sum = raw[j].map(|_| C64::new(0.0, 0.0));
                    for r in 0..size {
                        sum += &raw[r * size + j] * inverse[(i, r)];
                    }
                    sum
                })
                .collect()
        });
        let mut bordered = DMatrix::zeros(n + size, n + size);
        bordered.view_mut((0, 0), (n, n)).copy_from(&p0);
        bordered.view_mut((0, n), (n, size)).copy_from(&dpx);
        bordered
            .view_mut((n, 0), (size, n))
            .copy_from(&right.map(|z| z.conj()).transpose());
        let lu = bordered.lu();
        if !lu.is_invertible() {
            return None;
        }
        let ymx = left.transpose() * &mc * &right;
        let ydp = left.transpose() * &dp;
        let nv = along.len();
        let mut terms = ClusterTerms {
            lambda,
            right,
            left,
            ymx,
            first: Vec::with_capacity(nv),
            diagonal: Vec::with_capacity(nv),
            alpha: Vec::with_capacity(nv),
            moved: Vec::with_capacity(nv),
            xs: Vec::with_capacity(nv),
            us: Vec::with_capacity(nv),
            pairs,
        };
        for (a, &((ma, ca, ka), second)) in along.iter().enumerate() {
            let pa = complex(ma) * (l * l) + complex(ca) * l + complex(ka);
            let rhs = -(&pa * &terms.right);
            let mut padded = DMatrix::zeros(n + size, size);
            padded.view_mut((0, 0), (n, size)).copy_from(&rhs);
            let sol = lu.solve(&padded)?;
            let xa = sol.rows(0, n).into_owned();
            let ta = -(terms.left.transpose() * &pa * &terms.right);
            let alpha =
                terms.left.transpose() * (complex(ma) * (l * 2.0) + complex(ca)) * &terms.right;
            let ua = pa.transpose() * &terms.left;
            let moved = &ydp * &xa;
            let caa = match (second, &terms.pairs) {
                (Some((m2, c2, k2)), _) => {
                    let p2 = complex(m2) * (l * l) + complex(c2) * l + complex(k2);
                    terms.left.transpose() * p2 * &terms.right
                }
                (None, Some(pairs)) => {
                    DMatrix::from_fn(size, size, |i, j| pairs[i * size + j][(a, a)])
                }
                (None, None) => DMatrix::zeros(size, size),
            };
            let cross = ua.transpose() * &xa;
            let two = C64::new(2.0, 0.0);
            let taa =
                -(caa + (cross + &alpha * &ta + &moved * &ta + &terms.ymx * (&ta * &ta)) * two);
            terms.first.push(ta);
            terms.diagonal.push(taa);
            terms.alpha.push(alpha);
            terms.moved.push(moved);
            terms.xs.push(xa);
            terms.us.push(ua);
        }
        Some(terms)
    }

    /// The root's value (the members' mean).
    pub fn lambda(&self) -> C64 {
        self.lambda
    }

    /// Each member's first derivative along variable `a`: `tr(T_a)/k`, `None` where `T_a`
    /// splits the cluster.
    pub fn first(&self, a: usize) -> Option<C64> {
        as_one(&self.first[a])
    }

    /// Each member's second derivative along variable `a`, `None` where `T_aa` splits it.
    pub fn diagonal(&self, a: usize) -> Option<C64> {
        as_one(&self.diagonal[a])
    }

    /// Each member's mixed derivative for variables `a < b`, with `second` the matrices'
    /// mixed derivatives `(M̂_ab, Ĉ_ab, K̂_ab)` (`None` where they are zero or reverse mode
    /// gave the pairs); `None` where `T_ab` splits the cluster.
    pub fn mixed(&self, (a, b): (usize, usize), second: Option<Triple<'_>>) -> Option<C64> {
        let size = self.right.ncols();
        let l = self.lambda;
        let cab = match (second, &self.pairs) {
            (Some((m2, c2, k2)), _) => {
                let p2 = complex(m2) * (l * l) + complex(c2) * l + complex(k2);
                self.left.transpose() * p2 * &self.right
            }
            (None, Some(pairs)) => DMatrix::from_fn(size, size, |i, j| pairs[i * size + j][(a, b)]),
            (None, None) => DMatrix::zeros(size, size),
        };
        let (ta, tb) = (&self.first[a], &self.first[b]);
        let tab = -(cab
            + self.us[a].transpose() * &self.xs[b]
            + self.us[b].transpose() * &self.xs[a]
            + &self.alpha[a] * tb
            + &self.alpha[b] * ta
            + &self.moved[a] * tb
            + &self.moved[b] * ta
            + &self.ymx * (ta * tb + tb * ta));
        as_one(&tab)
    }
}
