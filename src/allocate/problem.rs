//! The allocation problem of one case: the first-order margin constraints of its nominal
//! study, its variables' costs and bounds, and the convex programme's solution at a given `β`
//! (see the [`super`] module documentation).

use super::{
    AllocateError, AllocateOptions, Constraint, DEFAULT_MAX_FACTOR, constraints,
    sigma_per_tolerance, solve,
};
use crate::compiled::Compiled;
use crate::model::{Cost, Model};
use crate::propagate::{Run, Study};
use statrs::distribution::{ContinuousCDF, Normal};

/// The allocation problem of `opt.case`'s variables (see the module documentation): the
/// first-order margin constraints of the nominal study, each variable's cost, its tolerance
/// before and its largest, and the constraints' coefficients `a = (∂m/∂x · σ per tolerance)²`.
pub(super) struct Problem {
    pub(super) vars: Vec<usize>,
    pub(super) cons: Vec<Constraint>,
    pub(super) costs: Vec<Cost>,
    pub(super) before: Vec<f64>,
    pub(super) max: Vec<f64>,
    a: Vec<Vec<f64>>,
}

impl Problem {
    /// The problem, refused where it has no requirement, variable or margin, is correlated, or
    /// the nominal design already fails a requirement.
    pub(super) fn new(model: &Compiled, opt: &AllocateOptions) -> Result<Problem, AllocateError> {
        let m = model.model();
        if m.requirements.is_empty() {
            return Err(AllocateError::NoRequirements);
        }
        if opt.case.correlation.is_some() {
            return Err(AllocateError::Correlated);
        }
        let vars: Vec<usize> = opt.case.tolerances.iter().map(|t| t.0).collect();
        if vars.is_empty() {
            return Err(AllocateError::NoVariables);
        }
        let pool = crate::threads::pool(opt.threads);
        let run = Run {
            cancel: &opt.cancel,
            pool: &pool,
            progress: &|_, _| {},
        };
        let study = Study::build(model, vars.clone(), opt.speeds.clone(), &run);
        if study.nominal.iter().all(Option::is_none) {
            let why = study
                .failures
                .first()
                .map_or(String::new(), |f| f.1.clone());
            return Err(AllocateError::NoSweep(why));
        }
        let cons = constraints(&study);
        if cons.is_empty() {
            return Err(AllocateError::NoMargins);
        }
        if let Some(c) = cons.iter().find(|c| c.margin <= 0.0) {
            return Err(AllocateError::NominalFails {
                requirement: m.requirements[c.requirement].name.clone(),
                speed: c.speed,
                margin: c.margin,
            });
        }
        if let Some((p, _)) = opt.costs.iter().find(|(p, _)| !vars.contains(p)) {
            return Err(AllocateError::CostWithoutTolerance(
                m.parameters[*p].name.clone(),
            ));
        }
        let costs: Vec<Cost> = vars
            .iter()
            .map(|v| {
                opt.costs
                    .iter()
                    .chain(&m.allocation.costs)
                    .find(|(p, _)| p == v)
                    .map_or(Cost::default(), |c| c.1)
            })
            .collect();
        let before: Vec<f64> = opt
            .case
            .tolerances
            .iter()
            .map(|(p, t)| t.absolute(m.parameters[*p].value))
            .collect();
        let max: Vec<f64> = vars
            .iter()
            .zip(&costs)
            .zip(&before)
            .map(|((v, c), b)| {
                c.max.map_or(DEFAULT_MAX_FACTOR * b, |t| {
                    t.absolute(m.parameters[*v].value)
                })
            })
            .collect();
        let s: Vec<f64> = vars
            .iter()
            .map(|&v| sigma_per_tolerance(m.parameters[v].distribution))
            .collect();
        // The study's variables are the case's, in its order.
        let a: Vec<Vec<f64>> = cons
            .iter()
            .map(|c| {
                c.gradient
                    .iter()
                    .zip(&s)
                    .map(|(g, s)| (g * s).powi(2))
                    .collect()
            })
            .collect();
        let problem = Problem {
            vars,
            cons,
            costs,
            before,
            max,
            a,
        };
        // The costs of the case's tolerances must be numbers (the allocated ones are checked
        // too).
        match problem.overflow(m, &problem.before) {
            Some(e) => Err(e),
            None => Ok(problem),
        }
    }

    /// The first variable whose cost at tolerance `t` is not a number, as the error.
    pub(super) fn overflow(&self, m: &Model, t: &[f64]) -> Option<AllocateError> {
        (0..self.vars.len())
            .find(|&k| !self.costs[k].of(t[k]).is_finite())
            .map(|k| AllocateError::CostOverflow {
                parameter: m.parameters[self.vars[k]].name.clone(),
                tolerance: t[k],
            })
    }

    /// The squares of the cheapest tolerances that keep every margin `β` of its first-order σ
    /// away from zero.
    pub(super) fn allocated(&self, beta: f64) -> Vec<f64> {
        let b: Vec<f64> = self.costs.iter().map(|c| c.b).collect();
        let e: Vec<f64> = self.costs.iter().map(|c| c.k).collect();
        let umax: Vec<f64> = self.max.iter().map(|x| x * x).collect();
        let c: Vec<f64> = self
            .cons
            .iter()
            .map(|c| (c.margin / beta).powi(2))
            .collect();
        solve(&b, &e, &umax, &self.a, &c)
    }

    /// The first-order yield of the tolerances whose squares are `u`: the least probability
    /// over the constraints that a margin stays positive.
    pub(super) fn predicted(&self, u: &[f64]) -> f64 {
        let normal = Normal::standard();
        self.cons
            .iter()
            .zip(&self.a)
            .map(|(c, a)| {
                let sd = a.iter().zip(u).map(|(a, u)| a * u).sum::<f64>().sqrt();
                normal.cdf(c.margin / sd)
            })
            .fold(1.0, f64::min)
    }
}
