//! The 2n roots paired into n modes: a complex root with its conjugate, real roots by the
//! similarity of their right vectors, zero roots with the decays of `K̂`'s null space first.

use super::rigid::RigidTest;
use super::tracking::similarities;
use super::{C64, Mode, Root, make_mode};
use nalgebra::DVector;

/// The modes of the roots with `Im λ ≥ 0` ([`FirstOrderForm::roots`]): each complex root with
/// its conjugate, in the roots' order, then the real roots paired ([`pair_real_roots`]).
pub(super) fn pair_roots(roots: Vec<Root>, scale: f64, rigid: &RigidTest) -> Vec<Mode> {
    let mut out = Vec::new();
    let mut real: Vec<Root> = Vec::new();
    for r in roots {
        if r.lambda.im > 0.0 {
            let conj = Root {
                lambda: r.lambda.conj(),
                right: r.right.map(|z| z.conj()),
                left: r.left.map(|z| z.conj()),
            };
            out.push(make_mode(r, conj, scale));
        } else if r.lambda.im == 0.0 {
            real.push(r);
        }
    }
    pair_real_roots(real, scale, rigid, &mut out);
    out
}

/// Pairs the real roots `real` into modes (pushed onto `out`), the larger real part first in
/// each: zero roots with decays of `K̂`'s null space first, then by the similarity of their
/// right vectors (see the comment within).
fn pair_real_roots(real: Vec<Root>, scale: f64, rigid: &RigidTest, out: &mut Vec<Mode>) {
    // Pair real roots whose right vectors are most alike: greedily, the most alike pair of
    // those left first. Where several directions are held by nothing (a rod spinning about its
    // own axis on a cone that may precess), rounding often gives their zero roots one shared
    // vector (a pair snapped to the real axis), more alike to each other than to the
    // directions' decays `−c/m`, whose vectors lie in `K̂`'s null space too: each zero root
    // is paired with such a decay first (each rigid direction is one mode, its zero and its
    // decay), so that two zeros and two decays do not make a double-zero rigid mode and a
    // spurious overdamped one.
    let rights: Vec<DVector<C64>> = real.iter().map(|r| r.right.clone()).collect();
    let s = similarities(&rights, &rights);
    let zero: Vec<bool> = real.iter().map(|r| rigid.zero(r)).collect();
    let decay: Vec<bool> = match zero
        .iter()
        .any(|&z| z)
        .then(|| rigid.null_space())
        .flatten()
    {
        Some(null) => (real.iter().zip(&zero))
            .map(|(r, &z)| !z && RigidTest::share(&null, &r.right) >= 0.5)
            .collect(),
        None => vec![false; real.len()],
    };
    // 1 for a zero root and a decay of the null space, else 0.
    let rank = |a: usize, b: usize| u8::from((zero[a] && decay[b]) || (zero[b] && decay[a]));
    let mut pairs: Vec<(usize, usize)> = (0..real.len())
        .flat_map(|i| (i + 1..real.len()).map(move |j| (i, j)))
        .collect();
    // Stable: equal similarities in the order of the roots.
    pairs.sort_by(|&(a, b), &(c, d)| {
        rank(c, d)
            .cmp(&rank(a, b))
            .then(s[(c, d)].total_cmp(&s[(a, b)]))
    });
    let mut real: Vec<Option<Root>> = real.into_iter().map(Some).collect();
    for (i, j) in pairs {
        if real[i].is_none() || real[j].is_none() {
            continue;
        }
        let (a, b) = (real[i].take(), real[j].take());
        let (a, b) = (a.expect("unpaired"), b.expect("unpaired"));
        let (hi, lo) = if a.lambda.re >= b.lambda.re {
            (a, b)
        } else {
            (b, a)
        };
        out.push(make_mode(hi, lo, scale));
    }
}
