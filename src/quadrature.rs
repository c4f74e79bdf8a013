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
//!    [`crate::montecarlo::parameters_at`]: correlations through the Cholesky factor, uniform
//!    variables through `Φ`). Only the variables the case tolerances count.
//! 2. The line direction `α` is the dominant eigenvector of `Σ ĝ ĝᵀ`, the normalised exact
//!    gradients (in `z`) of every output and pair discriminant at every speed (an active
//!    subspace, Constantine, *Active Subspaces*, SIAM 2015): the direction across which the
//!    outputs change, and so change character. `z = α t + V y` with `V` its orthogonal
//!    complement.
//! 3. Transverse points `y` carry weights: one line for one variable; the tensor 3-point
//!    Gauss–Hermite rule for two to four variables, checked against the 2-point rule; for
//!    five or more, randomised quasi-Monte Carlo (eight independently Owen-scrambled Sobol
//!    sets, Owen 1997; the error from their spread).
//! 4. Along each line, nodes `t` on a uniform grid over `[−6, 6]`, refined by halving until
//!    the estimated error meets the requested accuracy. **Every node is a sample**: its design
//!    is swept from the lowest speed with the Monte Carlo's own continuation
//!    ([`crate::montecarlo::sample_sweep`]), so it sits on the branch a sweep follows.
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
//! difference between the 3- and the 2-point Gauss–Hermite tensor rules (both degree ≥ 3)
//! or the Student-t 95 % half-width of the scrambled replicates. They add.
//!
//! What it does not handle: two modes crossing between nodes (their carriers are matched by
//! shape and may swap; the error estimate then grows, as the refinement does not converge
//! there), and boundaries not crossed by the line direction in the transverse directions
//! (they are integrated by the transverse rule and show in its error estimate).

use crate::compiled::Compiled;
use crate::model::Distribution;
use crate::montecarlo::{correlation_factor, parameters_at, sample_sweep};
use crate::sensitivity::TransferAt;
use crate::sweep::Point;
use crate::tolerance::{LocalModel, Output, Quantity, Spread, sigma_of, value};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Settings of the quadrature.
#[derive(Debug, Clone, Copy)]
pub struct QuadOptions {
    /// Requested error of mean and σ, relative to the larger of the output's σ at that speed
    /// and 2 % of its largest σ over the speeds; also the absolute target for probabilities
    /// (times 5). Refinement stops there or at the largest grid.
    pub tolerance: f64,
    /// Worker threads (`None`: rayon's default).
    pub threads: Option<usize>,
}

impl Default for QuadOptions {
    fn default() -> Self {
        QuadOptions {
            tolerance: 1e-3,
            threads: None,
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
}

/// A change of character whose probability is reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The mode's roots are real (and not unstable).
    Overdamped,
    /// The equilibrium is unstable (a root with positive real part).
    Unstable,
    /// The design is on another equilibrium branch than the nominal one at this speed.
    OtherBranch,
}

impl Event {
    pub fn as_str(self) -> &'static str {
        match self {
            Event::Overdamped => "overdamped",
            Event::Unstable => "unstable",
            Event::OtherBranch => "other_branch",
        }
    }
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

/// Result of [`integrate`] for one case.
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
}

/// Half-width of the node grid along a line in standard deviations (normal mass outside:
/// 2·10⁻⁹).
const HALF_WIDTH: f64 = 6.0;
/// Where the extrapolated tails end (normal mass outside: 2·10⁻¹⁹).
const TAIL_END: f64 = 9.0;
/// Relative precision of one node's outputs (Newton's certified step and the eigensolver are
/// near 10⁻¹², a little amplified near a bifurcation): a floor of the error estimates, times
/// the size of the output.
const EVAL_PRECISION: f64 = 1e-9;

/// The transverse rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Transverse {
    /// One variable: a single line.
    Single,
    /// Tensor Gauss–Hermite (3 points), checked by the 2-point rule.
    Tensor,
    /// Scrambled Sobol replicates.
    Scrambled { replicates: usize },
}

/// One line: its transverse point and weight; `check` lines belong to the 2-point
/// Gauss–Hermite rule that only checks the transverse error.
#[derive(Debug, Clone)]
struct Line {
    y: Vec<f64>,
    weight: f64,
    check: bool,
    replicate: usize,
}

/// Node grids along a line: `2^k + 1` points, nested.
#[derive(Debug, Clone, Copy)]
struct Levels {
    first: usize,
    last: usize,
}

impl Levels {
    /// Nodes at level `k` (stride in the finest grid follows).
    fn nodes(k: usize) -> usize {
        (1 << k) + 1
    }
}

/// What the nodes' sweeps gave, per line and node of the finest grid.
struct NodeData {
    /// Carriers per speed: `s, p` of every mode, then |H|.
    width: usize,
    speeds: usize,
    /// `[line][finest node]`: `None` until swept.
    data: Vec<Vec<Option<Sweep>>>,
}

/// One node's sweep: per speed, the branch count (`None`: failed) and the carriers.
struct Sweep {
    branch: Vec<Option<u32>>,
    carriers: Vec<f64>,
}

/// Integrates every output of `outs` at every speed for one case. `locals` are the nominal
/// local models (their gradients choose the line direction), `nominal` the nominal sweep.
#[allow(clippy::too_many_arguments)]
pub fn integrate(
    model: &Compiled,
    vars: &[usize],
    spread: &Spread,
    speeds: &[f64],
    nominal: &[Option<Point>],
    locals: &[Option<LocalModel>],
    outs: &[Output],
    transfer: Option<&crate::model::Transfer>,
    opt: QuadOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> QuadResult {
    // One ω_d output per mode (see `crate::tolerance::outputs`).
    let modes = outs
        .iter()
        .filter(|o| o.quantity == Quantity::DampedFrequency)
        .count();
    let active: Vec<usize> = (0..vars.len()).filter(|&k| spread.sigma[k] > 0.0).collect();
    let d = active.len();
    let branches = crate::montecarlo::branch_counts(nominal);
    // The nominal values: the shift of the accumulated sums, and the answer when nothing varies.
    let nominal_values: Vec<Vec<f64>> = speeds
        .iter()
        .zip(nominal)
        .map(|(&w, pt)| {
            let tf = transfer.map(|t| TransferAt::at_speed(t, w));
            outs.iter()
                .map(|o| {
                    pt.as_ref()
                        .and_then(|pt| value(pt, o, tf))
                        .unwrap_or(f64::NAN)
                })
                .collect()
        })
        .collect();
    if d == 0 {
        return deterministic(&nominal_values, nominal, modes);
    }
    // Standard normals of the active variables.
    let sub = DMatrix::from_fn(d, d, |i, j| spread.correlation[(active[i], active[j])]);
    let chol = correlation_factor(&sub);
    let sub_vars: Vec<usize> = active.iter().map(|&k| vars[k]).collect();
    let sub_spread = Spread {
        sigma: active.iter().map(|&k| spread.sigma[k]).collect(),
        distribution: active.iter().map(|&k| spread.distribution[k]).collect(),
        correlation: sub.clone(),
        covariance: DMatrix::from_fn(d, d, |i, j| spread.covariance[(active[i], active[j])]),
    };
    let basis = directions(locals, &active, &sub_spread, &chol);
    let (transverse, lines, levels) = design(d);
    let p0 = model.nominal();
    let width = 2 * modes + 1;
    let finest = Levels::nodes(levels.last);
    let mut store = NodeData {
        width,
        speeds: speeds.len(),
        data: lines
            .iter()
            .map(|_| (0..finest).map(|_| None).collect())
            .collect(),
    };
    let pool = crate::threads::pool(opt.threads);
    let normal = Normal::standard();
    let node_params = |line: &Line, t: f64| {
        let mut z = DVector::<f64>::zeros(d);
        z += basis.column(0) * t;
        for (k, &y) in line.y.iter().enumerate() {
            z += basis.column(k + 1) * y;
        }
        let u: Vec<f64> = z.iter().map(|&x| normal.cdf(x)).collect();
        parameters_at(&p0, &sub_vars, &sub_spread, &chol, z.as_slice(), &u)
    };
    let sweep_node = |params: Vec<f64>| {
        let mut branch = vec![None; speeds.len()];
        let mut carriers = vec![f64::NAN; speeds.len() * width];
        sample_sweep(model, params, speeds, nominal, |i, pts| {
            let Some((_, pt, switches)) = pts else { return };
            let c = &mut carriers[i * width..(i + 1) * width];
            for (m, mode) in pt.modes.iter().enumerate() {
                let (a, b) = (mode.root.lambda, mode.partner.lambda);
                c[2 * m] = (a + b).re;
                c[2 * m + 1] = (a * b).re;
            }
            if let Some(t) = transfer {
                let tf = TransferAt::at_speed(t, speeds[i]);
                let o = Output {
                    quantity: Quantity::TransferMagnitude,
                    mode: None,
                };
                c[2 * modes] = value(pt, &o, Some(tf)).unwrap_or(f64::NAN);
            } else {
                c[2 * modes] = 0.0;
            }
            // The node holds where its modes do: an |H| without a value (a resonance at this
            // node) leaves |H| alone without one, not the modes' outputs.
            if c[..2 * modes].iter().all(|v| v.is_finite()) {
                branch[i] = Some(switches as u32);
            }
        });
        Sweep { branch, carriers }
    };
    let mut swept = 0;
    let budget: usize = lines
        .iter()
        .map(|l| {
            if l.check {
                Levels::nodes(levels.first)
            } else {
                finest
            }
        })
        .sum();
    let mut level = levels.first;
    let mut result;
    loop {
        // Sweep the nodes this level adds (the check lines only at the first level).
        let stride = 1 << (levels.last - level);
        let todo: Vec<(usize, usize)> = lines
            .iter()
            .enumerate()
            .filter(|(_, l)| !l.check || level == levels.first)
            .flat_map(|(li, _)| (0..finest).step_by(stride).map(move |j| (li, j)))
            .filter(|&(li, j)| store.data[li][j].is_none())
            .collect();
        let done = std::sync::atomic::AtomicUsize::new(swept);
        let new: Vec<Sweep> = pool.install(|| {
            todo.par_iter()
                .map(|&(li, j)| {
                    let t = grid(finest, j);
                    let s = sweep_node(node_params(&lines[li], t));
                    let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    progress(n, budget);
                    s
                })
                .collect()
        });
        swept += new.len();
        for (&(li, j), s) in todo.iter().zip(new) {
            store.data[li][j] = Some(s);
        }
        result = pool.install(|| {
            evaluate(
                &store,
                &lines,
                transverse,
                stride,
                stride << 1,
                levels.first,
                levels.last,
                &nominal_values,
                &branches,
                outs,
                modes,
            )
        });
        if level == levels.last || converged(&result, opt.tolerance) {
            break;
        }
        level += 1;
    }
    let rule = format!(
        "{d} variable(s); {}; {} node(s) per line at most; {swept} nodes swept",
        match transverse {
            Transverse::Single => "one line".to_string(),
            Transverse::Tensor => format!(
                "{} lines (3-point Gauss–Hermite tensor, checked by the 2-point rule)",
                lines.iter().filter(|l| !l.check).count()
            ),
            Transverse::Scrambled { replicates } => format!(
                "{} lines ({replicates} scrambled Sobol replicates)",
                lines.len()
            ),
        },
        finest
    );
    QuadResult {
        stats: result.0,
        probabilities: result.1,
        nodes: swept,
        rule,
    }
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

/// Position of node `j` of an `n`-node grid on `[−6, 6]`.
fn grid(n: usize, j: usize) -> f64 {
    -HALF_WIDTH + 2.0 * HALF_WIDTH * j as f64 / (n - 1) as f64
}

/// The line direction first, then an orthonormal basis of its complement (columns, in `z`).
fn directions(
    locals: &[Option<LocalModel>],
    active: &[usize],
    s: &Spread,
    chol: &DMatrix<f64>,
) -> DMatrix<f64> {
    let d = active.len();
    if d == 1 {
        return DMatrix::identity(1, 1);
    }
    // ∂b/∂z at z = 0.
    let phi0 = 1.0 / (2.0 * std::f64::consts::PI).sqrt();
    let jac = DMatrix::from_fn(d, d, |i, k| match s.distribution[i] {
        Distribution::Normal => s.sigma[i] * chol[(i, k)],
        Distribution::Uniform if i == k => s.sigma[i] * 3f64.sqrt() * 2.0 * phi0,
        Distribution::Uniform => 0.0,
    });
    let mut c = DMatrix::<f64>::zeros(d, d);
    for lm in locals.iter().flatten() {
        let grads = lm
            .grad
            .iter()
            .flatten()
            .chain(lm.disc.iter().filter_map(|(_, g, _)| g.as_ref().ok()));
        for g in grads {
            let gb = DVector::from_iterator(d, active.iter().map(|&k| g[k]));
            let gz = jac.transpose() * gb;
            let n = gz.norm();
            if n.is_finite() && n > 0.0 {
                let u = gz / n;
                c += &u * u.transpose();
            }
        }
    }
    if c.iter().all(|v| *v == 0.0) {
        c = DMatrix::identity(d, d);
    }
    let Some(eig) = crate::linalg::symmetric_eigen(c) else {
        return DMatrix::identity(d, d);
    };
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    DMatrix::from_fn(d, d, |i, j| {
        let col = eig.eigenvectors.column(order[j]);
        // A fixed sign: the largest component positive.
        let big = col
            .iter()
            .fold(0.0f64, |m, &v| if v.abs() > m.abs() { v } else { m });
        col[i] * big.signum()
    })
}

/// The transverse rule, its lines and the node levels for `d` variables.
fn design(d: usize) -> (Transverse, Vec<Line>, Levels) {
    match d {
        1 => (
            Transverse::Single,
            vec![Line {
                y: Vec::new(),
                weight: 1.0,
                check: false,
                replicate: 0,
            }],
            Levels { first: 5, last: 7 },
        ),
        2..=4 => {
            let mut lines = tensor(
                d - 1,
                &[-3f64.sqrt(), 0.0, 3f64.sqrt()],
                &[1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
                false,
            );
            lines.extend(tensor(d - 1, &[-1.0, 1.0], &[0.5, 0.5], true));
            (Transverse::Tensor, lines, Levels { first: 4, last: 5 })
        }
        _ => {
            let (replicates, per) = (8, 16);
            let normal = Normal::standard();
            let lines = (0..replicates)
                .flat_map(|r| {
                    (0..per).map(move |i| Line {
                        y: (0..d - 1)
                            .map(|k| {
                                let u = sobol_burley::sample(i as u32, k as u32, 0x5eed + r as u32)
                                    as f64
                                    + 0.5 / (1u64 << 24) as f64;
                                normal.inverse_cdf(u.clamp(1e-12, 1.0 - 1e-12))
                            })
                            .collect(),
                        weight: 1.0 / (replicates * per) as f64,
                        check: false,
                        replicate: r,
                    })
                })
                .collect();
            (
                Transverse::Scrambled { replicates },
                lines,
                Levels { first: 3, last: 4 },
            )
        }
    }
}

/// Tensor product of a 1-D rule in `dims` dimensions.
fn tensor(dims: usize, nodes: &[f64], weights: &[f64], check: bool) -> Vec<Line> {
    let mut lines = vec![Line {
        y: Vec::new(),
        weight: 1.0,
        check,
        replicate: 0,
    }];
    for _ in 0..dims {
        lines = lines
            .into_iter()
            .flat_map(|l| {
                nodes.iter().zip(weights).map(move |(&x, &w)| {
                    let mut y = l.y.clone();
                    y.push(x);
                    Line {
                        y,
                        weight: l.weight * w,
                        check,
                        replicate: 0,
                    }
                })
            })
            .collect();
    }
    lines
}

/// Sums of one line (or of a rule) at one speed: per output the mass where it is defined and
/// the first two moments about the nominal value; the event masses; the total mass.
#[derive(Debug, Clone, Default)]
struct Sums {
    mass: f64,
    defined: Vec<f64>,
    s1: Vec<f64>,
    s2: Vec<f64>,
    /// Overdamped per mode, then unstable, then other branch.
    events: Vec<f64>,
}

impl Sums {
    fn new(outs: usize, modes: usize) -> Sums {
        Sums {
            mass: 0.0,
            defined: vec![0.0; outs],
            s1: vec![0.0; outs],
            s2: vec![0.0; outs],
            events: vec![0.0; modes + 2],
        }
    }

    fn add_scaled(&mut self, b: &Sums, w: f64) {
        self.mass += w * b.mass;
        for (x, y) in self
            .defined
            .iter_mut()
            .chain(&mut self.s1)
            .chain(&mut self.s2)
            .chain(&mut self.events)
            .zip(b.defined.iter().chain(&b.s1).chain(&b.s2).chain(&b.events))
        {
            *x += w * y;
        }
    }

    /// Mean and σ of output `o` (shifted back by `shift`).
    fn moments(&self, o: usize, shift: f64) -> Option<(f64, f64)> {
        let w = self.defined[o];
        (w > 0.0).then(|| {
            let m1 = self.s1[o] / w;
            (m1 + shift, sigma_of(self.s2[o] / w - m1 * m1))
        })
    }

    fn probability(&self, e: usize) -> f64 {
        if self.mass > 0.0 {
            self.events[e] / self.mass
        } else {
            f64::NAN
        }
    }
}

/// Statistics at every speed from the nodes at `stride` (the answer) and at `coarse` (its
/// along-line error estimate).
#[allow(clippy::too_many_arguments)]
fn evaluate(
    store: &NodeData,
    lines: &[Line],
    transverse: Transverse,
    stride: usize,
    coarse: usize,
    first_level: usize,
    last_level: usize,
    nominal_values: &[Vec<f64>],
    branches: &[usize],
    outs: &[Output],
    modes: usize,
) -> (Vec<Vec<Option<QuadStat>>>, Vec<Vec<Probability>>) {
    let check_stride = 1 << (last_level - first_level);
    let per_speed: Vec<(Vec<Option<QuadStat>>, Vec<Probability>)> = (0..store.speeds)
        .into_par_iter()
        .map(|i| {
            let shift: Vec<f64> = nominal_values[i]
                .iter()
                .map(|v| if v.is_finite() { *v } else { 0.0 })
                .collect();
            let ctx = Context {
                store,
                speed: i,
                outs,
                modes,
                shift: &shift,
                branch: branches[i] as u32,
            };
            let mut fine = Sums::new(outs.len(), modes);
            let mut rough = Sums::new(outs.len(), modes);
            let mut check = Sums::new(outs.len(), modes);
            let mut main_at_check = Sums::new(outs.len(), modes);
            let replicates = match transverse {
                Transverse::Scrambled { replicates } => replicates,
                _ => 1,
            };
            let mut reps = vec![Sums::new(outs.len(), modes); replicates];
            let mut atoms: Vec<Vec<(f64, f64)>> = vec![Vec::new(); outs.len()];
            for (li, line) in lines.iter().enumerate() {
                if line.check {
                    let s = ctx.line(li, check_stride, None);
                    check.add_scaled(&s, line.weight);
                    continue;
                }
                let s = ctx.line(li, stride, Some((&mut atoms, line.weight)));
                fine.add_scaled(&s, line.weight);
                reps[line.replicate].add_scaled(&s, line.weight * replicates as f64);
                rough.add_scaled(&ctx.line(li, coarse, None), line.weight);
                if transverse == Transverse::Tensor {
                    main_at_check.add_scaled(&ctx.line(li, check_stride, None), line.weight);
                }
            }
            // Transverse error of a statistic computed from sums.
            let t975 = if replicates > 1 {
                StudentsT::new(0.0, 1.0, (replicates - 1) as f64)
                    .map_or(2.0, |t| t.inverse_cdf(0.975))
            } else {
                0.0
            };
            let transverse_error = |f: &dyn Fn(&Sums) -> Option<f64>| -> f64 {
                match transverse {
                    Transverse::Single => 0.0,
                    Transverse::Tensor => match (f(&main_at_check), f(&check)) {
                        (Some(a), Some(b)) => (a - b).abs(),
                        _ => f64::NAN,
                    },
                    Transverse::Scrambled { .. } => {
                        let v: Option<Vec<f64>> = reps.iter().map(f).collect();
                        v.map_or(f64::NAN, |v| {
                            let r = v.len() as f64;
                            let m = v.iter().sum::<f64>() / r;
                            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (r - 1.0);
                            t975 * (var / r).sqrt()
                        })
                    }
                }
            };
            let stats = (0..outs.len())
                .map(|o| {
                    let (mean, std) = fine.moments(o, shift[o])?;
                    let (rm, rs) = rough.moments(o, shift[o]).unwrap_or((f64::NAN, f64::NAN));
                    let floor = EVAL_PRECISION * (mean.abs() + std);
                    let mean_error = 2.0 * (mean - rm).abs()
                        + floor
                        + transverse_error(&|s: &Sums| s.moments(o, shift[o]).map(|m| m.0));
                    let std_error = 2.0 * (std - rs).abs()
                        + floor
                        + transverse_error(&|s: &Sums| s.moments(o, shift[o]).map(|m| m.1));
                    Some(QuadStat {
                        mean,
                        std,
                        quantiles: quantiles(&mut atoms[o]),
                        mean_error: if mean_error.is_finite() {
                            mean_error
                        } else {
                            f64::INFINITY
                        },
                        std_error: if std_error.is_finite() {
                            std_error
                        } else {
                            f64::INFINITY
                        },
                    })
                })
                .collect();
            let probabilities = if fine.mass > 0.0 {
                (0..modes + 2)
                    .map(|e| {
                        let p = fine.probability(e);
                        let err = 2.0 * (p - rough.probability(e)).abs()
                            + transverse_error(&|s: &Sums| Some(s.probability(e)));
                        Probability {
                            event: match e {
                                e if e < modes => Event::Overdamped,
                                e if e == modes => Event::Unstable,
                                _ => Event::OtherBranch,
                            },
                            mode: (e < modes).then_some(e),
                            probability: p,
                            error: if err.is_finite() { err } else { 1.0 },
                        }
                    })
                    .collect()
            } else {
                Vec::new()
            };
            (stats, probabilities)
        })
        .collect();
    per_speed.into_iter().unzip()
}

/// The 5, 50 and 95 % quantiles of weighted atoms (value, weight).
fn quantiles(atoms: &mut [(f64, f64)]) -> [f64; 3] {
    atoms.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = atoms.iter().map(|a| a.1).sum();
    [0.05, 0.5, 0.95].map(|q| {
        let target = q * total;
        let mut acc = 0.0;
        for (k, &(v, w)) in atoms.iter().enumerate() {
            // Each atom's weight centred on it: interpolate between neighbours' centres.
            let centre = acc + 0.5 * w;
            if centre >= target {
                if k == 0 {
                    return v;
                }
                let (pv, pw) = atoms[k - 1];
                let pc = acc - 0.5 * pw;
                let f = ((target - pc) / (centre - pc)).clamp(0.0, 1.0);
                return pv + f * (v - pv);
            }
            acc += w;
        }
        atoms.last().map_or(f64::NAN, |a| a.0)
    })
}

/// Was the along-line error met everywhere?
fn converged(result: &(Vec<Vec<Option<QuadStat>>>, Vec<Vec<Probability>>), tol: f64) -> bool {
    let outs = result.0.first().map_or(0, |r| r.len());
    for o in 0..outs {
        let largest = result
            .0
            .iter()
            .filter_map(|r| r[o].map(|s| s.std))
            .fold(0.0f64, f64::max);
        for row in &result.0 {
            if let Some(s) = row[o] {
                let target = tol * s.std.max(0.02 * largest);
                if !(s.mean_error <= target && s.std_error <= target) {
                    return false;
                }
            }
        }
    }
    result.1.iter().flatten().all(|p| p.error <= 5.0 * tol)
}

/// Gauss–Legendre, 5 points on [−1, 1].
const GL_X: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683_1,
    0.0,
    0.538_469_310_105_683_1,
    0.906_179_845_938_664,
];
const GL_W: [f64; 5] = [
    0.236_926_885_056_189_1,
    0.478_628_670_499_366_5,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
];

/// Where a line integral collects its weighted output values for the quantiles (per output),
/// and the line's weight.
type Atoms<'a> = (&'a mut Vec<Vec<(f64, f64)>>, f64);

/// What a line integral needs at one speed.
struct Context<'a> {
    store: &'a NodeData,
    speed: usize,
    outs: &'a [Output],
    modes: usize,
    shift: &'a [f64],
    /// The nominal branch count here.
    branch: u32,
}

/// An interpolant: Lagrange through nodes (positions and carrier rows).
struct Stencil<'a> {
    t: Vec<f64>,
    rows: Vec<&'a [f64]>,
    branch: u32,
}

impl Stencil<'_> {
    fn eval(&self, t: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (i, (&ti, row)) in self.t.iter().zip(&self.rows).enumerate() {
            let l: f64 = self
                .t
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &tj)| (t - tj) / (ti - tj))
                .product();
            for (o, &c) in out.iter_mut().zip(row.iter()) {
                *o += l * c;
            }
        }
    }
}

impl Context<'_> {
    /// Integrates one line with the nodes at `stride`; with `atoms`, also collects the
    /// weighted output values for the quantiles.
    fn line(&self, li: usize, stride: usize, mut atoms: Option<Atoms>) -> Sums {
        let data = &self.store.data[li];
        let finest = data.len();
        let w = self.store.width;
        let idx: Vec<usize> = (0..finest).step_by(stride).collect();
        let t: Vec<f64> = idx.iter().map(|&j| grid(finest, j)).collect();
        let node = |k: usize| data[idx[k]].as_ref().expect("swept");
        let sig: Vec<Option<u32>> = (0..idx.len()).map(|k| node(k).branch[self.speed]).collect();
        let row = |k: usize| &node(k).carriers[self.speed * w..(self.speed + 1) * w];
        // Runs of equal signature.
        let mut run_of = vec![(0usize, 0usize); idx.len()];
        let mut start = 0;
        for k in 1..=idx.len() {
            if k == idx.len() || sig[k] != sig[start] {
                for r in run_of.iter_mut().take(k).skip(start) {
                    *r = (start, k - 1);
                }
                start = k;
            }
        }
        let stencil = |from: usize, to: usize| Stencil {
            t: t[from..=to].to_vec(),
            rows: (from..=to).map(row).collect(),
            branch: sig[from].unwrap_or(0),
        };
        // Up to 4 nodes of the run `(r0, r1)` around the interval starting at `k`.
        let around = |k: usize, (r0, r1): (usize, usize)| {
            let len = (r1 - r0 + 1).min(4);
            let from = k.saturating_sub(1).clamp(r0, r1 + 1 - len);
            stencil(from, from + len - 1)
        };
        let mut sums = Sums::new(self.outs.len(), self.modes);
        for k in 0..idx.len() - 1 {
            let (a, b) = (t[k], t[k + 1]);
            match (sig[k], sig[k + 1]) {
                (None, None) => sums.mass += normal_mass(a, b),
                (x, y) if x == y => {
                    let st = around(k, run_of[k]);
                    self.piece(&st, a, b, &mut sums, &mut atoms);
                }
                (Some(_), None) => {
                    let m = 0.5 * (a + b);
                    let (r0, _) = run_of[k];
                    let st = stencil(k.saturating_sub(3).max(r0), k);
                    self.piece(&st, a, m, &mut sums, &mut atoms);
                    sums.mass += normal_mass(m, b);
                }
                (None, Some(_)) => {
                    let m = 0.5 * (a + b);
                    let (_, r1) = run_of[k + 1];
                    let st = stencil(k + 1, (k + 4).min(r1));
                    sums.mass += normal_mass(a, m);
                    self.piece(&st, m, b, &mut sums, &mut atoms);
                }
                (Some(_), Some(_)) => {
                    let (r0, _) = run_of[k];
                    let (_, r1) = run_of[k + 1];
                    let left = stencil(k.saturating_sub(3).max(r0), k);
                    let right = stencil(k + 1, (k + 4).min(r1));
                    let m = self.switch_point(&left, &right, a, b);
                    self.piece(&left, a, m, &mut sums, &mut atoms);
                    self.piece(&right, m, b, &mut sums, &mut atoms);
                }
            }
        }
        // The tails beyond ±6 (normal mass 2·10⁻⁹, but 4·10⁻⁸ of a variance): the end runs'
        // interpolants extrapolated to ±9 (mass beyond: 2·10⁻¹⁹).
        let last = idx.len() - 1;
        match sig[0] {
            Some(_) => {
                let st = stencil(0, run_of[0].1.min(3));
                self.piece(&st, -TAIL_END, t[0], &mut sums, &mut atoms);
            }
            None => sums.mass += normal_mass(-TAIL_END, t[0]),
        }
        match sig[last] {
            Some(_) => {
                let st = stencil(run_of[last].0.max(last.saturating_sub(3)), last);
                self.piece(&st, t[last], TAIL_END, &mut sums, &mut atoms);
            }
            None => sums.mass += normal_mass(t[last], TAIL_END),
        }
        sums
    }

    /// Where the branch changes in `[a, b]`: the zero of the extrapolated `Π p` (det K̂/det M̂,
    /// zero at a static bifurcation) from each side, averaged; the middle if neither has one.
    fn switch_point(&self, left: &Stencil, right: &Stencil, a: f64, b: f64) -> f64 {
        let mut c = vec![0.0; self.store.width];
        // Rigid-body modes (`p` exactly zero on both sides, [`crate::modal::ModeClass::Rigid`])
        // would make the product zero everywhere: they are left out.
        let rigid: Vec<bool> = (0..self.modes)
            .map(|m| {
                [left, right]
                    .iter()
                    .all(|st| st.rows.iter().all(|r| r[2 * m + 1] == 0.0))
            })
            .collect();
        let mut g = |st: &Stencil, t: f64| {
            st.eval(t, &mut c);
            (0..self.modes)
                .filter(|&m| !rigid[m])
                .map(|m| c[2 * m + 1])
                .product::<f64>()
        };
        let roots: Vec<f64> = [left, right]
            .into_iter()
            .filter_map(|st| root_in(&mut |t| g(st, t), a, b))
            .collect();
        if roots.is_empty() {
            0.5 * (a + b)
        } else {
            roots.iter().sum::<f64>() / roots.len() as f64
        }
    }

    /// Integrates the interpolant `st` over `[a, b]`, split where a mode changes character.
    fn piece(&self, st: &Stencil, a: f64, b: f64, sums: &mut Sums, atoms: &mut Option<Atoms>) {
        if b <= a {
            return;
        }
        let mut c = vec![0.0; self.store.width];
        // Breakpoints: sign changes of D, p and s of every mode.
        // Breakpoints (and whether ω_d has a square-root edge there): sign changes of D, p
        // and s of every mode.
        let mut cuts = vec![(a, false), (b, false)];
        for m in 0..self.modes {
            for f in 0..3 {
                let mut h = |t: f64| {
                    st.eval(t, &mut c);
                    let (s, p) = (c[2 * m], c[2 * m + 1]);
                    match f {
                        0 => p - 0.25 * s * s,
                        1 => p,
                        _ => growth(s, p),
                    }
                };
                cuts.extend(roots_in(&mut h, a, b).into_iter().map(|r| (r, f == 0)));
            }
        }
        cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
        let other = st.branch != self.branch;
        let modes = self.modes;
        // A mode can be unstable between nodes only where one of the stencil's nodes says so:
        // otherwise an excursion of the interpolant is the interpolation's, not the mode's
        // (the sum `s` of a rigid-body mode's roots, its partner alone, jumps between nodes
        // where two such modes trade places, and the interpolant overshoots above 0).
        let may_be_unstable: Vec<bool> = (0..modes)
            .map(|m| {
                st.rows
                    .iter()
                    .any(|r| growth(r[2 * m], r[2 * m + 1]) > 0.0 || r[2 * m + 1] < 0.0)
            })
            .collect();
        for seg in cuts.windows(2) {
            let ((x0, e0), (x1, e1)) = (seg[0], seg[1]);
            if x1 <= x0 {
                continue;
            }
            let len = x1 - x0;
            // Character on the sub-piece (constant there): from its midpoint.
            st.eval(0.5 * (x0 + x1), &mut c);
            let unstable = (0..modes).any(|m| {
                may_be_unstable[m] && (growth(c[2 * m], c[2 * m + 1]) > 0.0 || c[2 * m + 1] < 0.0)
            });
            // Overdamped: two real roots of one sign, both negative (`p > 0`); a rigid-body
            // mode (a zero root, `p = 0` exactly) is neither overdamped nor unstable.
            let overdamped: Vec<bool> = (0..modes)
                .map(|m| {
                    let (s, p) = (c[2 * m], c[2 * m + 1]);
                    p - 0.25 * s * s <= 0.0 && p > 0.0 && growth(s, p) <= 0.0
                })
                .collect();
            for (&x, &wx) in GL_X.iter().zip(&GL_W) {
                // Gauss–Legendre in u ∈ [0, 1]; towards a square-root edge t − edge ∝ u² (both
                // edges: 1 − cos πu), which makes √(t − edge) smooth in u.
                let u = 0.5 + 0.5 * x;
                let (t, dt) = match (e0, e1) {
                    (false, false) => (x0 + len * u, len),
                    (true, false) => (x0 + len * u * u, 2.0 * len * u),
                    (false, true) => (x1 - len * (1.0 - u) * (1.0 - u), 2.0 * len * (1.0 - u)),
                    (true, true) => {
                        let pi = std::f64::consts::PI;
                        (
                            x0 + len * 0.5 * (1.0 - (pi * u).cos()),
                            len * 0.5 * pi * (pi * u).sin(),
                        )
                    }
                };
                let wt = 0.5 * wx * dt * density(t);
                sums.mass += wt;
                for (m, &o) in overdamped.iter().enumerate() {
                    if o {
                        sums.events[m] += wt;
                    }
                }
                if unstable {
                    sums.events[modes] += wt;
                }
                if other {
                    sums.events[modes + 1] += wt;
                }
                st.eval(t, &mut c);
                for (o, out) in self.outs.iter().enumerate() {
                    let v = carrier_value(out, &c, modes);
                    if !v.is_finite() {
                        continue;
                    }
                    let dv = v - self.shift[o];
                    sums.defined[o] += wt;
                    sums.s1[o] += wt * dv;
                    sums.s2[o] += wt * dv * dv;
                    if let Some((atoms, lw)) = atoms.as_mut() {
                        atoms[o].push((v, wt * *lw));
                    }
                }
            }
        }
    }
}

/// Relative growth rate below which a pair counts as stable (as in [`crate::modal`]: an
/// undamped pair has `s` at rounding level around zero).
const GROWTH_TOL: f64 = 1e-9;

/// The pair's growth rate `Re λ = s/2` less [`GROWTH_TOL`] of its size `√|p|`: positive when
/// the pair is unstable through a complex pair (flutter) or a positive real root.
fn growth(s: f64, p: f64) -> f64 {
    0.5 * s - GROWTH_TOL * p.abs().sqrt()
}

/// An output from the carriers: ω_d = √max(0, p − s²/4), ζ = −s/(2√|p|), |H| (not below 0).
fn carrier_value(o: &Output, c: &[f64], modes: usize) -> f64 {
    match (o.quantity, o.mode) {
        (Quantity::DampedFrequency, Some(m)) => {
            let (s, p) = (c[2 * m], c[2 * m + 1]);
            (p - 0.25 * s * s).max(0.0).sqrt()
        }
        (Quantity::DampingRatio, Some(m)) => -c[2 * m] / (2.0 * c[2 * m + 1].abs().sqrt()),
        // `f64::max` would turn a node's missing |H| (NaN: a resonance there) into 0.
        (Quantity::TransferMagnitude, _) if c[2 * modes].is_nan() => f64::NAN,
        (Quantity::TransferMagnitude, _) => c[2 * modes].max(0.0),
        _ => f64::NAN,
    }
}

fn density(t: f64) -> f64 {
    (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Normal mass of `[a, b]`.
fn normal_mass(a: f64, b: f64) -> f64 {
    let n = Normal::standard();
    n.cdf(b) - n.cdf(a)
}

/// Sub-points per piece scanned for sign changes.
const SCAN: usize = 8;

/// The roots of `f` in `(a, b)`: sign changes on a scan of [`SCAN`] sub-intervals, refined by
/// bisection to rounding.
fn roots_in(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64) -> Vec<f64> {
    // Far from zero at both ends and the middle against the curvature there: no root (the
    // interpolants are low-degree polynomials over one node interval).
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let same = (fa < 0.0) == (fm < 0.0) && (fm < 0.0) == (fb < 0.0);
    if same && fa.abs().min(fm.abs()).min(fb.abs()) > 2.0 * (fa - 2.0 * fm + fb).abs() {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut x0 = a;
    let mut f0 = f(a);
    for k in 1..=SCAN {
        let x1 = a + (b - a) * k as f64 / SCAN as f64;
        let f1 = f(x1);
        if f0.is_finite() && f1.is_finite() && (f0 < 0.0) != (f1 < 0.0) {
            out.push(bisect(f, x0, x1, f0));
        }
        (x0, f0) = (x1, f1);
    }
    out
}

/// One root of `f` in `[a, b]` (the one nearest the middle if several), if any.
fn root_in(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64) -> Option<f64> {
    let mid = 0.5 * (a + b);
    roots_in(f, a, b)
        .into_iter()
        .min_by(|x, y| (x - mid).abs().total_cmp(&(y - mid).abs()))
}

fn bisect(f: &mut dyn FnMut(f64) -> f64, mut a: f64, mut b: f64, fa: f64) -> f64 {
    let neg = fa < 0.0;
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if (f(m) < 0.0) == neg {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_quantiles_of_a_fine_normal_grid() {
        // Atoms of N(0,1) on a fine grid: the quantiles are ±1.6449 and 0.
        let mut atoms: Vec<(f64, f64)> = (0..=20000)
            .map(|k| {
                let t = -8.0 + 16.0 * k as f64 / 20000.0;
                (t, density(t) * 16.0 / 20000.0)
            })
            .collect();
        let q = quantiles(&mut atoms);
        assert!((q[0] + 1.644_853_6).abs() < 1e-3, "{q:?}");
        assert!(
            q[1].abs() < 1e-3 && (q[2] - 1.644_853_6).abs() < 1e-3,
            "{q:?}"
        );
    }

    #[test]
    fn tensor_rules_integrate_low_degree_moments() {
        // E[y₁² y₂²] = 1 and E[y₁⁴] = 3 for the 3-point rule; E[y₁²] = 1 for the 2-point rule.
        let r3 = tensor(
            2,
            &[-3f64.sqrt(), 0.0, 3f64.sqrt()],
            &[1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
            false,
        );
        let e = |r: &[Line], f: &dyn Fn(&[f64]) -> f64| {
            r.iter().map(|l| l.weight * f(&l.y)).sum::<f64>()
        };
        assert!((e(&r3, &|y| y[0] * y[0] * y[1] * y[1]) - 1.0).abs() < 1e-14);
        assert!((e(&r3, &|y| y[0].powi(4)) - 3.0).abs() < 1e-14);
        let r2 = tensor(2, &[-1.0, 1.0], &[0.5, 0.5], true);
        assert!((e(&r2, &|y| y[1] * y[1]) - 1.0).abs() < 1e-14);
        assert!(r2.iter().all(|l| l.check));
    }

    #[test]
    fn roots_are_found_to_rounding() {
        let mut f = |t: f64| (t - 0.3) * (t + 0.7);
        let r = roots_in(&mut f, -1.0, 1.0);
        assert_eq!(r.len(), 2);
        assert!(
            (r[0] + 0.7).abs() < 1e-14 && (r[1] - 0.3).abs() < 1e-14,
            "{r:?}"
        );
    }
}
