//! The roots' derivatives along a direction of the matrices: `dλ = −yᵀ(λ²M' + λC' + K')x /
//! yᵀ(2λM + C)x` for every simple root of a point at once, the members of a repeated root's
//! cluster from the cluster's projection ([`crate::modal::cluster`]), and a mode's derivatives
//! from its roots'.

use super::{ModeSensitivity, Status};
use crate::modal::cluster::{Cluster, as_one, of_modes};
use crate::modal::{C64, Mode, Root, Smoothness};
use crate::pair;
use nalgebra::{DMatrix, DVector};

/// Derivatives of a mode from the derivatives of its two roots (`None` where they do not
/// exist along this direction: a repeated root that it splits); `invariants`, when given, are
/// the exact derivatives of `λ₁ + λ₂` and `λ₁ λ₂` (used instead of the roots' sums). `Ok` only
/// where the mode's roots are simple ([`Smoothness::Simple`]) or repeated and moving as one
/// along the direction, and the derivatives finite.
pub(crate) fn mode_derivative(
    m: &Mode,
    smooth: Smoothness,
    roots: Option<(C64, C64)>,
    invariants: Option<(f64, f64)>,
) -> ModeSensitivity {
    let (l1, l2) = (m.root.lambda, m.partner.lambda);
    let nan = C64::new(f64::NAN, f64::NAN);
    let (d1, d2) = roots.unwrap_or((nan, nan));
    let differentiable = matches!(smooth, Smoothness::Simple | Smoothness::Repeated { .. });
    let status = if !differentiable || !d1.re.is_finite() || !d2.re.is_finite() {
        Status::NotDifferentiable
    } else {
        Status::Ok
    };
    let p = (l1 * l2).re;
    let s = (l1 + l2).re;
    let (ds, dp) = invariants.unwrap_or(((d1 + d2).re, (d1 * l2 + l1 * d2).re));
    let wn = m.natural_frequency;
    let dwn = pair::d_natural_frequency(p, wn, dp);
    let dzeta = pair::d_damping_ratio(s, wn, ds, dwn);
    ModeSensitivity {
        status,
        d_eigen_re: d1.re,
        d_eigen_im: d1.im,
        d_damped_frequency: if l1.im > 0.0 { d1.im } else { 0.0 },
        d_natural_frequency: dwn,
        d_damping_ratio: dzeta,
        d_sum: ds,
        d_product: dp,
    }
}

/// `dλ = −yᵀ(λ²M' + λC' + K')x / yᵀ(2λM + C)x` for one root.
pub fn eigenvalue_derivative(
    lambda: C64,
    x: &DVector<C64>,
    y: &DVector<C64>,
    (m, c): (&DMatrix<f64>, &DMatrix<f64>),
    (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
) -> C64 {
    let b = |a: &DMatrix<f64>| bilinear(y, a, x);
    -(lambda * lambda * b(dm) + lambda * b(dc) + b(dk)) / (lambda * 2.0 * b(m) + b(c))
}

/// `yᵀ A x` for a real `A` (no complex matrix formed).
fn bilinear(y: &DVector<C64>, a: &DMatrix<f64>, x: &DVector<C64>) -> C64 {
    a.column_iter()
        .zip(x.iter())
        .map(|(col, &xj)| {
            col.iter()
                .zip(y.iter())
                .map(|(&v, &yi)| yi * v)
                .sum::<C64>()
                * xj
        })
        .sum()
}

/// [`eigenvalue_derivative`] for all the simple roots of a point at once, and the projections
/// of the repeated roots' clusters. The simple roots' right vectors are the columns of one
/// matrix, so that a design variable costs three real matrix products (`M'X`, `C'X`, `K'X`,
/// blocked) and O(n) per root, where a root at a time is a pass over three matrices each
/// (memory-bound, and 2n roots); the denominators `yᵀ(2λM + C)x` do not depend on the variable
/// and are computed once. A conjugate partner's derivative is the conjugate, bitwise.
pub(crate) struct RootDerivatives {
    /// Per mode, where its root is and where its partner is (`None` when it is the root's
    /// conjugate).
    places: Vec<(Place, Option<Place>)>,
    /// The simple roots in column order.
    simple: Vec<Root>,
    /// Real and imaginary parts of the simple roots' right vectors, as columns.
    xr: DMatrix<f64>,
    xi: DMatrix<f64>,
    /// `yᵀ(2λM + C)x` per simple root.
    den: Vec<C64>,
    /// The repeated roots' clusters (`None` where the roots are not one repeated root).
    clusters: Vec<Option<Cluster>>,
}

/// Where a root's derivative comes from.
#[derive(Debug, Clone, Copy)]
enum Place {
    /// A simple root: its column.
    Simple(usize),
    /// A member of a cluster of repeated roots.
    Member(usize),
}

impl RootDerivatives {
    /// The roots of `modes` (each mode's smoothness `smooth`) of the pencil `(m, c, k)`.
    pub(crate) fn new(
        modes: &[Mode],
        smooth: &[Smoothness],
        (m, c, k): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Self {
        let (clusters, in_cluster) = of_modes(modes, smooth, (m, c, k));
        let mut simple: Vec<Root> = Vec::new();
        let mut place = |r: &Root, cluster: Option<usize>| match cluster {
            Some(g) => Place::Member(g),
            None => {
                simple.push(r.clone());
                Place::Simple(simple.len() - 1)
            }
        };
        let places = (modes.iter().zip(&in_cluster))
            .map(|(md, &(r, p))| {
                let partner = (!md.partner_is_conjugate()).then_some(&md.partner);
                (place(&md.root, r), partner.map(|q| place(q, p)))
            })
            .collect();
        let clusters = clusters.into_iter().map(Result::ok).collect();
        let n = m.nrows();
        let xr = DMatrix::from_fn(n, simple.len(), |i, k| simple[k].right[i].re);
        let xi = DMatrix::from_fn(n, simple.len(), |i, k| simple[k].right[i].im);
        let (mr, mi, cr, ci) = (m * &xr, m * &xi, c * &xr, c * &xi);
        let den = simple
            .iter()
            .enumerate()
            .map(|(k, r)| {
                (0..n)
                    .map(|i| {
                        let mx = C64::new(mr[(i, k)], mi[(i, k)]);
                        let cx = C64::new(cr[(i, k)], ci[(i, k)]);
                        r.left[i] * (r.lambda * 2.0 * mx + cx)
                    })
                    .sum()
            })
            .collect();
        RootDerivatives {
            places,
            simple,
            xr,
            xi,
            den,
            clusters,
        }
    }

    /// Each cluster's projection `T_a` along `(M', C', K')` (`None` where the roots are not
    /// one repeated root).
    pub(crate) fn projections(
        &self,
        mats: (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Vec<Option<DMatrix<C64>>> {
        (self.clusters.iter())
            .map(|cl| cl.as_ref().map(|cl| cl.derivative(mats)))
            .collect()
    }

    /// The number of clusters ([`RootDerivatives::projections`]' length).
    pub(super) fn projections_count(&self) -> usize {
        self.clusters.len()
    }

    /// The modes whose root (not a partner) is a member of cluster `g`, in index order.
    pub(crate) fn members(&self, g: usize) -> Vec<usize> {
        (self.places.iter().enumerate())
            .filter(|(_, (r, _))| matches!(r, Place::Member(h) if *h == g))
            .map(|(i, _)| i)
            .collect()
    }

    /// `(dλ_root, dλ_partner)` per mode along `(M', C', K')`; `None` where a root is repeated
    /// and the direction splits its cluster, or the cluster is not one repeated root.
    pub(crate) fn along(
        &self,
        (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Vec<Option<(C64, C64)>> {
        let prod = |a: &DMatrix<f64>| (a * &self.xr, a * &self.xi);
        let ((mr, mi), (cr, ci), (kr, ki)) = (prod(dm), prod(dc), prod(dk));
        let n = dm.nrows();
        let simple: Vec<C64> = (self.simple.iter().enumerate())
            .map(|(k, r)| {
                let l = r.lambda;
                let num: C64 = (0..n)
                    .map(|i| {
                        let at =
                            |re: &DMatrix<f64>, im: &DMatrix<f64>| C64::new(re[(i, k)], im[(i, k)]);
                        r.left[i] * (l * l * at(&mr, &mi) + l * at(&cr, &ci) + at(&kr, &ki))
                    })
                    .sum();
                -num / self.den[k]
            })
            .collect();
        let members: Vec<Option<C64>> = (self.projections((dm, dc, dk)).iter())
            .map(|t| t.as_ref().and_then(as_one))
            .collect();
        let at = |p: Place| match p {
            Place::Simple(k) => Some(simple[k]),
            Place::Member(g) => members[g],
        };
        self.places
            .iter()
            .map(|&(r, p)| {
                let d1 = at(r)?;
                Some((d1, p.map_or(Some(d1.conj()), at)?))
            })
            .collect()
    }
}
