//! One operating point: Newton from a guess, the stable branch looked for past a divergence,
//! the linearisation and the modes.

use super::point::{Branch, BranchKind, Origin, Point, PointError};
use super::{Options, initial_guess};
use crate::compiled::Compiled;
use crate::equations::Rates;
use crate::equilibrium::{EquilibriumError, Problem, Solution, Start};
use crate::linearize::{choose_independent, reduce};
use crate::mechanics::ports::ports_at;
use crate::modal::{C64, Mode, ModeClass, modes};
use crate::model::Model;
use crate::program::Workspace;
use nalgebra::{DMatrix, DVector};

/// Solves one operating point from the guess `q0`.
pub fn point(
    model: &Compiled,
    p: &[f64],
    speed: f64,
    q0: &[f64],
    opt: &Options,
) -> Result<Point, PointError> {
    let workspace = Workspace::default();
    let solver = Solver {
        model,
        p,
        opt,
        workspace: &workspace,
    };
    solver.point_from(speed, q0, Start::default())
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

/// The operating points of one design: the model, its parameters `p`, the options, and the
/// workspace the recorded program's passes run in.
#[derive(Debug, Clone, Copy)]
pub struct Solver<'a> {
    pub model: &'a Compiled,
    pub p: &'a [f64],
    pub opt: &'a Options,
    pub workspace: &'a Workspace,
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

/// Is the symmetric part of the stiffness `k` positive definite? Then `k` is regular
/// (`xᵀkx > 0` for every `x ≠ 0`): the equilibrium is isolated and continues smoothly with the
/// speed and the parameters, no branch bifurcates from it, and an instability there is flutter,
/// driven by circulatory forces or negative damping (Kelvin–Tait–Chetaev: with the symmetric
/// stiffness positive definite, gyroscopic and dissipative forces alone cannot destabilise;
/// Merkin, *Gyroscopic Systems*, 1956; Kirillov, *Nonconservative Stability Problems of Modern
/// Physics*, 2013, §1.2). A rotor whirling unstable on cross-coupled bearings is one: stepping
/// off its axis along the whirl finds no other equilibrium, so none is looked for.
fn positive_definite(k: &DMatrix<f64>) -> bool {
    let sym = (k + k.transpose()) * 0.5;
    sym.nrows() > 0 && sym.iter().all(|v| v.is_finite()) && sym.cholesky().is_some()
}

impl Solver<'_> {
    /// The point at `speed` from the guess `q0`, with more to start Newton from (see
    /// [`Start`]); past an unstable equilibrium, the stable one found by stepping along its
    /// unstable modes (unless [`Options::no_branch_switch`]).
    pub fn point_from(&self, speed: f64, q0: &[f64], start: Start) -> Result<Point, PointError> {
        let Solver { model, p, opt, .. } = *self;
        // On the model's route (the recorded program when there is one).
        let problem = model.problem(p, speed, (opt.tier, self.workspace))?;
        let solved = self.solve(&problem, speed, q0, start)?;
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
        let unstable = |searched: bool, flutter_only: bool| {
            let (mode, root) = worst.unwrap_or_default();
            BranchKind::Unstable {
                mode,
                re: root.re,
                im: root.im,
                searched,
                flutter_only,
            }
        };
        let directions = search_directions(&first);
        let flutter_only = positive_definite(&first.linear.k);
        if opt.no_branch_switch || directions.is_empty() || flutter_only {
            first.branch.kind = unstable(false, flutter_only && !opt.no_branch_switch);
            return Ok(first);
        }
        let found = self.stable_nearby(&problem, q0, &first, &directions)?;
        Ok(found.unwrap_or_else(|| {
            first.branch.kind = unstable(true, false);
            first
        }))
    }

    /// Newton's solve of `problem` from `q0`; a failure with redundant cut joints or couplers
    /// is reported as such, naming them.
    fn solve(
        &self,
        problem: &Problem,
        speed: f64,
        q0: &[f64],
        start: Start,
    ) -> Result<Solution, EquilibriumError> {
        problem
            .solve(speed, q0, start, self.opt.newton)
            .map_err(|e| {
                let redundant = problem.redundant_equations(q0);
                if redundant.is_empty() {
                    return e;
                }
                let model = self.model.model();
                let owners = model.equation_owners();
                let mut names: Vec<String> =
                    redundant.iter().map(|&k| owners[k].to_string()).collect();
                names.dedup();
                EquilibriumError::RedundantConstraints {
                    names,
                    rank: model.n_constraints() - redundant.len(),
                    equations: model.n_constraints(),
                }
            })
    }

    /// A stable equilibrium near the unstable one `first` (solved from `q0`), by Newton from
    /// steps of growing amplitude along `directions` ([`search_directions`]); `None` where no
    /// step finds one.
    fn stable_nearby(
        &self,
        problem: &Problem,
        q0: &[f64],
        first: &Point,
        directions: &[(usize, C64, bool, Vec<f64>)],
    ) -> Result<Option<Point>, PointError> {
        let Solver { model, p, opt, .. } = *self;
        let speed = first.speed;
        let free = &first.linear.free;
        // Prefer the side the Newton start lies on (in a sweep, the last solution: a sweep
        // that fell onto the unstable equilibrium returns to its own branch), else the side of
        // the model's initial guess (then the positive side).
        let guess = initial_guess(model.model(), p, speed)?;
        let side = |q: &[f64], dir: &[f64]| -> f64 {
            free.iter()
                .enumerate()
                .map(|(k, &i)| dir[k] * (q[i] - first.equilibrium.q[i]))
                .sum()
        };
        // A stable equilibrium on the side stepped to is taken at once; one that Newton
        // reached across the unstable equilibrium only if no step finds one on its own side.
        let mut across = None;
        for amp in SEARCH_AMPLITUDES {
            for (k, root, imaginary_part, dir) in directions {
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
                    if let Ok(pt) = analyse(model.model(), p, problem, solved, opt)
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
                            return Ok(Some(pt));
                        }
                        across.get_or_insert(pt);
                    }
                }
            }
        }
        Ok(across)
    }
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
    rank_kept(model, p, eq.speed, &eq.q)?;
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
            reduce(&free, &independent, &phi_r, [mass, damping, stiffness])?
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

/// Checks that the cut joints' equations dropped as redundant as drawn still hold at the
/// equilibrium `q` (the loop's constraint rank is the same there); only for models with such
/// equations.
fn rank_kept(model: &Model, p: &[f64], speed: f64, q: &[f64]) -> Result<(), EquilibriumError> {
    if model.constraints.iter().all(|c| c.dropped.is_empty()) {
        return Ok(());
    }
    // A field that does not evaluate failed the solve before this.
    let Ok(sys) = crate::mechanics::System::<f64>::new(model, p, speed) else {
        return Ok(());
    };
    let poses = crate::mechanics::kinematics::poses(&sys, q);
    // The model's size: the tolerance of a violated equation (lengths, and angles' sines).
    let size = model_size(&sys).max(1.0);
    for (k, v) in crate::mechanics::dynamics::dropped_values(&sys, &poses) {
        if v.is_nan() || v.abs() > 1e-8 * size {
            return Err(EquilibriumError::RankChanged {
                name: model.constraints[k].name.clone(),
                violation: if v.is_finite() {
                    format!("is violated by {v:.3e}")
                } else {
                    "has no finite value".into()
                },
            });
        }
    }
    Ok(())
}

/// The largest distance from the origin of a joint, a cut joint's point or a body's centre of
/// mass as drawn.
fn model_size(sys: &crate::mechanics::System<f64>) -> f64 {
    let joints = sys.joints.iter().map(|j| j.geometry.at.norm());
    let cuts = sys
        .constraints
        .iter()
        .flat_map(|c| [c.geometry.point1.norm(), c.geometry.point2.norm()]);
    let bodies = sys.bodies.iter().map(|b| b.cm.norm());
    joints.chain(cuts).chain(bodies).fold(0.0, f64::max)
}
