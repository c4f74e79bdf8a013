//! Modes followed across speeds and samples by the similarity of their shapes.

use super::cluster::groups;
use super::{C64, Mode};
use nalgebra::{DMatrix, DVector};

/// |aᴴ b| / (|a| |b|): 1 for parallel vectors.
pub fn similarity(a: &DVector<C64>, b: &DVector<C64>) -> f64 {
    let d = a.dotc(b).norm();
    d / (a.norm() * b.norm()).max(f64::MIN_POSITIVE)
}

/// [`similarity`] of every vector of `a` (rows) with every vector of `b` (columns), all of one
/// length, with each norm computed once; from 16 384 multiply-adds on (`PRODUCTS_FROM`), the
/// normalised vectors' products `Aᴴ B` by four real matrix products. Pairing and tracking
/// compare every mode with every mode; one [`similarity`] call each made that O(n³) with the
/// norms recomputed in every call (a 480-segment chain with overdamped modes spent a minute
/// pairing its real roots).
pub fn similarities(a: &[DVector<C64>], b: &[DVector<C64>]) -> DMatrix<f64> {
    let len = a.iter().chain(b).next().map_or(0, |v| v.len());
    let inverse_norms = |v: &[DVector<C64>]| -> Vec<f64> {
        v.iter()
            .map(|x| {
                let n = x.norm();
                if n > 0.0 { 1.0 / n } else { 0.0 }
            })
            .collect()
    };
    let (sa, sb) = (inverse_norms(a), inverse_norms(b));
    if a.len() * b.len() * len < PRODUCTS_FROM {
        return DMatrix::from_fn(a.len(), b.len(), |i, j| {
            a[i].dotc(&b[j]).norm() * sa[i] * sb[j]
        });
    }
    let parts = |v: &[DVector<C64>], scale: &[f64]| {
        (
            DMatrix::from_fn(len, v.len(), |i, j| v[j][i].re * scale[j]),
            DMatrix::from_fn(len, v.len(), |i, j| v[j][i].im * scale[j]),
        )
    };
    let ((ar, ai), (br, bi)) = (parts(a, &sa), parts(b, &sb));
    // Transposed first: `*` runs the blocked product, `tr_mul` a dot product per entry.
    let (ar, ai) = (ar.transpose(), ai.transpose());
    let re = &ar * &br + &ai * &bi;
    let im = &ar * &bi - &ai * &br;
    re.zip_map(&im, f64::hypot)
}

/// Size (vectors × vectors × length) from which [`similarities`] multiplies matrices: below,
/// setting the products up costs more than they save (a one-mode model's tracking took 0.4 µs
/// a speed by products, 0.05 µs by dot products).
const PRODUCTS_FROM: usize = 1 << 14;

/// `items` in the order `order` (a permutation of their indices).
pub fn permute<T>(items: Vec<T>, order: &[usize]) -> Vec<T> {
    let mut items: Vec<Option<T>> = items.into_iter().map(Some).collect();
    order
        .iter()
        .map(|&i| items[i].take().expect("a permutation"))
        .collect()
}

/// For each reference mode shape, the index of the most similar shape of `cur` (as many; greedy on the
/// largest similarity first): tracks modes across speeds and matches a sample's modes to the
/// nominal ones.
pub fn match_shapes(prev: &[DVector<C64>], cur: &[DVector<C64>]) -> Vec<usize> {
    greedy(&similarities(prev, cur))
}

/// For each row of the similarities `s` (reference × current), the column it is matched to:
/// greedy on the largest similarity first, each column taken once (`usize::MAX` where none is
/// left).
fn greedy(s: &DMatrix<f64>) -> Vec<usize> {
    let (n, m) = s.shape();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(n * m);
    for i in 0..n {
        for j in 0..m {
            pairs.push((s[(i, j)], i, j));
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out = vec![usize::MAX; n];
    let mut used = vec![false; m];
    for (_, i, j) in pairs {
        if out[i] == usize::MAX && !used[j] {
            out[i] = j;
            used[j] = true;
        }
    }
    out
}

/// [`similarity`] in the metric of the mass matrix `mass` (symmetric, positive semi-definite):
/// `|aᴴMb| / √(aᴴMa · bᴴMb)`, every vector of `a` (rows) with every vector of `b` (columns).
/// An undamped system's modes are orthogonal in it, however unlike their coordinates' units
/// and inertias: a shaft's bending modes share translations in metres with rotations in
/// radians, and two of its modes a decade apart can be 0.96 alike in the plain metric.
fn similarities_in(mass: &DMatrix<f64>, a: &[DVector<C64>], b: &[DVector<C64>]) -> DMatrix<f64> {
    let weighted = |v: &DVector<C64>| -> DVector<C64> {
        let (re, im) = (mass * v.map(|z| z.re), mass * v.map(|z| z.im));
        re.zip_map(&im, C64::new)
    };
    let ma: Vec<DVector<C64>> = a.iter().map(weighted).collect();
    let norm = |v: &DVector<C64>, mv: &DVector<C64>| v.dotc(mv).norm().sqrt();
    let na: Vec<f64> = a.iter().zip(&ma).map(|(v, mv)| norm(v, mv)).collect();
    let nb: Vec<f64> = b.iter().map(|v| norm(v, &weighted(v))).collect();
    DMatrix::from_fn(a.len(), b.len(), |i, j| {
        ma[i].dotc(&b[j]).norm() / (na[i] * nb[j]).max(f64::MIN_POSITIVE)
    })
}

/// The modes `cur` matched to the modes `reference` (with their shapes in the free coordinates
/// and the reference's mass matrix over them): for each reference mode, the index of its match
/// in `cur`. Shapes decide, compared in the mass metric (`similarities_in`), except within a
/// cluster of repeated reference roots ([`super::cluster::groups`]): there the reference's
/// shapes are any basis of the eigenspace, so the cluster's matches are told apart by their
/// values instead, taken by the members in the order of ω_d, then of the root's real part.
/// So a member of a double root is the lower or the upper of the pair the perturbation makes
/// of it, in a sample as in a finite difference.
pub fn match_modes(
    (reference, shapes, mass): (&[Mode], &[DVector<C64>], &DMatrix<f64>),
    (cur, cur_shapes): (&[Mode], &[DVector<C64>]),
) -> Vec<usize> {
    let mut order = greedy(&similarities_in(mass, shapes, cur_shapes));
    let roots: Vec<C64> = reference.iter().map(|m| m.root.lambda).collect();
    for members in groups(&roots) {
        let mut matched: Vec<usize> = members.iter().map(|&i| order[i]).collect();
        if matched.iter().any(|&j| j >= cur.len()) {
            continue;
        }
        let key = |j: usize| (cur[j].damped_frequency, cur[j].root.lambda.re);
        matched.sort_by(|&a, &b| {
            let ((fa, ra), (fb, rb)) = (key(a), key(b));
            fa.total_cmp(&fb).then(ra.total_cmp(&rb)).then(a.cmp(&b))
        });
        for (&i, j) in members.iter().zip(matched) {
            order[i] = j;
        }
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn all_similarities_at_once_agree_with_each_pair() {
        // Both routes (dot products, and matrix products for many long vectors) against each
        // pair's `|xᴴy|/(|x||y|)`, with a zero vector (similar to nothing), a parallel pair and
        // vectors of very different sizes.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (len, extra) in [(9, 1), (64, 20)] {
            let mut v = |scale: f64| {
                DVector::from_fn(len, |_, _| {
                    C64::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale
                })
            };
            let mut a: Vec<DVector<C64>> = vec![v(1.0), v(1e-150), DVector::zeros(len), v(1e150)];
            let mut b: Vec<DVector<C64>> =
                vec![v(3.0), a[0].map(|z| z * C64::new(0.0, -2.0)), v(1e-9)];
            for _ in 0..extra {
                a.push(v(1.0));
                b.push(v(0.5));
            }
            assert_eq!(
                a.len() * b.len() * len >= PRODUCTS_FROM,
                len == 64,
                "the two cases take the two routes"
            );
            let s = similarities(&a, &b);
            assert_eq!(s.shape(), (a.len(), b.len()));
            for (i, x) in a.iter().enumerate() {
                for (j, y) in b.iter().enumerate() {
                    let (nx, ny) = (x.norm(), y.norm());
                    let pairwise = if nx > 0.0 {
                        (x / C64::from(nx)).dotc(&(y / C64::from(ny))).norm()
                    } else {
                        0.0
                    };
                    assert!((s[(i, j)] - pairwise).abs() < 1e-14, "{len}: {i} {j}");
                }
            }
            assert!((s[(0, 1)] - 1.0).abs() < 1e-15);
            assert!(
                s.row(2).iter().all(|&v| v == 0.0),
                "a zero vector is similar to nothing"
            );
        }
    }
}
