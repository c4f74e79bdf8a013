//! A sweep over speeds: continuation of the equilibrium (a predictor over the last solutions,
//! or over their offsets from a reference design's points) and tracking of the modes by their
//! shapes.

use super::point::{BranchKind, Origin, Point, PointError};
use super::solve::Solver;
use super::{Options, initial_guess};
use crate::compiled::Compiled;
use crate::equilibrium::{EquilibriumError, Start};
use crate::modal::{C64, match_shapes, permute};
use crate::program::Workspace;
use nalgebra::{DMatrix, DVector};

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

/// A field of a kept state (its coordinates, multipliers or Jacobian entries).
type Field = for<'s, 't> fn(&'s Solved<'t>) -> &'s [f64];

/// A converged state kept for continuation.
struct Solved<'a> {
    speed: f64,
    q: Vec<f64>,
    lambda: Vec<f64>,
    /// Newton's Jacobian there.
    jacobian: DMatrix<f64>,
    /// The point was found by a switch of branch.
    switched: bool,
    /// The reference design's point at the same speed, where the sweep follows one
    /// ([`Sweep::step_beside`]).
    beside: Option<&'a Point>,
}

impl<'a> Solved<'a> {
    fn from(pt: &Point, beside: Option<&'a Point>) -> Self {
        Solved {
            speed: pt.speed,
            q: pt.equilibrium.q.clone(),
            lambda: pt.equilibrium.lambda.clone(),
            jacobian: pt.equilibrium.jacobian.clone(),
            switched: pt.switched_from.is_some(),
            beside,
        }
    }
}

/// A sweep over speeds with continuation of the equilibrium and tracking of the modes.
pub struct Sweep<'a> {
    model: &'a Compiled,
    params: Vec<f64>,
    options: Options,
    /// The last solutions, newest first (at most [`PREDICTOR_NODES`]), for the predictor.
    history: Vec<Solved<'a>>,
    /// The reference design's point at the speed being solved ([`Sweep::step_beside`]).
    beside: Option<&'a Point>,
    /// Switches of branch since the first step: the design's own, and the reference's
    /// between the points it was stepped beside (the design starts on the reference's first
    /// one).
    switches: [usize; 2],
    /// A point of the reference was stepped beside.
    stepped_beside: bool,
    /// The steady-state check passed at an earlier speed where every drive turned (the
    /// parameters do not change; at a speed where a drive stands still it is not checked).
    steady_known: bool,
    last_shapes: Option<Vec<DVector<C64>>>,
    last_stable: Option<bool>,
    /// Where the recorded program's passes run.
    workspace: Memory<'a>,
}

/// A sweep's working memory: its own, or lent by a caller that runs many sweeps on one
/// thread (a Monte Carlo or quadrature worker).
enum Memory<'a> {
    Own(Box<Workspace>),
    Lent(&'a Workspace),
}

impl Memory<'_> {
    fn get(&self) -> &Workspace {
        match self {
            Memory::Own(w) => w,
            Memory::Lent(w) => w,
        }
    }
}

impl<'a> Sweep<'a> {
    /// A sweep of the design `params` with its own working memory.
    pub fn new(model: &'a Compiled, params: Vec<f64>, options: Options) -> Self {
        Sweep::with_memory(model, params, options, Memory::Own(Box::default()))
    }

    /// The working memory its passes run in (lent on to the derivatives at its points).
    pub fn workspace(&self) -> &Workspace {
        self.workspace.get()
    }

    /// A sweep of the design `params` whose passes run in the caller's `workspace`.
    pub fn in_workspace(
        model: &'a Compiled,
        params: Vec<f64>,
        options: Options,
        workspace: &'a Workspace,
    ) -> Self {
        Sweep::with_memory(model, params, options, Memory::Lent(workspace))
    }

    fn with_memory(
        model: &'a Compiled,
        params: Vec<f64>,
        options: Options,
        workspace: Memory<'a>,
    ) -> Self {
        Sweep {
            model,
            params,
            options,
            history: Vec::new(),
            beside: None,
            switches: [0, 0],
            stepped_beside: false,
            steady_known: false,
            last_shapes: None,
            last_stable: None,
            workspace,
        }
    }

    /// Continues from `pt` as if it had been solved last (its equilibrium, Jacobian and mode
    /// shapes): a Monte Carlo sample starts from the nominal point at its first speed instead of
    /// the model's initial guess.
    pub fn warm_start(&mut self, pt: &'a Point) {
        self.history = vec![Solved::from(pt, Some(pt))];
        self.last_shapes = Some(pt.shapes.clone());
        self.last_stable = Some(pt.stable());
    }

    /// [`Sweep::step`] for a design beside a reference design whose point at `speed` is
    /// `beside` (a Monte Carlo sample or a quadrature node beside the nominal design): the
    /// predictor extrapolates the design's offsets from the reference's points, which are
    /// small and smooth where the designs are near, rather than its solutions themselves,
    /// while the design is on the reference's branch (as often switched since the start). On
    /// the moving 40-segment blade and the paper's governor a sample's points then take about one
    /// fresh Jacobian each instead of two (`docs/benchmarks.md`).
    pub fn step_beside(&mut self, speed: f64, beside: &'a Point) -> Result<Point, PointError> {
        self.switches[1] += usize::from(self.stepped_beside && beside.new_branch);
        self.stepped_beside = true;
        self.beside = (beside.speed.to_bits() == speed.to_bits()).then_some(beside);
        let pt = self.step(speed);
        self.beside = None;
        pt
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
        let mut pt = self.solve(speed)?;
        if pt.switched_from.is_some() {
            self.judge_switch(&mut pt);
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
        self.switches[0] += usize::from(pt.new_branch);
        let on_reference = self.switches[0] == self.switches[1];
        let beside = self.beside.filter(|_| on_reference);
        self.history.insert(0, Solved::from(&pt, beside));
        let eq = &pt.equilibrium;
        self.steady_known |= (self.model.model().driven().iter()).all(|&c| eq.qd[c] != 0.0);
        self.last_shapes = Some(pt.shapes.clone());
        self.last_stable = Some(pt.stable());
        Ok(pt)
    }

    /// The point at `speed` from the first start that converges: the extrapolated one, the
    /// last solution with its Jacobian, the model's initial guess (each made only when the
    /// starts before it failed).
    fn solve(&self, speed: f64) -> Result<Point, PointError> {
        let mut result = Err(PointError::Equilibrium(EquilibriumError::NotFinite {
            iterations: 0,
        }));
        let last = std::iter::once_with(|| {
            self.history.first().map(|s1| Guess {
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
        let predicted = self.predicted(speed);
        for guess in predicted.into_iter().chain(last).map(Ok).chain(fallback) {
            let guess = guess?;
            let start = Start {
                lambda: guess.lambda.as_deref(),
                jacobian: guess.jacobian.as_ref(),
                steady_known: self.steady_known,
            };
            let solver = Solver {
                model: self.model,
                p: &self.params,
                opt: &self.options,
                workspace: self.workspace.get(),
            };
            result = solver.point_from(speed, &guess.q, start);
            if let Ok(pt) = &mut result {
                pt.branch.origin = guess.origin;
                break;
            }
        }
        result
    }

    /// The extrapolation of the last solutions to `speed` (coordinates and multipliers: up to
    /// a cubic on a smooth branch, down to the secant where the higher orders do not settle)
    /// with the secant extrapolation of their Jacobians; `None` with fewer than two.
    fn predicted(&self, speed: f64) -> Option<Guess> {
        if let Some(guess) = self.predicted_beside(speed) {
            return Some(guess);
        }
        let nodes: Vec<&Solved> = self.history.iter().collect();
        if nodes.len() < 2 {
            return None;
        }
        let predict = |nodes: &[&Solved], field: Field| {
            let weights = extrapolation(speed, nodes)?;
            let mut out = vec![0.0; field(nodes[0]).len()];
            for (w, s) in weights.iter().zip(nodes) {
                for (o, v) in out.iter_mut().zip(field(s)) {
                    *o += w * v;
                }
            }
            Some(out)
        };
        let (q, used) = settled(nodes[0].q.clone(), nodes.len(), |k| {
            predict(&nodes[..k], |s| &s.q)
        });
        if used < 2 {
            return None;
        }
        // The Jacobian extrapolated too: chord steps with it contract by O(Δspeed²) rather
        // than O(Δspeed), so that a point usually takes two residuals, not three.
        let n = nodes[0].jacobian.nrows();
        let jacobian = predict(&nodes[..2], |s| s.jacobian.as_slice())
            .filter(|_| nodes[1].jacobian.shape() == nodes[0].jacobian.shape())
            .map(|j| DMatrix::from_vec(n, n, j));
        Some(Guess {
            q,
            lambda: predict(&nodes[..used], |s| &s.lambda),
            jacobian,
            origin: Origin::Continued {
                speed: nodes[0].speed,
            },
        })
    }

    /// Beside a reference design ([`Sweep::step_beside`]): the reference's point at `speed`
    /// plus the extrapolation of the offsets `x − x_ref` of the last solutions that have a
    /// reference point (coordinates, multipliers and Jacobian). The offsets are of the order
    /// of the designs' difference, so the predictor's error is that fraction of the plain
    /// extrapolation's, and with one solution the last offset alone (the reference's own
    /// change from speed to speed) predicts. Up to a cubic for the coordinates and
    /// multipliers, each order where its correction is small against the one below's (as in
    /// [`Sweep::predicted`]); the secant for the Jacobian. `None` without a reference point,
    /// off the reference's branch or where the shapes differ.
    fn predicted_beside(&self, speed: f64) -> Option<Guess> {
        // Only while the design is on the reference's branch (as often switched), and from
        // the solutions since it was: offsets between branches are neither small nor smooth,
        // and would carry the design across a switch of the reference's unnoticed, where its
        // own sweep makes the switch and counts it.
        let here = self
            .beside
            .filter(|_| self.switches[0] == self.switches[1])?;
        let nodes: Vec<(&Solved, &Point)> = (self.history.iter())
            .map_while(|s| s.beside.map(|b| (s, b)))
            .collect();
        let same = |s: &Solved, b: &Point| {
            let e = &b.equilibrium;
            s.q.len() == e.q.len()
                && s.lambda.len() == e.lambda.len()
                && s.jacobian.shape() == e.jacobian.shape()
        };
        let (newest, _) = nodes.first()?;
        if !nodes.iter().all(|(s, b)| same(s, b)) || !same(newest, here) {
            return None;
        }
        let solved: Vec<&Solved> = nodes.iter().map(|(s, _)| *s).collect();
        // The reference's `field` at `speed` plus the offsets of the first `k` nodes
        // extrapolated (the newest one's alone for `k = 1`).
        let offset = |k: usize, field: Field, base: fn(&Point) -> &[f64]| {
            let weights = match k {
                1 => vec![1.0],
                _ => extrapolation(speed, &solved[..k])?,
            };
            let mut out = base(here).to_vec();
            for (w, (s, b)) in weights.iter().zip(&nodes) {
                for ((o, v), r) in out.iter_mut().zip(field(s)).zip(base(b)) {
                    *o += w * (v - r);
                }
            }
            Some(out)
        };
        let q_of: fn(&Point) -> &[f64] = |p| &p.equilibrium.q;
        let (q, order) = settled(offset(1, |s| &s.q, q_of)?, nodes.len(), |k| {
            offset(k, |s| &s.q, q_of)
        });
        let n = newest.jacobian.nrows();
        let jacobian = offset(
            order.min(2),
            |s| s.jacobian.as_slice(),
            |p| p.equilibrium.jacobian.as_slice(),
        )
        .map(|j| DMatrix::from_vec(n, n, j));
        Some(Guess {
            q,
            lambda: offset(order, |s| &s.lambda, |p| &p.equilibrium.lambda),
            jacobian,
            origin: Origin::Continued {
                speed: newest.speed,
            },
        })
    }

    /// After a switch of branch at `pt`: did the branch followed lose its stability, or did
    /// Newton from the previous solution fall onto an unstable equilibrium nearby (near a
    /// pitchfork the stable branch moves like √Δspeed) and the switch return to the branch
    /// followed (the search leans towards the start, see [`Solver::point_from`])? With u the
    /// unstable equilibrium and f the stable one found, the previous solution p lies near u in
    /// the first case (it drifts by O(Δspeed) while f − u is O(√Δspeed) or O(1)) and on f's
    /// side of u in the second. A switch starts the predictor's history anew: extrapolating
    /// through solutions of another branch leads Newton back onto it.
    fn judge_switch(&mut self, pt: &mut Point) {
        let Some(unstable) = &pt.switched_from else {
            return;
        };
        if let Some(prev) = self.history.first() {
            let (mut pf, mut ff) = (0.0, 0.0);
            for ((p, f), u) in prev.q.iter().zip(&pt.equilibrium.q).zip(unstable) {
                pf += (p - u) * (f - u);
                ff += (f - u) * (f - u);
            }
            // Right after a switch the predictor has a single solution to go on, and a
            // return to the same side is a return to the branch just switched to.
            pt.new_branch = !(ff > 0.0 && pf > 0.0 && (prev.switched || pf > RETURN_FRACTION * ff));
        }
        self.history.clear();
    }
}

/// The extrapolation's order, chosen by its corrections: from `base`, the prediction by the
/// newest solution alone, each prediction `by(k)` from the newest `k` solutions (`k` from 2 to
/// `most`) replaces the one below where its correction to it is at most a tenth of that one's
/// own correction (a smooth branch; the secant's is always taken), and not past the first that
/// is not or cannot be made (say just past a bifurcation, where the branch has a kink). The
/// prediction and the solutions it used.
fn settled(
    base: Vec<f64>,
    most: usize,
    by: impl Fn(usize) -> Option<Vec<f64>>,
) -> (Vec<f64>, usize) {
    let (mut q, mut used, mut correction) = (base, 1, f64::INFINITY);
    for k in 2..=most {
        let Some(next) = by(k) else {
            break;
        };
        let c = (next.iter().zip(&q)).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        if k > 2 && c > 0.1 * correction {
            break;
        }
        (q, used, correction) = (next, k, c);
    }
    (q, used)
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
