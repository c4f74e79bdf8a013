//! The roots of a model with constraint equations as the roots of the augmented pencil over the
//! free coordinates and the multipliers, where reverse mode gives their mixed terms.
//!
//! The linearisation's roots are those of the reduced pencil `P̂(λ) = Rᵀ P(λ) R`, `P = λ²M +
//! λC + K` over the free coordinates and `R` a basis of the null space of `Φ_R`. Its second
//! derivatives read the basis's second derivatives, which no recorded equation holds. The same
//! finite roots are those of the augmented pencil
//!
//! ```text
//! P̃(λ) = [P(λ)  Φ_Rᵀ]      x̃ = [R x]      ỹ = [R y]      Φ_Rᵀν = −P R x,  Φ_Rᵀη = −Pᵀ R y
//!        [Φ_R    0  ]           [ ν ]           [ η ]
//! ```
//!
//! (the rows of `P R x` lie in the range of `Φ_Rᵀ` exactly where `Rᵀ P R x = 0`), whose matrices
//! are the recorded equations' own: `F`'s Jacobian over `[q_R; λ]`, and `M`, `C` on the
//! coordinates' block. So `ỹᵀP̃_ab x̃` is what [`crate::program::Program::pencil_hessian`]
//! contracts, and the roots' closed forms (`root.rs`) hold unchanged for the augmented pencil
//! (a simple finite root of a regular matrix polynomial; `ỹᵀP̃'x̃ = yᵀP̂'x`). Expanding
//! `yᵀP̂_ab x` directly instead would add nine products of first derivatives per pair, and
//! `Φ_R R_ab` by twice differentiating `Φ_R R = 0`; the augmented pencil carries all of that.
//!
//! # Reference
//! Tisseur & Meerbergen, *The quadratic eigenvalue problem*, SIAM Review 43 (2001), §3 (the
//! constrained problem and its augmented form); Andrew & Tan, SIAM J. Matrix Anal. Appl. 20
//! (1998), for the bordered equations of a pencil's simple root.

use super::root::{complex, pencil_matrix};
use crate::linearize::Linearization;
use crate::modal::{C64, Root};
use nalgebra::{DMatrix, DVector};

/// The augmented pencil's matrices `[M 0; 0 0]`, `[C 0; 0 0]`, `[K Φ_Rᵀ; Φ_R 0]` from those over
/// the free coordinates and `Φ_R` (constraint equations × free coordinates).
pub fn matrices([m, c, k]: [&DMatrix<f64>; 3], phi: &DMatrix<f64>) -> [DMatrix<f64>; 3] {
    let (nf, nc) = (m.nrows(), phi.nrows());
    let corner = |a: &DMatrix<f64>| {
        let mut out = DMatrix::zeros(nf + nc, nf + nc);
        out.view_mut((0, 0), (nf, nf)).copy_from(a);
        out
    };
    let mut stiffness = corner(k);
    stiffness.view_mut((nf, 0), (nc, nf)).copy_from(phi);
    stiffness
        .view_mut((0, nf), (nf, nc))
        .copy_from(&phi.transpose());
    [corner(m), corner(c), stiffness]
}

/// The augmented pencil's matrices at the linearisation `lin`.
pub fn nominal(lin: &Linearization<f64>) -> [DMatrix<f64>; 3] {
    matrices([&lin.m_full, &lin.c_full, &lin.k_full], &lin.phi)
}

/// Each of `roots` (of `lin`'s reduced pencil) with its right and left vectors extended to the
/// augmented pencil's (see the module documentation); `None` where `Φ_R Φ_Rᵀ` is singular.
pub fn roots(lin: &Linearization<f64>, roots: &[&Root]) -> Option<Vec<Root>> {
    let (basis, phi) = (complex(&lin.basis), complex(&lin.phi));
    let gram = (&phi * phi.transpose()).lu();
    if !gram.is_invertible() {
        return None;
    }
    // `[v; w]` with `w` the multipliers for which `Φ_Rᵀw = −p` (`p` in the range of `Φ_Rᵀ`).
    let extend = |v: DVector<C64>, p: DVector<C64>| -> Option<DVector<C64>> {
        let w = -gram.solve(&(&phi * p))?;
        Some(DVector::from_iterator(
            v.len() + w.len(),
            v.iter().chain(w.iter()).copied(),
        ))
    };
    roots
        .iter()
        .map(|root| {
            let l = root.lambda;
            let pencil = pencil_matrix(l, (&lin.m_full, &lin.c_full, &lin.k_full));
            let (x, y) = (&basis * &root.right, &basis * &root.left);
            let px = &pencil * &x;
            let pty = pencil.transpose() * &y;
            Some(Root {
                lambda: l,
                right: extend(x, px)?,
                left: extend(y, pty)?,
            })
        })
        .collect()
}
