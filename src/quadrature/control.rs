//! The second-order expansion of every output as a **control variate** of the many-variable
//! rule.
//!
//! With many variables the lines' transverse points are few (randomised QMC), and an output's
//! spread across them is most of its variance: integrated as it is, that spread is where the
//! error comes from. Every output at every speed already has its exact gradient `g` and Hessian
//! `H` (the second-order method's), so its expansion `q(z) = f₀ + ĝᵀz + ½ zᵀĤz` in the standard
//! normals `z` (`ĝ = Jᵀg`, `Ĥ = JᵀHJ`, `J = ∂b/∂z` at 0) has exact moments:
//!
//! `E[q − f₀] = ½ tr(HA)`, `E[(q − f₀)²] = gᵀAg + ½ tr((HA)²) + ¼ tr(HA)²`, `A = JJᵀ`.
//!
//! The rule then integrates only `f − q` and `(f − f₀)² − (q − f₀)²` (the estimator of
//! control variates with a known coefficient, Glasserman, *Monte Carlo Methods in Financial
//! Engineering*, 2004, § 4.1; with a Taylor model as the control, Lemieux, *Monte Carlo and
//! Quasi-Monte Carlo Sampling*, 2009, § 4.4): where the output is smooth over the spread the
//! residual is third order and its transverse error is small, and where it is not (a change of
//! class, a branch switch) the estimator is still exact in the limit, only its replicates
//! spread more and the rule refines. The expansion is taken in `z`, so its moments are exact for
//! uniform variables too (their map `Φ` has no second derivative at 0).
//!
//! Along one line `z = α t + z₀` the expansion is a quadratic in `t`,
//! `q − f₀ = a + b t + c t²`, so the line integrals need it only at the atoms.

use crate::tolerance::LocalModel;
use nalgebra::{DMatrix, DVector};

/// One output's expansion at one speed, in the variables `b` (the active ones): gradient,
/// Hessian, and the exact moments of `q − f₀` under `z`.
struct Expansion<'a> {
    g: DVector<f64>,
    /// The local model's Hessian (over all the study's variables: the active ones are picked
    /// by [`Control::active`]); `None` for a linear expansion.
    h: Option<&'a DMatrix<f64>>,
    /// `E[q − f₀]` and `E[(q − f₀)²]`.
    moments: (f64, f64),
    /// Along the lines' direction `d = Jα`: `gᵀd`, `Hd` and `½ dᵀHd`.
    slope: f64,
    hd: DVector<f64>,
    c: f64,
}

/// The expansion of one output along one line: `q − f₀ = a + b t + c t²`, and the exact
/// moments of `q − f₀` (the same for every line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct OnLine {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub moments: (f64, f64),
}

impl OnLine {
    /// `q − f₀` at `t`.
    pub fn at(&self, t: f64) -> f64 {
        self.a + t * (self.b + t * self.c)
    }

    /// `∫ (q − f₀) φ` and `∫ (q − f₀)² φ` over `[lo, hi]` (φ the standard normal density),
    /// in closed form.
    pub fn integrals(&self, lo: f64, hi: f64) -> (f64, f64) {
        let m = truncated_moments(lo, hi);
        let (a, b, c) = (self.a, self.b, self.c);
        (
            a * m[0] + b * m[1] + c * m[2],
            a * a * m[0]
                + 2.0 * a * b * m[1]
                + (b * b + 2.0 * a * c) * m[2]
                + 2.0 * b * c * m[3]
                + c * c * m[4],
        )
    }
}

/// `∫ tᵏ φ(t) dt` over `[lo, hi]`, k = 0…4 (by `∫ tᵏ φ = (k−1) ∫ tᵏ⁻² φ − [tᵏ⁻¹ φ]`).
fn truncated_moments(lo: f64, hi: f64) -> [f64; 5] {
    use statrs::distribution::{ContinuousCDF, Normal};
    let n = Normal::standard();
    let phi = |t: f64| (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let (pl, ph) = (phi(lo), phi(hi));
    let mut m = [0.0; 5];
    m[0] = n.cdf(hi) - n.cdf(lo);
    m[1] = pl - ph;
    for k in 2..5 {
        m[k] = (k - 1) as f64 * m[k - 2] + lo.powi(k as i32 - 1) * pl - hi.powi(k as i32 - 1) * ph;
    }
    m
}

/// The expansions of every output at every speed, and the lines they are taken along (in the
/// variables: `u = J z`).
pub(super) struct Control<'a> {
    /// `[speed][output]`; `None` where an output has no gradient there (it is then integrated
    /// as it is).
    expansions: Vec<Vec<Option<Expansion<'a>>>>,
    /// The active variables (indices into the local models' gradients), `None` where they are
    /// all of them in order.
    active: Option<Vec<usize>>,
    /// `J z₀` of every line.
    offsets: Vec<DVector<f64>>,
}

impl<'a> Control<'a> {
    /// The expansions of the local models `locals` (one per speed) in the variables `active`
    /// (indices into their gradients), mapped by `jac = ∂b/∂z` at 0, along the lines
    /// `z = α t + z₀` (`alpha`, `offsets`). The Hessians stay where they are.
    pub fn new(
        locals: &'a [Option<LocalModel>],
        active: &[usize],
        jac: &DMatrix<f64>,
        alpha: &DVector<f64>,
        offsets: &[DVector<f64>],
    ) -> Control<'a> {
        let a = jac * jac.transpose();
        let direction = jac * alpha;
        let diagonal = a
            .iter()
            .enumerate()
            .all(|(k, v)| *v == 0.0 || k % (a.nrows() + 1) == 0);
        let d = active.len();
        let expansions = locals
            .iter()
            .map(|lm| {
                let Some(lm) = lm else { return Vec::new() };
                lm.grad
                    .iter()
                    .zip(&lm.hess)
                    .map(|(g, h)| {
                        let g = g.as_ref().ok()?;
                        let g = DVector::from_iterator(d, active.iter().map(|&k| g[k]));
                        if !g.iter().all(|v| v.is_finite()) {
                            return None;
                        }
                        // Without a Hessian (or a finite one), the linear expansion.
                        let h = h.as_ref().ok().filter(|h| {
                            active
                                .iter()
                                .all(|&i| active.iter().all(|&j| h[(i, j)].is_finite()))
                        });
                        let sub =
                            h.map(|h| DMatrix::from_fn(d, d, |i, j| h[(active[i], active[j])]));
                        let sub = sub.unwrap_or_else(|| DMatrix::zeros(d, d));
                        let moments = quadratic_moments(&g, &sub, &a, diagonal);
                        let hd = &sub * &direction;
                        Some(Expansion {
                            slope: g.dot(&direction),
                            c: 0.5 * direction.dot(&hd),
                            g,
                            h,
                            moments,
                            hd,
                        })
                    })
                    .collect()
            })
            .collect();
        let all = locals.iter().flatten().next().is_none_or(|lm| {
            active.len() == lm.vars.len() && active.iter().enumerate().all(|(i, &k)| i == k)
        });
        Control {
            expansions,
            active: (!all).then(|| active.to_vec()),
            offsets: offsets.iter().map(|z0| jac * z0).collect(),
        }
    }

    /// Every one of the `outputs` expansions at `speed` along line `line` (`None` where it
    /// has none).
    pub fn on_line(&self, speed: usize, line: usize, outputs: usize) -> Vec<Option<OnLine>> {
        let row = &self.expansions[speed];
        if row.is_empty() {
            return vec![None; outputs];
        }
        let u0 = &self.offsets[line];
        row.iter()
            .map(|e| {
                let e = e.as_ref()?;
                let curvature = e.h.map_or(0.0, |h| u0.dot(&self.product(h, u0)));
                Some(OnLine {
                    a: e.g.dot(u0) + 0.5 * curvature,
                    b: e.slope + e.hd.dot(u0),
                    c: e.c,
                    moments: e.moments,
                })
            })
            .collect()
    }
}

impl Control<'_> {
    /// `H u` over the active variables.
    fn product(&self, h: &DMatrix<f64>, u: &DVector<f64>) -> DVector<f64> {
        match &self.active {
            None => h * u,
            Some(active) => DVector::from_fn(active.len(), |i, _| {
                active
                    .iter()
                    .zip(u.iter())
                    .map(|(&j, &uj)| h[(active[i], j)] * uj)
                    .sum()
            }),
        }
    }
}

/// `E[q]` and `E[q²]` of `q = gᵀu + ½ uᵀHu`, `u ~ N(0, A)`: `½ tr(HA)` and
/// `gᵀAg + ½ tr((HA)²) + ¼ tr(HA)²` (O(p²) when `A` is diagonal).
fn quadratic_moments(
    g: &DVector<f64>,
    h: &DMatrix<f64>,
    a: &DMatrix<f64>,
    diagonal: bool,
) -> (f64, f64) {
    let (trace, trace2) = if diagonal {
        let n = g.len();
        let mut trace = 0.0;
        let mut trace2 = 0.0;
        for i in 0..n {
            trace += h[(i, i)] * a[(i, i)];
            for j in 0..n {
                trace2 += h[(i, j)] * h[(j, i)] * a[(i, i)] * a[(j, j)];
            }
        }
        (trace, trace2)
    } else {
        let ha = h * a;
        (ha.trace(), ha.component_mul(&ha.transpose()).sum())
    };
    let mean = 0.5 * trace;
    let var = g.dot(&(a * g)) + 0.5 * trace2;
    (mean, var + mean * mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncated_moments_add_up_to_the_normal_ones() {
        // Over two pieces that cover the line: 1, 0, 1, 0, 3.
        let (l, r) = (truncated_moments(-40.0, 0.7), truncated_moments(0.7, 40.0));
        for (k, want) in [1.0, 0.0, 1.0, 0.0, 3.0].into_iter().enumerate() {
            assert!((l[k] + r[k] - want).abs() < 1e-14, "moment {k}");
        }
        // Against a fine midpoint rule on [−0.3, 1.9].
        let n = 200_000;
        let h = 2.2 / n as f64;
        let mut fine = [0.0; 5];
        for i in 0..n {
            let t = -0.3 + (i as f64 + 0.5) * h;
            let w = h * (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
            for (k, f) in fine.iter_mut().enumerate() {
                *f += w * t.powi(k as i32);
            }
        }
        let m = truncated_moments(-0.3, 1.9);
        for k in 0..5 {
            assert!(
                (m[k] - fine[k]).abs() < 1e-10,
                "moment {k}: {} {}",
                m[k],
                fine[k]
            );
        }
    }

    #[test]
    fn a_lines_quadratic_is_the_expansion_over_the_active_variables() {
        // Three variables, two of them active (0 and 2): along z = α t + z₀ the coefficients
        // equal the expansion in u = J z evaluated at three points, over the active block of
        // g and H only.
        use crate::output::{Output, Quantity};
        let h = DMatrix::from_row_slice(3, 3, &[2.0, 9.0, -0.3, 9.0, 7.0, 9.0, -0.3, 9.0, 0.7]);
        let lm = LocalModel {
            vars: vec![4, 5, 6],
            outputs: vec![Output {
                quantity: Quantity::DampedFrequency,
                mode: Some(0),
            }],
            value: vec![1.0],
            grad: vec![Ok(vec![0.4, 100.0, 0.3])],
            hess: vec![Ok(h.clone())],
            disc: Vec::new(),
            splits: Vec::new(),
        };
        let locals = [Some(lm)];
        let jac = DMatrix::from_row_slice(2, 2, &[0.5, 0.0, 0.2, 0.3]);
        let alpha = DVector::from_vec(vec![0.6, 0.8]);
        let z0 = DVector::from_vec(vec![-0.7, 1.3]);
        let control = Control::new(&locals, &[0, 2], &jac, &alpha, std::slice::from_ref(&z0));
        let line = control.on_line(0, 0, 1)[0].unwrap();
        let g = DVector::from_vec(vec![0.4, 0.3]);
        let hs = DMatrix::from_row_slice(2, 2, &[2.0, -0.3, -0.3, 0.7]);
        for t in [-2.0, 0.5, 3.0] {
            let u = &jac * (&alpha * t + &z0);
            let q = g.dot(&u) + 0.5 * u.dot(&(&hs * &u));
            assert!(
                (line.at(t) - q).abs() < 1e-14,
                "t = {t}: {} {q}",
                line.at(t)
            );
        }
        let a = &jac * jac.transpose();
        assert_eq!(line.moments, quadratic_moments(&g, &hs, &a, false));
    }

    #[test]
    fn moments_of_a_quadratic_match_a_tensor_rule_exact_for_its_degree() {
        // q = gᵀu + ½ uᵀHu with u = Jz, correlated: against the expectation over a fine tensor
        // Gauss–Hermite rule (exact for this degree).
        let g = DVector::from_vec(vec![0.4, -1.1, 0.3]);
        let h = DMatrix::from_row_slice(3, 3, &[2.0, 0.5, -0.3, 0.5, -1.0, 0.2, -0.3, 0.2, 0.7]);
        let jac = DMatrix::from_row_slice(3, 3, &[0.5, 0.0, 0.0, 0.2, 0.3, 0.0, -0.1, 0.4, 0.6]);
        let a = &jac * jac.transpose();
        let (m1, m2) = quadratic_moments(&g, &h, &a, false);
        // 3-point Gauss–Hermite (probabilists') per dimension integrates degree 5 exactly.
        let (x, w) = (
            [-3f64.sqrt(), 0.0, 3f64.sqrt()],
            [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
        );
        let (mut e1, mut e2) = (0.0, 0.0);
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    let z = DVector::from_vec(vec![x[i], x[j], x[k]]);
                    let u = &jac * z;
                    let q = g.dot(&u) + 0.5 * u.dot(&(&h * &u));
                    e1 += w[i] * w[j] * w[k] * q;
                    e2 += w[i] * w[j] * w[k] * q * q;
                }
            }
        }
        assert!(
            (m1 - e1).abs() < 1e-13 && (m2 - e2).abs() < 1e-13,
            "{m1} {e1} {m2} {e2}"
        );
        // The diagonal route agrees with the dense one.
        let d = DMatrix::from_diagonal(&DVector::from_vec(vec![0.3, 1.2, 0.05]));
        let (a1, a2) = quadratic_moments(&g, &h, &d, true);
        let (b1, b2) = quadratic_moments(&g, &h, &d, false);
        assert!((a1 - b1).abs() < 1e-14 && (a2 - b2).abs() < 1e-14);
    }
}
