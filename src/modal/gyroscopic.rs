//! The modes of a conservative gyroscopic system (`M̂`, `K̂` symmetric positive definite, `Ĉ`
//! skew-symmetric and nonzero: an undamped rotor, a spinning mechanism without dampers) from
//! the Hermitian form of [`linalg::gyroscopic`], each root refined by the gyroscopic Rayleigh
//! quotient and checked by its backward error on the pencil.

use super::{C64, IM_TOL, MAX_MASS_CONDITION, Mode, Root, make_mode, normalize};
use crate::linalg;
use nalgebra::DMatrix;

/// Largest backward error `‖P(λ)x‖ / ((|λ|²‖M̂‖ + |λ|‖Ĉ‖ + ‖K̂‖)‖x‖)` (Frobenius norms;
/// Tisseur 2000, Linear Algebra Appl. 309:339) accepted from the Hermitian route; a backward
/// stable solve leaves a few `n ε`. A root above it sends the pencil to the general route.
const BACKWARD_ERROR: f64 = 1e-10;

/// The modes of `λ²M̂ + λĈ + K̂` where it is conservative gyroscopic (see
/// [`linalg::gyroscopic`]), each root `iω` with right vector `x` and left vector `x̄` (the
/// left vector of `yᵀP(λ) = 0`: `P(iω)ᵀ = P(−iω)` and `P(−iω) x̄ = conj(P(iω) x)`), its partner
/// `−iω` with the vectors swapped. `None` where the general route must decide: the pencil is
/// not of that form, a root is as close to zero as rounding (a neutral mode, which that route
/// classes), a root's backward error exceeds [`BACKWARD_ERROR`], or `M̂` is conditioned so that
/// the general route would divide by `K̂` or refuse it (see `first_order_modes`).
///
/// Each `ω` is refined on the pencil by the root of the gyroscopic Rayleigh quotient
/// `xᴴP(iω)x = k − gω − mω² = 0` (`m = xᴴM̂x`, `k = xᴴK̂x`, `ig = xᴴĈx`; Lancaster 1966,
/// *Lambda-Matrices and Vibrating Systems*, §7.2): stationary at an eigenvector, so the root
/// is the pencil's to the square of the vector's error, and on the imaginary axis. Unlike the
/// general route's two-sided step it needs no isolated root: any vector of a repeated root's
/// eigenspace is an eigenvector.
pub(super) fn gyroscopic_modes(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
) -> Option<Vec<Mode>> {
    let d = linalg::gyroscopic(m, c, k)?;
    // Where the general route would divide by K̂ (M̂ the worse conditioned) or refuse M̂.
    let mass = d.mass_condition;
    if mass > MAX_MASS_CONDITION
        || (mass > linalg::WELL_CONDITIONED && d.stiffness_condition < mass)
    {
        return None;
    }
    let n = m.nrows();
    let columns: Vec<_> = (d.vectors.column_iter())
        .map(|v| normalize(v.into_owned()))
        .collect();
    let x = DMatrix::from_fn(n, n, |i, j| columns[j][i]);
    // M̂x, Ĉx, K̂x of every root as real products, real and imaginary parts side by side.
    let parts = DMatrix::from_fn(n, 2 * n, |i, j| {
        let z = x[(i, j % n)];
        if j < n { z.re } else { z.im }
    });
    let [mx, cx, kx] = [m, c, k].map(|a| a * &parts);
    let column = |p: &DMatrix<f64>, j: usize, i: usize| C64::new(p[(i, j)], p[(i, n + j)]);
    let [nm, nc, nk] = [m, c, k].map(|a| a.norm());
    let mut frequencies = Vec::with_capacity(n);
    for (j, &w0) in d.frequencies.iter().enumerate() {
        let (mut mm, mut kk, mut gg) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let xc = x[(i, j)].conj();
            mm += (xc * column(&mx, j, i)).re;
            kk += (xc * column(&kx, j, i)).re;
            gg += (xc * column(&cx, j, i)).im;
        }
        // The positive root of k − gω − mω², without cancellation.
        let disc = (gg * gg + 4.0 * mm * kk).sqrt();
        let w1 = if gg >= 0.0 {
            2.0 * kk / (gg + disc)
        } else {
            (disc - gg) / (2.0 * mm)
        };
        let w = if w1.is_finite() && (w1 - w0).abs() <= 1e-6 * w0 {
            w1
        } else {
            w0
        };
        // ‖P(iω)x‖ = ‖K̂x − ω²M̂x + iωĈx‖, `x` of unit norm.
        let residual = (0..n)
            .map(|i| {
                let cxi = column(&cx, j, i);
                (column(&kx, j, i) - column(&mx, j, i) * (w * w) + C64::new(-cxi.im, cxi.re) * w)
                    .norm_sqr()
            })
            .sum::<f64>()
            .sqrt();
        if residual.is_nan() || residual > BACKWARD_ERROR * (w * w * nm + w * nc + nk) {
            return None;
        }
        frequencies.push(w);
    }
    let scale = frequencies
        .iter()
        .fold(0.0f64, |s, &w| s.max(w))
        .max(f64::MIN_POSITIVE);
    if frequencies.iter().any(|&w| w <= IM_TOL * scale) {
        return None;
    }
    let modes = (frequencies.iter().enumerate())
        .map(|(j, &w)| {
            let right = x.column(j).into_owned();
            let left = right.map(|z| z.conj());
            let partner = Root {
                lambda: C64::new(0.0, -w),
                right: left.clone(),
                left: right.clone(),
            };
            let root = Root {
                lambda: C64::new(0.0, w),
                right,
                left,
            };
            make_mode(root, partner, scale)
        })
        .collect();
    Some(modes)
}

#[cfg(test)]
mod tests {
    use super::super::first_order::first_order_modes;
    use super::super::rigid::RigidTest;
    use super::super::{ModeClass, similarity};
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random conservative gyroscopic pencil of size `n`: `M̂`, `K̂` symmetric positive
    /// definite, `Ĉ` skew-symmetric, of scales a rotor's (stiffness 1e6 times the mass).
    fn pencil(n: usize, seed: u64) -> [DMatrix<f64>; 3] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut r = |n| DMatrix::<f64>::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
        let (a, b, g) = (r(n), r(n), r(n));
        let m = &a * a.transpose() + DMatrix::identity(n, n) * 0.5;
        let k = (&b * b.transpose() + DMatrix::identity(n, n) * 0.1) * 1e6;
        let c = (&g - g.transpose()) * 300.0;
        [m, c, k]
    }

    /// `‖P(λ)x‖` and `‖yᵀP(λ)‖` relative to `(|λ|²‖M̂‖ + |λ|‖Ĉ‖ + ‖K̂‖)`, unit vectors.
    fn residuals(p: &[DMatrix<f64>; 3], root: &Root) -> (f64, f64) {
        let l = root.lambda;
        let [m, c, k] = p.clone().map(|a| a.map(|v| C64::new(v, 0.0)));
        let pl = m * (l * l) + c * l + k;
        let scale = l.norm_sqr() * p[0].norm() + l.norm() * p[1].norm() + p[2].norm();
        let right = (&pl * &root.right).norm() / root.right.norm();
        let left = (pl.transpose() * &root.left).norm() / root.left.norm();
        (right / scale, left / scale)
    }

    /// The Hermitian route against the first-order form on random gyroscopic pencils: the same
    /// frequencies and shapes, every mode undamped (on the axis by construction), its roots
    /// and left vectors those of the pencil, its partner the conjugate.
    #[test]
    fn gyroscopic_modes_agree_with_the_first_order_form() {
        for (n, seed) in [(5, 1), (12, 2), (30, 3)] {
            let p = pencil(n, seed);
            let [m, c, k] = &p;
            let mut fast = gyroscopic_modes(m, c, k).expect("conservative gyroscopic");
            let mut general = first_order_modes(m, c, k, &RigidTest::new(m, c, k, 0.0)).unwrap();
            for v in [&mut fast, &mut general] {
                v.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
            }
            assert_eq!(fast.len(), n);
            for (a, b) in fast.iter().zip(&general) {
                let w = a.natural_frequency;
                assert!((w - b.natural_frequency).abs() <= 1e-12 * w, "{w} vs {b:?}");
                assert_eq!(a.class, ModeClass::Undamped, "n = {n}, ω = {w}");
                assert_eq!((a.root.lambda.re, a.damping_ratio), (0.0, 0.0));
                assert!(a.partner_is_conjugate());
                assert!(similarity(&a.root.right, &b.root.right) > 1.0 - 1e-9);
                assert!(similarity(&a.root.left, &b.root.left) > 1.0 - 1e-9);
                for root in [&a.root, &a.partner] {
                    let (right, left) = residuals(&p, root);
                    assert!(
                        right < 1e-14 && left < 1e-14,
                        "ω = {w}: {right:e}, {left:e}"
                    );
                }
            }
            // Passed to `modes`, the pencil takes this route: every mode exactly on the axis.
            let out = super::super::modes(m, c, k, 0.0).unwrap();
            assert!(out.iter().all(|x| x.class == ModeClass::Undamped));
        }
    }

    /// Two identical spinning disks on isotropic tilt springs (`I_d θ̈ ± Ω I_p θ̇ + k θ = 0`
    /// about two axes each): the whirl frequencies `ω = (±Ω I_p + √(Ω²I_p² + 4 I_d k)) / 2I_d`
    /// in closed form, each twice. A repeated root's vectors are any of its eigenspace; each
    /// still satisfies the pencil.
    #[test]
    fn spinning_disks_whirl_at_their_closed_form_frequencies_twice() {
        let (id, ip, kt, spin) = (0.02, 0.035, 4.0e4, 900.0);
        let mut m = DMatrix::zeros(4, 4);
        let mut c = DMatrix::zeros(4, 4);
        let mut k = DMatrix::zeros(4, 4);
        for d in [0, 2] {
            for i in 0..2 {
                m[(d + i, d + i)] = id;
                k[(d + i, d + i)] = kt;
            }
            c[(d, d + 1)] = spin * ip;
            c[(d + 1, d)] = -spin * ip;
        }
        let out = gyroscopic_modes(&m, &c, &k).expect("conservative gyroscopic");
        let root =
            |s: f64| (s * spin * ip + ((spin * ip).powi(2) + 4.0 * id * kt).sqrt()) / (2.0 * id);
        let mut got: Vec<f64> = out.iter().map(|x| x.natural_frequency).collect();
        got.sort_by(f64::total_cmp);
        let want = [root(-1.0), root(-1.0), root(1.0), root(1.0)];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 1e-14 * w, "{g} against {w}");
        }
        let p = [m, c, k];
        for x in &out {
            let (right, left) = residuals(&p, &x.root);
            assert!(right < 1e-15 && left < 1e-15, "{right:e}, {left:e}");
        }
    }

    /// Scaling the whole pencil (a change of units of force) leaves the frequencies: down to
    /// 1e-200 and up to 1e200 the route gives them to rounding, or declines and the general
    /// route answers or refuses with its reason; no NaN, no panic.
    #[test]
    fn a_pencil_of_any_scale_keeps_its_frequencies_or_is_refused() {
        let p = pencil(8, 5);
        let want: Vec<f64> = {
            let [m, c, k] = &p;
            let out = super::super::modes(m, c, k, 0.0).unwrap();
            out.iter().map(|x| x.natural_frequency).collect()
        };
        for s in [1e-200, 1e-100, 1e100, 1e200, 1e300] {
            let [m, c, k] = p.clone().map(|a| a * s);
            if let Some(out) = gyroscopic_modes(&m, &c, &k) {
                let mut got: Vec<f64> = out.iter().map(|x| x.natural_frequency).collect();
                got.sort_by(f64::total_cmp);
                for (g, w) in got.iter().zip(&want) {
                    assert!((g - w).abs() <= 1e-12 * w, "scale {s:e}: {g} against {w}");
                }
            }
            match super::super::modes(&m, &c, &k, 0.0) {
                Ok(out) => {
                    for (g, w) in out.iter().zip(&want) {
                        let g = g.natural_frequency;
                        assert!((g - w).abs() <= 1e-10 * w, "scale {s:e}: {g} against {w}");
                    }
                }
                Err(e) => assert!(!e.to_string().is_empty()),
            }
        }
    }

    /// Only a conservative gyroscopic pencil with positive definite `M̂` and `K̂` takes the
    /// route, and only where the general route would divide by `M̂`.
    #[test]
    fn the_gyroscopic_route_refuses_other_pencils() {
        let [m, c, k] = pencil(6, 4);
        let damped = &c + DMatrix::identity(6, 6) * 1e-9 * c.amax();
        assert!(gyroscopic_modes(&m, &damped, &k).is_none());
        assert!(gyroscopic_modes(&m, &DMatrix::zeros(6, 6), &k).is_none());
        let mut asymmetric = k.clone();
        asymmetric[(0, 1)] += 1e-9 * k.amax();
        assert!(gyroscopic_modes(&m, &c, &asymmetric).is_none());
        // A negative stiffness (divergence, or gyroscopic stabilisation): the general route.
        let soft = &k - DMatrix::identity(6, 6) * 2.0 * k.amax();
        assert!(gyroscopic_modes(&m, &c, &soft).is_none());
        assert!(super::super::modes(&m, &c, &soft, 0.0).is_ok());
        // An ill-conditioned M̂ with a better conditioned K̂: the general route divides by K̂.
        let mut light = m.clone();
        light[(5, 5)] = 1e-7;
        for j in 0..5 {
            light[(5, j)] = 0.0;
            light[(j, 5)] = 0.0;
        }
        assert!(gyroscopic_modes(&light, &c, &k).is_none());
    }
}
