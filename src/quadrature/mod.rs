//! Deterministic integration of the whole nonlinear pipeline (equilibrium → modes → |H|) over
//! the design-variable distribution: the `quadrature` propagation method.
//!
//! Taylor methods are exact only where an output is smooth over the spread of the variables.
//! Where a mode turns overdamped (ω_d = √max(0, D) has a square-root edge), where a sample's
//! sweep passes its own bifurcation (the equilibrium it follows switches branch) or where a
//! resonance sits, the moments are integrals of a piecewise-smooth function. This module
//! computes them by **pre-integration along one direction** (Griewank, Kuo, Leövey & Sloan,
//! *High-dimensional integration of kinks and jumps — smoothing by preintegration*, J. Comput.
//! Appl. Math. 2018; the "line sampling" of Koutsourelakis, Pradlwarter & Schuëller, Prob. Eng.
//! Mech. 2004) with a **multi-element rule split at the located boundaries** along it (Jakeman,
//! Narayan & Xiu, *Minimal multi-element stochastic collocation for uncertainty quantification
//! of discontinuous functions*, JCP 2013):
//!
//! 1. The variables are written as independent standard normals `z` (the Monte Carlo's map,
//!    [`crate::sampling::DesignMap::parameters`]: correlations through the Cholesky factor, uniform
//!    variables through `Φ`). Only the variables the case tolerances count.
//! 2. The line direction `α` is the dominant eigenvector of `Σ ĝ ĝᵀ`, the normalised exact
//!    gradients (in `z`) of every output and pair discriminant at every speed (an active
//!    subspace, Constantine, *Active Subspaces*, SIAM 2015): the direction across which the
//!    outputs change, and so change character. `z = α t + V y` with `V` its orthogonal
//!    complement.
//! 3. Transverse points `y` carry weights: one line for one variable; the tensor 3-point
//!    Gauss–Hermite rule for two to four variables, checked against the 2-point rule (then the
//!    5- and 7-point rules where the transverse error is what misses the request); for
//!    five or more, randomised quasi-Monte Carlo (eight independently Owen-scrambled Sobol
//!    sets, Owen 1997; the error from their spread), two lines each at first, doubled where the
//!    transverse error is what misses the request, within a budget of a tenth of the default
//!    Monte Carlo or the nodes asked for ([`QuadOptions::nodes`], `rules.rs`). With that many variables most of an output's variance lies
//!    across the lines, so there the rule integrates only what the output's exact
//!    second-order expansion leaves (the expansion as a **control variate**, its moments
//!    exact: `control.rs`).
//! 4. Along each line, nodes `t` on a uniform grid over `[−6, 6]`, refined by halving where
//!    the along-line error is what misses the requested accuracy. **Every node is a sample**: its design
//!    is swept from the lowest speed with the Monte Carlo's own continuation
//!    ([`crate::propagate::Study::sweep_design`]), so it sits on the branch a sweep follows.
//! 5. At each speed, per line: the nodes are grouped into runs on the same branch; between
//!    nodes the smooth carriers are interpolated by cubics within a run (the pair invariants
//!    `s = λ₁+λ₂`, `p = λ₁λ₂` of every mode and |H|); where the branch changes between two
//!    nodes the boundary is where the extrapolated `Π p` (det K̂ / det M̂, zero at a static
//!    bifurcation) vanishes. Each piece is split again where `D = p − s²/4`, `p` or `s`
//!    change sign (overdamping, static and dynamic stability boundaries), and integrated by
//!    5-point Gauss–Legendre against the normal density. Outputs are the exact maps of the
//!    carriers: ω_d = √max(0, D), ζ = −s / (2√|p|), so the square-root edge is integrated, not
//!    interpolated.
//! 6. The Gauss–Legendre atoms give the mean, σ, the quantiles (weighted atoms) and the
//!    probabilities of character (overdamped, unstable, on another branch than the nominal).
//!
//! **Error estimates**: the along-line error is the difference between the result on the
//! node grid and on every other node of it (the coarser rule is worse, so the difference
//! bounds the finer rule's error for any convergent sequence); the transverse error is the
//! difference between the Gauss–Hermite tensor rule in use and the one of the order below
//! or the Student-t 95 % half-width of the scrambled replicates (of the control-variate
//! estimator where it is used). They add; where one of them alone takes more than half the
//! request of a row that misses it, that one is refined (the larger first), until every row
//! meets the request or the rule's largest stage or budget is reached (the rows then say so:
//! [`QuadStat::within_request`]).
//!
//! What it does not handle: two modes crossing between nodes (their carriers are matched by
//! shape and may swap; the error estimate then grows, as the refinement does not converge
//! there), and boundaries not crossed by the line direction in the transverse directions
//! (they are integrated by the transverse rule and show in its error estimate).

mod control;
mod directions;
mod line;
mod roots;
mod rules;
mod sums;
mod surrogate;
mod table;
mod yields;

use crate::output::{Output, Quantity};
use crate::pair::Carriers;
use crate::program::{Tier, Workspace};
use crate::propagate::{DesignAt, Estimate, Propagation, Run, Study, Termination};
use crate::sampling::DesignMap;
use crate::sweep::Point;
use crate::table::Event;
use crate::tolerance::{Spread, value};
use control::Control;
use directions::{design_jacobian, directions};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use rules::{Levels, Line, Rule, Stage, Transverse, design, grid};
use statrs::distribution::{ContinuousCDF, Normal};
use sums::{evaluate, next_stage, within};
pub use yields::{AtTarget, MarginStat, QuadYield};
use yields::{Requirements, evaluate_yield, final_yield};

/// Settings of the quadrature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadOptions {
    /// Requested error of mean and σ, relative to the larger of the output's σ at that speed
    /// and 2 % of its largest σ over the speeds (where that spread is below what the
    /// evaluation resolves, 10⁻⁸ of the output's size or of 1 for a damping ratio, that
    /// resolution instead); also the absolute target for probabilities (times 5). Refinement
    /// stops there or at the largest grid.
    pub tolerance: f64,
    /// The most nodes (designs swept across the speeds, as a Monte Carlo sample is) a case may
    /// take; `None`: the rule's own budget (a tenth of the default Monte Carlo for five or more
    /// variables, the default Monte Carlo for two to four, every node of the finest grid for
    /// one). The rule's first stage is swept whatever is asked (the rule then says so).
    pub nodes: Option<usize>,
}

impl Default for QuadOptions {
    fn default() -> Self {
        QuadOptions {
            tolerance: 1e-3,
            nodes: None,
        }
    }
}

/// Statistics of one output at one speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadStat {
    pub mean: f64,
    pub std: f64,
    /// The 5, 50 and 95 % quantiles.
    pub quantiles: [f64; 3],
    /// Error estimates of the mean and of σ.
    pub mean_error: f64,
    pub std_error: f64,
    /// Do both error estimates meet the requested accuracy ([`QuadOptions::tolerance`],
    /// relative to the larger of this σ and 2 % of the output's largest σ over the speeds)?
    /// Where not, the rule's finest grid was reached first: the row says so.
    pub within_request: bool,
}

/// Probability of one event at one speed, with its error estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probability {
    pub event: Event,
    /// 0-based mode for [`Event::Overdamped`].
    pub mode: Option<usize>,
    pub probability: f64,
    pub error: f64,
}

/// Result of the [`Quadrature`] of one case.
#[derive(Debug, Clone)]
pub struct QuadResult {
    /// `[speed][output]`; `None` where no node gave the output.
    pub stats: Vec<Vec<Option<QuadStat>>>,
    /// `[speed]`: overdamped per mode, unstable, other branch.
    pub probabilities: Vec<Vec<Probability>>,
    /// Nodes swept (each one a whole sweep over the speeds).
    pub nodes: usize,
    /// The rule, in words.
    pub rule: String,
    /// The yield of the model's requirements (`None` without requirements).
    pub yields: Option<QuadYield>,
}

/// What the nodes' sweeps gave, per line and node of the finest grid.
struct NodeData {
    /// Carriers per speed: `s, p` of every mode, then |H|.
    width: usize,
    speeds: usize,
    /// `[line][finest node]`: `None` until swept.
    data: Vec<Vec<Option<Sweep>>>,
}

impl NodeData {
    /// Nothing swept yet on the lines of `rule`.
    fn new(rule: &Rule, width: usize, speeds: usize) -> NodeData {
        let finest = Levels::nodes(rule.levels.last);
        NodeData {
            width,
            speeds,
            data: rule
                .lines
                .iter()
                .map(|_| (0..finest).map(|_| None).collect())
                .collect(),
        }
    }
}

/// One node's sweep: per speed, the branch count (`None`: failed) and the carriers.
struct Sweep {
    branch: Vec<Option<u32>>,
    carriers: Vec<f64>,
}

/// The quadrature as a propagation method: one case's spread integrated through the whole
/// pipeline (see the module documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct Quadrature {
    pub options: QuadOptions,
}

impl Propagation for Quadrature {
    /// `None` when the run was cancelled before it started.
    type Value = Option<QuadResult>;

    /// Integrates every output at every speed for one case; the study's local models'
    /// gradients choose the line direction.
    fn propagate(&self, study: &Study, spread: &Spread, run: &Run) -> Estimate<Self::Value> {
        if run.cancel.is_cancelled() {
            return Estimate {
                value: None,
                termination: Termination::Cancelled,
            };
        }
        Estimate {
            value: Some(integrate(study, spread, self.options, run)),
            termination: Termination::Completed,
        }
    }
}

/// The nominal values (the shift of the accumulated sums, and the answer when nothing
/// varies) `[speed][output]`, NaN where there is none.
fn nominal_values(study: &Study) -> Vec<Vec<f64>> {
    study
        .nominal
        .iter()
        .enumerate()
        .map(|(i, pt)| {
            let tf = study.transfer_at(i);
            study
                .outputs
                .iter()
                .map(|o| {
                    pt.as_ref()
                        .and_then(|pt| value(pt, o, tf))
                        .unwrap_or(f64::NAN)
                })
                .collect()
        })
        .collect()
}

/// The whole integration of one case to the requested relative tolerance, within the nodes
/// asked for.
fn integrate(study: &Study, spread: &Spread, options: QuadOptions, run: &Run) -> QuadResult {
    let tolerance = options.tolerance;
    // One ω_d output per mode (see `crate::output::outputs`).
    let modes = study
        .outputs
        .iter()
        .filter(|o| o.quantity == Quantity::DampedFrequency)
        .count();
    let active: Vec<usize> = (0..study.vars.len())
        .filter(|&k| spread.sigma[k] > 0.0)
        .collect();
    let values = nominal_values(study);
    if active.is_empty() {
        return deterministic(&values, &study.nominal, modes);
    }
    let nodes = Nodes::new(study, spread, (&active, options.nodes), modes);
    let rule = &nodes.rule;
    let nominal = Reference {
        values: &values,
        branches: &study.branches,
        outs: &study.outputs,
        modes,
    };
    let mut store = NodeData::new(rule, Carriers::width(modes), study.speeds.len());
    let mut count = Count {
        swept: 0,
        budget: rule.budget(),
    };
    let requirements = &study.model.model().requirements;
    let reqs = (!requirements.is_empty()).then(|| Requirements {
        list: requirements,
        request: tolerance,
        speeds: &study.speeds,
        shift: nominal_margins(study, requirements),
        offset: vec![0.0; requirements.len()],
        // The refinement reads the probabilities' errors; the margins' moments are
        // integrated once, at the last stage.
        moments: false,
        target: study.model.model().allocation.target_yield,
    });
    let mut stage = rule.first();
    let mut result;
    let mut yields;
    loop {
        nodes.sweep_stage(stage, &mut store, run, &mut count);
        result = run
            .pool
            .install(|| evaluate(&store, rule, stage, &nominal, nodes.control.as_ref()));
        yields = reqs.as_ref().map(|reqs| {
            run.pool
                .install(|| evaluate_yield(&store, rule, stage, &nominal, reqs))
        });
        let yield_error = yields.as_ref().map(|(y, parts)| {
            // Every yield row: over the ranges, per speed, and the operating ranges met.
            let worst = y
                .each
                .iter()
                .chain([&y.all])
                .chain(y.curves.iter().chain(&y.prefix).flatten())
                .map(|e| e.1)
                .filter(|e| !e.is_nan())
                .fold(0.0, f64::max);
            (*parts, worst)
        });
        match next_stage(&result, &study.outputs, yield_error, rule, stage, tolerance) {
            Some(next) => stage = next,
            None => break,
        }
    }
    let yields = reqs.map(|reqs| {
        let reqs = Requirements {
            moments: true,
            ..reqs
        };
        run.pool
            .install(|| final_yield(&store, rule, stage, &nominal, &reqs))
    });
    let met = within(&result.stats, &study.outputs, tolerance);
    for (row, within) in result.stats.iter_mut().zip(met) {
        for (stat, ok) in row.iter_mut().zip(within) {
            if let (Some(stat), Some(ok)) = (stat, ok) {
                stat.within_request = ok;
            }
        }
    }
    QuadResult {
        stats: result.stats,
        probabilities: result.probabilities,
        nodes: count.swept,
        rule: rule.describe(active.len(), stage, count.swept),
        yields,
    }
}

/// Each requirement's worst margin over its range at the nominal design (the shift of the
/// margins' sums; 0 where it has none).
fn nominal_margins(study: &Study, requirements: &[crate::model::Requirement]) -> Vec<f64> {
    let mut worst = vec![f64::INFINITY; requirements.len()];
    for (i, pt) in study.nominal.iter().enumerate() {
        let at = pt.as_ref().map(|pt| DesignAt {
            nominal: pt,
            point: pt,
            switches: study.branches[i],
            same_branch: true,
            transfer: study.transfer_at(i),
        });
        study.margins(i, at.as_ref(), crate::margins::covers, |r, m| {
            worst[r] = worst[r].min(m);
        });
    }
    worst
        .into_iter()
        .map(|w| if w.is_finite() { w } else { 0.0 })
        .collect()
}

/// Nodes swept so far, and at most.
struct Count {
    swept: usize,
    budget: usize,
}

/// Where the nodes of one case lie and how each is swept: the active variables' design map,
/// the line direction and its complement (in independent standard normals `z = α t + V y`),
/// the rule, and (for the many-variable rule) the outputs' expansions as control variates.
struct Nodes<'a> {
    study: &'a Study<'a>,
    map: DesignMap,
    basis: DMatrix<f64>,
    rule: Rule,
    control: Option<Control<'a>>,
    /// Carriers per speed: `s, p` of every mode, then |H|.
    width: usize,
}

impl<'a> Nodes<'a> {
    /// The nodes of the variables `active` (indices into the study's variables) of `spread`,
    /// at most `asked` of them where given ([`QuadOptions::nodes`]).
    fn new(
        study: &'a Study<'a>,
        spread: &Spread,
        (active, asked): (&[usize], Option<usize>),
        modes: usize,
    ) -> Self {
        let d = active.len();
        // Standard normals of the active variables.
        let sub = DMatrix::from_fn(d, d, |i, j| spread.correlation[(active[i], active[j])]);
        let sub_vars: Vec<usize> = active.iter().map(|&k| study.vars[k]).collect();
        let sub_spread = Spread {
            sigma: active.iter().map(|&k| spread.sigma[k]).collect(),
            distribution: active.iter().map(|&k| spread.distribution[k]).collect(),
            correlation: sub,
            covariance: DMatrix::from_fn(d, d, |i, j| spread.covariance[(active[i], active[j])]),
        };
        let map = DesignMap::new(study.model.model().nominal(), sub_vars, sub_spread.clone());
        let basis = directions(&study.locals, active, &sub_spread, map.factor());
        let rule = design(d, asked);
        let control = matches!(rule.transverse, Transverse::Scrambled { .. }).then(|| {
            let jac = design_jacobian(&sub_spread, map.factor());
            let offsets: Vec<DVector<f64>> = rule.lines.iter().map(|l| offset(&basis, l)).collect();
            let alpha = basis.column(0).into_owned();
            Control::new(&study.locals, active, &jac, &alpha, &offsets)
        });
        Nodes {
            study,
            map,
            basis,
            rule,
            control,
            width: Carriers::width(modes),
        }
    }

    /// The design at position `t` along `line`.
    fn parameters(&self, line: &Line, t: f64) -> Vec<f64> {
        let normal = Normal::standard();
        let z = offset(&self.basis, line) + self.basis.column(0) * t;
        let u: Vec<f64> = z.iter().map(|&x| normal.cdf(x)).collect();
        self.map.parameters(z.as_slice(), &u)
    }

    /// Sweeps the design `params` across the speeds as a sample is ([`Study::sweep_design`]) and
    /// keeps its carriers and branch counts.
    fn sweep(&self, params: Vec<f64>, run: (Tier, &Workspace)) -> Sweep {
        let (study, width) = (self.study, self.width);
        let speeds = &study.speeds;
        let mut branch = vec![None; speeds.len()];
        let mut carriers = vec![f64::NAN; speeds.len() * width];
        study.sweep_design(params, run, |i, at| {
            let Some(at) = at else { return };
            let c = &mut carriers[i * width..(i + 1) * width];
            at.write_carriers(c);
            // The node holds where its modes do: an |H| without a value (a resonance at this
            // node) leaves |H| alone without one, not the modes' outputs.
            if Carriers::new(c)
                .pairs()
                .all(|(s, p)| s.is_finite() && p.is_finite())
            {
                branch[i] = Some(at.switches as u32);
            }
        });
        Sweep { branch, carriers }
    }

    /// Sweeps the nodes refinement `stage` adds (the check lines only at the first level), in
    /// parallel.
    fn sweep_stage(&self, stage: Stage, store: &mut NodeData, run: &Run, count: &mut Count) {
        let (lines, levels) = (&self.rule.lines, self.rule.levels);
        let finest = Levels::nodes(levels.last);
        let todo: Vec<(usize, usize)> = lines
            .iter()
            .enumerate()
            .filter(|(_, l)| self.rule.uses(l, stage))
            .flat_map(|(li, l)| {
                let level = if self.rule.checks(l, stage) {
                    levels.first
                } else {
                    stage.level
                };
                (0..finest)
                    .step_by(1 << (levels.last - level))
                    .map(move |j| (li, j))
            })
            .filter(|&(li, j)| store.data[li][j].is_none())
            .collect();
        let tier = Tier::for_points(todo.len() * self.study.speeds.len());
        let done = std::sync::atomic::AtomicUsize::new(count.swept);
        let new: Vec<Sweep> = run.pool.install(|| {
            todo.par_iter()
                .map_init(Workspace::default, |workspace, &(li, j)| {
                    let t = grid(finest, j);
                    let s = self.sweep(self.parameters(&lines[li], t), (tier, workspace));
                    let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    (run.progress)(n, count.budget);
                    s
                })
                .collect()
        });
        count.swept += new.len();
        for (&(li, j), s) in todo.iter().zip(new) {
            store.data[li][j] = Some(s);
        }
    }
}

/// The transverse point `V y` of `line` (in `z`; the line direction is the basis's first
/// column).
fn offset(basis: &DMatrix<f64>, line: &Line) -> DVector<f64> {
    let mut z = DVector::<f64>::zeros(basis.nrows());
    for (k, &y) in line.y.iter().enumerate() {
        z += basis.column(k + 1) * y;
    }
    z
}

/// What the statistics are measured against at each speed: the nominal values (the shift of
/// the sums), the nominal branch counts, the outputs and the number of modes.
struct Reference<'a> {
    values: &'a [Vec<f64>],
    branches: &'a [usize],
    outs: &'a [Output],
    modes: usize,
}

/// The result when no variable varies: the nominal values, σ = 0.
fn deterministic(values: &[Vec<f64>], nominal: &[Option<Point>], modes: usize) -> QuadResult {
    let stats = values
        .iter()
        .map(|row| {
            row.iter()
                .map(|&v| {
                    v.is_finite().then_some(QuadStat {
                        mean: v,
                        std: 0.0,
                        quantiles: [v; 3],
                        mean_error: 0.0,
                        std_error: 0.0,
                        within_request: true,
                    })
                })
                .collect()
        })
        .collect();
    let probabilities = nominal
        .iter()
        .map(|pt| match pt {
            Some(pt) => events_of(
                modes,
                |m| pt.modes[m].class == crate::modal::ModeClass::Overdamped,
                !pt.stable(),
                false,
                1.0,
            ),
            None => Vec::new(),
        })
        .collect();
    QuadResult {
        stats,
        probabilities,
        nodes: 0,
        rule: "no variable varies".into(),
        yields: None,
    }
}

fn events_of(
    modes: usize,
    overdamped: impl Fn(usize) -> bool,
    unstable: bool,
    other: bool,
    mass: f64,
) -> Vec<Probability> {
    let mut v: Vec<Probability> = (0..modes)
        .map(|m| Probability {
            event: Event::Overdamped,
            mode: Some(m),
            probability: if overdamped(m) { mass } else { 0.0 },
            error: 0.0,
        })
        .collect();
    for (event, on) in [(Event::Unstable, unstable), (Event::OtherBranch, other)] {
        v.push(Probability {
            event,
            mode: None,
            probability: if on { mass } else { 0.0 },
            error: 0.0,
        });
    }
    v
}
