//! The matrices' mixed second derivatives where a root reads them, `yᵀP_ab x` for every pair of
//! variables at once: at most `p` Hessian-vector products per root instead of a pass per pair.
//!
//! A root's second derivative reads the matrices' mixed derivatives only through `yᵀP_ab x`
//! (`root.rs`), at the fixed `λ`, `x`, `y`. That is the Hessian of `Ψ(b) = yᵀP(b)x` along the
//! equilibrium `z(b) = [q_R; λ](b)`: with `w = (b, z)`, the equilibrium's first moves `d_a =
//! (e_a, z_a)` (`z_a = −J⁻¹F_a`) and the adjoint `μ̄ = J⁻ᵀΨ_z`,
//!
//! ```text
//! Ψ_ab = d_aᵀ ∇²ℒ d_b,   ℒ(w) = Ψ(w) − μ̄ᵀF(w)
//! ```
//!
//! (differentiating `F(w(b)) = 0` twice and eliminating `z_ab`: the second-order adjoint of an
//! implicit function). [`crate::program::Program::pencil_hessian`] gives `∇²ℒ v` by forward
//! over reverse mode over the recorded equations, [`crate::program::BATCH`] directions `v` a
//! sweep, against one hyper-dual pass of the whole linearisation per pair (`p²/2` passes, each
//! carrying every coordinate's three lanes). The directions are the fewer of two sets:
//!
//! * **along each variable**, `v = d_a`: `p` products, `Ψ_ab` read off product `a`;
//! * **compressed**: splitting `d_a = e_a + Q e_a` (`Q` the moves over the unknowns),
//!   `Ψ = A_pp + A_pq Q + Qᵀ A_qp + Qᵀ A_qq Q` in the blocks of `A = ∇²ℒ`. The parameters'
//!   block `A_pp` (the equilibrium held) is sparse with a pattern read from the recorded
//!   operations, so its columns are compressed by a colouring (`colouring.rs`: a harmonic-mean
//!   spring couples two variables, a density factor is a hub of its own, a mass couples with
//!   nothing); the equilibrium's move takes one unit direction per unknown it moves (`A_qp`,
//!   `A_qq`), none where the parameters leave the equilibrium put. So the products number
//!   `colours + moving unknowns`: 3 instead of 80 on the 40-segment blade with
//!   harmonic-mean springs, 2 with a density factor, 44 instead of 81 with gravity along the
//!   spin axis as well.
//!
//! The pairs then cost `O(p²)` reads, plus `O(p²m)` for the move's blocks (real matrix
//! products, `m` moving unknowns). Measured: see `examples/scale_chain.rs` and the module
//! documentation of [`crate::hessian`].
//!
//! Without constraint equations `P` is the program's own pencil (the linearisation's basis is
//! the identity). With them, the reduced pencil's mixed derivatives would also read the basis's
//! second derivatives; the roots are then taken as the augmented pencil's over the free
//! coordinates and the multipliers (`augmented.rs`), which is the program's own again, and the
//! multipliers are unknowns of the equilibrium like the coordinates.
//!
//! # Reference
//! Griewank & Walther, *Evaluating Derivatives* (2008), §5.4 and §15.3 (second-order adjoints,
//! of implicit functions too); Christianson, *Automatic Hessians by reverse accumulation*, IMA
//! J. Numer. Anal. 12 (1992); Walther, *Computing sparse Hessians with automatic
//! differentiation*, ACM TOMS 34 (2008), and Gebremedhin, Manne & Pothen, SIAM Review 47
//! (2005), for the compressed products.

use super::Expansion;
use super::colouring::Colouring;
use crate::modal::{C64, Root};
use crate::program::{BATCH, Contraction};
use crate::sweep::PointError;
use nalgebra::{DMatrix, DVector};

/// For each of `roots` (the augmented pencil's where the model has constraint equations),
/// `yᵀP_ab x` for every pair of `vars` (variables × variables), or `None` where the route does
/// not apply (no recorded program, a singular Jacobian).
pub(super) fn pencil_pairs(
    x: &Expansion<'_>,
    p: &[f64],
    vars: &[usize],
    roots: &[&Root],
    colouring: Colouring,
) -> Result<Option<Vec<DMatrix<C64>>>, PointError> {
    let eq = &x.pt.equilibrium;
    let free = &x.pt.linear.free;
    let Some(program) = x.model.program() else {
        return Ok(None);
    };
    // The unknowns of `F`: the free coordinates, then the multipliers.
    let nf = free.len();
    let nz = nf + eq.lambda.len();
    let input = |j: usize| {
        if j < nf {
            program.coordinate_input(free[j])
        } else {
            program.multiplier_input(j - nf)
        }
    };
    let nv = vars.len();
    let w = program.input_vector(p, x.pt.speed, &eq.q, &eq.lambda);
    // The equilibrium's first moves, `z_a = −J⁻¹ F_a`, and the directions `d_a` over the inputs.
    let fp = program.parameter_derivatives(p, x.pt.speed, (&eq.q, &eq.lambda), vars, x.workspace);
    let mut moves = Vec::with_capacity(nv);
    for a in 0..nv {
        let column: Vec<f64> = (0..nz).map(|r| -fp[r * nv + a]).collect();
        let Some(z) = x.lu.solve(&column) else {
            return Ok(None);
        };
        moves.push(z);
    }
    // The unknowns the equilibrium moves along (none where the parameters leave it put).
    let moving: Vec<usize> = (0..nz)
        .filter(|&j| moves.iter().any(|z| z[j] != 0.0))
        .collect();
    let compressed = colouring.directions + moving.len();
    let route = if compressed.div_ceil(BATCH) < nv.div_ceil(BATCH) {
        Route::Compressed { colouring, moving }
    } else {
        Route::Along
    };
    let unit = |k: usize| {
        let mut d = vec![0.0; w.len()];
        d[k] = 1.0;
        d
    };
    let directions: Vec<Vec<f64>> = match &route {
        Route::Along => (vars.iter().zip(&moves))
            .map(|(&k, z)| {
                let mut d = unit(k);
                for (j, &v) in z.iter().enumerate() {
                    d[input(j)] = v;
                }
                d
            })
            .collect(),
        Route::Compressed { colouring, moving } => (0..colouring.directions)
            .map(|c| {
                let mut d = vec![0.0; w.len()];
                for a in colouring.members(c) {
                    d[vars[a]] = 1.0;
                }
                d
            })
            .chain(moving.iter().map(|&j| unit(input(j))))
            .collect(),
    };
    let Some(transposed) = Some(eq.jacobian.transpose().lu()).filter(|lu| lu.is_invertible())
    else {
        return Ok(None);
    };
    let solve = |b: &[C64]| -> Option<Vec<C64>> {
        let part = |f: fn(&C64) -> f64| DVector::from_iterator(nz, b.iter().map(f));
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
        let psi_z: Vec<C64> = (0..nz).map(|j| gradient[input(j)]).collect();
        let Some(mu) = solve(&psi_z) else {
            return Ok(None);
        };
        let products = program.pencil_hessian(&w, &c, &mu, &directions);
        out.push(match &route {
            Route::Along => DMatrix::from_fn(nv, nv, |a, b| {
                let g = &products[a];
                let along_z: C64 = (moves[b].iter().enumerate())
                    .map(|(j, &z)| g[input(j)] * z)
                    .sum();
                g[vars[b]] + along_z
            }),
            Route::Compressed { colouring, moving } => {
                let own = DMatrix::from_fn(nv, nv, |a, b| {
                    colouring
                        .source(a, b)
                        .map_or(C64::new(0.0, 0.0), |(d, row)| products[d][vars[row]])
                });
                if moving.is_empty() {
                    own
                } else {
                    let coordinates: Vec<usize> = moving.iter().map(|&j| input(j)).collect();
                    let along = &products[colouring.directions..];
                    own + through_equilibrium(along, (vars, &coordinates), &moves, moving)
                }
            }
        });
    }
    Ok(Some(out))
}

/// Which directions the Hessian-vector products take.
enum Route {
    /// The equilibrium's first move along each variable, `d_a = (e_a, q_a)`: `p` products.
    Along,
    /// The parameters' block by colours (`colouring.rs`), and a unit direction along each
    /// unknown the equilibrium moves along (`moving`, indices into `[q_R; λ]`):
    /// `Ψ_ab = A_pp + A_pq Q + Qᵀ A_qp + Qᵀ A_qq Q` with `Q` the moves.
    Compressed {
        colouring: Colouring,
        moving: Vec<usize>,
    },
}

/// `A_pq Q + Qᵀ A_qp + Qᵀ A_qq Q` (variables × variables) from the products `along` the moving
/// unknowns (their entries at the variables' inputs `vars` and the unknowns' inputs
/// `coordinates`), `moves[a]` the equilibrium's move along variable `a` over the unknowns
/// `[q_R; λ]`, `moving` the unknowns it moves: `X + Xᵀ` with `X = Qᵀ(A_qp + ½ A_qq Q)`,
/// in real arithmetic part by part (the moves are real).
fn through_equilibrium(
    along: &[Vec<C64>],
    (vars, coordinates): (&[usize], &[usize]),
    moves: &[Vec<f64>],
    moving: &[usize],
) -> DMatrix<C64> {
    let (m, nv) = (moving.len(), vars.len());
    let q = DMatrix::from_fn(m, nv, |j, a| moves[a][moving[j]]);
    let part = |f: fn(&C64) -> f64| {
        let gp = DMatrix::from_fn(m, nv, |j, a| f(&along[j][vars[a]]));
        // `A_qq` symmetrised (it is symmetric but for rounding).
        let gq = DMatrix::from_fn(m, m, |j, k| {
            0.5 * (f(&along[j][coordinates[k]]) + f(&along[k][coordinates[j]]))
        });
        let x = q.tr_mul(&(gp + gq * &q * 0.5));
        &x + x.transpose()
    };
    let (re, im) = (part(|z| z.re), part(|z| z.im));
    re.zip_map(&im, C64::new)
}
