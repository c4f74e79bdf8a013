//! One operating point (equilibrium → linearisation → modes) and sweeps over speed.
//!
//! At each speed the equilibrium is found by Newton from the previous speed's solution
//! (continuation). If the equilibrium found is unstable through a real root (a static
//! divergence, as the hanging pendulum past `√(3g/2L)`), the branch has bifurcated: the solver
//! steps off along the diverging mode's shape, both ways and at growing amplitudes, and takes the
//! nearest stable equilibrium, noting the switch. Modes keep their identity across speeds by
//! the similarity of their shapes in the free coordinates, not by sorting.

use crate::compiled::Compiled;
use crate::equations::Rates;
use crate::equilibrium::{Equilibrium, EquilibriumError, Problem, Settings, Solution, Start};
use crate::linearize::{Linearization, LinearizeError, choose_independent, reduce};
use crate::mechanics::ports::ports_at;
use crate::modal::{C64, ModalError, Mode, ModeClass, match_shapes, modes, permute};
use crate::model::{FieldError, Model};
use crate::program::Tier;
use nalgebra::{DMatrix, DVector};

/// Why a speed produced no result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointError {
    #[error("{0}")]
    Field(#[from] FieldError),
    #[error("equilibrium: {0}")]
    Equilibrium(#[from] EquilibriumError),
    #[error("linearisation: {0}")]
    Linearize(#[from] LinearizeError),
    #[error("modes: {0}")]
    Modal(#[from] ModalError),
}

/// Everything computed at one speed.
#[derive(Debug, Clone)]
pub struct Point {
    pub speed: f64,
    pub equilibrium: Equilibrium,
    pub linear: Linearization<f64>,
    pub modes: Vec<Mode>,
    /// Shape of each mode in the free coordinates (`R x`), for tracking.
    pub shapes: Vec<DVector<C64>>,
    /// Remarks, e.g. a switch to the stable branch.
    pub note: Option<String>,
    /// The equilibrium continued from the previous speed was unstable and this point is on
    /// the stable branch found instead: the coordinates of that unstable equilibrium.
    pub switched_from: Option<Vec<f64>>,
    /// This point is on another branch than the previous speed's: the branch followed lost
    /// its stability and the sweep switched (see [`Sweep::step`]).
    pub new_branch: bool,
    /// Which equilibrium this is and why it is the one reported.
    pub branch: Branch,
}

/// Where Newton started from.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Origin {
    /// The model's initial guess (the joints' `initial` values).
    InitialGuess,
    /// The solution at the previous speed of a sweep (extrapolated).
    Continued { speed: f64 },
    /// Coordinates the caller gave.
    Given,
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::InitialGuess => write!(f, "the model's initial guess"),
            Origin::Continued { speed } => write!(f, "the solution at {speed} rad/s"),
            Origin::Given => write!(f, "the coordinates given"),
        }
    }
}

/// Which equilibrium a point is on. Where a mechanism has several equilibria at a speed (a
/// pendulum past its bifurcation: hanging, and tilted either way), the one reported depends on
/// where Newton starts; this says which and why, in every output.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Branch {
    /// Where Newton started from.
    pub origin: Origin,
    pub kind: BranchKind,
}

/// Whether the equilibrium reached is the one reported.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum BranchKind {
    /// The equilibrium Newton reached is stable.
    Stable,
    /// The equilibrium Newton reached is unstable through its mode `mode` (0-based here,
    /// 1-based in JSON; among that equilibrium's modes, which are not reported) with the root
    /// `re + i·im`; the stable one found by stepping `amplitude` (rad or m at the largest coordinate) along that mode's
    /// shape (its real or imaginary part, `sign`) is reported instead.
    Switched {
        #[serde(serialize_with = "one_based")]
        mode: usize,
        re: f64,
        im: f64,
        imaginary_part: bool,
        sign: f64,
        amplitude: f64,
    },
    /// The equilibrium Newton reached is unstable through `mode` (0-based here, 1-based in
    /// JSON; among the point's modes) and reported as it is:
    /// `searched` says whether a stable one was looked for along the unstable modes (and none
    /// found) or not (switching off, [`Options::no_branch_switch`]).
    Unstable {
        #[serde(serialize_with = "one_based")]
        mode: usize,
        re: f64,
        im: f64,
        searched: bool,
    },
}

/// Writes a 0-based mode index as the 1-based number every output shows.
fn one_based<S: serde::Serializer>(mode: &usize, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(*mode as u64 + 1)
}

impl Branch {
    /// `stable`, `switched` or `unstable`.
    pub fn as_str(&self) -> &'static str {
        match self.kind {
            BranchKind::Stable => "stable",
            BranchKind::Switched { .. } => "switched",
            BranchKind::Unstable { .. } => "unstable",
        }
    }
}

impl std::fmt::Display for Branch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let root = |mode: Option<usize>, re: f64, im: f64| {
            let how = if im == 0.0 {
                "a positive real root: static divergence"
            } else {
                "a complex pair with positive real part: flutter"
            };
            let which = mode.map_or("a mode".to_string(), |k| format!("mode {}", k + 1));
            format!("{which} has λ = {re:.6e} {im:+.6e}i, {how}")
        };
        match self.kind {
            BranchKind::Stable => {
                write!(f, "the equilibrium reached from {} is stable", self.origin)
            }
            BranchKind::Switched {
                mode: _,
                re,
                im,
                imaginary_part,
                sign,
                amplitude,
            } => write!(
                f,
                "the equilibrium reached from {} is unstable ({}); switched to the stable \
                 equilibrium found by stepping {amplitude} along {}{} of that mode's shape",
                self.origin,
                root(None, re, im),
                if sign < 0.0 { "minus " } else { "" },
                if imaginary_part {
                    "the imaginary part"
                } else {
                    "the real part"
                },
            ),
            BranchKind::Unstable {
                mode,
                re,
                im,
                searched,
            } => write!(
                f,
                "the equilibrium reached from {} is unstable ({}); {}",
                self.origin,
                root(Some(mode), re, im),
                if searched {
                    "no stable equilibrium was found along its unstable modes' shapes"
                } else {
                    "reported as reached (no search for a stable branch)"
                }
            ),
        }
    }
}

impl Point {
    /// Is every mode stable?
    pub fn stable(&self) -> bool {
        self.modes.iter().all(|m| m.class != ModeClass::Unstable)
    }
}

/// Options of a point solve.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Independent coordinates (coordinate indices), overriding the model's choice.
    pub independent: Option<Vec<usize>>,
    /// Newton settings.
    pub newton: Settings,
    /// Do not look for a stable branch when the equilibrium found is unstable.
    pub no_branch_switch: bool,
    /// How the recorded program's passes run: [`Tier::Many`] (a sweep's) by default; a single
    /// point asks for [`Tier::Few`], a Monte Carlo run for [`Tier::Native`]. The results are
    /// the same at every tier, only the time differs.
    pub tier: Tier,
}

impl Options {
    /// The defaults for a single point ([`Tier::Few`]).
    pub fn single() -> Options {
        Options {
            tier: Tier::Few,
            ..Options::default()
        }
    }
}

/// The model's initial guesses at parameters `p` and `speed`.
pub fn initial_guess(model: &Model, p: &[f64], speed: f64) -> Result<Vec<f64>, FieldError> {
    let mut q = vec![0.0; model.coordinates.len()];
    for j in &model.joints {
        for (k, c) in j.coords.clone().enumerate() {
            q[c] = j.initial[k].eval(p, speed)?;
        }
    }
    Ok(q)
}

/// Solves one operating point from the guess `q0`.
pub fn point(
    model: &Compiled,
    p: &[f64],
    speed: f64,
    q0: &[f64],
    opt: &Options,
) -> Result<Point, PointError> {
    point_from(model, p, speed, q0, Start::default(), opt)
}

/// Solves one operating point from the model's initial guess (what `modal` reports).
pub fn point_at(
    model: &Compiled,
    p: &[f64],
    speed: f64,
    opt: &Options,
) -> Result<Point, PointError> {
    let q0 = initial_guess(model.model(), p, speed)?;
    let mut pt = point(model, p, speed, &q0, opt)?;
    pt.branch.origin = Origin::InitialGuess;
    Ok(pt)
}

/// Amplitudes (rad or m at the largest coordinate of a mode's shape) of the steps off an
/// unstable equilibrium from which Newton looks for a stable one, nearest first.
const SEARCH_AMPLITUDES: [f64; 6] = [1e-3, 1e-2, 0.05, 0.2, 0.5, 1.0];

/// The directions to search along for a stable equilibrium: the real and imaginary parts of
/// each unstable mode's shape in the free coordinates (a flutter mode's two parts span its
/// plane of motion: a conical pendulum's two tilts), largest growth first, each scaled to a
/// largest entry of 1; with the mode, its root and which part.
fn search_directions(first: &Point) -> Vec<(usize, C64, bool, Vec<f64>)> {
    let mut unstable: Vec<usize> = (0..first.modes.len())
        .filter(|&k| first.modes[k].class == ModeClass::Unstable)
        .collect();
    unstable.sort_by(|&a, &b| {
        let re = |k: usize| {
            first.modes[k]
                .root
                .lambda
                .re
                .max(first.modes[k].partner.lambda.re)
        };
        re(b).total_cmp(&re(a))
    });
    let mut out = Vec::new();
    for k in unstable {
        let z = &first.shapes[k];
        let top = z.iter().fold(0.0f64, |s, v| s.max(v.norm()));
        for imaginary in [false, true] {
            let d: Vec<f64> = z
                .iter()
                .map(|v| if imaginary { v.im } else { v.re })
                .collect();
            let big = d.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            // A part that is only rounding of the other gives no new direction.
            if big > 1e-3 * top {
                let root = first.modes[k].root.lambda;
                out.push((k, root, imaginary, d.iter().map(|v| v / big).collect()));
            }
        }
    }
    out
}

/// As [`point`], with more to start Newton from (see [`Start`]).
pub fn point_from(
    model: &Compiled,
    p: &[f64],
    speed: f64,
    q0: &[f64],
    start: Start,
    opt: &Options,
) -> Result<Point, PointError> {
    // On the model's route (the recorded program when there is one).
    let problem = model.problem(p, speed, q0, opt.tier)?;
    let solved = problem.solve(speed, q0, start, opt.newton).map_err(|e| {
        // A failed solve with redundant cut joints is reported as such, naming them.
        let redundant = problem.redundant_equations(q0);
        if redundant.is_empty() {
            return e;
        }
        let owners: Vec<&str> = model
            .model()
            .constraints
            .iter()
            .flat_map(|c| std::iter::repeat_n(c.name.as_str(), c.kind.equations()))
            .collect();
        let mut names: Vec<String> = redundant.iter().map(|&k| owners[k].to_string()).collect();
        names.dedup();
        EquilibriumError::RedundantConstraints {
            names,
            rank: model.model().n_constraints() - redundant.len(),
            equations: model.model().n_constraints(),
        }
    })?;
    let mut first = analyse(model.model(), p, &problem, solved, opt)?;
    if first.stable() {
        return Ok(first);
    }
    // The most unstable mode, for the record.
    let worst = (0..first.modes.len())
        .filter(|&k| first.modes[k].class == ModeClass::Unstable)
        .max_by(|&a, &b| {
            let re = |k: usize| first.modes[k].root.lambda.re;
            re(a).total_cmp(&re(b))
        })
        .map(|k| (k, first.modes[k].root.lambda));
    let unstable = |searched: bool| {
        let (mode, root) = worst.unwrap_or_default();
        BranchKind::Unstable {
            mode,
            re: root.re,
            im: root.im,
            searched,
        }
    };
    let directions = search_directions(&first);
    if opt.no_branch_switch || directions.is_empty() {
        first.branch.kind = unstable(!opt.no_branch_switch);
        first.branch.kind = unstable(false);
        return Ok(first);
    }
    let free = &first.linear.free;
    // Prefer the side the Newton start lies on (in a sweep, the last solution: a sweep that
    // fell onto the unstable equilibrium returns to its own branch), else the side of the
    // model's initial guess (then the positive side).
    let guess = initial_guess(model.model(), p, speed)?;
    let side = |q: &[f64], dir: &[f64]| -> f64 {
        free.iter()
            .enumerate()
            .map(|(k, &i)| dir[k] * (q[i] - first.equilibrium.q[i]))
            .sum()
    };
    // A stable equilibrium on the side stepped to is taken at once; one that Newton reached
    // across the unstable equilibrium only if no step finds one on its own side.
    let mut across = None;
    for amp in SEARCH_AMPLITUDES {
        for (k, root, imaginary_part, dir) in &directions {
            let mut lean = side(q0, dir);
            if lean.abs() <= 1e-9 {
                lean = side(&guess, dir);
            }
            let signs = if lean < -1e-9 {
                [-1.0, 1.0]
            } else {
                [1.0, -1.0]
            };
            for s in signs {
                let mut q = first.equilibrium.q.clone();
                for (j, &i) in free.iter().enumerate() {
                    q[i] += s * amp * dir[j];
                }
                let Ok(solved) = problem.solve(speed, &q, Start::default(), opt.newton) else {
                    continue;
                };
                let eq = &solved.equilibrium;
                let moved = free.iter().fold(0.0f64, |m, &i| {
                    m.max((eq.q[i] - first.equilibrium.q[i]).abs())
                });
                if moved < 1e-7 {
                    continue;
                }
                let own_side = side(&eq.q, dir) * s > 0.0;
                if let Ok(pt) = analyse(model.model(), p, &problem, solved, opt)
                    && pt.stable()
                {
                    let kind = BranchKind::Switched {
                        mode: *k,
                        re: root.re,
                        im: root.im,
                        imaginary_part: *imaginary_part,
                        sign: s,
                        amplitude: amp,
                    };
                    let pt = Point {
                        switched_from: Some(first.equilibrium.q.clone()),
                        new_branch: true,
                        branch: Branch {
                            kind,
                            ..first.branch.clone()
                        },
                        ..pt
                    };
                    if own_side {
                        return Ok(pt);
                    }
                    across.get_or_insert(pt);
                }
            }
        }
    }
    first.branch.kind = unstable(true);
    Ok(across.unwrap_or(first))
}

/// Linearises and solves the modes at a converged equilibrium.
fn analyse(
    model: &Model,
    p: &[f64],
    problem: &Problem,
    Solution {
        equilibrium: eq,
        rates,
    }: Solution,
    opt: &Options,
) -> Result<Point, PointError> {
    let free = model.free();
    let nf = free.len();
    // Φ_R from the λ columns of Newton's Jacobian, which are [Φ_Rᵀ; 0].
    let m = eq.lambda.len();
    let phi_r = DMatrix::from_fn(m, nf, |k, j| eq.jacobian[(j, nf + k)]);
    let user = opt.independent.as_deref().or(model.independent.as_deref());
    let independent = if m == 0 {
        free.clone()
    } else {
        choose_independent(&phi_r, &free, user)?
    };
    let stiffness = eq.jacobian.view((0, 0), (nf, nf)).into_owned();
    let linear = match rates {
        Some(Rates { damping, mass }) => {
            reduce(&free, &independent, &phi_r, mass, damping, stiffness)?
        }
        // The recorded route always gives the rates; directly otherwise.
        None => problem
            .equations()
            .linearize(&eq.q, &eq.lambda, &independent, Some(&stiffness))?,
    };
    let linear = linear.with_ports(ports_at(model, p, eq.speed, &eq.q, &free)?);
    let modes = modes(&linear.m, &linear.c, &linear.k, eq.speed)?;
    let shapes = shapes(&linear.basis, &modes);
    Ok(Point {
        speed: eq.speed,
        equilibrium: eq,
        linear,
        modes,
        shapes,
        note: None,
        switched_from: None,
        new_branch: false,
        branch: Branch {
            origin: Origin::Given,
            kind: BranchKind::Stable,
        },
    })
}

/// Each mode's shape over all the coordinates, `basis · x` with `x` its right vector, summed over
/// the basis's nonzero entries only: a tree's basis is a selection (one entry a row), so that
/// this is O(n) a mode where the dense product is O(n²), a large part of a big model's point.
fn shapes(basis: &DMatrix<f64>, modes: &[Mode]) -> Vec<DVector<C64>> {
    let rows: Vec<Vec<(usize, f64)>> = basis
        .row_iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(c, v)| (c, *v))
                .collect()
        })
        .collect();
    modes
        .iter()
        .map(|m| {
            let x = &m.root.right;
            DVector::from_iterator(
                rows.len(),
                rows.iter()
                    .map(|r| r.iter().map(|&(c, v)| x[c] * v).sum::<C64>()),
            )
        })
        .collect()
}

/// Fraction of the way from the unstable equilibrium to the stable one found beyond which the
/// previous solution shows that the sweep was not on the unstable branch (see [`Sweep::step`]).
const RETURN_FRACTION: f64 = 0.1;

/// Solutions the predictor extrapolates from (up to a cubic).
const PREDICTOR_NODES: usize = 4;

/// A Newton start: coordinates, and the multipliers and a Jacobian for chord steps where known.
struct Guess {
    q: Vec<f64>,
    lambda: Option<Vec<f64>>,
    jacobian: Option<DMatrix<f64>>,
    origin: Origin,
}

/// A converged state kept for continuation.
struct Solved {
    speed: f64,
    q: Vec<f64>,
    lambda: Vec<f64>,
    /// Newton's Jacobian there.
    jacobian: DMatrix<f64>,
    /// The point was found by a switch of branch.
    switched: bool,
}

impl Solved {
    fn from(pt: &Point) -> Self {
        Solved {
            speed: pt.speed,
            q: pt.equilibrium.q.clone(),
            lambda: pt.equilibrium.lambda.clone(),
            jacobian: pt.equilibrium.jacobian.clone(),
            switched: pt.switched_from.is_some(),
        }
    }
}

/// A sweep over speeds with continuation of the equilibrium and tracking of the modes.
pub struct Sweep<'a> {
    model: &'a Compiled,
    params: Vec<f64>,
    options: Options,
    /// The last solutions, newest first (at most [`PREDICTOR_NODES`]), for the predictor.
    history: Vec<Solved>,
    /// The steady-state check passed at an earlier speed (the parameters do not change).
    steady_known: bool,
    last_shapes: Option<Vec<DVector<C64>>>,
    last_stable: Option<bool>,
}

impl<'a> Sweep<'a> {
    pub fn new(model: &'a Compiled, params: Vec<f64>, options: Options) -> Self {
        Sweep {
            model,
            params,
            options,
            history: Vec::new(),
            steady_known: false,
            last_shapes: None,
            last_stable: None,
        }
    }

    /// Continues from `pt` as if it had been solved last (its equilibrium, Jacobian and mode
    /// shapes): a Monte Carlo sample starts from the nominal point at its first speed instead of
    /// the model's initial guess.
    pub fn warm_start(&mut self, pt: &Point) {
        self.history = vec![Solved::from(pt)];
        self.last_shapes = Some(pt.shapes.clone());
        self.last_stable = Some(pt.stable());
    }

    /// Solves the next speed. Failures leave the continuation state as it was.
    ///
    /// The Newton start is the extrapolation of the last solutions (coordinates and
    /// multipliers: up to a cubic on a smooth branch, down to the secant where the higher
    /// orders do not settle, so that a branch that has just bent away from a bifurcation is
    /// followed, not jumped over) with the secant
    /// extrapolation of their Jacobians for chord steps; then the last solution with its
    /// Jacobian; then the model's initial guess.
    pub fn step(&mut self, speed: f64) -> Result<Point, PointError> {
        // The extrapolated start first.
        let mut predicted: Option<Guess> = None;
        let nodes: Vec<&Solved> = self.history.iter().collect();
        if nodes.len() >= 2 {
            let predict = |nodes: &[&Solved], field: fn(&Solved) -> &[f64]| {
                let weights = extrapolation(speed, nodes)?;
                let mut out = vec![0.0; field(nodes[0]).len()];
                for (w, s) in weights.iter().zip(nodes) {
                    for (o, v) in out.iter_mut().zip(field(s)) {
                        *o += w * v;
                    }
                }
                Some(out)
            };
            let diff = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            };
            // Each higher order where its correction to the one below is small against that
            // one's own correction (a smooth branch); not past the first that is not (say
            // just past a bifurcation, where the branch has a kink).
            let mut order = 0;
            let mut q: Option<Vec<f64>> = None;
            let mut correction = f64::INFINITY;
            for k in 1..nodes.len() {
                let Some(next) = predict(&nodes[..=k], |s| &s.q) else {
                    break;
                };
                let c = diff(&next, q.as_deref().unwrap_or(&nodes[0].q));
                if k > 1 && c > 0.1 * correction {
                    break;
                }
                (order, q, correction) = (k, Some(next), c);
            }
            if let Some(q) = q {
                // The Jacobian extrapolated too: chord steps with it contract by O(Δspeed²)
                // rather than O(Δspeed), so that a point usually takes two residuals, not three.
                let n = nodes[0].jacobian.nrows();
                let jacobian = predict(&nodes[..2], |s| s.jacobian.as_slice())
                    .filter(|_| nodes[1].jacobian.shape() == nodes[0].jacobian.shape())
                    .map(|j| DMatrix::from_vec(n, n, j));
                predicted = Some(Guess {
                    q,
                    lambda: predict(&nodes[..=order], |s| &s.lambda),
                    jacobian,
                    origin: Origin::Continued {
                        speed: nodes[0].speed,
                    },
                });
            }
        }
        let mut result = Err(PointError::Equilibrium(EquilibriumError::NotFinite {
            iterations: 0,
        }));
        // Then the last solution with its Jacobian, then the model's initial guess, each made
        // only when the starts before it failed.
        let last = std::iter::once_with(|| {
            nodes.first().map(|s1| Guess {
                q: s1.q.clone(),
                lambda: Some(s1.lambda.clone()),
                jacobian: Some(s1.jacobian.clone()),
                origin: Origin::Continued { speed: s1.speed },
            })
        })
        .flatten();
        let fallback = std::iter::once_with(|| {
            initial_guess(self.model.model(), &self.params, speed).map(|q| Guess {
                q,
                lambda: None,
                jacobian: None,
                origin: Origin::InitialGuess,
            })
        });
        for guess in predicted.into_iter().chain(last).map(Ok).chain(fallback) {
            let guess = guess?;
            let start = Start {
                lambda: guess.lambda.as_deref(),
                jacobian: guess.jacobian.as_ref(),
                steady_known: self.steady_known,
            };
            let q0 = &guess.q;
            result = point_from(self.model, &self.params, speed, q0, start, &self.options);
            if let Ok(pt) = &mut result {
                pt.branch.origin = guess.origin;
                break;
            }
        }
        let mut pt = result?;
        if let Some(unstable) = &pt.switched_from {
            // Did the branch followed lose its stability, or did Newton from the previous
            // solution fall onto an unstable equilibrium nearby (near a pitchfork the stable
            // branch moves like √Δspeed) and the switch return to the branch followed (the
            // search leans towards the start, see `point_from`)? With u the unstable
            // equilibrium and f the stable one found, the previous solution p lies near u in
            // the first case (it drifts by O(Δspeed) while f − u is O(√Δspeed) or O(1)) and on
            // f's side of u in the second.
            if let Some(prev) = self.history.first() {
                let (mut pf, mut ff) = (0.0, 0.0);
                for ((p, f), u) in prev.q.iter().zip(&pt.equilibrium.q).zip(unstable) {
                    pf += (p - u) * (f - u);
                    ff += (f - u) * (f - u);
                }
                // Right after a switch the predictor has a single solution to go on, and a
                // return to the same side is a return to the branch just switched to.
                pt.new_branch =
                    !(ff > 0.0 && pf > 0.0 && (prev.switched || pf > RETURN_FRACTION * ff));
            }
            // A switch starts the predictor's history anew: extrapolating through solutions of
            // another branch leads Newton back onto it.
            self.history.clear();
        }
        if let Some(prev) = &self.last_shapes
            && prev.len() == pt.modes.len()
        {
            let order = match_shapes(prev, &pt.shapes);
            pt.modes = permute(std::mem::take(&mut pt.modes), &order);
            pt.shapes = permute(std::mem::take(&mut pt.shapes), &order);
            if let BranchKind::Unstable { mode, .. } = &mut pt.branch.kind
                && let Some(j) = order.iter().position(|&k| k == *mode)
            {
                *mode = j;
            }
        }
        if let Some(was) = self.last_stable
            && was != pt.stable()
            && pt.note.is_none()
        {
            pt.note = Some(if was {
                "stability lost since the previous speed".into()
            } else {
                "stability regained since the previous speed".into()
            });
        }
        self.history.truncate(PREDICTOR_NODES - 1);
        self.history.insert(0, Solved::from(&pt));
        self.steady_known = true;
        self.last_shapes = Some(pt.shapes.clone());
        self.last_stable = Some(pt.stable());
        Ok(pt)
    }
}

/// Weights of the solutions `solved` (newest first) that extrapolate them to `speed`:
/// Lagrange through their speeds. `None` when the speed is more than two steps beyond the
/// newest or two speeds coincide.
fn extrapolation(speed: f64, solved: &[&Solved]) -> Option<Vec<f64>> {
    let nodes: Vec<f64> = solved.iter().map(|s| s.speed).collect();
    let dw = nodes[0] - nodes[1];
    let distinct = nodes
        .iter()
        .enumerate()
        .all(|(i, a)| nodes[..i].iter().all(|b| (a - b).abs() > 1e-12 * a.abs()));
    if !distinct || ((speed - nodes[0]) / dw).abs() > 2.0 {
        return None;
    }
    Some(
        (0..nodes.len())
            .map(|i| {
                (0..nodes.len())
                    .filter(|&j| j != i)
                    .map(|j| (speed - nodes[j]) / (nodes[i] - nodes[j]))
                    .product()
            })
            .collect(),
    )
}
