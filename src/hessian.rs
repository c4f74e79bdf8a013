//! Exact second derivatives of the modal outputs with respect to design variables, by hyper-dual
//! numbers carried through the equilibrium, the linearisation, the eigenproblem and the transfer
//! function.
//!
//! For a pair of design variables `(b_i, b_j)` every parameter becomes a hyper-dual number
//! `b + ε₁[i] + ε₂[j]` (`ε₁² = ε₂² = 0`); the `ε₁ε₂` part of any output is then `∂²f/∂b_i∂b_j`,
//! with no step size and no truncation error. Two implicit solves are expanded the same way, by
//! chord iterations from the nominal solution with the nominal (`f64`) Jacobian `J₀`:
//!
//! ```text
//! z ← z − J₀⁻¹ G(z, b)
//! ```
//!
//! Each iteration removes one order of the error (`e_{k+1} = (I − J₀⁻¹J) e_k + O(e_k²)` with
//! `J − J₀ = O(ε)`): the first makes the `ε₁`, `ε₂` parts exact, the second the `ε₁ε₂` part.
//!
//! 1. equilibrium: `G = F(q_R, λ; b)`, the equilibrium equations, `J₀` Newton's Jacobian;
//! 2. each root: `G = [P(λ) x; wᵀx − 1]`, `P(λ) = λ²M̂ + λĈ + K̂` over hyper-duals, with `w`
//!    fixing the scale of `x` (`wᵀx₀ = 1`) and `J₀ = [P(λ₀) P'(λ₀)x₀; wᵀ 0]`, invertible
//!    exactly where the root is simple, i.e. where it is differentiable.
//!
//! The linearisation and `H(jω)` are the generic code evaluated over hyper-duals, so they include
//! the move of the equilibrium and of the independent-coordinate basis. For one degree of
//! freedom the pair invariants come straight from the matrices (`λ₁+λ₂ = −ĉ/m̂`, `λ₁λ₂ = k̂/m̂`),
//! smooth even where the roots coalesce.
//!
//! # Reference
//! Fike & Alonso (2011), *The development of hyper-dual numbers for exact second-derivative
//! calculations*, AIAA 2011-886; Griewank & Walther, *Evaluating Derivatives* (2008), §15
//! (derivatives of iterative solvers).

use crate::equilibrium::equations;
use crate::frf::transfer;
use crate::linearize::linearize;
use crate::mechanics::System;
use crate::mechanics::dynamics::Lifted;
use crate::modal::{C64, Root};
use crate::model::Model;
use crate::real::lift1;
use crate::sensitivity::TransferAt;
use crate::sweep::{Point, PointError};
use crate::tolerance::{Output, Quantity};
use nalgebra::{Complex, DMatrix, DVector};
use num_dual::HyperDual64;

type Hd = HyperDual64;
type Chd = Complex<Hd>;

/// The four parts of a hyper-dual number.
const PARTS: usize = 4;

fn part(x: Hd, k: usize) -> f64 {
    match k {
        0 => x.re,
        1 => x.eps1,
        2 => x.eps2,
        _ => x.eps1eps2,
    }
}

fn with_part(mut x: Hd, k: usize, v: f64) -> Hd {
    match k {
        0 => x.re = v,
        1 => x.eps1 = v,
        2 => x.eps2 = v,
        _ => x.eps1eps2 = v,
    }
    x
}

/// Second derivatives at one point: per output (as [`crate::tolerance::outputs`] lists them)
/// and per mode for the discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4`; `None` where the output is not
/// twice differentiable there (a root not simple, `H` through zero).
#[derive(Debug, Clone)]
pub struct Hessians {
    pub outputs: Vec<Option<DMatrix<f64>>>,
    pub discriminant: Vec<Option<DMatrix<f64>>>,
}

/// Second-order expansion of one root `λ(b)` by two chord iterations on the bordered eigen
/// equations; `None` when the root is not simple.
fn root_expansion(
    root: &Root,
    (m, c, k): (&DMatrix<Hd>, &DMatrix<Hd>, &DMatrix<Hd>),
) -> Option<Chd> {
    let n = m.nrows();
    let l0 = root.lambda;
    let x0 = &root.right;
    let re = |a: &DMatrix<Hd>| a.map(|v| C64::new(v.re, 0.0));
    let (m0, c0, k0) = (re(m), re(c), re(k));
    let p0 = &m0 * (l0 * l0) + &c0 * l0 + &k0;
    let dp0 = (&m0 * (l0 * 2.0) + &c0) * x0;
    // w = x̄₀/|x₀|², so that wᵀx₀ = 1.
    let w = x0.map(|z| z.conj()) / C64::new(x0.norm_squared(), 0.0);
    let mut j0 = DMatrix::zeros(n + 1, n + 1);
    j0.view_mut((0, 0), (n, n)).copy_from(&p0);
    j0.view_mut((0, n), (n, 1)).copy_from(&dp0);
    j0.view_mut((n, 0), (1, n)).copy_from(&w.transpose());
    let scale = j0.iter().fold(0.0f64, |s, z| s.max(z.norm()));
    let lu = j0.lu();
    // A (nearly) singular bordered Jacobian: a multiple root, not differentiable.
    let det = lu.determinant().norm();
    if det.is_nan() || det <= 1e-10 * scale.powi(n as i32 + 1) {
        return None;
    }
    let lift = |z: C64| Chd::new(Hd::from_re(z.re), Hd::from_re(z.im));
    let mut x: Vec<Chd> = x0.iter().map(|&z| lift(z)).collect();
    let mut lambda = lift(l0);
    let cm = |a: &DMatrix<Hd>, i: usize, j: usize| Chd::new(a[(i, j)], Hd::from_re(0.0));
    for _ in 0..2 {
        let mut g = vec![Chd::new(Hd::from_re(0.0), Hd::from_re(0.0)); n + 1];
        for (i, gi) in g.iter_mut().take(n).enumerate() {
            for (j, xj) in x.iter().enumerate() {
                let pij = lambda * lambda * cm(m, i, j) + lambda * cm(c, i, j) + cm(k, i, j);
                *gi += pij * *xj;
            }
        }
        for (wj, xj) in w.iter().zip(&x) {
            g[n] += Chd::new(Hd::from_re(wj.re), Hd::from_re(wj.im)) * *xj;
        }
        g[n] -= Chd::new(Hd::from_re(1.0), Hd::from_re(0.0));
        // Correct the derivative parts only: the nominal root stays as the modal solve gave it.
        for pk in 1..PARTS {
            let rhs = DVector::from_iterator(
                n + 1,
                g.iter().map(|z| C64::new(part(z.re, pk), part(z.im, pk))),
            );
            let d = lu.solve(&rhs)?;
            let upd = |z: &mut Chd, dz: C64| {
                z.re = with_part(z.re, pk, part(z.re, pk) - dz.re);
                z.im = with_part(z.im, pk, part(z.im, pk) - dz.im);
            };
            for (xi, &di) in x.iter_mut().zip(d.iter()) {
                upd(xi, di);
            }
            upd(&mut lambda, d[n]);
        }
    }
    Some(lambda)
}

/// Hessians of `outs` (see [`crate::tolerance::outputs`]) and of each mode's discriminant with
/// respect to the parameters `vars`, at the nominal point `pt` of parameters `p`.
pub fn hessians(
    model: &Model,
    p: &[f64],
    pt: &Point,
    vars: &[usize],
    outs: &[Output],
    tf: Option<TransferAt>,
) -> Result<Hessians, PointError> {
    let nv = vars.len();
    let nm = pt.modes.len();
    let mut out: Vec<Option<DMatrix<f64>>> = vec![Some(DMatrix::zeros(nv, nv)); outs.len()];
    let mut disc: Vec<Option<DMatrix<f64>>> = vec![Some(DMatrix::zeros(nv, nv)); nm];
    let eq = &pt.equilibrium;
    let free = &pt.linear.free;
    let nf = free.len();
    let lu = eq.jacobian.clone().lu();
    let singular = || {
        PointError::Equilibrium(crate::equilibrium::EquilibriumError::SingularJacobian {
            iterations: 0,
        })
    };
    for a in 0..nv {
        for b in a..nv {
            let pd: Vec<Hd> = p
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    let e1 = if i == vars[a] { 1.0 } else { 0.0 };
                    let e2 = if i == vars[b] { 1.0 } else { 0.0 };
                    Hd::new(v, e1, e2, 0.0)
                })
                .collect();
            let sys = System::new(model, &pd, Hd::from_re(pt.speed))?;
            let lifted = Lifted::new(sys.clone());
            let qd = sys.steady_speeds();
            let mut q: Vec<Hd> = eq.q.iter().map(|&v| Hd::from_re(v)).collect();
            let mut lambda: Vec<Hd> = eq.lambda.iter().map(|&v| Hd::from_re(v)).collect();
            // Equilibrium expansion: two chord iterations with Newton's Jacobian.
            for _ in 0..2 {
                let f = equations(&lifted, free, &q, &qd, &lambda);
                for pk in 1..PARTS {
                    let rhs = DVector::from_iterator(f.len(), f.iter().map(|&v| part(v, pk)));
                    let d = lu.solve(&rhs).ok_or_else(singular)?;
                    for (k, &i) in free.iter().enumerate() {
                        q[i] = with_part(q[i], pk, part(q[i], pk) - d[k]);
                    }
                    for (k, l) in lambda.iter_mut().enumerate() {
                        *l = with_part(*l, pk, part(*l, pk) - d[nf + k]);
                    }
                }
            }
            let lin = linearize(
                &Lifted::new(sys.map(lift1)),
                free,
                &q,
                &qd,
                &lambda,
                &pt.linear.independent,
                None,
            )?;
            let mats = (&lin.m, &lin.c, &lin.k);
            // Per mode: ω_d, ζ and D as hyper-duals (None where not twice differentiable).
            let one_dof = lin.m.nrows() == 1;
            let mut mode_values = Vec::with_capacity(nm);
            for md in &pt.modes {
                let r1 = root_expansion(&md.root, mats);
                let r2 = root_expansion(&md.partner, mats);
                let roots = r1.zip(r2);
                let invariants = if one_dof {
                    let (m0, c0, k0) = (lin.m[(0, 0)], lin.c[(0, 0)], lin.k[(0, 0)]);
                    Some((-c0 / m0, k0 / m0))
                } else {
                    roots.map(|(l1, l2)| ((l1 + l2).re, (l1 * l2).re))
                };
                let wd = r1.map(|l1| {
                    if md.root.lambda.im > 0.0 {
                        l1.im
                    } else {
                        Hd::from_re(0.0)
                    }
                });
                let zeta = roots.and(invariants).map(|(s, pr)| {
                    -s / (num_dual::DualNum::sqrt(&num_traits::Signed::abs(&pr)) * 2.0)
                });
                let d = invariants.map(|(s, pr)| pr - s * s * 0.25);
                mode_values.push((wd, zeta, d));
            }
            let h = tf.and_then(|t| {
                transfer(&lin, t.input, t.output, t.omega)
                    .filter(|h| h.magnitude().re > 0.0)
                    .map(|h| h.magnitude())
            });
            let store = |slot: &mut Option<DMatrix<f64>>, v: Option<Hd>| match v {
                Some(v) if v.eps1eps2.is_finite() => {
                    if let Some(mm) = slot.as_mut() {
                        mm[(a, b)] = v.eps1eps2;
                        mm[(b, a)] = v.eps1eps2;
                    }
                }
                _ => *slot = None,
            };
            for (o, slot) in outs.iter().zip(out.iter_mut()) {
                let v = match (o.quantity, o.mode) {
                    (Quantity::DampedFrequency, Some(k)) => mode_values.get(k).and_then(|x| x.0),
                    (Quantity::DampingRatio, Some(k)) => mode_values.get(k).and_then(|x| x.1),
                    (Quantity::TransferMagnitude, _) => h,
                    _ => None,
                };
                store(slot, v);
            }
            for (k, slot) in disc.iter_mut().enumerate() {
                store(slot, mode_values[k].2);
            }
        }
    }
    Ok(Hessians {
        outputs: out,
        discriminant: disc,
    })
}
