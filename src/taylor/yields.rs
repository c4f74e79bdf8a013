//! The first-order yield: each requirement's margin linearised at the nominal design,
//! `P = Φ(β)`, `β = m₀/σ_m`, `σ_m² = ∇mᵀ Σ ∇m` (the mean-value first-order reliability index;
//! Hasofer & Lind 1974 for its invariant form), per speed. Over a range it gives the
//! probability at the worst speed, an upper bound on the range's (the events at the speeds are
//! not independent: the bound is attained when one speed decides), and none for the
//! requirements that are pass or fail (the branch) or are not a smooth function of the outputs
//! at the nominal design (stability, where no mode is close to it, has a first-order margin
//! only through its growth rate, which the local model does not carry).

use crate::margins::{carriers, covers, mode_margin, mode_margin_gradient, reaches};
use crate::model::Requirement;
use crate::output::{Output, Quantity};
use crate::pair::Carriers;
use crate::propagate::Study;
use crate::requirements::{Reading, Reads};
use crate::table::{Limit, Method, YieldRow, cpk, reach};
use crate::tolerance::Spread;
use num_dual::Dual64;
use statrs::distribution::{ContinuousCDF, Normal};

/// A requirement's first-order margin at speed `i`: its nominal value and its gradient over
/// the study's variables, `None` where first order does not apply (see the module
/// documentation) or a derivative is missing.
pub fn linear_margin(study: &Study, req: &Requirement, i: usize) -> Option<(f64, Vec<f64>)> {
    let pt = study.nominal[i].as_ref()?;
    let lm = study.locals[i].as_ref()?;
    let speed = study.speeds[i];
    let index = |q: Quantity, mode: Option<usize>| {
        study
            .outputs
            .iter()
            .position(|o| *o == Output { quantity: q, mode })
    };
    match req.kind.reads() {
        Reads::Branch | Reads::Growth => None,
        Reads::Transfer => {
            let k = index(Quantity::TransferMagnitude, None)?;
            let g = lm.grad[k].as_ref().ok()?;
            let h = lm.value[k];
            let m0 = req.kind.margin(speed, Reading::Transfer(h));
            let dh = req
                .kind
                .margin(speed, Reading::Transfer(Dual64::new(h, 1.0)))
                .eps;
            Some((m0, g.iter().map(|x| dh * x).collect()))
        }
        Reads::Mode => {
            let c = carriers(pt, None);
            let c = Carriers::new(&c);
            let modes = c.modes();
            let of = |m: usize| {
                let (s, p) = c.pair(m);
                mode_margin(req, speed, s, p)
            };
            // The mode asked, or the worst at the nominal design.
            let m = match req.mode {
                Some(m) => m,
                None => (0..modes)
                    .filter(|&m| !of(m).is_nan())
                    .min_by(|&a, &b| of(a).total_cmp(&of(b)))?,
            };
            let m0 = of(m);
            let (kw, kz) = (
                index(Quantity::DampedFrequency, Some(m))?,
                index(Quantity::DampingRatio, Some(m))?,
            );
            let (wd, zeta) = (lm.value[kw], lm.value[kz]);
            let (dw, dz) = mode_margin_gradient(req, speed, wd, zeta);
            let gw = if dw == 0.0 {
                None
            } else {
                Some(lm.grad[kw].as_ref().ok()?)
            };
            let gz = if dz == 0.0 {
                None
            } else {
                Some(lm.grad[kz].as_ref().ok()?)
            };
            let g = (0..study.vars.len())
                .map(|v| dw * gw.map_or(0.0, |g| g[v]) + dz * gz.map_or(0.0, |g| g[v]))
                .collect::<Vec<f64>>();
            (m0.is_finite() && g.iter().all(|x| x.is_finite())).then_some((m0, g))
        }
    }
}

/// `σ_m = √(gᵀ Σ g)` under `spread`.
fn margin_sigma(g: &[f64], spread: &Spread) -> f64 {
    let n = g.len();
    let mut v = 0.0;
    for a in 0..n {
        for b in 0..n {
            v += g[a] * spread.covariance[(a, b)] * g[b];
        }
    }
    v.max(0.0).sqrt()
}

/// `Φ(m₀/σ)`, 1 or 0 where σ = 0.
fn first_order_probability(m0: f64, sigma: f64) -> f64 {
    if sigma > 0.0 {
        Normal::standard().cdf(m0 / sigma)
    } else if m0 >= 0.0 {
        1.0
    } else {
        0.0
    }
}

/// The first-order rows of case `case`: per speed, and over the range at the worst speed, with
/// what the design meets at the model's target yield (the reach from the running minimum of the
/// per-speed probabilities, an upper bound like the range's probability).
pub(super) fn first_order_rows(study: &Study, case: usize, spread: &Spread) -> Vec<YieldRow> {
    let model = study.model.model();
    let (reqs, target) = (&model.requirements, model.allocation.target_yield);
    let z = Normal::standard().inverse_cdf(target);
    let mut out = Vec::new();
    let mut worst_all: Option<f64> = Some(1.0);
    for (r, req) in reqs.iter().enumerate() {
        let mut worst: Option<(f64, f64, f64)> = None;
        let mut at_target = f64::INFINITY;
        let mut complete = true;
        // (speed, probability of every speed from the range's start up to it), while known.
        let mut prefix: Vec<(f64, f64, (f64, f64))> = Vec::new();
        let mut running = Some(1.0f64);
        for (i, &w) in study.speeds.iter().enumerate() {
            if !reaches(req, w) {
                continue;
            }
            let Some((m0, g)) = linear_margin(study, req, i) else {
                running = None;
                complete &= !covers(req, w);
                continue;
            };
            let s = margin_sigma(&g, spread);
            let p = first_order_probability(m0, s);
            if let Some(x) = running.as_mut() {
                *x = x.min(p);
                prefix.push((w, *x, (*x, *x)));
            }
            if !covers(req, w) {
                continue;
            }
            out.push(YieldRow {
                case,
                method: Method::FirstOrder,
                requirement: Some(r),
                speed: Some(w),
                probability: p,
                ci: (p, p),
                margin: None,
                cpk: None,
                evaluations: 0,
                within_request: None,
                limit: None,
            });
            at_target = at_target.min(m0 - z * s);
            if worst.is_none_or(|x| p < x.0) {
                worst = Some((p, m0, s));
            }
        }
        match worst {
            Some((p, m0, s)) if complete => {
                out.push(YieldRow {
                    case,
                    method: Method::FirstOrder,
                    requirement: Some(r),
                    speed: None,
                    probability: p,
                    ci: (p, p),
                    margin: Some((m0, s)),
                    cpk: cpk(m0, s),
                    evaluations: 0,
                    within_request: None,
                    limit: Some(Limit::new(
                        reach(&prefix, target),
                        Some([at_target; 3]),
                        ["the margin's first-order quantile is unbounded"; 3],
                    )),
                });
                worst_all = worst_all.map(|x| x.min(p));
            }
            _ => worst_all = None,
        }
    }
    if let Some(p) = worst_all
        && !reqs.is_empty()
    {
        out.insert(
            0,
            YieldRow {
                case,
                method: Method::FirstOrder,
                requirement: None,
                speed: None,
                probability: p,
                ci: (p, p),
                margin: None,
                cpk: None,
                evaluations: 0,
                within_request: None,
                limit: None,
            },
        );
    }
    out
}
