//! Repeated roots as clusters: the invariant subspaces of a root of multiplicity k, and the
//! first-order perturbation of the cluster projected on them (degenerate perturbation theory).
//!
//! An axisymmetric rotor at rest, a spherical pendulum, any system with two identical planes
//! has double roots: the two members of the cluster are not differentiable one by one (their
//! order and their vectors jump with the direction of a perturbation). What is smooth is the
//! cluster as a whole. With `X` (n×k) a basis of the right eigenspace of `λ` and `Y` a basis of
//! the left one, normalised so that `Yᵀ P'(λ) X = I` (`P(λ) = λ²M̂ + λĈ + K̂`, `P' = 2λM̂ + Ĉ`),
//! the members move to first order along a variable `a` as the eigenvalues of
//!
//! ```text
//! T_a = −Yᵀ P_a X,   P_a = λ²M̂_a + λĈ_a + K̂_a
//! ```
//!
//! (Lancaster 1964; Andrew & Tan 1998 for the symmetric case). Where every `T_a` is a multiple
//! `t_a I` of the identity, as it is for every variable that keeps the symmetry making the root
//! repeated (a diameter, a density, an isotropic bearing's stiffness, a disk's mass), the members
//! move as one: each is differentiable and its derivative is `t_a = tr(T_a)/k`. A variable whose
//! `T_a` is not a multiple of the identity splits the cluster: the members' derivatives do not
//! exist there (they are the eigenvalues of `T_a`, one-sided).
//!
//! The bases come from two steps of block inverse iteration with `P(λ)` at the members' mean
//! from a fixed start, not from the members' own vectors: at a root repeated to rounding, the
//! solver's vectors of the two members may be nearly parallel (inverse iteration from one start
//! converges to one direction), while the eigenspace has full dimension k.
//!
//! # Reference
//! Lancaster, *On eigenvalues of matrices dependent on a parameter*, Numer. Math. 6 (1964);
//! Andrew & Tan, *Computation of derivatives of repeated eigenvalues and the corresponding
//! eigenvectors of symmetric matrix pencils*, SIAM J. Matrix Anal. Appl. 20 (1998); Seyranian &
//! Mailybaev, *Multiparameter Stability Theory with Mechanical Applications* (2003), ch. 2.

use super::{C64, Mode, SIMPLE_GAP, Smoothness};
use nalgebra::DMatrix;

/// Relative spread of a cluster's members below which they count as one root of multiplicity k
/// (a symmetric system's exact double root comes out of the solvers split by rounding,
/// 1e-16…1e-12 relative). Between this and [`SIMPLE_GAP`] the roots are nearly, not exactly,
/// repeated: their expansion about one value would carry the gap as an error.
pub const DEGENERATE_GAP: f64 = 1e-9;

/// Relative size below which a cluster's `T_a` counts as a multiple of the identity: its part
/// off the identity against its whole (the rounding of the bases, not a split).
pub const AS_ONE: f64 = 1e-8;

/// A root repeated k times with bases of its right and left eigenspaces.
#[derive(Debug, Clone)]
pub struct Cluster {
    /// The members' mean.
    pub lambda: C64,
    /// Right basis `X` (n×k), orthonormal columns.
    pub right: DMatrix<C64>,
    /// Left basis `Y` (n×k), with `Yᵀ P'(λ) X = I`.
    pub left: DMatrix<C64>,
}

/// Why a group of close roots is not treated as one repeated root.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotCluster {
    /// The members lie apart by more than rounding (nearly, not exactly, repeated), or the
    /// eigenspace has fewer dimensions than members.
    Apart,
    /// The root is defective (a Jordan block): its left and right eigenspaces do not pair.
    Defective,
}

/// The groups of two or more of `lambdas` that lie within [`SIMPLE_GAP`] of one another
/// (transitively), each in increasing index order.
pub fn groups(lambdas: &[C64]) -> Vec<Vec<usize>> {
    let close = |a: C64, b: C64| (a - b).norm() <= SIMPLE_GAP * a.norm().max(b.norm());
    let mut label: Vec<usize> = (0..lambdas.len()).collect();
    for i in 0..lambdas.len() {
        for j in 0..i {
            if close(lambdas[i], lambdas[j]) {
                let (a, b) = (label[i], label[j]);
                for l in label.iter_mut() {
                    if *l == a {
                        *l = b;
                    }
                }
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (i, &l) in label.iter().enumerate() {
        match out.iter_mut().find(|g| label[g[0]] == l) {
            Some(g) => g.push(i),
            None => out.push(vec![i]),
        }
    }
    out.retain(|g| g.len() > 1);
    out
}

/// Where each mode's roots sit among the clusters of a point's repeated roots (see
/// [`of_modes`]): the cluster of its root and of its own partner (`None` where simple, or
/// where the partner is the root's conjugate).
pub type Places = Vec<(Option<usize>, Option<usize>)>;

/// The clusters of the repeated roots of `modes` (each mode's smoothness `smooth`) in the
/// pencil `(m, c, k)`: each group of repeated roots ([`groups`] of the roots of the modes that
/// are [`Smoothness::Repeated`], and of their partners where those are not the conjugates), as
/// a cluster or why it is not one; and where each mode's roots sit ([`Places`]).
pub fn of_modes(
    modes: &[Mode],
    smooth: &[Smoothness],
    pencil: (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
) -> (Vec<Result<Cluster, NotCluster>>, Places) {
    let repeated: Vec<(usize, bool, C64)> = (modes.iter().zip(smooth).enumerate())
        .filter(|(_, (_, why))| matches!(why, Smoothness::Repeated { .. }))
        .flat_map(|(i, (md, _))| {
            let partner = (!md.partner_is_conjugate()).then_some((i, true, md.partner.lambda));
            std::iter::once((i, false, md.root.lambda)).chain(partner)
        })
        .collect();
    let lambdas: Vec<C64> = repeated.iter().map(|&(_, _, l)| l).collect();
    let groups = groups(&lambdas);
    let clusters = (groups.iter())
        .map(|g| Cluster::new(&g.iter().map(|&j| lambdas[j]).collect::<Vec<_>>(), pencil))
        .collect();
    let place = |i: usize, partner: bool| {
        groups.iter().position(|g| {
            g.iter()
                .any(|&j| repeated[j].0 == i && repeated[j].1 == partner)
        })
    };
    let places = (0..modes.len())
        .map(|i| (place(i, false), place(i, true)))
        .collect();
    (clusters, places)
}

/// A real matrix as a complex one.
fn complex(a: &DMatrix<f64>) -> DMatrix<C64> {
    a.map(|v| C64::new(v, 0.0))
}

/// Entry `(i, j)` of the fixed start of the inverse iteration: irregular (a golden-ratio
/// sequence), of one magnitude; the bases do not depend on it beyond rounding.
fn start(i: usize, j: usize) -> C64 {
    let g = |s: f64| {
        let v = 0.618_033_988_749_895 * s;
        v - v.floor() - 0.5
    };
    C64::new(
        g((i * 7 + j * 13 + 1) as f64),
        g((i * 11 + j * 5 + 3) as f64),
    )
}

/// Orthonormal columns spanning those of `z` (complex Householder QR: orthonormal to rounding
/// however nearly parallel the columns are; the next step of the iteration and the residual
/// test judge the span).
fn orthonormal(z: DMatrix<C64>) -> DMatrix<C64> {
    z.qr().q()
}

impl Cluster {
    /// The cluster of the roots `lambdas` (two or more, repeated) of the pencil
    /// `λ²m + λc + k`, or why they are not one repeated root.
    pub fn new(
        lambdas: &[C64],
        (m, c, k): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Result<Cluster, NotCluster> {
        let size = lambdas.len();
        let lambda = lambdas.iter().sum::<C64>() / size as f64;
        if lambdas
            .iter()
            .any(|l| (l - lambda).norm() > DEGENERATE_GAP * lambda.norm())
        {
            return Err(NotCluster::Apart);
        }
        let n = m.nrows();
        let (mc, cc, kc) = (complex(m), complex(c), complex(k));
        let pencil = &mc * (lambda * lambda) + &cc * lambda + &kc;
        // Three steps of block inverse iteration each way from a fixed start, with the pencil
        // at a shift `σ` off the mean by 1e-12 of its size (the pencil at the mean itself can
        // be singular to the last bit; the other roots lie at least 1e-6 away, so each step
        // takes a million times more of the cluster's directions than of theirs). After the
        // first step the columns may all lean to one member; orthonormalised, the others'
        // directions remain, and the next steps make them clean.
        let shift = lambda + C64::new(1.0, 1.0) * (1e-12 * lambda.norm().max(f64::MIN_POSITIVE));
        let at_shift = &mc * (shift * shift) + &cc * shift + &kc;
        let basis = |p: &DMatrix<C64>| -> Option<DMatrix<C64>> {
            let lu = p.clone().lu();
            let mut z = DMatrix::from_fn(n, size, start);
            for _ in 0..3 {
                z = orthonormal(lu.solve(&z)?);
            }
            Some(z)
        };
        let right = basis(&at_shift).ok_or(NotCluster::Apart)?;
        let left = basis(&at_shift.transpose()).ok_or(NotCluster::Apart)?;
        // The bases must be eigenspaces: `P(λ)X` and `P(λ)ᵀY` at the pencil's rounding.
        let scale = lambda.norm_sqr() * m.amax() + lambda.norm() * c.amax() + k.amax();
        let residual = (&pencil * &right)
            .camax()
            .max((pencil.transpose() * &left).camax());
        if residual > 1e-8 * scale {
            return Err(NotCluster::Apart);
        }
        let dp = &mc * (lambda * 2.0) + &cc;
        let pair = left.transpose() * &dp * &right;
        // A defective root's left and right eigenspaces are orthogonal through `P'`.
        let svd = pair.clone().svd(false, false);
        let (hi, lo) = (svd.singular_values.max(), svd.singular_values.min());
        let dp_scale = 2.0 * lambda.norm() * m.amax() + c.amax();
        if !(lo > 1e-6 * dp_scale && lo > 1e-8 * hi) {
            return Err(NotCluster::Defective);
        }
        let inverse = pair.try_inverse().ok_or(NotCluster::Defective)?;
        Ok(Cluster {
            lambda,
            right,
            left: left * inverse.transpose(),
        })
    }

    /// The number of members.
    pub fn size(&self) -> usize {
        self.right.ncols()
    }

    /// `T_a = −Yᵀ(λ²M_a + λC_a + K_a)X` along the matrices' derivatives `(dm, dc, dk)`.
    pub fn derivative(
        &self,
        (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> DMatrix<C64> {
        let l = self.lambda;
        let pa = complex(dm) * (l * l) + complex(dc) * l + complex(dk);
        -(self.left.transpose() * pa * &self.right)
    }
}

/// `tr(T)/k` where `T` is a multiple of the identity to [`AS_ONE`] (the members move as one),
/// `None` where it splits them.
pub fn as_one(t: &DMatrix<C64>) -> Option<C64> {
    let k = t.nrows();
    let mean = t.trace() / k as f64;
    let off = (t - DMatrix::<C64>::identity(k, k) * mean).norm();
    (off <= AS_ONE * t.norm()).then_some(mean)
}

/// A double root that the variables split, where it stays on the imaginary axis (a
/// conservative pair: an undamped rotor with one bearing's stiffness toleranced apart): to first
/// order its members' ω_d are `ω₀ + gᵀδb ± √(δbᵀQδb)`.
#[derive(Debug, Clone)]
pub struct Split {
    /// The two members' modes in index order: the lower member first (the order in which a
    /// sample's matches are taken, [`super::match_modes`]).
    pub modes: [usize; 2],
    /// `g`: the gradient of the members' mean ω_d.
    pub mean: Vec<f64>,
    /// `Q`: the half split's square `((ω₊ − ω₋)/2)²` as a quadratic form in the variables
    /// (symmetric, positive semi-definite).
    pub split: DMatrix<f64>,
}

/// The first-order split of a conservative double root from its projections `t` (one 2×2 `T_a`
/// per variable): the members' mean's gradient `g = Im tr(T_a)/2` and the quadratic form `Q` of
/// `−Δ`, `Δ = (tr G/2)² − det G` the discriminant of `G = Σ T_a δb_a`; `None` where the pair
/// is not conservative to rounding (a member would leave the imaginary axis: `Re tr T_a ≠ 0`,
/// or `Δ` not real and non-positive), or not a pair.
pub fn conservative_split(t: &[DMatrix<C64>]) -> Option<(Vec<f64>, DMatrix<f64>)> {
    // Not a pair, or a projection that overflowed: no split claimed (and no eigenvalues of a
    // non-finite form asked for).
    if t.iter()
        .any(|ta| ta.shape() != (2, 2) || ta.iter().any(|z| !z.is_finite()))
    {
        return None;
    }
    let p = t.len();
    let size: Vec<f64> = t.iter().map(|ta| ta.norm()).collect();
    // Each variable judged against its own size (the variables' units differ).
    if (t.iter().zip(&size)).any(|(ta, &n)| ta.trace().re.abs() > AS_ONE * n) {
        return None;
    }
    let d = DMatrix::from_fn(p, p, |a, b| {
        let (x, y) = (&t[a], &t[b]);
        x.trace() * y.trace() / 4.0
            - (x[(0, 0)] * y[(1, 1)] + y[(0, 0)] * x[(1, 1)]
                - x[(0, 1)] * y[(1, 0)]
                - y[(0, 1)] * x[(1, 0)])
                / 2.0
    });
    let scale = |a: usize, b: usize| (size[a] * size[b]).max(f64::MIN_POSITIVE);
    if (0..p).any(|a| (0..p).any(|b| d[(a, b)].im.abs() > AS_ONE * scale(a, b))) {
        return None;
    }
    let q = DMatrix::from_fn(p, p, |a, b| -(d[(a, b)].re + d[(b, a)].re) / 2.0);
    // Positive semi-definite, judged on the form scaled by the variables' sizes.
    let unit = |a: usize| if size[a] > 0.0 { 1.0 / size[a] } else { 0.0 };
    let scaled = DMatrix::from_fn(p, p, |a, b| q[(a, b)] * unit(a) * unit(b));
    let lowest = scaled.symmetric_eigenvalues().min();
    if lowest < -AS_ONE * scaled.amax().max(f64::MIN_POSITIVE) {
        return None;
    }
    let mean = t.iter().map(|ta| ta.trace().im / 2.0).collect();
    Some((mean, q))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two identical planes coupled by nothing: a double root; a variable scaling both planes'
    /// stiffness moves the members as one, a variable stiffening one plane splits them.
    #[test]
    fn a_symmetric_double_root_moves_as_one_and_a_plane_splits_it() {
        let m = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 2.0]);
        let c = DMatrix::from_row_slice(2, 2, &[0.4, 0.0, 0.0, 0.4]);
        let k = DMatrix::from_row_slice(2, 2, &[50.0, 0.0, 0.0, 50.0]);
        // Roots of 2λ² + 0.4λ + 50: −0.1 ± i√24.99.
        let l = C64::new(-0.1, 24.99_f64.sqrt());
        let cl = Cluster::new(&[l, l], (&m, &c, &k)).expect("a cluster");
        assert_eq!(cl.size(), 2);
        let zero = DMatrix::zeros(2, 2);
        let both = DMatrix::identity(2, 2);
        let t = cl.derivative((&zero, &zero, &both));
        // dλ/dk of 2λ² + 0.4λ + k = 0: −1/(4λ + 0.4).
        let exact = -C64::new(1.0, 0.0) / (l * 4.0 + 0.4);
        let t1 = as_one(&t).expect("moves as one");
        assert!((t1 - exact).norm() < 1e-13 * exact.norm(), "{t1} {exact}");
        let one = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        let t = cl.derivative((&zero, &zero, &one));
        assert!(as_one(&t).is_none(), "one plane stiffened splits the root");
        // Its eigenvalues are the members' one-sided derivatives: `exact` and 0.
        let ev = t.eigenvalues().expect("2×2");
        let (a, b) = (ev[0], ev[1]);
        let (hi, lo) = if a.norm() > b.norm() { (a, b) } else { (b, a) };
        assert!((hi - exact).norm() < 1e-12 * exact.norm() && lo.norm() < 1e-12);
        // Undamped, the split is conservative: stiffening one plane by δ₁ and both by δ₂
        // moves the members' ω by ω' δ₂ ± ω' δ₁/2 about ω' δ₁/2, `ω' = 1/(2mω)` (ω² = k/m).
        let c0 = DMatrix::zeros(2, 2);
        let w = C64::new(0.0, 5.0);
        let cl = Cluster::new(&[w, w], (&m, &c0, &k)).expect("a cluster");
        let t = [
            cl.derivative((&zero, &zero, &one)),
            cl.derivative((&zero, &zero, &both)),
        ];
        let (g, q) = conservative_split(&t).expect("a conservative pair");
        let dw = 1.0 / (2.0 * 2.0 * 5.0);
        assert!(
            (g[0] - dw / 2.0).abs() < 1e-14 && (g[1] - dw).abs() < 1e-14,
            "{g:?}"
        );
        // ((ω₊ − ω₋)/2)² = (ω' δ₁/2)²: only the first variable splits.
        let expected = DMatrix::from_row_slice(2, 2, &[dw * dw / 4.0, 0.0, 0.0, 0.0]);
        assert!((&q - expected).amax() < 1e-15, "{q}");
        // Damped, it is not conservative.
        let t = [cl.derivative((&zero, &one, &zero))];
        assert!(conservative_split(&t).is_none());
        // An overflowed projection claims no split.
        let mut t = [cl.derivative((&zero, &zero, &one))];
        t[0][(0, 1)] = C64::new(f64::NAN, 0.0);
        assert!(conservative_split(&t).is_none());
        assert_eq!(
            groups(&[l, C64::new(1.0, 0.0), l * (1.0 + 1e-12)]),
            vec![vec![0, 2]]
        );
    }

    /// A Jordan block (two masses' identical roots coupled so that the eigenspace is a line)
    /// is refused, and so are roots only nearly repeated.
    #[test]
    fn a_defective_or_nearly_repeated_root_is_not_a_cluster() {
        let m = DMatrix::identity(2, 2);
        let c = DMatrix::zeros(2, 2);
        // K = [[1, 1], [0, 1]]: the double root λ² = −1 has one eigenvector.
        let k = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 0.0, 1.0]);
        let i = C64::new(0.0, 1.0);
        assert!(Cluster::new(&[i, i], (&m, &c, &k)).is_err());
        let k = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0 + 1e-7]);
        let j = C64::new(0.0, (1.0 + 1e-7_f64).sqrt());
        assert_eq!(
            Cluster::new(&[i, j], (&m, &c, &k)).err(),
            Some(NotCluster::Apart)
        );
    }
}
