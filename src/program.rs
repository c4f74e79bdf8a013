//! The model's equilibrium equations recorded once as [`Tape`]s, for the operating-point solves.
//!
//! A sweep or a Monte Carlo run solves thousands of equilibria of one model with different
//! speeds and parameter values. [`Program::record`] traces the generic mechanics (the same
//! [`evaluate_rows`] the direct route runs) once per model with the parameters, the speed, the
//! coordinates, the free coordinates' rates and the multipliers as inputs:
//!
//! * `residual`: `F(q_R, λ) = [r_R + Φ_Rᵀ λ; Φ]` at `q̇_R = q̈_R = 0` (folded in);
//! * `full`: the same rows with `q̇_R` and `q̈_R` as inputs, so that one forward pass with the
//!   lanes `[q_R, λ, q̇_R, q̈_R]` gives Newton's Jacobian (whose `q_R` block is `K`), `C` and `M`;
//! * `drive`: the driven coordinates' rows, for the drive forces.
//!
//! Everything that depends on the parameters and the speed only is evaluated once per point
//! ([`Program::at`]). A recording that branched on a value, or that does not reproduce the direct
//! evaluation at a second, perturbed set of inputs, is discarded: the caller then keeps to the
//! direct route, which is always available.

use crate::equilibrium::equations;
use crate::mechanics::System;
use crate::mechanics::dynamics::{Lifted, evaluate_rows};
use crate::model::Model;
use crate::tape::{Forward, Seeding, Tape, Var, record};
use nalgebra::DMatrix;
use std::cell::RefCell;

/// The recorded equations of one model (see the module documentation).
#[derive(Debug, Clone)]
pub struct Program {
    np: usize,
    n: usize,
    free: Vec<usize>,
    m: usize,
    residual: Tape,
    full: Tape,
    drive: Tape,
    /// Lanes `[q_R, λ]` on `residual`.
    jacobian: Seeding,
    /// Lanes `[q_R, λ, q̇_R, q̈_R]` on `full`.
    linear: Seeding,
}

/// What the recorded function returns: the rows `rows` of `r + Φ_qᵀλ`, then `Φ`.
fn trace(model: &Model, x: &[Var], rates: bool, rows: &[usize]) -> Option<Vec<Var>> {
    let (np, n, m) = (
        model.parameters.len(),
        model.coordinates.len(),
        model.n_constraints(),
    );
    let free = model.free();
    let nf = free.len();
    let sys = System::new(model, &x[..np], x[np]).ok()?;
    let q = &x[np + 1..np + 1 + n];
    let mut qd = sys.steady_speeds();
    let mut qdd = vec![Var::Const(0.0); n];
    if rates {
        for (k, &i) in free.iter().enumerate() {
            qd[i] = x[np + 1 + n + k];
            qdd[i] = x[np + 1 + n + nf + k];
        }
    }
    let lambda = &x[np + 1 + n + 2 * nf..np + 1 + n + 2 * nf + m];
    let l = Lifted::new(sys);
    let d = evaluate_rows(&l, q, &qd, &qdd, rows);
    let g = d.with_multipliers(lambda);
    Some(rows.iter().map(|&i| g[i]).chain(d.phi).collect())
}

impl Program {
    /// Records the model's equations at parameters `p`, `speed` and coordinates `q` (any
    /// values at which the model evaluates). `None` when the recording is not valid everywhere
    /// (see the module documentation).
    pub fn record(model: &Model, p: &[f64], speed: f64, q: &[f64]) -> Option<Program> {
        let (np, n, m) = (p.len(), q.len(), model.n_constraints());
        let free = model.free();
        let driven = model.driven();
        let nf = free.len();
        let x = inputs(p, speed, q, &vec![1.0; m], nf);
        let fixed: Vec<usize> = (0..=np).collect();
        let residual = record(&x, |v| trace(model, v, false, &free))?.split(&fixed);
        let full = record(&x, |v| trace(model, v, true, &free))?.split(&fixed);
        let drive = record(&x, |v| trace(model, v, false, &driven))?;
        let drive = drive
            .prune(&(0..driven.len()).collect::<Vec<_>>())
            .split(&fixed);
        let o_lambda = np + 1 + n + 2 * nf;
        let mut seeds: Vec<(usize, usize)> = free
            .iter()
            .enumerate()
            .map(|(k, &i)| (np + 1 + i, k))
            .chain((0..m).map(|k| (o_lambda + k, nf + k)))
            .collect();
        let jacobian = residual.seeding(&seeds, nf + m);
        for k in 0..nf {
            seeds.push((np + 1 + n + k, nf + m + k));
            seeds.push((np + 1 + n + nf + k, 2 * nf + m + k));
        }
        let linear = full.seeding(&seeds, 3 * nf + m);
        let program = Program {
            np,
            n,
            free,
            m,
            residual,
            full,
            drive,
            jacobian,
            linear,
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
            let direct = equations(&Lifted::new(sys), &self.free, q, &qd, l);
            let here = self.at(p, w).residual(q, l);
            let scale = direct.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            here.len() == direct.len()
                && here
                    .iter()
                    .zip(&direct)
                    .all(|(a, b)| (a - b).abs() <= 1e-12 * scale)
        })
    }

    /// The program at parameters `p` and `speed`: the static parts evaluated.
    pub fn at(&self, p: &[f64], speed: f64) -> Instance<'_> {
        let x = inputs(
            p,
            speed,
            &vec![0.0; self.n],
            &vec![0.0; self.m],
            self.free.len(),
        );
        Instance {
            program: self,
            residual: self.residual.eval_static(&x),
            full: self.full.eval_static(&x),
            drive: self.drive.eval_static(&x),
            x: RefCell::new(x),
            work: RefCell::new(POOL.with(|p| p.borrow_mut().pop()).unwrap_or_default()),
        }
    }
}

/// Scratch space of an [`Instance`]: values, and one forward buffer per seeding.
type Work = (Vec<f64>, Forward<f64>, Forward<f64>);

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
fn inputs(p: &[f64], speed: f64, q: &[f64], lambda: &[f64], nf: usize) -> Vec<f64> {
    let mut x = Vec::with_capacity(p.len() + 1 + q.len() + 2 * nf + lambda.len());
    x.extend_from_slice(p);
    x.push(speed);
    x.extend_from_slice(q);
    x.extend(std::iter::repeat_n(0.0, 2 * nf));
    x.extend_from_slice(lambda);
    x
}

/// A [`Program`] at one set of parameters and one speed.
#[derive(Debug)]
pub struct Instance<'a> {
    program: &'a Program,
    residual: Vec<f64>,
    full: Vec<f64>,
    drive: Vec<f64>,
    /// The input vector, with the parameters and the speed in place.
    x: RefCell<Vec<f64>>,
    work: RefCell<Work>,
}

/// Newton's Jacobian with the linearisation's damping and mass matrices, at one state.
#[derive(Debug, Clone)]
pub struct Linear {
    /// `F`.
    pub residual: Vec<f64>,
    /// `∂F/∂[q_R; λ]`.
    pub jacobian: DMatrix<f64>,
    /// `∂r_R/∂q̇_R`.
    pub damping: DMatrix<f64>,
    /// `∂r_R/∂q̈_R`.
    pub mass: DMatrix<f64>,
}

impl Instance<'_> {
    fn set(&self, q: &[f64], lambda: &[f64]) {
        let pr = self.program;
        let mut x = self.x.borrow_mut();
        let o = pr.np + 1;
        x[o..o + pr.n].copy_from_slice(q);
        let ol = o + pr.n + 2 * pr.free.len();
        x[ol..ol + pr.m].copy_from_slice(lambda);
    }

    /// `F(q_R, λ)`.
    pub fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.set(q, lambda);
        let mut work = self.work.borrow_mut();
        self.program
            .residual
            .eval(&self.residual, &self.x.borrow(), &mut work.0)
    }

    /// The driven coordinates' rows of `r + Φ_qᵀλ` (the drive forces).
    pub fn drive_rows(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.set(q, lambda);
        let mut work = self.work.borrow_mut();
        self.program
            .drive
            .eval(&self.drive, &self.x.borrow(), &mut work.0)
    }

    /// `F` and its Jacobian with respect to `[q_R; λ]`.
    pub fn residual_and_jacobian(&self, q: &[f64], lambda: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        self.set(q, lambda);
        let pr = self.program;
        let nx = pr.free.len() + pr.m;
        let mut work = self.work.borrow_mut();
        let (f, d) =
            pr.residual
                .forward(&self.residual, &self.x.borrow(), &pr.jacobian, &mut work.1);
        (f, DMatrix::from_row_slice(nx, nx, &d))
    }

    /// `F`, its Jacobian, `C` and `M` in one forward pass.
    pub fn linear(&self, q: &[f64], lambda: &[f64]) -> Linear {
        self.set(q, lambda);
        let pr = self.program;
        let (nf, m) = (pr.free.len(), pr.m);
        let lanes = 3 * nf + m;
        let mut work = self.work.borrow_mut();
        let (f, d) = pr
            .full
            .forward(&self.full, &self.x.borrow(), &pr.linear, &mut work.2);
        let at = |r: usize, l: usize| d[r * lanes + l];
        Linear {
            residual: f,
            jacobian: DMatrix::from_fn(nf + m, nf + m, at),
            damping: DMatrix::from_fn(nf, nf, |r, c| at(r, nf + m + c)),
            mass: DMatrix::from_fn(nf, nf, |r, c| at(r, 2 * nf + m + c)),
        }
    }
}
