//! Analytic propagation of tolerances to the modal outputs (Kim & Yoo 2007, eq. 28, and beyond).
//!
//! At each speed a [`LocalModel`] holds every output's value, its exact gradient with respect to
//! the design variables (automatic differentiation through the equilibrium) and its exact Hessian
//! (hyper-dual numbers through the equilibrium and the eigenproblem, [`crate::hessian`]).
//! With the covariance `Σ` of the design variables (tolerance `T` read as ±3σ of a normal
//! distribution, or as the half-width of a uniform one, σ = T/√3; optional correlations):
//!
//! ```text
//! first_order:   mean = f(b₀),                 σ² = gᵀ Σ g                  (paper eq. 28)
//! second_order:  mean = f(b₀) + ½ tr(H Σ),     σ² = gᵀ Σ g + ½ tr(H Σ H Σ)  (normal variables)
//! invariant:     D = λ₁λ₂ − (λ₁+λ₂)²/4 propagated to second order, taken as normal, and mapped
//!                through ω_d = √max(0, D) exactly (E[max(0, D)] in closed form, E[√max(0, D)]
//!                by quadrature)
//! ```
//!
//! `first_order` is the paper's method: where ω_d has a kink (a mode turning overdamped) or an
//! output is stationary in the variables (|H| at the undamped resonance) it gives a spread of
//! zero or none at all. `second_order` repairs stationary points; `invariant` repairs the kink,
//! because the pair invariants λ₁+λ₂ and λ₁λ₂ (hence D) stay smooth where the roots coalesce.
//! For uniform variables without correlations the second-order variance uses their fourth moment
//! (`μ₄ = 9σ⁴/5`) instead of the normal one.
//!
//! # Reference
//! Kim, Yoo (2007) eq. 28; Kendall & Stuart, *The Advanced Theory of Statistics*, §10.6 (moments
//! of quadratic forms in normal variables).

use crate::compiled::Compiled;
use crate::modal::cluster::Split;
use crate::modal::{Smoothness, smoothness};
use crate::model::{Case, Distribution};
use crate::output::Missing;
use crate::pair;
use crate::sensitivity::{DesignPoint, Status, TransferAt};
use crate::sweep::{Point, PointError};
use nalgebra::DMatrix;

use crate::output::{Output, Quantity, outputs};

/// Value of an output at a point (modes in the point's order); `None` if not defined.
pub fn value(pt: &Point, o: &Output, tf: Option<TransferAt>) -> Option<f64> {
    match (o.quantity, o.mode) {
        (Quantity::DampedFrequency, Some(m)) => pt.modes.get(m).map(|x| x.damped_frequency),
        (Quantity::DampingRatio, Some(m)) => pt.modes.get(m).map(|x| x.damping_ratio),
        (Quantity::TransferMagnitude, _) => tf
            .and_then(|t| crate::sensitivity::nominal_transfer(pt, &t))
            .map(|h| h.magnitude()),
        _ => None,
    }
    .filter(|v| v.is_finite())
}

/// A scalar's value, gradient and Hessian (each, where it does not exist, the reason).
pub type Expansion = (
    f64,
    Result<Vec<f64>, Missing>,
    Result<DMatrix<f64>, Missing>,
);

/// Outputs, gradients and Hessians at one speed.
#[derive(Debug, Clone)]
pub struct LocalModel {
    /// Design variables (parameter indices), the order of gradients and Hessians.
    pub vars: Vec<usize>,
    pub outputs: Vec<Output>,
    /// NaN where the output has no value (the damping ratio of a rigid-body mode, |H| at an
    /// undamped resonance).
    pub value: Vec<f64>,
    /// The reason where the output is not differentiable (a mode changing class, a repeated
    /// root, a rigid-body mode, |H| through zero).
    pub grad: Vec<Result<Vec<f64>, Missing>>,
    pub hess: Vec<Result<DMatrix<f64>, Missing>>,
    /// Per mode: the discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4` (ω_d = √max(0, D)), its gradient
    /// and Hessian.
    pub disc: Vec<Expansion>,
    /// The conservative double roots that the variables split, to first order ([`Split`]):
    /// their members' ω_d have no gradient, but a first-order distribution
    /// ([`split_first_order`]).
    pub splits: Vec<Split>,
}

type FirstOrder = (
    Vec<f64>,
    Vec<Result<Vec<f64>, Missing>>,
    Vec<(f64, Result<Vec<f64>, Missing>)>,
    Vec<Split>,
);

/// Reorders the modes of `q` to match those of `reference` ([`crate::modal::match_modes`]).
pub fn match_modes(reference: &Point, mut q: Point) -> Point {
    if q.modes.len() != reference.modes.len() {
        return q;
    }
    let order = crate::modal::match_modes(
        (
            &reference.modes,
            &reference.shapes,
            &reference.linear.m_full,
        ),
        (&q.modes, &q.shapes),
    );
    q.modes = crate::modal::permute(std::mem::take(&mut q.modes), &order);
    q.shapes = crate::modal::permute(std::mem::take(&mut q.shapes), &order);
    q
}

impl DesignPoint<'_> {
    /// The local model at the point for design variables `vars`; with `hessian`, also the exact
    /// Hessians (hyper-dual numbers, see [`crate::hessian`]).
    pub fn local_model(&self, vars: &[usize], hessian: bool) -> Result<LocalModel, PointError> {
        let (pt, tf) = (self.point, self.transfer);
        let outs = outputs(pt.modes.len(), tf.is_some());
        if !hessian {
            let (value, grad, disc0, splits) = self.first(vars, &outs)?;
            return Ok(LocalModel {
                vars: vars.to_vec(),
                hess: grad
                    .iter()
                    .map(|g| g.clone().and(Err(Missing::NotComputed)))
                    .collect(),
                outputs: outs,
                value,
                grad,
                disc: disc0
                    .into_iter()
                    .map(|(v, g)| {
                        let h = g.clone().and(Err(Missing::NotComputed));
                        (v, g, h)
                    })
                    .collect(),
                splits,
            });
        }
        // Gradients and Hessians together from the second-order passes; the splits of double
        // roots from the first-order ones, where there are repeated roots.
        let h = self.hessians(vars, &outs)?;
        let repeated =
            (smoothness(&pt.modes).iter()).any(|s| matches!(s, Smoothness::Repeated { .. }));
        let splits = if repeated {
            self.analytic_with_splits(vars)?.1
        } else {
            Vec::new()
        };
        let value = outs
            .iter()
            .map(|o| value(pt, o, tf).unwrap_or(f64::NAN))
            .collect();
        Ok(LocalModel {
            vars: vars.to_vec(),
            outputs: outs,
            value,
            grad: h.gradients,
            hess: h.outputs,
            disc: discriminants(pt)
                .into_iter()
                .zip(h.discriminant_gradients)
                .zip(h.discriminant)
                .map(|((v, g), h)| (v, g, h))
                .collect(),
            splits,
        })
    }

    /// Adds the exact Hessians (and the gradients of the same passes' discriminants' Hessians)
    /// to a first-order local model `lm` of the point ([`DesignPoint::local_model`] without them): the
    /// second-order stage of a study. Where the second-order passes fail, every Hessian says why
    /// and the first-order model stays.
    pub fn add_hessians(&self, lm: &mut LocalModel) {
        match self.hessians(&lm.vars, &lm.outputs) {
            Ok(h) => {
                lm.hess = h.outputs;
                for (d, h) in lm.disc.iter_mut().zip(h.discriminant) {
                    d.2 = h;
                }
            }
            Err(e) => {
                let why = Missing::Failed(format!("second-order derivatives: {e}"));
                lm.hess.iter_mut().for_each(|h| *h = Err(why.clone()));
                lm.disc.iter_mut().for_each(|d| d.2 = Err(why.clone()));
            }
        }
    }

    /// Values and exact gradients of `outs`, and each mode's discriminant with its gradient.
    fn first(&self, vars: &[usize], outs: &[Output]) -> Result<FirstOrder, PointError> {
        let (pt, tf) = (self.point, self.transfer);
        let (s, splits) = self.analytic_with_splits(vars)?;
        let smooth = smoothness(&pt.modes);
        let finite = |g: Vec<f64>| {
            if g.iter().all(|x| x.is_finite()) {
                Ok(g)
            } else {
                Err(Missing::NotFinite)
            }
        };
        let mut values = Vec::with_capacity(outs.len());
        let mut grads = Vec::with_capacity(outs.len());
        for o in outs {
            values.push(value(pt, o, tf).unwrap_or(f64::NAN));
            let g: Result<Vec<f64>, Missing> = s
                .variables
                .iter()
                .map(|v| match (o.quantity, o.mode) {
                    (Quantity::TransferMagnitude, _) => {
                        v.d_transfer_magnitude
                            .ok_or(if s.transfer_magnitude.is_some() {
                                Missing::TransferZero
                            } else {
                                Missing::TransferUnbounded
                            })
                    }
                    (q, Some(m)) => {
                        let ms = &v.modes[m];
                        if smooth[m] == Smoothness::Rigid && q == Quantity::DampingRatio {
                            Err(Missing::RigidDamping { mode: m })
                        } else if ms.status == Status::Ok {
                            Ok(if q == Quantity::DampedFrequency {
                                ms.d_damped_frequency
                            } else {
                                ms.d_damping_ratio
                            })
                        } else {
                            Err(Missing::Mode {
                                mode: m,
                                why: smooth[m],
                            })
                        }
                    }
                    _ => Err(Missing::NoValue),
                })
                .collect::<Result<Vec<f64>, Missing>>()
                .and_then(finite);
            grads.push(g);
        }
        let discs = pt
            .modes
            .iter()
            .zip(discriminants(pt))
            .enumerate()
            .map(|(k, (m, d))| {
                let sum = (m.root.lambda + m.partner.lambda).re;
                let g: Vec<f64> = s
                    .variables
                    .iter()
                    .map(|v| v.modes[k].d_product - 0.5 * sum * v.modes[k].d_sum)
                    .collect();
                // A repeated root's discriminant where its cluster moves as one.
                let split = (s.variables.iter()).any(|v| v.modes[k].status != Status::Ok);
                let g = match smooth[k] {
                    Smoothness::Rigid => Err(Missing::Mode {
                        mode: k,
                        why: smooth[k],
                    }),
                    Smoothness::Repeated { .. } if split => Err(Missing::Mode {
                        mode: k,
                        why: smooth[k],
                    }),
                    _ => finite(g),
                };
                (d, g)
            })
            .collect();
        Ok((values, grads, discs, splits))
    }
}

/// Each mode's discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4` at a point.
fn discriminants(pt: &Point) -> Vec<f64> {
    pt.modes
        .iter()
        .map(|m| {
            let (l1, l2) = (m.root.lambda, m.partner.lambda);
            pair::discriminant((l1 + l2).re, (l1 * l2).re)
        })
        .collect()
}

/// The spread of the design variables in one tolerance case.
#[derive(Debug, Clone)]
pub struct Spread {
    /// Standard deviation of each design variable (0 when the case leaves it at nominal).
    pub sigma: Vec<f64>,
    pub distribution: Vec<Distribution>,
    /// Correlation matrix (identity unless the case gives one).
    pub correlation: DMatrix<f64>,
    pub covariance: DMatrix<f64>,
}

impl Spread {
    /// The spread of `vars` under `case` (tolerances not in the case are zero).
    pub fn new(model: &Compiled, case: &Case, vars: &[usize]) -> Spread {
        let n = vars.len();
        let mut sigma = vec![0.0; n];
        let mut distribution = vec![Distribution::Normal; n];
        for (i, &b) in vars.iter().enumerate() {
            let par = &model.model().parameters[b];
            distribution[i] = par.distribution;
            if let Some((_, t)) = case.tolerances.iter().find(|(p, _)| *p == b) {
                let half = t.absolute(par.value);
                sigma[i] = match par.distribution {
                    Distribution::Normal => half / 3.0,
                    Distribution::Uniform => half / 3f64.sqrt(),
                };
            }
        }
        let mut correlation = DMatrix::identity(n, n);
        if let Some(c) = &case.correlation {
            for (a, &pa) in c.params.iter().enumerate() {
                for (bb, &pb) in c.params.iter().enumerate() {
                    if let (Some(i), Some(j)) = (
                        vars.iter().position(|&v| v == pa),
                        vars.iter().position(|&v| v == pb),
                    ) {
                        correlation[(i, j)] = c.matrix[a][bb];
                    }
                }
            }
        }
        let covariance = DMatrix::from_fn(n, n, |i, j| sigma[i] * correlation[(i, j)] * sigma[j]);
        Spread {
            sigma,
            distribution,
            correlation,
            covariance,
        }
    }

    fn independent(&self) -> bool {
        (&self.correlation - DMatrix::identity(self.sigma.len(), self.sigma.len())).amax() == 0.0
    }
}

/// Mean and standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stat {
    pub mean: f64,
    pub std: f64,
}

/// First order (the paper's method): mean = value, σ² = gᵀΣg; shares `gᵢ (Σg)ᵢ / σ²` (each
/// variable's share of the variance; for independent variables `gᵢ²σᵢ²/σ²`).
pub fn first_order(value: f64, grad: &[f64], s: &Spread) -> (Stat, Vec<f64>) {
    let n = grad.len();
    let sg: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| s.covariance[(i, j)] * grad[j]).sum())
        .collect();
    let var: f64 = (0..n).map(|i| grad[i] * sg[i]).sum();
    let shares = (0..n)
        .map(|i| {
            if var > 0.0 {
                // `+ 0.0`: a variable without influence has share 0, not −0.
                grad[i] * sg[i] / var + 0.0
            } else {
                0.0
            }
        })
        .collect();
    (
        Stat {
            mean: value,
            std: sigma_of(var),
        },
        shares,
    )
}

/// First order at a split double root ([`Split`]): the member's ω_d is `ω₀ + gᵀz ± √(zᵀQz)`
/// (`upper`: `+`) with `z` the variables' deviations, normal with covariance `Σ`. By the
/// symmetry `z → −z`, which keeps `√(zᵀQz)` and reverses `gᵀz`:
///
/// ```text
/// mean = ω₀ ± E√(zᵀQz),   σ² = gᵀΣg + tr(QΣ) − (E√(zᵀQz))²
/// ```
///
/// with `E√(zᵀQz)` from the eigenvalues of `Σ^½ Q Σ^½` ([`expected_root`]). Each variable's
/// share: its share of `gᵀΣg` as in [`first_order`], plus the split's variance apportioned by
/// its part `(QΣ)ᵢᵢ` of `tr(QΣ)`. `None` where a variable that moves the pair is not normal
/// (the expectation of the root is then not the normal one's).
pub fn split_first_order(
    value: f64,
    split: &Split,
    upper: bool,
    s: &Spread,
) -> Option<(Stat, Vec<f64>)> {
    let n = split.mean.len();
    let moves = |i: usize| split.mean[i] != 0.0 || split.split.row(i).iter().any(|&v| v != 0.0);
    if (0..n).any(|i| moves(i) && s.sigma[i] > 0.0 && s.distribution[i] != Distribution::Normal) {
        return None;
    }
    let (linear, shares) = first_order(0.0, &split.mean, s);
    let linear = linear.std.powi(2);
    let qs = &split.split * &s.covariance;
    let trace = qs.trace();
    // Σ^½ Q Σ^½ from Σ's eigendecomposition (Σ may be singular: variables left at nominal).
    let eig = s.covariance.clone().symmetric_eigen();
    let root = &eig.eigenvectors
        * DMatrix::from_diagonal(&eig.eigenvalues.map(|v| v.max(0.0).sqrt()))
        * eig.eigenvectors.transpose();
    let form = &root * &split.split * &root;
    let q: Vec<f64> = (form.clone() + form.transpose())
        .scale(0.5)
        .symmetric_eigenvalues()
        .iter()
        .map(|&v| v.max(0.0))
        .collect();
    let e = expected_root(&q);
    let var = linear + trace - e * e;
    let part = if trace > 0.0 {
        (trace - e * e) / trace
    } else {
        0.0
    };
    let shares = (0..n)
        .map(|i| {
            if var > 0.0 {
                (shares[i] * linear + qs[(i, i)] * part) / var + 0.0
            } else {
                0.0
            }
        })
        .collect();
    let sign = if upper { 1.0 } else { -1.0 };
    Some((
        Stat {
            mean: value + sign * e,
            std: sigma_of(var),
        },
        shares,
    ))
}

/// `E√(Σᵢ qᵢ wᵢ²)` for independent standard normal `wᵢ` and `qᵢ ≥ 0`: from `√x = (2√π)⁻¹
/// ∫₀^∞ (1 − e^{−tx}) t^{−3/2} dt` and `E e^{−t qw²} = (1 + 2qt)^{−½}`,
///
/// ```text
/// E√(Σ qᵢwᵢ²) = (2√π)⁻¹ ∫ (1 − Πᵢ (1 + 2qᵢ e^u)^{−½}) e^{−u/2} du   (t = e^u, over ℝ)
/// ```
///
/// a smooth integrand that decays as `e^{−|u|/2}` both ways, taken by the trapezoid rule
/// (spectrally accurate: 1e-15 relative). One variable gives `√(2q/π)`, two equal ones
/// `√(πq/2)` (Rayleigh's mean), three `2√(2q/π)`.
pub fn expected_root(q: &[f64]) -> f64 {
    let total: f64 = q.iter().sum();
    if total.is_nan() {
        return f64::NAN;
    }
    if total <= 0.0 {
        return 0.0;
    }
    // Centred where `t·Σq` is 1; the tails beyond ±80 are below e^{−40}.
    let centre = -total.ln();
    let h = 0.05;
    let steps = (80.0 / h) as i32;
    let integrand = |u: f64| {
        let t = u.exp();
        let log: f64 = q.iter().map(|&qi| (2.0 * qi * t).ln_1p()).sum();
        -(-0.5 * log).exp_m1() * (-0.5 * u).exp()
    };
    let sum: f64 = (-steps..=steps)
        .map(|k| integrand(centre + k as f64 * h))
        .sum();
    sum * h / (2.0 * std::f64::consts::PI.sqrt())
}

/// √v of a variance `v` that rounding may leave a little below 0; NaN stays NaN (`f64::max`
/// would turn it into a σ of 0, hiding an overflow).
pub fn sigma_of(v: f64) -> f64 {
    if v.is_nan() { v } else { v.max(0.0).sqrt() }
}

/// Second order: mean + ½ tr(HΣ), σ² = gᵀΣg + ½ tr(HΣHΣ) (normal variables); for independent
/// variables the diagonal term uses each variable's fourth moment.
pub fn second_order(value: f64, grad: &[f64], hess: &DMatrix<f64>, s: &Spread) -> Stat {
    let n = grad.len();
    // tr(HΣ) = Σ H_ij Σ_ji: O(p²), no product formed.
    let mean = value + 0.5 * hess.component_mul(&s.covariance.transpose()).sum();
    let first: f64 = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| grad[i] * s.covariance[(i, j)] * grad[j])
                .sum::<f64>()
        })
        .sum();
    let second = if s.independent() {
        let mut v = 0.0;
        for i in 0..n {
            for j in 0..n {
                let term = hess[(i, j)].powi(2) * s.sigma[i].powi(2) * s.sigma[j].powi(2);
                if i == j {
                    // ¼ H_ii² (μ₄ − σ⁴): ½ H_ii² σ⁴ for a normal variable, ⅕ for a uniform one.
                    v += term
                        * if s.distribution[i] == Distribution::Uniform {
                            0.2
                        } else {
                            0.5
                        };
                } else {
                    v += 0.5 * term;
                }
            }
        }
        v
    } else {
        let hs = hess * &s.covariance;
        0.5 * hs.component_mul(&hs.transpose()).sum()
    };
    Stat {
        mean,
        std: sigma_of(first + second),
    }
}

/// Invariant-based ω_d: `D` (value, gradient, optional Hessian) propagated to second order and
/// taken as normal, then mapped through `√max(0, D)` exactly.
pub fn invariant(value: f64, grad: &[f64], hess: Option<&DMatrix<f64>>, s: &Spread) -> Stat {
    let d = discriminant(value, grad, hess, s);
    sqrt_positive_part(d.mean, d.std)
}

/// Mean and σ of the discriminant `D` itself (second order when its Hessian is known).
pub fn discriminant(value: f64, grad: &[f64], hess: Option<&DMatrix<f64>>, s: &Spread) -> Stat {
    match hess {
        Some(h) => second_order(value, grad, h, s),
        None => first_order(value, grad, s).0,
    }
}

/// Distance from a change of class, in standard deviations of `D`, below which the
/// `analytic` choice takes the invariant method for ω_d (`P(D < 0) > 3·10⁻⁵` for normal `D`).
pub const KINK_SIGMAS: f64 = 4.0;

/// From this many σ above zero, [`sqrt_positive_part`] takes the moments' series instead of
/// the quadrature.
const SERIES_FROM: f64 = 30.0;

/// Mean and σ of `√max(0, D)` for `D ~ N(μ, σ²)`: `E[max(0, D)] = μΦ(μ/σ) + σφ(μ/σ)` and
/// `E[√max(0, D)] = ∫₀^∞ 2u² φ((u² − μ)/σ)/σ du` (substitution `D = u²`, composite
/// Gauss–Legendre), or
/// its series in `σ/μ` far from zero.
pub fn sqrt_positive_part(mu: f64, sigma: f64) -> Stat {
    if sigma <= 0.0 || !sigma.is_finite() {
        let v = mu.max(0.0).sqrt();
        return Stat { mean: v, std: 0.0 };
    }
    let phi = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let big_phi = |z: f64| 0.5 * libm_erfc(-z / std::f64::consts::SQRT_2);
    let z = mu / sigma;
    let second = mu * big_phi(z) + sigma * phi(z);
    if z >= SERIES_FROM {
        // Far from zero: E√(μ(1 + sε)) = √μ Σ C(½, 2k) (2k−1)!! s^{2k}, s = σ/μ; the first
        // omitted term is below 3·10⁻¹² relative at z = 30 (and P(D < 0) < e⁻⁴⁵⁰).
        let s2 = 1.0 / (z * z);
        let series = 1.0 - s2 * (1.0 / 8.0 + s2 * (15.0 / 128.0 + s2 * (315.0 / 1024.0)));
        let mean = mu.sqrt() * series;
        return Stat {
            mean,
            std: sigma_of(second - mean * mean),
        };
    }
    let upper = (mu + 10.0 * sigma).max(0.0).sqrt();
    // Below √(μ − 10σ) the integrand is under e⁻⁵⁰ of its peak.
    let lower = (mu - 10.0 * sigma).max(0.0).sqrt();
    if upper == 0.0 {
        return Stat {
            mean: 0.0,
            std: 0.0,
        };
    }
    // [lower, upper] spans at most 20σ of D, and the integrand is smooth (entire) on it:
    // composite 8-point Gauss–Legendre converges geometrically. With 16 panels (128
    // evaluations) it is accurate to ~1e-12, worst near μ = 10σ where the lower limit reaches
    // zero (tested against a 200 000-panel Simpson reference).
    let h = (upper - lower) / PANELS as f64;
    let f = |u: f64| 2.0 * u * u * phi((u * u - mu) / sigma) / sigma;
    let mut sum = 0.0;
    for k in 0..PANELS {
        let centre = lower + (k as f64 + 0.5) * h;
        for (x, w) in GAUSS_LEGENDRE_8 {
            sum += w * (f(centre - 0.5 * h * x) + f(centre + 0.5 * h * x));
        }
    }
    let mean = 0.5 * h * sum;
    Stat {
        mean,
        std: sigma_of(second - mean * mean),
    }
}

/// Panels of [`sqrt_positive_part`]'s quadrature.
const PANELS: usize = 16;

/// The 8-point Gauss–Legendre rule on [−1, 1]: the positive nodes and their weights
/// (Abramowitz & Stegun, table 25.4).
const GAUSS_LEGENDRE_8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Complementary error function (statrs).
fn libm_erfc(x: f64) -> f64 {
    statrs::function::erf::erfc(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `E√(Σ qᵢwᵢ²)` against its closed forms: the half-normal's and the chi distributions'
    /// means, and for two unequal weights `√(2q₁/π) E(1 − q₂/q₁)` (the complete elliptic integral
    /// of the second kind, `E(3/4) = 1.2110560275684594`).
    #[test]
    fn the_expected_root_of_a_normal_quadratic_form_has_its_closed_forms() {
        use std::f64::consts::PI;
        let cases = [
            (vec![1.0], (2.0 / PI).sqrt()),
            (vec![2.5, 2.5], (PI * 2.5 / 2.0).sqrt()),
            (vec![1e-6; 3], 2.0 * (2e-6 / PI).sqrt()),
            (
                vec![4e8, 1e8, 0.0],
                (2.0 * 4e8 / PI).sqrt() * 1.2110560275684594,
            ),
        ];
        for (q, exact) in cases {
            let e = expected_root(&q);
            assert!(
                (e - exact).abs() <= 1e-14 * exact,
                "{q:?}: {e} against {exact}"
            );
        }
        assert_eq!(expected_root(&[0.0, 0.0]).to_bits(), 0.0f64.to_bits());
        assert!(
            expected_root(&[1.0, f64::NAN]).is_nan(),
            "a NaN is not hidden"
        );
    }

    /// The first-order statistics of a split double root against the first-order model sampled
    /// directly (`ω₀ + gᵀz ± √(zᵀQz)`, 4·10⁵ correlated normal samples): means and σ within
    /// four standard errors.
    #[test]
    fn a_split_double_roots_first_order_statistics_match_its_sampled_model() {
        use rand::{RngExt, SeedableRng};
        let n = 3;
        let corr = DMatrix::from_row_slice(n, n, &[1.0, 0.3, 0.0, 0.3, 1.0, -0.2, 0.0, -0.2, 1.0]);
        let sigma = vec![0.5, 2.0, 1.0];
        let cov = DMatrix::from_fn(n, n, |i, j| sigma[i] * corr[(i, j)] * sigma[j]);
        let s = Spread {
            sigma: sigma.clone(),
            distribution: vec![Distribution::Normal; n],
            correlation: corr,
            covariance: cov.clone(),
        };
        let a = DMatrix::from_row_slice(2, n, &[1.0, 0.2, -0.5, 0.0, 0.7, 0.4]);
        let split = Split {
            modes: [0, 1],
            mean: vec![0.3, -0.1, 0.8],
            split: a.transpose() * &a,
        };
        let l = cov.cholesky().expect("positive definite").l();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        // Standard normals by Box and Muller.
        let mut normal = move || {
            let (u, v): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        };
        let samples = 400_000;
        let mut sums = [[0.0; 2]; 2];
        for _ in 0..samples {
            let w = nalgebra::DVector::from_fn(n, |_, _| normal());
            let z = &l * w;
            let lin: f64 = (0..n).map(|i| split.mean[i] * z[i]).sum();
            let root = (z.transpose() * &split.split * &z)[(0, 0)].max(0.0).sqrt();
            for (k, v) in [lin - root, lin + root].into_iter().enumerate() {
                sums[k][0] += v;
                sums[k][1] += v * v;
            }
        }
        for (k, upper) in [false, true].into_iter().enumerate() {
            let (stat, shares) = split_first_order(10.0, &split, upper, &s).expect("normal");
            let mean = 10.0 + sums[k][0] / samples as f64;
            let var = sums[k][1] / samples as f64 - (mean - 10.0).powi(2);
            let se = (var / samples as f64).sqrt();
            assert!(
                (stat.mean - mean).abs() < 4.0 * se,
                "{upper}: {stat:?} {mean}"
            );
            let rel = 4.0 / (2.0 * samples as f64).sqrt();
            assert!(
                (stat.std - var.sqrt()).abs() < rel * stat.std,
                "{stat:?} {}",
                var.sqrt()
            );
            assert!(
                (shares.iter().sum::<f64>() - 1.0).abs() < 1e-12,
                "{shares:?}"
            );
        }
        // A uniform variable that moves the pair: no first-order distribution claimed.
        let mut u = s.clone();
        u.distribution[1] = Distribution::Uniform;
        assert!(split_first_order(10.0, &split, true, &u).is_none());
    }

    #[test]
    fn sqrt_positive_part_limits() {
        // Far from zero: √D ≈ √μ with σ_ω ≈ σ/(2√μ).
        let s = sqrt_positive_part(100.0, 1.0);
        assert!((s.mean - (10.0 - 1.0 / 8000.0)).abs() < 1e-6, "{s:?}");
        assert!((s.std - 0.05).abs() < 1e-4, "{s:?}");
        // Centred at zero: E√max(0,D) = σ^½ Γ(3/4) / (2^{3/4} √π)... check against the moments.
        let s = sqrt_positive_part(0.0, 4.0);
        let exact_mean = 2.0f64.sqrt() * 4.0f64.sqrt() * 1.2254167024651776
            / (2.0 * std::f64::consts::PI.sqrt())
            / 2f64.powf(0.25);
        assert!(
            (s.mean - exact_mean).abs() < 1e-6 * exact_mean,
            "{} vs {exact_mean}",
            s.mean
        );
        assert!(
            (s.mean * s.mean + s.std * s.std - 4.0 / (2.0 * std::f64::consts::PI).sqrt()).abs()
                < 1e-9
        );
    }

    #[test]
    fn sqrt_positive_part_matches_a_fine_reference() {
        // Reference: 200 000 Simpson panels over [0, √(μ + 10σ)].
        let reference = |mu: f64, sigma: f64| {
            let phi = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
            let upper = (mu + 10.0 * sigma).sqrt();
            let n = 200_000;
            let h = upper / n as f64;
            let f = |u: f64| 2.0 * u * u * phi((u * u - mu) / sigma) / sigma;
            let mut sum = f(0.0) + f(upper);
            for k in 1..n {
                sum += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            sum * h / 3.0
        };
        for z in [
            -3.0, -0.5, 0.0, 0.7, 1.5, 3.0, 5.0, 8.0, 9.99, 10.01, 12.0, 20.0, 29.99, 30.0, 45.0,
            1000.0,
        ] {
            let sigma = 2.5e-3;
            let s = sqrt_positive_part(z * sigma, sigma);
            let r = reference(z * sigma, sigma);
            assert!(
                (s.mean - r).abs() <= 1e-11 * r,
                "μ/σ = {z}: {} vs {r}",
                s.mean
            );
        }
    }

    #[test]
    fn second_order_of_a_quadratic_is_exact() {
        // f = g x + ½ h x², x ~ N(0, σ²): mean ½hσ², var g²σ² + ½h²σ⁴.
        let s = Spread {
            sigma: vec![0.3],
            distribution: vec![Distribution::Normal],
            correlation: DMatrix::identity(1, 1),
            covariance: DMatrix::from_element(1, 1, 0.09),
        };
        let st = second_order(1.0, &[2.0], &DMatrix::from_element(1, 1, 5.0), &s);
        assert!((st.mean - (1.0 + 0.5 * 5.0 * 0.09)).abs() < 1e-15);
        assert!((st.std - (4.0 * 0.09 + 0.5 * 25.0 * 0.0081f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_variable_outside_the_case_has_share_zero_not_minus_zero() {
        // The second variable is not toleranced in this case (σ = 0) and lowers the output.
        let s = Spread {
            sigma: vec![0.3, 0.0],
            distribution: vec![Distribution::Normal; 2],
            correlation: DMatrix::identity(2, 2),
            covariance: DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.09, 0.0])),
        };
        let (_, shares) = first_order(1.0, &[2.0, -3.0], &s);
        assert!(shares[0].to_bits() == 1f64.to_bits());
        assert_eq!(shares[1].to_string(), "0");
    }
}
