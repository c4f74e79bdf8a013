//! The model's equilibrium equations recorded once as [`Tape`]s, for the operating-point solves.
//!
//! A sweep or a Monte Carlo run solves thousands of equilibria of one model with different
//! speeds and parameter values. [`Program::record`] traces the generic mechanics (the same
//! [`evaluate_rows`] the direct route runs) once per model with the parameters, the speed, the
//! coordinates, the free coordinates' rates and the multipliers as inputs:
//!
//! * `residual`: `F(q_R, λ) = [r_R + Φ_Rᵀ λ; Φ]` at `q̇_R = q̈_R = 0` (folded in), made when
//!   the residual is evaluated often (see [`SPECIALISE_AFTER`]);
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

use crate::equations::{Equations, Evaluation, Fit, Rates};
use crate::linearize::{Linearization, LinearizeError, reduce};
use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, equilibrium_residual, evaluate_rows};
use crate::model::Model;
use crate::real::Real;
use crate::tape::{Forward, NativePass, Rows, Seeding, Tape, Var, record};
use nalgebra::{DMatrix, DVector};
use std::cell::{OnceCell, RefCell};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock, RwLock};

/// The recorded equations of one model (see the module documentation).
#[derive(Debug, Clone)]
pub struct Program {
    np: usize,
    n: usize,
    free: Vec<usize>,
    m: usize,
    residual: Residual,
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
    /// For each set of parameters the sensitivities were asked along (a few per run):
    /// `residual` with the other parameters and the speed static, and its lanes along those
    /// (`∂F/∂p`), made when first needed.
    parametric: Parametric,
    /// When the `f64` passes run as native code.
    tier: Tier,
}

/// Evaluations of a program after which its `f64` passes are compiled to native code
/// ([`crate::tape::NativePass`]): compiling takes 10–400 ms and saves 1–14 µs an evaluation
/// on the shipped examples, so a single point or a sweep stays interpreted and a Monte Carlo
/// run or a quadrature switches early in its course. The compiled passes give the same
/// results to the bit.
pub const NATIVE_AFTER: usize = 20_000;

/// Residuals evaluated through `full` before `residual` is made from it. Until then a residual
/// is `full`'s value pass at zero rates: the rates' terms evaluated and added as zeros, where
/// `residual` folds them away, so such a pass costs about 1.4 residuals. Making `residual` costs
/// 9–15 of those passes (the shipped examples and chains of 40 and 160 segments), so it pays
/// back after 30–50 residuals. A single cold point evaluates two or three residuals, a sweep or
/// a Monte Carlo run thousands: the first never pay for it, the second pay once, at about the
/// break-even (the rent-or-buy rule). Both give the same values to the bit (the folded terms
/// are zeros, and `F`'s signed zeros are made `+0`), so when a run switches does not change its
/// results.
pub const SPECIALISE_AFTER: usize = 32;

/// The program of `F` alone at zero rates, made from `full` when first needed.
#[derive(Debug)]
struct Residual {
    tape: OnceLock<Tape>,
    /// Residuals evaluated through `full` so far.
    through_full: AtomicUsize,
}

impl Clone for Residual {
    fn clone(&self) -> Self {
        Residual {
            tape: self.tape.clone(),
            through_full: AtomicUsize::new(self.through_full.load(Ordering::Relaxed)),
        }
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

/// The native code of a [`Program`] and when it is made.
#[derive(Debug)]
struct Tier {
    /// Exact evaluations and residuals so far.
    evaluations: AtomicUsize,
    /// Compile once `evaluations` reaches this (`usize::MAX`: never).
    after: AtomicUsize,
    native: OnceLock<Native>,
}

/// The compiled `full` pass with [`Program::linear`]'s lanes, and the compiled residual (each
/// `None` where its program is not compiled).
#[derive(Debug)]
struct Native {
    full: Option<NativePass>,
    residual: Option<NativePass>,
}

impl Default for Tier {
    fn default() -> Self {
        Tier {
            evaluations: AtomicUsize::new(0),
            after: AtomicUsize::new(NATIVE_AFTER),
            native: OnceLock::new(),
        }
    }
}

/// A copy counts its evaluations afresh and compiles its own code.
impl Clone for Tier {
    fn clone(&self) -> Self {
        let tier = Tier::default();
        tier.after
            .store(self.after.load(Ordering::Relaxed), Ordering::Relaxed);
        tier
    }
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
        // the 12-arm governor's 80 %).
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
        let linear = full.seeding(&seeds, 3 * nf, differentiated);
        let program = Program {
            driven: OnceLock::new(),
            parametric: Parametric::default(),
            np,
            n,
            free,
            m,
            residual: Residual {
                tape: OnceLock::new(),
                through_full: AtomicUsize::new(0),
            },
            recorded_at: x,
            full,
            jacobian: OnceLock::new(),
            linear,
            tier: Tier::default(),
        };
        program.reproduces(model, p, speed, q).then_some(program)
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
            let Some(here) = self.at(p, w).map(|i| i.residual(q, l)) else {
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

    /// `residual`, made now where it is not yet (see [`SPECIALISE_AFTER`]): `full` replayed with
    /// the rates as zeros, then pruned to `F` and ordered.
    fn residual_tape(&self) -> &Tape {
        self.residual.tape.get_or_init(|| {
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

    /// The program of `F` alone, where it is made yet (see [`SPECIALISE_AFTER`]).
    pub fn residual_program(&self) -> Option<&Tape> {
        self.residual.tape.get()
    }

    /// `residual` where it is made or due, counting one more residual through `full` where not.
    fn specialised(&self) -> Option<&Tape> {
        if let Some(tape) = self.residual.tape.get() {
            return Some(tape);
        }
        let count = self.residual.through_full.fetch_add(1, Ordering::Relaxed);
        (count >= SPECIALISE_AFTER).then(|| self.residual_tape())
    }

    /// Compile the `f64` passes to native code after `evaluations` more exact evaluations and
    /// residuals of the program (`None`: never; `Some(0)`: at the next). The default is
    /// [`NATIVE_AFTER`] evaluations; the results are the same either way, only the time
    /// differs (timings compare the two with this). `None` also turns compiled code off.
    pub fn native_after(&self, evaluations: Option<usize>) {
        let at = evaluations.map_or(usize::MAX, |n| {
            n.saturating_add(self.tier.evaluations.load(Ordering::Relaxed))
        });
        self.tier.after.store(at, Ordering::Relaxed);
    }

    /// Does the exact evaluation run as native code now (see [`Program::native_after`])?
    pub fn is_native(&self) -> bool {
        self.tier.after.load(Ordering::Relaxed) != usize::MAX
            && self.tier.native.get().is_some_and(|n| n.full.is_some())
    }

    /// The native code, counting one evaluation; compiled here once they reach the threshold
    /// (`None` while interpreted, and always where [`Program::native_after`] said never).
    fn native(&self) -> Option<&Native> {
        let after = self.tier.after.load(Ordering::Relaxed);
        if after == usize::MAX {
            return None;
        }
        if let Some(native) = self.tier.native.get() {
            return Some(native);
        }
        let count = self.tier.evaluations.fetch_add(1, Ordering::Relaxed);
        (count >= after).then(|| {
            self.tier.native.get_or_init(|| Native {
                full: self.full.compile_forward(&self.linear),
                residual: self.residual_tape().compile_eval(),
            })
        })
    }

    /// The program at parameters `p` and `speed`: the parts that depend on them alone
    /// evaluated. `None` where one of those is not finite: a field of the model does not
    /// evaluate there (the direct route names it).
    pub fn at(&self, p: &[f64], speed: f64) -> Option<Instance<'_>> {
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
            residual: OnceCell::new(),
            full,
            x: RefCell::new(x),
            work: RefCell::new(POOL.with(|p| p.borrow_mut().pop()).unwrap_or_default()),
        })
    }
}

thread_local! {
    /// Forward-mode scratch buffers of any scalar type, kept for the next pass on this thread
    /// (a buffer over hyper-dual numbers is hundreds of kilobytes).
    static BUFFERS: RefCell<Vec<Box<dyn std::any::Any>>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with a forward-mode buffer over `S` from this thread's pool.
fn with_buffer<S: Real, R>(f: impl FnOnce(&mut Forward<S>) -> R) -> R {
    let mut work = BUFFERS
        .with(|b| {
            let mut b = b.borrow_mut();
            let i = b.iter().position(|x| x.is::<Forward<S>>())?;
            b.swap_remove(i).downcast::<Forward<S>>().ok()
        })
        .unwrap_or_default();
    let out = f(&mut work);
    BUFFERS.with(|b| {
        let mut b = b.borrow_mut();
        if b.len() < 8 {
            b.push(work);
        }
    });
    out
}

/// Scratch space of an [`Instance`]: values, one forward buffer per seeding (kept, as switching
/// a buffer's seeding clears it), and values at three points.
#[derive(Debug, Default)]
struct Work {
    values: Vec<f64>,
    jacobian: Forward<f64>,
    linear: Forward<f64>,
    varied: Vec<[f64; 3]>,
}

thread_local! {
    /// Scratch spaces of finished instances on this thread, reused by the next ones (a sweep
    /// makes one instance per speed).
    static POOL: RefCell<Vec<Work>> = const { RefCell::new(Vec::new()) };
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        let work = std::mem::take(self.work.get_mut());
        POOL.with(|p| {
            let mut p = p.borrow_mut();
            if p.len() < 4 {
                p.push(work);
            }
        });
    }
}

/// The input vector `[p, speed, q, q̇_R = 0, q̈_R = 0, λ]`.
fn inputs<S: Real>(p: &[S], speed: S, q: &[S], lambda: &[S], nf: usize) -> Vec<S> {
    let mut x = Vec::with_capacity(p.len() + 1 + q.len() + 2 * nf + lambda.len());
    x.extend_from_slice(p);
    x.push(speed);
    x.extend_from_slice(q);
    x.extend(std::iter::repeat_n(S::from(0.0), 2 * nf));
    x.extend_from_slice(lambda);
    x
}

/// A [`Program`] at one set of parameters and one speed.
#[derive(Debug)]
pub struct Instance<'a> {
    program: &'a Program,
    /// The static values of `residual`, once it is used.
    residual: OnceCell<Vec<f64>>,
    full: Vec<f64>,
    /// The input vector, with the parameters and the speed in place.
    x: RefCell<Vec<f64>>,
    work: RefCell<Work>,
}

/// Newton's Jacobian `∂F/∂[q_R; λ]` from the derivatives `d` (rows of `F`, `lanes` each) whose
/// lane `stride · k` is along the free coordinate `k`: the `λ` columns are `[Φ_Rᵀ; 0]`, `Φ_R`
/// being the `q_R` derivatives of the `Φ` rows.
fn jacobian<S: Real>(d: &[S], lanes: usize, stride: usize, nf: usize, m: usize) -> DMatrix<S> {
    let zero = S::from(0.0);
    DMatrix::from_fn(nf + m, nf + m, |r, c| match (r < nf, c < nf) {
        (_, true) => d[r * lanes + stride * c],
        (true, false) => d[c * lanes + stride * r],
        (false, false) => zero,
    })
}

/// Newton's Jacobian with the linearisation's damping and mass matrices, at one state.
#[derive(Debug, Clone)]
pub struct Linear<S: Real = f64> {
    /// `F`.
    pub residual: Vec<S>,
    /// `∂F/∂[q_R; λ]`.
    pub jacobian: DMatrix<S>,
    /// `∂r_R/∂q̇_R`.
    pub damping: DMatrix<S>,
    /// `∂r_R/∂q̈_R`.
    pub mass: DMatrix<S>,
    /// `∂²Φ_k/∂q_R²` for each constraint equation `k`: how the Jacobian's `q_R` block changes
    /// with `λ_k` (see [`Linear::shift_multipliers`]). Empty from [`Program::linear_over`]:
    /// the sensitivities and Hessians do not shift multipliers, and the 12-arm governor's
    /// twelve 13×13 matrices over dual numbers were 6 % of its sensitivities.
    pub curvature: Vec<DMatrix<S>>,
    /// The driven coordinates' rows of `r + Φ_qᵀλ`: the drive forces at a steady state.
    pub drive: Vec<S>,
    /// `Φ_D`, constraint equations × driven coordinates (how `drive` changes with `λ`).
    phi_d: DMatrix<S>,
}

impl<S: Real> Linear<S> {
    /// From a forward pass with [`Program::linear`]'s lanes over the `full` program's outputs
    /// (`F`, then the entries of `Φ_R`), with the constraints' curvature when `curvature`.
    fn from_forward(mut f: Vec<S>, d: &Rows<'_, S>, nf: usize, m: usize, curvature: bool) -> Self {
        let nd = (f.len() - nf - m - m * nf) / (1 + m);
        let phi_d = DMatrix::from_row_slice(m, nd, &f[f.len() - m * nd..]);
        let drive = f[nf + m + m * nf..nf + m + m * nf + nd].to_vec();
        f.truncate(nf + m);
        // The lanes of coordinate `c` are `3c` (`q_c`), `3c + 1` (`q̇_c`), `3c + 2` (`q̈_c`).
        let zero = S::from(0.0);
        let mut jacobian = DMatrix::from_element(nf + m, nf + m, zero);
        let mut damping = DMatrix::from_element(nf, nf, zero);
        let mut mass = DMatrix::from_element(nf, nf, zero);
        for r in 0..nf + m {
            let row = d.row(r);
            for c in 0..nf {
                jacobian[(r, c)] = row[3 * c];
                if r < nf {
                    damping[(r, c)] = row[3 * c + 1];
                    mass[(r, c)] = row[3 * c + 2];
                } else {
                    // `Φ_R`'s transpose: the multipliers' columns of the `r` rows.
                    jacobian[(c, r)] = row[3 * c];
                }
            }
        }
        let curvature = (0..if curvature { m } else { 0 })
            .map(|k| {
                let mut h = DMatrix::from_element(nf, nf, zero);
                for j in 0..nf {
                    let row = d.row(nf + m + k * nf + j);
                    for i in 0..nf {
                        h[(j, i)] = row[3 * i];
                    }
                }
                h
            })
            .collect();
        Linear {
            drive,
            phi_d,
            residual: f,
            jacobian,
            damping,
            mass,
            curvature,
        }
    }

    /// As Newton's method takes it, with the drive rows when `drive`.
    fn evaluation(self, drive: bool) -> Evaluation<S> {
        Evaluation {
            residual: self.residual,
            jacobian: self.jacobian,
            rates: Some(Rates {
                damping: self.damping,
                mass: self.mass,
            }),
            drive: drive.then_some(self.drive),
        }
    }

    /// The linearisation (`K` is the `q_R` block of the Jacobian, `Φ_R` its `λ` columns).
    pub fn reduce(
        self,
        free: &[usize],
        independent: &[usize],
    ) -> Result<Linearization<S>, LinearizeError> {
        let nf = free.len();
        let m = self.jacobian.nrows() - nf;
        let phi_r = DMatrix::from_fn(m, nf, |k, j| self.jacobian[(j, nf + k)]);
        let k = self.jacobian.view((0, 0), (nf, nf)).into_owned();
        reduce(free, independent, &phi_r, self.mass, self.damping, k)
    }
}

impl Linear {
    /// The same at the multipliers `λ + δ`: `F`, the Jacobian and the drive rows are affine in
    /// `λ` (by `Φ_Rᵀ`, the constraints' curvature and `Φ_Dᵀ`), and `Φ`, `Φ_R`, `C` and `M` do not
    /// depend on it.
    /// So one pass at any multipliers serves every multiplier at that `q`.
    pub fn shift_multipliers(&mut self, delta: &[f64]) {
        assert_eq!(
            self.curvature.len(),
            delta.len(),
            "multipliers are shifted on an evaluation with the constraints' curvature"
        );
        let curvature = std::mem::take(&mut self.curvature);
        let nf = self.mass.nrows();
        self.shift(delta, nf, |k, j| &curvature[k].as_slice()[j..]);
        self.curvature = curvature;
    }

    /// [`Linear::shift_multipliers`] with the curvature `∂²Φ_k/∂q_j∂q_i` at
    /// `row(k, j)[stride · i]`.
    fn shift<'h>(&mut self, delta: &[f64], stride: usize, row: impl Fn(usize, usize) -> &'h [f64]) {
        let nf = self.mass.nrows();
        let rows = self.jacobian.nrows();
        for (k, &dk) in delta.iter().enumerate() {
            for j in 0..nf {
                self.residual[j] += self.jacobian[(j, nf + k)] * dk;
            }
            for (j, v) in self.drive.iter_mut().enumerate() {
                *v += self.phi_d[(k, j)] * dk;
            }
            // The `q_R` block (column-major: entry `(j, i)` at `j + rows · i`).
            let jac = self.jacobian.as_mut_slice();
            for j in 0..nf {
                let h = row(k, j);
                for i in 0..nf {
                    jac[j + rows * i] += h[stride * i] * dk;
                }
            }
        }
    }
}

impl Instance<'_> {
    /// Number of constraint equations.
    pub fn constraints(&self) -> usize {
        self.program.m
    }

    fn set(&self, q: &[f64], lambda: &[f64]) {
        let pr = self.program;
        let mut x = self.x.borrow_mut();
        let o = pr.np + 1;
        x[o..o + pr.n].copy_from_slice(q);
        let ol = o + pr.n + 2 * pr.free.len();
        x[ol..ol + pr.m].copy_from_slice(lambda);
    }

    /// The values of the residual program's static operations here.
    fn residual_static(&self) -> &[f64] {
        self.residual
            .get_or_init(|| self.program.residual_tape().eval_static(&self.x.borrow()))
    }

    /// `F(q_R, λ)`: through `full` until the residual program is made ([`SPECIALISE_AFTER`]).
    pub fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.set(q, lambda);
        let mut work = self.work.borrow_mut();
        let (pr, x) = (self.program, self.x.borrow());
        let mut f = match pr.specialised() {
            None => {
                let mut f = pr.full.eval(&self.full, &x, &mut work.values);
                f.truncate(pr.free.len() + pr.m);
                f
            }
            Some(tape) => match pr.native().and_then(|n| n.residual.as_ref()) {
                Some(pass) => tape.eval_native(pass, self.residual_static(), &x, &mut work.values),
                None => tape.eval(self.residual_static(), &x, &mut work.values),
            },
        };
        // The folded terms are zeros, which can only change the sign of a zero: `-0 + 0 = +0`.
        for v in &mut f {
            *v += 0.0;
        }
        f
    }

    /// `F` at the values `q_c + offsets[l]` of the `d`-th driven coordinate `c` (the other
    /// coordinates and the multipliers as given), in one pass: the largest `|F|` at each.
    pub fn residual_at_drive_offsets(
        &self,
        q: &[f64],
        lambda: &[f64],
        d: usize,
        offsets: [f64; 3],
    ) -> [f64; 3] {
        self.set(q, lambda);
        let pr = self.program;
        let seeding = &pr.driven.get_or_init(|| {
            let (np, n) = (pr.np, pr.n);
            (0..n)
                .filter(|i| !pr.free.contains(i))
                .map(|i| {
                    pr.residual_tape()
                        .seeding(&[(np + 1 + i, 0)], 1, pr.free.len() + pr.m)
                })
                .collect()
        })[d];
        let c = seeding.seeds()[0].0 - pr.np - 1;
        let values = offsets.map(|o| q[c] + o);
        let mut work = self.work.borrow_mut();
        let f = pr.residual_tape().eval_varied(
            self.residual_static(),
            &self.x.borrow(),
            seeding,
            values,
            &mut work.varied,
        );
        std::array::from_fn(|l| f.iter().fold(0.0f64, |a, v| a.max(v[l].abs())))
    }

    /// `F` and its Jacobian with respect to `[q_R; λ]`.
    pub fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        self.set(q, lambda);
        let pr = self.program;
        let mut work = self.work.borrow_mut();
        let seeding = pr.jacobian.get_or_init(|| {
            let seeds: Vec<(usize, usize)> = (pr.free.iter().enumerate())
                .map(|(k, &i)| (pr.np + 1 + i, k))
                .collect();
            pr.residual_tape()
                .seeding(&seeds, pr.free.len(), pr.free.len() + pr.m)
        });
        let (f, d) = pr.residual_tape().forward(
            self.residual_static(),
            &self.x.borrow(),
            seeding,
            &mut work.jacobian,
        );
        (f, jacobian(&d, pr.free.len(), 1, pr.free.len(), pr.m))
    }

    /// `F`, its Jacobian, `C`, `M`, the constraints' curvature and the drive rows in one
    /// forward pass.
    pub fn linear(&self, q: &[f64], lambda: &[f64]) -> Linear {
        self.full_pass(q, lambda, |f, d| {
            Linear::from_forward(f, d, self.program.free.len(), self.program.m, true)
        })
    }

    /// [`Instance::linear`] without the curvature (which only a shift of the multipliers
    /// reads).
    fn linear_plain(&self, q: &[f64], lambda: &[f64]) -> Linear {
        self.full_pass(q, lambda, |f, d| {
            Linear::from_forward(f, d, self.program.free.len(), self.program.m, false)
        })
    }

    /// `full`'s forward pass with [`Program::linear`]'s lanes at `(q, λ)`, read by `read`.
    fn full_pass<R>(
        &self,
        q: &[f64],
        lambda: &[f64],
        read: impl FnOnce(Vec<f64>, &Rows<'_, f64>) -> R,
    ) -> R {
        self.set(q, lambda);
        let pr = self.program;
        let mut work = self.work.borrow_mut();
        let x = self.x.borrow();
        let (f, d) = match pr.native().and_then(|n| n.full.as_ref()) {
            Some(pass) => {
                pr.full
                    .forward_native(pass, &self.full, &x, &pr.linear, &mut work.linear)
            }
            None => pr
                .full
                .forward_rows(&self.full, &x, &pr.linear, &mut work.linear),
        };
        read(f, &d)
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
    /// evaluated without lanes, once per call.
    pub fn parameter_derivatives(
        &self,
        p: &[f64],
        speed: f64,
        q: &[f64],
        lambda: &[f64],
        wrt: &[usize],
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
        with_buffer(|work| tape.forward(&fixed, &x, seeding, work).1)
    }

    /// `F`, its Jacobian, `C` and `M` over any [`Real`] (without the constraints' curvature).
    pub fn linear_over<S: Real>(&self, p: &[S], speed: S, q: &[S], lambda: &[S]) -> Linear<S> {
        let x = inputs(p, speed, q, lambda, self.free.len());
        let fixed = self.full.eval_static(&x);
        with_buffer(|work| {
            let (f, d) = self.full.forward_rows(&fixed, &x, &self.linear, work);
            Linear::from_forward(f, &d, self.free.len(), self.m, false)
        })
    }
}

/// The recorded program at parameters `p` and `speed` over any [`Real`]: the
/// [`Equations`] the sensitivities and the Hessians evaluate over dual numbers (in `f64`,
/// [`Instance`] evaluates what depends on the parameters and the speed once).
pub struct Recorded<'a, S: Real> {
    pub program: &'a Program,
    pub p: Vec<S>,
    pub speed: S,
}

impl<S: Real> Recorded<'_, S> {
    fn linear(&self, q: &[S], lambda: &[S]) -> Linear<S> {
        self.program.linear_over(&self.p, self.speed, q, lambda)
    }
}

impl<S: Real> Equations<S> for Recorded<'_, S> {
    fn free(&self) -> &[usize] {
        &self.program.free
    }

    fn constraints(&self) -> usize {
        self.program.m
    }

    fn residual(&self, q: &[S], lambda: &[S]) -> Vec<S> {
        self.program.residual_over(&self.p, self.speed, q, lambda)
    }

    fn residual_and_jacobian(&self, q: &[S], lambda: &[S]) -> (Vec<S>, DMatrix<S>) {
        let lin = self.linear(q, lambda);
        (lin.residual, lin.jacobian)
    }

    fn evaluate(&self, q: &[S], lambda: &[S], drive: bool) -> Evaluation<S> {
        self.linear(q, lambda).evaluation(drive)
    }

    /// The pass at `λ = 0` gives `r_R` and `Φ_R`; a second pass is at the fitted multipliers.
    fn evaluate_fitted(&self, q: &[S], drive: bool, fit: Fit<'_, S>) -> (Vec<S>, Evaluation<S>) {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let lin = self.linear(q, &vec![S::from(0.0); m]);
        let lambda = fit(
            lin.jacobian.view((0, nf), (nf, m)).into_owned(),
            DVector::from_iterator(nf, lin.residual[..nf].iter().map(|&v| -v)),
        );
        let e = self.evaluate(q, &lambda, drive);
        (lambda, e)
    }

    /// The recorded drive rows are those of the model's driven coordinates, in order.
    fn drive_rows(&self, q: &[S], lambda: &[S], _driven: &[usize]) -> Vec<S> {
        self.linear(q, lambda).drive
    }

    /// The `λ` columns of the Jacobian are `[Φ_Rᵀ; 0]`.
    fn constraint_jacobian(&self, q: &[S]) -> DMatrix<S> {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (_, j) = self.residual_and_jacobian(q, &vec![S::from(0.0); m]);
        j.view((0, nf), (nf, m)).transpose()
    }

    fn linearize(
        &self,
        q: &[S],
        lambda: &[S],
        independent: &[usize],
        _stiffness: Option<&DMatrix<S>>,
    ) -> Result<Linearization<S>, LinearizeError> {
        self.linear(q, lambda)
            .reduce(&self.program.free, independent)
    }
}

impl Equations<f64> for Instance<'_> {
    fn free(&self) -> &[usize] {
        &self.program.free
    }

    fn constraints(&self) -> usize {
        self.program.m
    }

    fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        Instance::residual(self, q, lambda)
    }

    fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        Instance::residual_and_jacobian(self, q, lambda)
    }

    fn evaluate(&self, q: &[f64], lambda: &[f64], drive: bool) -> Evaluation {
        self.linear_plain(q, lambda).evaluation(drive)
    }

    /// One pass: the pass at `λ = 0` gives `r_R` and `Φ_R`, and is then shifted to the
    /// multipliers ([`Linear::shift_multipliers`]).
    fn evaluate_fitted(&self, q: &[f64], drive: bool, fit: Fit<'_, f64>) -> (Vec<f64>, Evaluation) {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (lambda, lin) = self.full_pass(q, &vec![0.0; m], |f, d| {
            let mut lin = Linear::from_forward(f, d, nf, m, false);
            let lambda = fit(
                lin.jacobian.view((0, nf), (nf, m)).into_owned(),
                DVector::from_iterator(nf, lin.residual[..nf].iter().map(|v| -v)),
            );
            // The curvature read where the pass left it, not gathered into matrices first.
            lin.shift(&lambda, 3, |k, j| d.row(nf + m + k * nf + j));
            (lambda, lin)
        });
        (lambda, lin.evaluation(drive))
    }

    /// The recorded drive rows are those of the model's driven coordinates, in order.
    fn drive_rows(&self, q: &[f64], lambda: &[f64], _driven: &[usize]) -> Vec<f64> {
        self.linear_plain(q, lambda).drive
    }

    fn residual_at_drive_offsets(
        &self,
        q: &[f64],
        lambda: &[f64],
        d: usize,
        _c: usize,
        offsets: [f64; 3],
    ) -> [f64; 3] {
        Instance::residual_at_drive_offsets(self, q, lambda, d, offsets)
    }

    /// The `λ` columns of the Jacobian are `[Φ_Rᵀ; 0]`.
    fn constraint_jacobian(&self, q: &[f64]) -> DMatrix<f64> {
        let (nf, m) = (self.program.free.len(), self.program.m);
        let (_, j) = Instance::residual_and_jacobian(self, q, &vec![0.0; m]);
        j.view((0, nf), (nf, m)).transpose()
    }

    fn linearize(
        &self,
        q: &[f64],
        lambda: &[f64],
        independent: &[usize],
        _stiffness: Option<&DMatrix<f64>>,
    ) -> Result<Linearization<f64>, LinearizeError> {
        self.linear_plain(q, lambda)
            .reduce(&self.program.free, independent)
    }
}
