//! Exact first and second derivatives of the modal outputs with respect to design variables, by
//! truncated Taylor numbers carried through the equilibrium, the linearisation, the eigenproblem
//! and the transfer function.
//!
//! For a pair of design variables `(b_i, b_j)` every parameter becomes a hyper-dual number
//! `b + ε₁[i] + ε₂[j]` (`ε₁² = ε₂² = 0`); the `ε₁ε₂` part of any output is then `∂²f/∂b_i∂b_j`.
//! For a single variable a `Dual2` number `b + ε[i]` gives `∂f/∂b_i` and `∂²f/∂b_i²` at once, so
//! the gradient comes with the diagonal (checked against the first-order formulas of
//! [`crate::sensitivity`] in the tests). No step size, no truncation error. Two implicit
//! solves are expanded the same way, by two chord steps on the parts from the nominal solution
//! with the nominal (`f64`) Jacobian `J₀` ([`crate::implicit::correct`]: the first step makes
//! the first-order parts exact, the second the second-order part); Newton's Jacobian is
//! factorised once for all the passes, the bordered one once per pass and root:
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

use crate::compiled::Compiled;
use crate::equilibrium::Factor;
use crate::frf::transfer;
use crate::implicit;
use crate::jet::Jet;
use crate::mechanics::ports::ports_at;
use crate::modal::{C64, Root, Smoothness, smoothness};
use crate::output::{Missing, Output, Quantity};
use crate::pair;
use crate::program::{Tier, Workspace};
use crate::sensitivity::TransferAt;
use crate::sweep::{Point, PointError};
use nalgebra::{Complex, DMatrix, DVector};
use num_dual::{Dual2_64, HyperDual64};

/// Scalar of the mixed (pair) passes.
type Hd = HyperDual64;

/// First and second derivatives at one point: per output (as [`crate::output::outputs`]
/// lists them) and per mode for the discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4`; where an output is
/// not differentiable there (roots coalescing or repeated, a rigid-body mode, `H` through zero),
/// the reason instead.
#[derive(Debug, Clone)]
pub struct Hessians {
    pub gradients: Vec<Result<Vec<f64>, Missing>>,
    pub outputs: Vec<Result<DMatrix<f64>, Missing>>,
    pub discriminant_gradients: Vec<Result<Vec<f64>, Missing>>,
    pub discriminant: Vec<Result<DMatrix<f64>, Missing>>,
}

/// Second-order expansion of one simple root `λ(b)` by two chord iterations on the bordered
/// eigen equations (whether the root is simple is decided beforehand, by
/// [`crate::modal::smoothness`], scale-invariantly); `None` only where the bordered Jacobian
/// is exactly singular.
fn root_expansion<J: Jet>(
    root: &Root,
    (m, c, k): (&DMatrix<J>, &DMatrix<J>, &DMatrix<J>),
) -> Option<Complex<J>> {
    let n = m.nrows();
    let l0 = root.lambda;
    let x0 = &root.right;
    let re = |a: &DMatrix<J>| a.map(|v| C64::new(v.re(), 0.0));
    let (m0, c0, k0) = (re(m), re(c), re(k));
    let p0 = &m0 * (l0 * l0) + &c0 * l0 + &k0;
    let dp0 = (&m0 * (l0 * 2.0) + &c0) * x0;
    // w = x̄₀/|x₀|², so that wᵀx₀ = 1.
    let w = x0.map(|z| z.conj()) / C64::new(x0.norm_squared(), 0.0);
    let mut j0 = DMatrix::zeros(n + 1, n + 1);
    j0.view_mut((0, 0), (n, n)).copy_from(&p0);
    j0.view_mut((0, n), (n, 1)).copy_from(&dp0);
    j0.view_mut((n, 0), (1, n)).copy_from(&w.transpose());
    let lu = j0.lu();
    // The unknowns `[x; λ]` as real and imaginary parts, in that order.
    let mut z: Vec<J> = x0
        .iter()
        .chain([&l0])
        .flat_map(|v| [J::from(v.re), J::from(v.im)])
        .collect();
    let cm = |a: &DMatrix<J>, i: usize, j: usize| Complex::new(a[(i, j)], J::from(0.0));
    let complex =
        |z: &[J]| -> Vec<Complex<J>> { z.chunks(2).map(|c| Complex::new(c[0], c[1])).collect() };
    // G = [P(λ) x; wᵀx − 1].
    let bordered = |z: &[J]| -> Vec<J> {
        let u = complex(z);
        let (x, lambda) = (&u[..n], u[n]);
        let lift = |z: C64| Complex::new(J::from(z.re), J::from(z.im));
        let mut g = vec![lift(C64::new(0.0, 0.0)); n + 1];
        for (i, gi) in g.iter_mut().take(n).enumerate() {
            for (j, xj) in x.iter().enumerate() {
                let pij = lambda * lambda * cm(m, i, j) + lambda * cm(c, i, j) + cm(k, i, j);
                *gi += pij * *xj;
            }
        }
        for (wj, xj) in w.iter().zip(x) {
            g[n] += lift(*wj) * *xj;
        }
        g[n] -= lift(C64::new(1.0, 0.0));
        g.iter().flat_map(|v| [v.re, v.im]).collect()
    };
    let solve = |r: &[f64]| {
        let rhs = DVector::from_iterator(n + 1, r.chunks(2).map(|c| C64::new(c[0], c[1])));
        let d = lu.solve(&rhs)?;
        Some(d.iter().flat_map(|v| [v.re, v.im]).collect())
    };
    // Corrects the derivative parts only: the nominal root stays as the modal solve gave it.
    implicit::correct(&mut z, 2, bordered, solve)?;
    Some(Complex::new(z[2 * n], z[2 * n + 1]))
}

/// The outputs `outs` and each mode's discriminant as jets: the pipeline at `pt` evaluated with
/// the parameters `seeded` (the reason where an output is not differentiable there).
type Jets<J> = (Vec<Result<J, Missing>>, Vec<Result<J, Missing>>);

/// What every pass of one point's expansion shares: the point, Newton's Jacobian factorised
/// once, the outputs, and the working memory of the recorded program's passes.
struct Expansion<'a> {
    model: &'a Compiled,
    lu: Factor,
    pt: &'a Point,
    smooth: Vec<Smoothness>,
    outs: &'a [Output],
    tf: Option<TransferAt>,
    workspace: &'a Workspace,
}

fn expand<J: Jet>(x: &Expansion<'_>, seeded: &[J]) -> Result<Jets<J>, PointError> {
    let Expansion {
        model,
        lu,
        pt,
        smooth,
        outs,
        tf,
        workspace,
    } = x;
    let (pt, outs, tf) = (*pt, *outs, *tf);
    let eq = &pt.equilibrium;
    let free = &pt.linear.free;
    let nf = free.len();
    let equations = model.at(seeded, J::from(pt.speed), &eq.q, (Tier::Few, workspace))?;
    // Equilibrium expansion: two chord steps with Newton's Jacobian on `[q_R; λ]`.
    let mut z: Vec<J> = (free.iter().map(|&i| eq.q[i]))
        .chain(eq.lambda.iter().copied())
        .map(J::from)
        .collect();
    let mut q: Vec<J> = eq.q.iter().map(|&v| J::from(v)).collect();
    let mut unpack = |z: &[J]| -> Vec<J> {
        for (k, &i) in free.iter().enumerate() {
            q[i] = z[k];
        }
        q.clone()
    };
    implicit::correct(
        &mut z,
        2,
        |z| equations.residual(&unpack(z), &z[nf..]),
        |r| lu.solve(r),
    )
    .ok_or(PointError::Equilibrium(
        crate::equilibrium::EquilibriumError::SingularJacobian { iterations: 0 },
    ))?;
    let q = unpack(&z);
    let lambda = &z[nf..];
    let lin = equations
        .linearize(&q, lambda, &pt.linear.independent, None)?
        .with_ports(ports_at(
            model.model(),
            seeded,
            J::from(pt.speed),
            &q,
            free,
        )?);
    let mats = (&lin.m, &lin.c, &lin.k);
    let one_dof = lin.m.nrows() == 1;
    // Per mode: ω_d, ζ and D, or why not.
    let mode_values: Vec<[Result<J, Missing>; 3]> = pt
        .modes
        .iter()
        .zip(smooth.iter())
        .enumerate()
        .map(|(i, (md, &why))| {
            let not = Missing::Mode { mode: i, why };
            let roots = match why {
                Smoothness::Rigid => {
                    return [
                        Err(not.clone()),
                        Err(Missing::RigidDamping { mode: i }),
                        Err(not),
                    ];
                }
                Smoothness::Repeated { .. } => {
                    return [Err(not.clone()), Err(not.clone()), Err(not)];
                }
                // Coalescing roots are not differentiable one by one; their sum and product
                // are, and for one degree of freedom come straight from the matrices.
                Smoothness::Coalescing => Err(not),
                Smoothness::Simple => root_expansion(&md.root, mats)
                    .zip(root_expansion(&md.partner, mats))
                    .ok_or(Missing::SingularExpansion { mode: i }),
            };
            let invariants = if one_dof {
                let (m0, c0, k0) = (lin.m[(0, 0)], lin.c[(0, 0)], lin.k[(0, 0)]);
                Ok((-c0 / m0, k0 / m0))
            } else {
                roots.clone().map(|(l1, l2)| ((l1 + l2).re, (l1 * l2).re))
            };
            let wd = roots.map(|(l1, _)| {
                if md.root.lambda.im > 0.0 {
                    l1.im
                } else {
                    J::from(0.0)
                }
            });
            let zeta = invariants.clone().map(|(s, pr)| pair::damping_ratio(s, pr));
            let d = invariants.map(|(s, pr)| pair::discriminant(s, pr));
            [wd, zeta, d]
        })
        .collect();
    // |H| is not differentiable where H passes through zero, unless H vanishes identically
    // to this order (a transfer that symmetry makes zero): then |H| ≡ 0.
    let h = tf.map(|t| {
        let h = transfer(&lin, t.input, t.output, t.omega).ok_or(Missing::TransferUnbounded)?;
        let zero = [h.re, h.im]
            .iter()
            .all(|v| v.re() == 0.0 && (0..J::PARTS).all(|k| v.part(k) == 0.0));
        if h.magnitude().re() > 0.0 {
            Ok(h.magnitude())
        } else if zero {
            Ok(J::from(0.0))
        } else {
            Err(Missing::TransferZero)
        }
    });
    let outputs = outs
        .iter()
        .map(|o| match (o.quantity, o.mode) {
            (Quantity::DampedFrequency, Some(k)) => mode_values[k][0].clone(),
            (Quantity::DampingRatio, Some(k)) => mode_values[k][1].clone(),
            (Quantity::TransferMagnitude, _) => h.clone().unwrap_or(Err(Missing::NoValue)),
            _ => Err(Missing::NoValue),
        })
        .collect();
    Ok((
        outputs,
        mode_values.into_iter().map(|[_, _, d]| d).collect(),
    ))
}

/// Gradients and Hessians of `outs` (see [`crate::output::outputs`]) and of each mode's
/// discriminant with respect to the parameters `vars`, at the nominal point `pt` of parameters
/// `p`: one `Dual2` pass per variable (its gradient entry and diagonal Hessian entry), one
/// hyper-dual pass per pair of variables (the mixed entry).
pub fn hessians(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    vars: &[usize],
    outs: &[Output],
    tf: Option<TransferAt>,
    workspace: &Workspace,
) -> Result<Hessians, PointError> {
    let nv = vars.len();
    let nm = pt.modes.len();
    // Newton's Jacobian, factorised once for every pass (balanced: a model's scale does not
    // cost the chord steps accuracy); the caller's workspace for every pass.
    let x = Expansion {
        model,
        lu: pt.equilibrium.factor(),
        pt,
        smooth: smoothness(&pt.modes),
        outs,
        tf,
        workspace,
    };
    let mut grad: Vec<Result<Vec<f64>, Missing>> = vec![Ok(vec![0.0; nv]); outs.len()];
    let mut dgrad: Vec<Result<Vec<f64>, Missing>> = vec![Ok(vec![0.0; nv]); nm];
    let mut hess: Vec<Result<DMatrix<f64>, Missing>> = vec![Ok(DMatrix::zeros(nv, nv)); outs.len()];
    let mut dhess: Vec<Result<DMatrix<f64>, Missing>> = vec![Ok(DMatrix::zeros(nv, nv)); nm];
    /// Stores one gradient entry and one Hessian entry (both halves), or the first reason why
    /// not.
    fn put(
        g: Option<&mut Result<Vec<f64>, Missing>>,
        h: &mut Result<DMatrix<f64>, Missing>,
        (a, b): (usize, usize),
        first: Result<f64, Missing>,
        second: Result<f64, Missing>,
    ) {
        let finite = |x: Result<f64, Missing>| {
            x.and_then(|x| {
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(Missing::NotFinite)
                }
            })
        };
        if let Some(g) = g
            && let Ok(v) = g
        {
            match finite(first) {
                Ok(x) => v[a] = x,
                Err(e) => *g = Err(e),
            }
        }
        if let Ok(m) = h {
            match finite(second) {
                Ok(x) => {
                    m[(a, b)] = x;
                    m[(b, a)] = x;
                }
                Err(e) => *h = Err(e),
            }
        }
    }
    for a in 0..nv {
        let seeded: Vec<Dual2_64> = p
            .iter()
            .enumerate()
            .map(|(i, &v)| Dual2_64::new(v, if i == vars[a] { 1.0 } else { 0.0 }, 0.0))
            .collect();
        let (o, d) = expand(&x, &seeded)?;
        for (k, v) in o.iter().enumerate() {
            put(
                Some(&mut grad[k]),
                &mut hess[k],
                (a, a),
                v.clone().map(|x| x.v1),
                v.clone().map(|x| x.v2),
            );
        }
        for (k, v) in d.iter().enumerate() {
            put(
                Some(&mut dgrad[k]),
                &mut dhess[k],
                (a, a),
                v.clone().map(|x| x.v1),
                v.clone().map(|x| x.v2),
            );
        }
        for b in a + 1..nv {
            let seeded: Vec<Hd> = p
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    let e1 = if i == vars[a] { 1.0 } else { 0.0 };
                    let e2 = if i == vars[b] { 1.0 } else { 0.0 };
                    Hd::new(v, e1, e2, 0.0)
                })
                .collect();
            let (o, d) = expand(&x, &seeded)?;
            for (k, v) in o.iter().enumerate() {
                put(
                    None,
                    &mut hess[k],
                    (a, b),
                    Ok(0.0),
                    v.clone().map(|x| x.eps1eps2),
                );
            }
            for (k, v) in d.iter().enumerate() {
                put(
                    None,
                    &mut dhess[k],
                    (a, b),
                    Ok(0.0),
                    v.clone().map(|x| x.eps1eps2),
                );
            }
        }
    }
    Ok(Hessians {
        gradients: grad,
        outputs: hess,
        discriminant_gradients: dgrad,
        discriminant: dhess,
    })
}
