//! The model's equilibrium equations recorded once as [`Tape`]s, for the operating-point solves.
//!
//! A sweep or a Monte Carlo run solves thousands of equilibria of one model with different
//! speeds and parameter values. [`Program::record`] traces the generic mechanics (the same
//! [`evaluate_rows`] the direct route runs) once per model with the parameters, the speed, the
//! coordinates, the free coordinates' rates and the multipliers as inputs:
//!
//! * `residual`: `F(q_R, λ) = [r_R + Φ_Rᵀ λ; Φ]` at `q̇_R = q̈_R = 0` (folded in), made when
//!   the residual is evaluated often (a sweep: see [`Tier`]);
//! * `full`: the same rows with `q̇_R` and `q̈_R` as inputs, so that one forward pass with the
//!   lanes `(q_k, q̇_k, q̈_k)` of each free coordinate gives Newton's Jacobian (whose `q_R` block
//!   is `K`), `C` and `M`; `F` is linear in `λ`, so the Jacobian's `λ` columns are `[Φ_Rᵀ; 0]`,
//!   read off the derivatives of the `Φ` rows along the `q_R` lanes. Its further outputs, `Φ_R`
//!   (whose derivatives give the change of `K` with `λ`) and the driven coordinates' rows (the
//!   drive forces, values only), make that one pass everything a converged point needs. (The
//!   drive rows are a few value-only operations: one program with them serves every pass, where
//!   a second program without them would cost its own pruning, ordering and seeding at every
//!   recording, a large part of a big model's first point.)
//!
//! The program of `∂F/∂p` (the sensitivities) is ordered and seeded when first asked for.
//!
//! Everything that depends on the parameters and the speed only is evaluated once per point
//! ([`Program::at`]). A recording that branched on a value, or that does not reproduce the direct
//! evaluation at a second, perturbed set of inputs, is discarded: the caller then keeps to the
//! direct route, which is always available.

mod adjoint;
mod instance;
mod linear;
mod routes;
mod workspace;

pub use adjoint::{BATCH, Contraction};
pub use instance::Instance;
pub use linear::Linear;
pub use routes::Recorded;
pub use workspace::Workspace;

use instance::inputs;

use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, equilibrium_residual, evaluate_rows};
use crate::model::Model;
use crate::real::Real;
use crate::tape::{NativePass, Pattern, Seeding, Tape, Var, record};
use std::cell::{OnceCell, RefCell};
use std::sync::{Arc, OnceLock, RwLock};

/// The recorded equations of one model (see the module documentation).
#[derive(Debug, Clone)]
pub struct Program {
    np: usize,
    n: usize,
    free: Vec<usize>,
    m: usize,
    /// The program of `F` alone at zero rates, made from `full` when first needed.
    residual: OnceLock<Tape>,
    /// `full`, with the drive rows.
    full: Tape,
    /// The inputs the trace was recorded at (where `residual` is replayed).
    recorded_at: Vec<f64>,
    /// Lanes `q_R` on `residual`, made when first needed: Newton's Jacobians come from the
    /// exact evaluation (`linear`), so only diagnoses use these (at 160 segments they cost a
    /// twentieth of the recording).
    jacobian: OnceLock<Seeding>,
    /// Lanes `(q_k, q̇_k, q̈_k)` for each free coordinate `k` on `full`.
    linear: Seeding,
    /// For each driven coordinate, what depends on it in `residual` (the steady-state check),
    /// made when first needed (a drive proved steady by symmetry never needs it).
    driven: OnceLock<Vec<Seeding>>,
    /// Three lanes along fixed directions on `full` (`F` and the linearisation's products
    /// that the steady-state check compares), made when first needed.
    probe: OnceLock<Seeding>,
    /// For each set of parameters the sensitivities were asked along (a few per run):
    /// `residual` with the other parameters and the speed static, and its lanes along those
    /// (`∂F/∂p`), made when first needed.
    parametric: Parametric,
    /// The `f64` passes compiled to native code, made when [`Tier::Native`] first asks.
    native: Arc<OnceLock<Native>>,
    /// Which pairs of parameters `F` can have a mixed second derivative in
    /// ([`Tape::hessian_pattern`]), made when first asked for.
    pattern: OnceLock<Pattern>,
}

/// How a program's `f64` passes run, chosen by the caller for the work ahead: every tier gives
/// the same results to the bit (the folded rates are zeros, and `F`'s signed zeros are made
/// `+0`; the compiled passes do the interpreter's arithmetic), only the time differs.
///
/// Making the residual's own program costs 9–15 residual passes (the shipped examples and
/// chains of 40 and 160 segments) and saves a third of each later one, so it pays back after
/// 30–50 residuals: a single point (two or three residuals) never pays for it, a sweep pays
/// once. Compiling to native code takes 10–400 ms and saves 1–14 µs an evaluation on the
/// shipped examples, so it pays back after some tens of thousands of evaluations
/// ([`NATIVE_AFTER`]): a Monte Carlo run's, not a sweep's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tier {
    /// A few evaluations (one point): a residual is `full`'s value pass at zero rates (the
    /// rates' terms evaluated and added as zeros, about 1.4 residuals), unless the residual's
    /// own program is made already.
    Few,
    /// Many (a sweep): the residual's own program, made at the first residual.
    #[default]
    Many,
    /// Tens of thousands (a Monte Carlo run): [`Tier::Many`]'s programs compiled to native
    /// code ([`crate::tape::NativePass`]) at the first evaluation.
    Native,
}

/// Evaluations (exact evaluations and residuals) from which compiling the passes to native
/// code pays back (see [`Tier`]).
pub const NATIVE_AFTER: usize = 20_000;

/// Exact evaluations and residuals of a warm-started point of a sweep, about: a Newton solve
/// of two or three steps and the linearisation's pass.
pub const EVALUATIONS_PER_POINT: usize = 4;

impl Tier {
    /// The tier for about `evaluations` exact evaluations and residuals of one program.
    pub fn for_evaluations(evaluations: usize) -> Tier {
        if evaluations >= NATIVE_AFTER {
            Tier::Native
        } else {
            Tier::Many
        }
    }

    /// The tier for `points` points of sweeps (samples or quadrature nodes × speeds).
    pub fn for_points(points: usize) -> Tier {
        Tier::for_evaluations(points.saturating_mul(EVALUATIONS_PER_POINT))
    }
}

/// The program of `∂F/∂p` along a set of parameters, and its lanes.
type ParameterPass = Arc<(Tape, Seeding)>;

/// The programs of `∂F/∂p` along sets of parameters, with those sets.
#[derive(Debug, Default)]
struct Parametric(RwLock<Vec<(Vec<usize>, ParameterPass)>>);

impl Clone for Parametric {
    fn clone(&self) -> Self {
        Parametric(RwLock::new(
            self.0.read().unwrap_or_else(|e| e.into_inner()).clone(),
        ))
    }
}

/// The compiled `full` pass with [`Program::linear`]'s lanes, and the compiled residual (each
/// `None` where its program is not compiled).
#[derive(Debug)]
struct Native {
    full: Option<NativePass>,
    residual: Option<NativePass>,
}

/// What the recorded function returns: `F`, that is the free coordinates' rows of
/// `r + Φ_qᵀλ` and then `Φ`, as functions of the free coordinates' rates too; the entries of
/// `Φ_R` (constraint by constraint; their derivatives along `q_R` are the constraints' second
/// derivatives); the driven coordinates' rows of `r + Φ_qᵀλ` (the drive forces at zero rates)
/// and the entries of `Φ_D`. The programs are cut from this one trace ([`Tape::finish`] prunes
/// before it fuses, so a product that only the drive rows share with `F` is still fused where
/// they are left out).
fn trace(model: &Model, x: &[Var]) -> Option<Vec<Var>> {
    let (np, n, m) = (
        model.parameters.len(),
        model.coordinates.len(),
        model.n_constraints(),
    );
    let (free, driven) = (model.free(), model.driven());
    let nf = free.len();
    let sys = System::new(model, &x[..np], x[np]).ok()?;
    let q = &x[np + 1..np + 1 + n];
    let mut qd = sys.steady_speeds();
    let mut qdd = vec![Var::Const(0.0); n];
    for (k, &i) in free.iter().enumerate() {
        qd[i] = x[np + 1 + n + k];
        qdd[i] = x[np + 1 + n + nf + k];
    }
    let mut rows = free.clone();
    rows.extend(&driven);
    rows.sort_unstable();
    let lambda = &x[np + 1 + n + 2 * nf..np + 1 + n + 2 * nf + m];
    let l = Lifted::new(sys);
    let d = evaluate_rows(&l, q, &qd, &qdd, &rows);
    let g = d.with_multipliers(lambda);
    let phi = |coords: &[usize]| {
        (0..m)
            .flat_map(|k| coords.iter().map(move |&i| (k, i)))
            .map(|(k, i)| d.phi_q[(k, i)])
            .collect::<Vec<_>>()
    };
    let mut out: Vec<Var> = free
        .iter()
        .map(|&i| g[i])
        .chain(d.phi.iter().copied())
        .collect();
    out.extend(phi(&free));
    out.extend(driven.iter().map(|&i| g[i]));
    out.extend(phi(&driven));
    Some(out)
}

impl Program {
    /// Records the model's equations at parameters `p`, `speed` and coordinates `q` (any
    /// values at which the model evaluates). `None` when the recording is not valid everywhere
    /// (see the module documentation).
    pub fn record(model: &Model, p: &[f64], speed: f64, q: &[f64]) -> Option<Program> {
        let (np, n, m) = (p.len(), q.len(), model.n_constraints());
        let free = model.free();
        let nf = free.len();
        let x = inputs(p, speed, q, &vec![1.0; m], nf);
        let fixed: Vec<usize> = (0..=np).collect();
        // One trace with every output; `full` is cut from it now, the residual's own program
        // from `full` when residuals are many (`residual_tape`).
        let raw = record(&x, |v| trace(model, v))?;
        let differentiated = nf + m + m * nf;
        let full = raw.finish_split(&(0..raw.n_outputs()).collect::<Vec<_>>(), &fixed);
        // A coordinate's three lanes side by side: an operation depends on the rates of the
        // coordinates whose positions it depends on, so its lane range stays narrow (the
        // governor's pass is 43 % fewer lane operations than with `[q_R, q̇_R, q̈_R]` in blocks,
        // the 12-arm governor's 80 %). Where the equations are banded (a meshed shaft), the
        // coordinates that never meet in a row share lanes, each coordinate's three lanes
        // packed as a group (`Tape::seeding_in_groups`).
        let seeds: Vec<(usize, usize)> = free
            .iter()
            .enumerate()
            .flat_map(|(k, &i)| {
                [
                    (np + 1 + i, 3 * k),
                    (np + 1 + n + k, 3 * k + 1),
                    (np + 1 + n + nf + k, 3 * k + 2),
                ]
            })
            .collect();
        // Derivatives of F and Φ_R; the drive rows are values only.
        let linear = full.seeding_in_groups(&seeds, (3 * nf, 3), differentiated);
        let program = Program {
            driven: OnceLock::new(),
            probe: OnceLock::new(),
            parametric: Parametric::default(),
            np,
            n,
            free,
            m,
            residual: OnceLock::new(),
            recorded_at: x,
            full,
            jacobian: OnceLock::new(),
            linear,
            native: Arc::default(),
            pattern: OnceLock::new(),
        };
        program.reproduces(model, p, speed, q).then_some(program)
    }

    /// The pairs of parameters whose mixed second derivative of `F` (and of its derivatives
    /// along the coordinates, rates and multipliers) may be nonzero at any inputs: the
    /// structure of the parameters' Hessian, from the recorded operations.
    pub fn parameter_pattern(&self) -> &Pattern {
        self.pattern
            .get_or_init(|| self.full.hessian_pattern(self.np))
    }

    /// Does the program give the direct route's residual here and at a perturbed point?
    fn reproduces(&self, model: &Model, p: &[f64], speed: f64, q: &[f64]) -> bool {
        let m = self.m;
        let lambda: Vec<f64> = (0..m).map(|k| 1.0 + 0.1 * k as f64).collect();
        let p2: Vec<f64> = p
            .iter()
            .enumerate()
            .map(|(k, v)| v * (1.0 + 1e-3 * (k % 7 + 1) as f64))
            .collect();
        let q2: Vec<f64> = q
            .iter()
            .enumerate()
            .map(|(k, v)| v + 0.01 * (k % 5 + 1) as f64)
            .collect();
        let l2: Vec<f64> = lambda.iter().map(|v| -0.5 * v).collect();
        [
            (p, speed, q, &lambda),
            (&p2[..], 1.01 * speed + 0.1, &q2[..], &l2),
        ]
        .into_iter()
        .all(|(p, w, q, l)| {
            let Ok(sys) = System::new(model, p, w) else {
                return false;
            };
            let qd = sys.steady_speeds();
            let direct = equilibrium_residual(&Lifted::new(sys), &self.free, q, &qd, l);
            let workspace = Workspace::default();
            let Some(here) = (self.at(p, w, Tier::Few, &workspace)).map(|i| i.residual(q, l))
            else {
                return false;
            };
            let scale = direct.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            here.len() == direct.len()
                && here
                    .iter()
                    .zip(&direct)
                    .all(|(a, b)| (a - b).abs() <= 1e-12 * scale)
        })
    }

    /// `residual`, made now where it is not yet (see [`Tier`]): `full` replayed with
    /// the rates as zeros, then pruned to `F` and ordered.
    fn residual_tape(&self) -> &Tape {
        self.residual.get_or_init(|| {
            let (np, n, nf) = (self.np, self.n, self.free.len());
            let rates: Vec<(usize, f64)> = (np + 1 + n..np + 1 + n + 2 * nf)
                .map(|k| (k, 0.0))
                .collect();
            let keep: Vec<usize> = (0..nf + self.m).collect();
            let fixed: Vec<usize> = (0..=np).collect();
            // A replay does not branch; were it to, `full` pruned to `F` is a residual too.
            self.full
                .specialise(&self.recorded_at, &rates, &keep)
                .unwrap_or_else(|| self.full.clone())
                .finish_split(&keep, &fixed)
        })
    }

    /// The program of `F` alone, where it is made yet (see [`Tier`]).
    pub fn residual_program(&self) -> Option<&Tape> {
        self.residual.get()
    }

    /// The residual's own program where `tier` asks for it or it is made already (`None`:
    /// residuals through `full`).
    fn residual_at(&self, tier: Tier) -> Option<&Tape> {
        match tier {
            Tier::Few => self.residual.get(),
            Tier::Many | Tier::Native => Some(self.residual_tape()),
        }
    }

    /// Is the native code made (by a [`Tier::Native`] evaluation)?
    pub fn is_native(&self) -> bool {
        self.native.get().is_some_and(|n| n.full.is_some())
    }

    /// The native code where `tier` asks for it, compiled at the first such call.
    fn native(&self, tier: Tier) -> Option<&Native> {
        (tier == Tier::Native).then(|| {
            self.native.get_or_init(|| Native {
                full: self.full.compile_forward(&self.linear),
                residual: self.residual_tape().compile_eval(),
            })
        })
    }

    /// The program at parameters `p` and `speed`, its passes run at `tier` in `workspace`: the
    /// parts that depend on them alone evaluated. `None` where one of those is not finite: a
    /// field of the model does not evaluate there (the direct route names it).
    pub fn at<'a>(
        &'a self,
        p: &[f64],
        speed: f64,
        tier: Tier,
        workspace: &'a Workspace,
    ) -> Option<Instance<'a>> {
        let x = inputs(
            p,
            speed,
            &vec![0.0; self.n],
            &vec![0.0; self.m],
            self.free.len(),
        );
        let full = self.full.eval_static(&x);
        full.iter().all(|x| x.is_finite()).then(|| Instance {
            program: self,
            tier,
            residual: OnceCell::new(),
            full,
            x: RefCell::new(x),
            work: &workspace.work,
        })
    }
}

impl Program {
    /// `F` at parameters, speed, coordinates and multipliers over any [`Real`] (dual numbers
    /// seeded in the parameters give the equations' derivatives with respect to them).
    pub fn residual_over<S: Real>(&self, p: &[S], speed: S, q: &[S], lambda: &[S]) -> Vec<S> {
        let x = inputs(p, speed, q, lambda, self.free.len());
        let tape = self.residual_tape();
        let fixed = tape.eval_static(&x);
        tape.eval(&fixed, &x, &mut Vec::new())
    }

    /// `∂F/∂p_b` for the parameters `b` of `wrt` at parameters `p`, `speed`, `q` and `λ`: one
    /// forward pass along them (rows of `F` × `wrt`, row-major), where one dual-number residual
    /// per parameter would give one column each. What depends on the other parameters only is
    /// evaluated without lanes, once per call. The pass runs in `workspace`.
    pub fn parameter_derivatives(
        &self,
        p: &[f64],
        speed: f64,
        (q, lambda): (&[f64], &[f64]),
        wrt: &[usize],
        workspace: &Workspace,
    ) -> Vec<f64> {
        let x = inputs(p, speed, q, lambda, self.free.len());
        let known = |sets: &[(Vec<usize>, ParameterPass)]| {
            sets.iter().find(|(w, _)| w == wrt).map(|(_, t)| t.clone())
        };
        let read = known(&self.parametric.0.read().unwrap_or_else(|e| e.into_inner()));
        let pass = read.unwrap_or_else(|| {
            // The parameters of `wrt` as inputs that move: one lane each.
            let fixed: Vec<usize> = (0..=self.np).filter(|k| !wrt.contains(k)).collect();
            let tape = self.residual_tape().split(&fixed);
            let seeds: Vec<(usize, usize)> = wrt.iter().enumerate().map(|(l, &k)| (k, l)).collect();
            let seeding = tape.seeding(&seeds, wrt.len(), self.free.len() + self.m);
            let pass = Arc::new((tape, seeding));
            let mut sets = self.parametric.0.write().unwrap_or_else(|e| e.into_inner());
            if known(&sets).is_none() {
                sets.push((wrt.to_vec(), pass.clone()));
            }
            pass
        });
        let (tape, seeding) = &*pass;
        let fixed = tape.eval_static(&x);
        workspace.with_buffer(|work| tape.forward(&fixed, &x, seeding, work).1)
    }

    /// `F`, its Jacobian, `C` and `M` over any [`Real`] (without the constraints' curvature),
    /// the pass run in `workspace`.
    pub fn linear_over<S: Real>(
        &self,
        p: &[S],
        speed: S,
        (q, lambda): (&[S], &[S]),
        workspace: &Workspace,
    ) -> Linear<S> {
        let x = inputs(p, speed, q, lambda, self.free.len());
        let fixed = self.full.eval_static(&x);
        workspace.with_buffer(|work| {
            let (f, d) = self.full.forward_rows(&fixed, &x, &self.linear, work);
            Linear::from_forward(f, &d, self.free.len(), self.m, false)
        })
    }
}
