//! The Sobol indices against exact indices, and their intervals' coverage.

use super::*;

/// The receptance magnitude of one degree of freedom, `|H| = 1/|k − mω² + icω|`, with
/// `m`, `k`, `c` normal about 1, 1, 0.1 (σ 5 %, 5 %, 20 %), near resonance: skewed and
/// far from additive, as |H| is.
fn receptance(omega: f64) -> impl Fn(&[f64; 3]) -> f64 {
    move |z| {
        let (m, k, c) = (
            1.0 + 0.05 * z[0],
            1.0 + 0.05 * z[1],
            0.1 * (1.0 + 0.2 * z[2]),
        );
        1.0 / ((k - m * omega * omega).powi(2) + (c * omega).powi(2)).sqrt()
    }
}

/// The exact first-order and total indices by a 40-point Gauss–Hermite tensor rule:
/// `S_i = Var(E[f|x_i])/V`, `S_Ti = E[Var(f|x_~i)]/V`.
fn exact(f: &impl Fn(&[f64; 3]) -> f64) -> [(f64, f64); 3] {
    const P: usize = 40;
    let (x, w) = crate::linalg::gauss_hermite(P);
    let at = |i: usize, k: usize, p: usize, q: usize| -> [usize; 3] {
        match i {
            0 => [k, p, q],
            1 => [p, k, q],
            _ => [p, q, k],
        }
    };
    let mut vals = vec![0.0; P * P * P];
    for a in 0..P {
        for b in 0..P {
            for c in 0..P {
                vals[(a * P + b) * P + c] = f(&[x[a], x[b], x[c]]);
            }
        }
    }
    let v = |n: [usize; 3]| vals[(n[0] * P + n[1]) * P + n[2]];
    let (mut m1, mut m2) = (0.0, 0.0);
    for a in 0..P {
        for b in 0..P {
            for c in 0..P {
                let wt = w[a] * w[b] * w[c];
                m1 += wt * v([a, b, c]);
                m2 += wt * v([a, b, c]).powi(2);
            }
        }
    }
    let var = m2 - m1 * m1;
    std::array::from_fn(|i| {
        let (mut c1, mut c2, mut total) = (0.0, 0.0, 0.0);
        for k in 0..P {
            let mut cond = 0.0;
            for p in 0..P {
                for q in 0..P {
                    cond += w[p] * w[q] * v(at(i, k, p, q));
                }
            }
            c1 += w[k] * cond;
            c2 += w[k] * cond * cond;
        }
        for p in 0..P {
            for q in 0..P {
                let (mut s1, mut s2) = (0.0, 0.0);
                for (k, wk) in w.iter().enumerate() {
                    let y = v(at(i, k, p, q));
                    s1 += wk * y;
                    s2 += wk * y * y;
                }
                total += w[p] * w[q] * (s2 - s1 * s1);
            }
        }
        ((c2 - c1 * c1) / var, total / var)
    })
}

/// Over `reps` independent pick-freeze estimates with `n` rows: how often each kind of
/// interval misses the exact index, `(first, total)`, out of `3 reps`.
fn misses(f: &impl Fn(&[f64; 3]) -> f64, n: usize, reps: usize, seed: u64) -> (usize, usize) {
    let exact = exact(f);
    let normal = Normal::standard();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut z = || normal.inverse_cdf(rng.random::<f64>().clamp(1e-12, 1.0 - 1e-12));
    let (mut first, mut total) = (0, 0);
    for _ in 0..reps {
        let a: Vec<[f64; 3]> = (0..n).map(|_| [z(), z(), z()]).collect();
        let b: Vec<[f64; 3]> = (0..n).map(|_| [z(), z(), z()]).collect();
        for (i, e) in exact.iter().enumerate() {
            let rows: Vec<(f64, f64, f64)> = (0..n)
                .map(|j| {
                    let mut ab = a[j];
                    ab[i] = b[j][i];
                    (f(&a[j]), f(&b[j]), f(&ab))
                })
                .collect();
            let (_, _, fc, tc) = estimate(&rows).unwrap();
            first += usize::from(!(fc.0 <= e.0 && e.0 <= fc.1));
            total += usize::from(!(tc.0 <= e.1 && e.1 <= tc.1));
        }
    }
    (first, total)
}

/// The Wilson score interval (z = 2.576, 99 %) of a proportion `k/n`.
fn wilson99(k: usize, n: usize) -> (f64, f64) {
    let (z, n, p) = (2.576, n as f64, k as f64 / n as f64);
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    (centre - half, centre + half)
}

/// The 95 % intervals of |H|'s indices hold the exact ones 95 % of the time: over 2400
/// intervals of each kind (|H| below and above resonance, three variables, 400
/// repetitions), the 99 % interval of the miss rate holds 5 %: the first-order indices'
/// at `N` = 256 (the bootstrap percentile intervals used before missed 7 % there, which
/// this refuses), the totals' at `N` = 1024 (at 256 they miss about 7 %: the estimator's
/// skew is not yet normal).
#[test]
fn intervals_of_a_resonant_magnitude_cover_the_exact_indices_at_their_level() {
    for (n, kind) in [(256, 0), (1024, 1)] {
        let (mut missed, mut count) = (0, 0);
        for (omega, seed) in [(0.95, 1), (1.05, 2)] {
            let m = misses(&receptance(omega), n, 400, seed);
            missed += [m.0, m.1][kind];
            count += 3 * 400;
        }
        let w = wilson99(missed, count);
        let what = ["first-order", "total"][kind];
        eprintln!("{what} at N = {n}: {missed} of {count} missed, 99 % interval {w:?}");
        assert!(
            w.0 <= 0.05 && 0.05 <= w.1,
            "{what}: {missed} of {count} missed"
        );
    }
}

/// The delete-one jackknife from the sums equals the one recomputed from the rows left.
#[test]
fn the_jackknife_from_sums_equals_the_estimates_recomputed() {
    let f = receptance(1.0);
    let rows: Vec<(f64, f64, f64)> = (0..7)
        .map(|j| {
            let x = j as f64 * 0.37 - 1.0;
            (f(&[x, 0.3, -x]), f(&[-x, x, 0.5]), f(&[x, x, -x]))
        })
        .collect();
    let direct = |r: &[(f64, f64, f64)]| {
        let n = r.len() as f64;
        let mean = r.iter().map(|x| x.0 + x.1).sum::<f64>() / (2.0 * n);
        let var = r
            .iter()
            .map(|x| (x.0 - mean).powi(2) + (x.1 - mean).powi(2))
            .sum::<f64>()
            / (2.0 * n);
        let first = r.iter().map(|x| (x.1 - mean) * (x.2 - x.0)).sum::<f64>() / n / var;
        let total = r.iter().map(|x| (x.0 - x.2).powi(2)).sum::<f64>() / (2.0 * n) / var;
        (first, total)
    };
    let (first, total, fc, _) = estimate(&rows).unwrap();
    let whole = direct(&rows);
    assert!((first - whole.0).abs() < 1e-12 && (total - whole.1).abs() < 1e-12);
    let left: Vec<f64> = (0..rows.len())
        .map(|j| {
            let mut r = rows.clone();
            r.remove(j);
            direct(&r).0
        })
        .collect();
    let n = rows.len() as f64;
    let m = left.iter().sum::<f64>() / n;
    let se = ((n - 1.0) / n * left.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt();
    assert!((fc.1 - fc.0 - 2.0 * Z95 * se).abs() < 1e-10, "{fc:?} {se}");
}
