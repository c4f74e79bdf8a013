//! Global sensitivity: which tolerance matters. First-order and total Sobol indices of every
//! output at every speed and of every requirement's worst margin, by the pick-freeze Monte Carlo
//! of Saltelli et al. (2010), with jackknife confidence intervals, beside the derivative-based
//! upper bound on the total index from the exact gradients and Hessians.
//!
//! Two independent sample matrices `A`, `B` of `N` designs and, per variable `i`, `A_B^(i)`
//! (`A` with its column `i` from `B`): `N (d + 2)` sweeps for `d` variables. With `V` the
//! variance of the `2N` values of `A` and `B` (Sobol 1993; Saltelli et al. 2010, Table 2):
//!
//! ```text
//! S_i  = (1/N) Σ_j f(B)_j (f(A_B^(i))_j − f(A)_j) / V          (first order, Saltelli 2010)
//! S_Ti = (1/2N) Σ_j (f(A)_j − f(A_B^(i))_j)² / V               (total, Jansen 1999)
//! ```
//!
//! Their 95 % intervals are the estimate ± 1.96 delete-one jackknife standard errors over the
//! `N` rows (Efron & Stein 1981), computed from the estimators' sums in `O(N)`: deterministic;
//! the total's on the log scale (it is a mean of squares, skewed to the right). A coverage
//! study against exact indices (the tests below: |H| of one resonance, 2400 intervals of each
//! kind) chose them over the bootstrap percentile intervals used before: at `N` = 256 those
//! held the exact first-order index in 93.0 % of the cases, these in 94.3 %; the totals' hold
//! it in 94.8 % at `N` = 1024 and about 93 % at `N` = 256, where the estimator's skew is not
//! yet normal (a small `N` gives intervals a little too narrow).
//!
//! The **derivative bound** (Sobol & Kucherenko 2009; Lamboni et al.
//! 2013 for the Poincaré constant of the normal law) is `S_Ti ≤ σ_i² E[(∂f/∂x_i)²] / V` (a
//! uniform variable's constant is `(b − a)²/π² = 12σ²/π²`). The expectation and `V` are
//! integrated by one rule over the distribution with the exact gradient at every node: the
//! 5-point Gauss–Hermite tensor rule for up to four variables (deterministic, so the bound
//! holds to the rule's accuracy), else the first 256 designs of `A` (an estimate with Monte
//! Carlo error: for a variable on which the output depends almost linearly the bound is tight
//! and the estimate may fall on either side of it). Correlated variables have no
//! Sobol decomposition of this kind: a case with a correlation matrix is refused.
//!
//! Variables enter as independent standard normals through the Monte Carlo's map (uniform
//! variables through `Φ`), so a design of `A` is the design a Monte Carlo would sweep there.

use crate::model::Distribution;
use crate::program::{Tier, Workspace};
use crate::propagate::{Run, Study};
use crate::requirement;
use crate::sampling::{DesignMap, sample_sweep};
use crate::tolerance::{Spread, local_model, value};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

/// The standard normal's 97.5 % quantile: the intervals' half-width in standard errors.
const Z95: f64 = 1.959_963_984_540_054;

/// Settings of the Sobol indices.
#[derive(Debug, Clone, Copy)]
pub struct SobolOptions {
    /// Base samples `N` (the sweeps are `N (d + 2)`).
    pub samples: usize,
    pub seed: u64,
}

/// What an index is of: an output at one speed, or a requirement's worst margin over its
/// range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// `(speed index, output index)`.
    Output(usize, usize),
    /// Requirement index.
    Margin(usize),
}

impl Target {
    /// The target in words: `margin of NAME`, or `QUANTITY[ mode K] at SPEED rad/s` with the
    /// speed as `speed` writes it.
    pub fn describe(
        &self,
        requirements: &[crate::model::Requirement],
        speeds: &[f64],
        outputs: &[crate::output::Output],
        speed: impl Fn(f64) -> String,
    ) -> String {
        match *self {
            Target::Margin(r) => format!("margin of {}", requirements[r].name),
            Target::Output(i, o) => {
                let out = outputs[o];
                format!(
                    "{}{} at {} rad/s",
                    out.quantity.as_str(),
                    out.mode
                        .map_or(String::new(), |m| format!(" mode {}", m + 1)),
                    speed(speeds[i])
                )
            }
        }
    }
}

/// The indices of one target and one variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SobolIndex {
    pub target: Target,
    /// Index into the study's variables.
    pub variable: usize,
    pub first: f64,
    pub first_ci: (f64, f64),
    pub total: f64,
    pub total_ci: (f64, f64),
    /// The derivative-based upper bound on the total index (outputs only; `None` where a
    /// derivative is missing).
    pub bound: Option<f64>,
    /// Rows used (designs with a value in `A`, `B` and `A_B^(i)`).
    pub rows: usize,
}

/// Why no indices.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SobolError {
    #[error("Sobol indices need independent variables: the case gives a correlation matrix")]
    Correlated,
}

/// The indices of every output at every speed and of every requirement's worst margin, for
/// each variable the case tolerances.
pub fn sobol(
    study: &Study,
    spread: &Spread,
    opt: SobolOptions,
    run: &Run,
) -> Result<Vec<SobolIndex>, SobolError> {
    let n = spread.sigma.len();
    if (&spread.correlation - nalgebra::DMatrix::<f64>::identity(n, n)).amax() != 0.0 {
        return Err(SobolError::Correlated);
    }
    let active: Vec<usize> = (0..n).filter(|&k| spread.sigma[k] > 0.0).collect();
    let d = active.len();
    if d == 0 || opt.samples < 2 {
        return Ok(Vec::new());
    }
    let map = DesignMap::new(
        study.model.model().nominal(),
        study.vars.clone(),
        spread.clone(),
    );
    let normal = Normal::standard();
    // Uniforms of A (rows 0..N) and B (rows N..2N), one stream per row.
    let draw = |row: usize| -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(opt.seed);
        rng.set_stream(row as u64);
        (0..n)
            .map(|_| rng.random::<f64>().clamp(1e-12, 1.0 - 1e-12))
            .collect()
    };
    let big_n = opt.samples;
    // Design (row of A or B, with column i from B): `(j, Some(i))` is A_B^(i)'s row j.
    let designs: Vec<(usize, Option<usize>)> = (0..2 * big_n)
        .map(|j| (j, None))
        .chain((0..d).flat_map(|i| (0..big_n).map(move |j| (j, Some(i)))))
        .collect();
    let speeds = study.speeds.len();
    let outs = study.outputs.len();
    let reqs = &study.model.model().requirements;
    let width = speeds * outs + reqs.len();
    let tier = Tier::for_points(designs.len() * speeds);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let values: Vec<Vec<f64>> = run.pool.install(|| {
        designs
            .par_iter()
            .map_init(Workspace::default, |workspace, &(j, col)| {
                let mut u = draw(j);
                if let Some(i) = col {
                    u[active[i]] = draw(big_n + j)[active[i]];
                }
                let z: Vec<f64> = u.iter().map(|&x| normal.inverse_cdf(x)).collect();
                let v = evaluate(study, map.parameters(&z, &u), (tier, workspace), width);
                let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                (run.progress)(k, designs.len());
                v
            })
            .collect()
    });
    let a = |j: usize, t: usize| values[j][t];
    let b = |j: usize, t: usize| values[big_n + j][t];
    let ab = |i: usize, j: usize, t: usize| values[2 * big_n + i * big_n + j][t];
    let targets: Vec<Target> = (0..speeds)
        .flat_map(|s| (0..outs).map(move |o| Target::Output(s, o)))
        .chain((0..reqs.len()).map(Target::Margin))
        .collect();
    let bounds = derivative_bounds(study, spread, &active, &map, &draw, big_n, run);
    let mut out = Vec::new();
    for (t, &target) in targets.iter().enumerate() {
        if let Target::Margin(r) = target
            && !requirement::has_margin(&reqs[r])
        {
            continue;
        }
        for (i, &var) in active.iter().enumerate() {
            let rows: Vec<(f64, f64, f64)> = (0..big_n)
                .map(|j| (a(j, t), b(j, t), ab(i, j, t)))
                .filter(|x| x.0.is_finite() && x.1.is_finite() && x.2.is_finite())
                .collect();
            if rows.len() < 2 {
                continue;
            }
            let Some((first, total, first_ci, total_ci)) = estimate(&rows) else {
                continue;
            };
            let bound = match target {
                Target::Output(s, o) => bounds[s][o].as_ref().map(|(nu, v)| nu[i] / v),
                Target::Margin(_) => None,
            };
            out.push(SobolIndex {
                target,
                variable: var,
                first,
                first_ci,
                total,
                total_ci,
                bound,
                rows: rows.len(),
            });
        }
    }
    Ok(out)
}

/// One design's values: every output at every speed (NaN where none), then every
/// requirement's worst margin over its range (NaN where the design fails it without one).
fn evaluate(study: &Study, p: Vec<f64>, run: (Tier, &Workspace), width: usize) -> Vec<f64> {
    let outs = &study.outputs;
    let reqs = &study.model.model().requirements;
    let base = study.speeds.len() * outs.len();
    let mut v = vec![f64::NAN; width];
    for x in &mut v[base..] {
        *x = f64::INFINITY;
    }
    sample_sweep(
        study.model,
        p,
        &study.speeds,
        &study.nominal,
        run,
        |i, pts| {
            let tf = study.transfer_at(i);
            let at = pts.map(|(_, pt, switches)| (pt, switches == study.branches[i]));
            requirement::margins_at(
                reqs,
                study.speeds[i],
                at,
                tf,
                requirement::covers,
                |r, m| {
                    v[base + r] = v[base + r].min(m);
                },
            );
            if let Some((_, pt, _)) = pts {
                for (o, out) in outs.iter().enumerate() {
                    v[i * outs.len() + o] = value(pt, out, tf).unwrap_or(f64::NAN);
                }
            }
        },
    );
    for x in &mut v[base..] {
        if !x.is_finite() {
            *x = f64::NAN;
        }
    }
    v
}

/// The sums the two estimators are made of, over rows `(f(A), f(B), f(A_B^(i)))` shifted by
/// one constant (the pooled mean of all rows, so that the variance is not a difference of
/// large numbers). A row is added or, for the jackknife, taken out again.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: f64,
    a: f64,
    b: f64,
    aa: f64,
    bb: f64,
    /// `Σ f(B) (f(A_B^(i)) − f(A))`.
    bd: f64,
    /// `Σ (f(A_B^(i)) − f(A))`.
    d: f64,
    /// `Σ (f(A_B^(i)) − f(A))²`.
    dd: f64,
}

impl Sums {
    fn add(&mut self, (fa, fb, fab): (f64, f64, f64), sign: f64) {
        let d = fab - fa;
        self.n += sign;
        self.a += sign * fa;
        self.b += sign * fb;
        self.aa += sign * fa * fa;
        self.bb += sign * fb * fb;
        self.bd += sign * fb * d;
        self.d += sign * d;
        self.dd += sign * d * d;
    }

    /// `(S_i, S_Ti, V)`. The first-order sum is taken with `f(B)` centred on the pooled mean
    /// (the same estimator in the limit; its variance does not grow with the output's mean).
    fn indices(&self) -> (f64, f64, f64) {
        let n = self.n;
        let mean = (self.a + self.b) / (2.0 * n);
        let var = (self.aa + self.bb) / (2.0 * n) - mean * mean;
        let first = (self.bd - mean * self.d) / n / var;
        let total = self.dd / (2.0 * n) / var;
        (first, total, var)
    }
}

/// `S_i`, `S_Ti` and their 95 % intervals of `S_i` and `S_Ti` from the rows
/// `(f(A), f(B), f(A_B^(i)))`: the estimate ± 1.96 delete-one jackknife standard errors
/// (Efron & Stein 1981; the estimators are smooth functions of means, asymptotically normal,
/// Janon et al. 2014). `None` where the variance or a delete-one estimate is not positive and
/// finite (too few distinct rows for an interval).
#[allow(clippy::type_complexity)]
fn estimate(rows: &[(f64, f64, f64)]) -> Option<(f64, f64, (f64, f64), (f64, f64))> {
    let shift = rows.iter().map(|r| r.0 + r.1).sum::<f64>() / (2 * rows.len()) as f64;
    let shifted = |r: &(f64, f64, f64)| (r.0 - shift, r.1 - shift, r.2 - shift);
    let mut all = Sums::default();
    for r in rows {
        all.add(shifted(r), 1.0);
    }
    let (first, total, var) = all.indices();
    if !(var > 0.0 && first.is_finite() && total.is_finite()) {
        return None;
    }
    let mut deleted = Vec::with_capacity(rows.len());
    for r in rows {
        let mut s = all;
        s.add(shifted(r), -1.0);
        let (f, t, v) = s.indices();
        if !(v > 0.0 && f.is_finite() && t.is_finite()) {
            return None;
        }
        deleted.push((f, t));
    }
    let n = rows.len() as f64;
    let interval = |x: &dyn Fn(&(f64, f64)) -> f64, at: f64| {
        let m = deleted.iter().map(x).sum::<f64>() / n;
        let se = ((n - 1.0) / n * deleted.iter().map(|d| (x(d) - m).powi(2)).sum::<f64>()).sqrt();
        (at - Z95 * se, at + Z95 * se)
    };
    let first_ci = interval(&|d| d.0, first);
    // The total is a mean of squares, skewed to the right: its interval on the log scale
    // (exact at 0, where every row agrees and the variable has no effect).
    let total_ci = if total > 0.0 && deleted.iter().all(|d| d.1 > 0.0) {
        let (lo, hi) = interval(&|d| d.1.ln(), total.ln());
        (lo.exp(), hi.exp())
    } else {
        interval(&|d| d.1, total)
    };
    Some((first, total, first_ci, total_ci))
}

/// Nodes of the derivative bound's rule per variable for up to [`TENSOR_MAX`] variables.
const TENSOR_ORDER: usize = 5;
/// The most variables integrated by the tensor rule; more take the first rows of `A`.
const TENSOR_MAX: usize = 4;
/// The most rows of `A` the derivative bound takes with more variables.
const BOUND_ROWS: usize = 256;

/// Per speed and output, the derivative bound's parts: `C_i E[(∂f/∂x_i)²]` per active variable
/// (`C_i` the Poincaré constant: σ² for a normal variable, `(b − a)²/π² = 12σ²/π²` for a
/// uniform one) and `Var f`, both integrated by the same rule over the distribution with the
/// exact gradients at each node (the 5-point Gauss–Hermite tensor rule for up to four
/// variables, else the first rows of `A`: an estimate). `None` where a node has no gradient.
#[allow(clippy::type_complexity)]
fn derivative_bounds(
    study: &Study,
    spread: &Spread,
    active: &[usize],
    map: &DesignMap,
    draw: &(dyn Fn(usize) -> Vec<f64> + Sync),
    rows: usize,
    run: &Run,
) -> Vec<Vec<Option<(Vec<f64>, f64)>>> {
    let n = spread.sigma.len();
    let d = active.len();
    let normal = Normal::standard();
    // The rule's nodes in standard normals (all variables; inactive ones at 0) and weights.
    let nodes: Vec<(Vec<f64>, f64)> = if d <= TENSOR_MAX {
        let (x, w) = crate::linalg::gauss_hermite(TENSOR_ORDER);
        (0..TENSOR_ORDER.pow(d as u32))
            .map(|mut k| {
                let mut z = vec![0.0; n];
                let mut wt = 1.0;
                for &a in active {
                    z[a] = x[k % TENSOR_ORDER];
                    wt *= w[k % TENSOR_ORDER];
                    k /= TENSOR_ORDER;
                }
                (z, wt)
            })
            .collect()
    } else {
        let m = rows.min(BOUND_ROWS);
        (0..m)
            .map(|j| {
                let z = draw(j).iter().map(|&u| normal.inverse_cdf(u)).collect();
                (z, 1.0 / m as f64)
            })
            .collect()
    };
    let speeds = study.speeds.len();
    let outs = study.outputs.len();
    let transfer = study.transfer;
    // Per node: per speed and output, the value and the gradient over the study's variables.
    type NodeGrad = Vec<Option<(f64, Vec<f64>)>>;
    let per_node: Vec<NodeGrad> = run.pool.install(|| {
        nodes
            .par_iter()
            .map_init(
                || (Workspace::default(), Workspace::default()),
                |(ws, ws2), (z, _)| {
                    let u: Vec<f64> = z.iter().map(|&x| normal.cdf(x)).collect();
                    let p = map.parameters(z, &u);
                    let mut out: NodeGrad = vec![None; speeds * outs];
                    let tier = Tier::for_points(speeds);
                    sample_sweep(
                        study.model,
                        p.clone(),
                        &study.speeds,
                        &study.nominal,
                        (tier, ws),
                        |i, pts| {
                            let Some((_, pt, _)) = pts else { return };
                            let Ok(lm) = local_model(
                                study.model,
                                &p,
                                pt,
                                &study.vars,
                                transfer.as_ref(),
                                false,
                                ws2,
                            ) else {
                                return;
                            };
                            for o in 0..outs.min(lm.value.len()) {
                                if let Ok(g) = &lm.grad[o]
                                    && lm.value[o].is_finite()
                                {
                                    out[i * outs + o] = Some((lm.value[o], g.clone()));
                                }
                            }
                        },
                    );
                    out
                },
            )
            .collect()
    });
    let constant = |a: usize| {
        let s2 = spread.sigma[a].powi(2);
        match spread.distribution[a] {
            Distribution::Normal => s2,
            Distribution::Uniform => 12.0 * s2 / std::f64::consts::PI.powi(2),
        }
    };
    (0..speeds)
        .map(|i| {
            (0..outs)
                .map(|o| {
                    let (mut m1, mut m2) = (0.0, 0.0);
                    let mut nu = vec![0.0; d];
                    for ((_, w), node) in nodes.iter().zip(&per_node) {
                        let (f, g) = node[i * outs + o].as_ref()?;
                        m1 += w * f;
                        m2 += w * f * f;
                        for (k, &a) in active.iter().enumerate() {
                            nu[k] += w * g[a] * g[a];
                        }
                    }
                    let var = m2 - m1 * m1;
                    let nu: Vec<f64> = nu
                        .iter()
                        .zip(active)
                        .map(|(x, &a)| constant(a) * x)
                        .collect();
                    (var > 0.0).then_some((nu, var))
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
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
}
