//! The matrices' mixed second derivatives where a root reads them, `yᵀP_ab x` for every pair of
//! variables at once: `p` Hessian-vector products per root instead of a pass per pair.
//!
//! A root's second derivative reads the matrices' mixed derivatives only through `yᵀP_ab x`
//! (`root.rs`), at the fixed `λ`, `x`, `y`. That is the Hessian of `Ψ(b) = yᵀP(b)x` along the
//! equilibrium `q(b)`: with `w = (b, q)`, the equilibrium's first moves `d_a = (e_a, q_a)`
//! (`q_a = −J⁻¹F_a`) and the adjoint `μ̄ = J⁻ᵀΨ_q`,
//!
//! ```text
//! Ψ_ab = d_aᵀ ∇²ℒ d_b,   ℒ(w) = Ψ(w) − μ̄ᵀF(w)
//! ```
//!
//! (differentiating `F(w(b)) = 0` twice and eliminating `q_ab`: the second-order adjoint of an
//! implicit function). [`crate::program::Program::pencil_hessian`] gives `∇²ℒ d_a` by forward
//! over reverse mode over the recorded equations, [`crate::program::BATCH`] directions a
//! sweep. So a root costs `p/BATCH` sweeps of the program, and the pairs cost `O(p²)` dot products, against one
//! hyper-dual pass of the whole linearisation per pair (`p²/2` passes, each carrying every
//! coordinate's three lanes). Measured on the 40-segment blade with gravity along the spin axis
//! and 81 variables, where every pair couples: see `examples/scale_chain.rs` and the module
//! documentation of [`crate::hessian`].
//!
//! Here for models without constraint equations: there `P` is the program's own pencil (the
//! linearisation's basis is the identity). With constraints the reduced pencil's mixed
//! derivatives also read the basis's second derivatives, and the pairs keep their passes.
//!
//! # Reference
//! Griewank & Walther, *Evaluating Derivatives* (2008), §5.4 and §15.3 (second-order adjoints,
//! of implicit functions too); Christianson, *Automatic Hessians by reverse accumulation*, IMA
//! J. Numer. Anal. 12 (1992).

use super::Expansion;
use crate::modal::{C64, Root};
use crate::program::Contraction;
use crate::sweep::PointError;
use nalgebra::{DMatrix, DVector};

/// For each of `roots`, `yᵀP_ab x` for every pair of `vars` (variables × variables), or `None`
/// where the route does not apply (constraint equations, no recorded program, a singular
/// Jacobian).
pub(super) fn pencil_pairs(
    x: &Expansion<'_>,
    p: &[f64],
    vars: &[usize],
    roots: &[&Root],
) -> Result<Option<Vec<DMatrix<C64>>>, PointError> {
    let eq = &x.pt.equilibrium;
    let free = &x.pt.linear.free;
    let Some(program) = x.model.program() else {
        return Ok(None);
    };
    if !eq.lambda.is_empty() {
        return Ok(None);
    }
    let nf = free.len();
    let nv = vars.len();
    let w = program.input_vector(p, x.pt.speed, &eq.q, &eq.lambda);
    // The equilibrium's first moves, `q_a = −J⁻¹ F_a`, and the directions `d_a` over the inputs.
    let fp = program.parameter_derivatives(p, x.pt.speed, (&eq.q, &eq.lambda), vars, x.workspace);
    let mut moves = Vec::with_capacity(nv);
    for a in 0..nv {
        let column: Vec<f64> = (0..nf).map(|r| -fp[r * nv + a]).collect();
        let Some(z) = x.lu.solve(&column) else {
            return Ok(None);
        };
        moves.push(z);
    }
    let directions: Vec<Vec<f64>> = (vars.iter().zip(&moves))
        .map(|(&k, z)| {
            let mut d = vec![0.0; w.len()];
            d[k] = 1.0;
            for (j, &i) in free.iter().enumerate() {
                d[program.coordinate_input(i)] = z[j];
            }
            d
        })
        .collect();
    let Some(transposed) = Some(eq.jacobian.transpose().lu()).filter(|lu| lu.is_invertible())
    else {
        return Ok(None);
    };
    let solve = |b: &[C64]| -> Option<Vec<C64>> {
        let part = |f: fn(&C64) -> f64| DVector::from_iterator(nf, b.iter().map(f));
        let (re, im) = (
            transposed.solve(&part(|z| z.re))?,
            transposed.solve(&part(|z| z.im))?,
        );
        Some(
            re.iter()
                .zip(im.iter())
                .map(|(&r, &i)| C64::new(r, i))
                .collect(),
        )
    };
    let mut out = Vec::with_capacity(roots.len());
    for root in roots {
        let c = Contraction {
            lambda: root.lambda,
            right: root.right.iter().copied().collect(),
            left: root.left.iter().copied().collect(),
        };
        let gradient = program.pencil_gradient(&w, &c);
        let psi_q: Vec<C64> = free
            .iter()
            .map(|&i| gradient[program.coordinate_input(i)])
            .collect();
        let Some(mu) = solve(&psi_q) else {
            return Ok(None);
        };
        let products = program.pencil_hessian(&w, &c, &mu, &directions);
        out.push(DMatrix::from_fn(nv, nv, |a, b| {
            let g = &products[a];
            let along_q: C64 = (free.iter().zip(&moves[b]))
                .map(|(&i, &z)| g[program.coordinate_input(i)] * z)
                .sum();
            g[vars[b]] + along_q
        }));
    }
    Ok(Some(out))
}
