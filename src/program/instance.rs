//! A [`Program`] at one set of parameters and one speed: what depends on them alone evaluated
//! once, then the residual, Newton's Jacobian and the linearisation's passes at any state.

use super::Program;
use super::linear::Linear;
use super::workspace::Work;
use crate::equations::{Probed, probe_directions};
use crate::real::Real;
use crate::tape::Rows;
use nalgebra::DMatrix;
use std::cell::{OnceCell, RefCell};

/// The input vector `[p, speed, q, q̇_R = 0, q̈_R = 0, λ]`.
pub(super) fn inputs<S: Real>(p: &[S], speed: S, q: &[S], lambda: &[S], nf: usize) -> Vec<S> {
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
    pub(super) program: &'a Program,
    /// How its `f64` passes run.
    pub(super) tier: super::Tier,
    /// The static values of `residual`, once it is used.
    pub(super) residual: OnceCell<Vec<f64>>,
    pub(super) full: Vec<f64>,
    /// The input vector, with the parameters and the speed in place.
    pub(super) x: RefCell<Vec<f64>>,
    /// Its scratch space, the caller's ([`super::Workspace`]).
    pub(super) work: &'a RefCell<Work>,
}

/// Newton's Jacobian `∂F/∂[q_R; λ]` from the derivatives `d` (rows of `F`, `lanes` each) whose
/// lane `stride · k` is along the free coordinate `k`: the `λ` columns are `[Φ_Rᵀ; 0]`, `Φ_R`
/// being the `q_R` derivatives of the `Φ` rows.
pub(super) fn jacobian<S: Real>(
    d: &[S],
    lanes: usize,
    stride: usize,
    nf: usize,
    m: usize,
) -> DMatrix<S> {
    let zero = S::from(0.0);
    DMatrix::from_fn(nf + m, nf + m, |r, c| match (r < nf, c < nf) {
        (_, true) => d[r * lanes + stride * c],
        (true, false) => d[c * lanes + stride * r],
        (false, false) => zero,
    })
}

impl Instance<'_> {
    /// Number of constraint equations.
    pub fn constraints(&self) -> usize {
        self.program.m
    }

    pub(super) fn set(&self, q: &[f64], lambda: &[f64]) {
        let pr = self.program;
        let mut x = self.x.borrow_mut();
        let o = pr.np + 1;
        x[o..o + pr.n].copy_from_slice(q);
        let ol = o + pr.n + 2 * pr.free.len();
        x[ol..ol + pr.m].copy_from_slice(lambda);
    }

    /// The values of the residual program's static operations here.
    pub(super) fn residual_static(&self) -> &[f64] {
        self.residual
            .get_or_init(|| self.program.residual_tape().eval_static(&self.x.borrow()))
    }

    /// `F(q_R, λ)`: through `full` or the residual's own program, as the [`super::Tier`] says.
    pub fn residual(&self, q: &[f64], lambda: &[f64]) -> Vec<f64> {
        self.set(q, lambda);
        let mut work = self.work.borrow_mut();
        let (pr, x) = (self.program, self.x.borrow());
        let mut f = match pr.residual_at(self.tier) {
            None => {
                let mut f = pr.full.eval(&self.full, &x, &mut work.values);
                f.truncate(pr.free.len() + pr.m);
                f
            }
            Some(tape) => match pr.native(self.tier).and_then(|n| n.residual.as_ref()) {
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
    pub(super) fn linear_plain(&self, q: &[f64], lambda: &[f64]) -> Linear {
        self.full_pass(q, lambda, |f, d| {
            Linear::from_forward(f, d, self.program.free.len(), self.program.m, false)
        })
    }

    /// [`Equations::probe_linearisation`](crate::equations::Equations::probe_linearisation):
    /// one forward pass of `full` with three lanes, the free coordinates moving along `v` in
    /// the first, their rates along `w` in the second, their accelerations along `u` in the
    /// third ([`probe_directions`]), where the linearisation carries three lanes per free
    /// coordinate. `F` and `Φ_R` are among `full`'s values.
    pub(super) fn probe(&self, q: &[f64], lambda: &[f64]) -> Probed {
        self.set(q, lambda);
        let pr = self.program;
        let (nf, m) = (pr.free.len(), pr.m);
        let seeding = pr.probe.get_or_init(|| {
            let [v, w, u] = probe_directions(nf);
            let (oq, orate) = (pr.np + 1, pr.np + 1 + pr.n);
            let directions: Vec<(usize, usize, f64)> = (pr.free.iter().enumerate())
                .flat_map(|(k, &c)| {
                    [
                        (oq + c, 0, v[k]),
                        (orate + k, 1, w[k]),
                        (orate + nf + k, 2, u[k]),
                    ]
                })
                .collect();
            pr.full.seeding_along(&directions, 3, nf)
        });
        let mut work = self.work.borrow_mut();
        let (f, d) = (pr.full).forward_rows(&self.full, &self.x.borrow(), seeding, &mut work.probe);
        Probed {
            products: [0, 1, 2].map(|l| (0..nf).map(|r| d.row(r)[l]).collect()),
            phi: DMatrix::from_fn(m, nf, |k, j| f[nf + m + k * nf + j]),
            residual: f[..nf + m].iter().map(|v| v + 0.0).collect(),
        }
    }

    /// `full`'s forward pass with [`Program::linear`]'s lanes at `(q, λ)`, read by `read`.
    pub(super) fn full_pass<R>(
        &self,
        q: &[f64],
        lambda: &[f64],
        read: impl FnOnce(Vec<f64>, &Rows<'_, f64>) -> R,
    ) -> R {
        self.set(q, lambda);
        let pr = self.program;
        let mut work = self.work.borrow_mut();
        let x = self.x.borrow();
        let (f, d) = match pr.native(self.tier).and_then(|n| n.full.as_ref()) {
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
