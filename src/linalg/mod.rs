//! Small dense helpers over any [`Real`](crate::real::Real): forward-mode Jacobians, a pivoted solve, Newton's LU
//! factorisation ([`Lu`], `f64`), the choice of independent columns of a constraint Jacobian,
//! and bounded forms of nalgebra's iterative factorisations.
//!
//! nalgebra's factorisations need a `ComplexField`, which nested dual numbers are not, so the
//! few solves that must carry derivatives (the independent-coordinate basis) use this
//! elimination, pivoting on real parts.
//!
//! **Every iterative factorisation goes through this module** ([`svd`], [`schur`],
//! [`eigen_dense`], [`symmetric_eigen`], [`symmetric_definite`], [`gyroscopic`]). nalgebra's
//! plain calls iterate without bound and panic on a NaN they
//! produce themselves: entries near `f64::MAX` overflow inside the QR sweeps, after which the
//! iteration never converges (a hang) or a singular value is NaN (a panic). Here the input must be
//! finite, is scaled by a power of two (exact) so that its largest entry lies in `[½, 1)`, and the
//! iteration count is bounded (LAPACK allows 30 QR sweeps per eigenvalue; we allow
//! [`SWEEPS_PER_ROW`]). The result is unscaled; a result that overflows on unscaling is not
//! finite and the caller reports it as a failure.

mod bounded;
mod gyroscopic;
mod rank;
mod solve;

pub use bounded::{
    Definite, DenseEigen, SWEEPS_PER_ROW, WELL_CONDITIONED, eigen_dense, schur, svd, svd_real,
    symmetric_definite, symmetric_eigen,
};
pub use gyroscopic::{Gyroscopic, gyroscopic};
pub use rank::{dependent_rows, dependent_rows_after, pivot_columns};
pub use solve::{Lu, jacobian, least_squares, solve};

use nalgebra::DMatrix;

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

/// The `n`-point Gauss–Hermite rule for the standard normal density (nodes, weights adding up
/// to one): the 2- and 3-point rules in closed form, the others by Golub & Welsch (1969), the
/// eigenvalues of the Jacobi matrix of the probabilists' Hermite polynomials (off-diagonal
/// `√k`) and the squared first components of its eigenvectors.
pub fn gauss_hermite(n: usize) -> (Vec<f64>, Vec<f64>) {
    match n {
        2 => (vec![-1.0, 1.0], vec![0.5, 0.5]),
        3 => (
            vec![-3f64.sqrt(), 0.0, 3f64.sqrt()],
            vec![1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
        ),
        _ => {
            let jacobi = nalgebra::DMatrix::from_fn(n, n, |i, j| {
                if i.abs_diff(j) == 1 {
                    (i.max(j) as f64).sqrt()
                } else {
                    0.0
                }
            });
            let eig = jacobi.symmetric_eigen();
            let mut pairs: Vec<(f64, f64)> = (0..n)
                .map(|k| (eig.eigenvalues[k], eig.eigenvectors[(0, k)].powi(2)))
                .collect();
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            pairs.into_iter().unzip()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;
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
    fn dependent_rows_after_reports_the_later_duplicate_whatever_its_size() {
        // Row 1 is 100 × row 0: complete pivoting alone would keep the larger, row 1.
        let a = DMatrix::from_row_slice(3, 2, &[0.01, -0.01, 1.0, -1.0, 0.0, 1.0]);
        assert_eq!(dependent_rows(&a), vec![0]);
        assert_eq!(dependent_rows_after(&a, 1), vec![1]);
        // Rows before `first` that repeat each other are weighed among themselves (complete
        // pivoting keeps the larger).
        let b = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 2.0, 0.0, 0.0, 1.0]);
        assert_eq!(dependent_rows_after(&b, 2), vec![0]);
    }

    #[test]
    fn pivot_columns_detects_rank_deficiency() {
        let a = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 0.0, 2.0, 4.0, 0.0]);
        assert!(pivot_columns(&a).is_none());
        let a = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.1, 0.0, 0.0, 3.0]);
        assert_eq!(pivot_columns(&a), Some(vec![0, 2]));
    }

    /// The blocked SVD against nalgebra's on matrices from its threshold up: a graded matrix
    /// (singular values from 1 to 1e-9), a rank-deficient one and a wide one give the same
    /// singular values (to 1e-12 of the largest), factors that reproduce the matrix, and the
    /// same least-squares solution (as `solve` reads it).
    #[test]
    fn the_blocked_svd_agrees_with_nalgebras() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let n = bounded::BLOCKED_SVD_FROM + 9;
        let mut random =
            |r: usize, c: usize| DMatrix::from_fn(r, c, |_, _| rng.random_range(-1.0..1.0));
        let graded = {
            let (q1, q2) = (random(n, n).qr().q(), random(n, n).qr().q());
            let d = DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| {
                10f64.powf(-9.0 * i as f64 / (n - 1) as f64)
            }));
            q1 * d * q2.transpose()
        };
        let deficient = {
            let b = random(n, n - 5);
            &b * b.transpose()
        };
        for a in [graded, deficient, random(n, n + 17), random(n + 17, n)] {
            let fast = bounded::blocked_svd(&a, true, true).expect("the blocked route holds");
            let slow = svd(a.clone(), true, true).expect("decomposes");
            let top = slow.singular_values.max();
            for (x, y) in fast.singular_values.iter().zip(slow.singular_values.iter()) {
                assert!((x - y).abs() <= 1e-12 * top, "{x} against {y}");
            }
            let (u, vt) = (fast.u.clone().unwrap(), fast.v_t.clone().unwrap());
            let back = &u * DMatrix::from_diagonal(&fast.singular_values) * &vt;
            assert!((back - &a).norm() <= 1e-12 * a.norm());
            let b = DVector::from_fn(a.nrows(), |i, _| (i as f64).sin());
            let (xf, xs) = (
                fast.solve(&b, 1e-10 * top).unwrap(),
                slow.solve(&b, 1e-10 * top).unwrap(),
            );
            assert!(
                (&xf - &xs).norm() <= 1e-8 * xs.norm(),
                "{}",
                (&xf - &xs).norm() / xs.norm()
            );
            // Without vectors: the same values, no factors.
            let bare = svd_real(a, false, false).expect("decomposes");
            assert!(bare.u.is_none() && bare.v_t.is_none());
            assert_eq!(bare.singular_values, fast.singular_values);
        }
    }
}
