//! The roots of a conservative gyroscopic pencil `λ²M + λG + K` (`M`, `K` symmetric positive
//! definite, `G` skew-symmetric: an undamped rotor on isotropic or anisotropic undamped
//! bearings, a spinning mechanism without dampers) from a Hermitian eigenproblem.
//!
//! With `u = [x; ẋ]` the equations `M ẍ + G ẋ + K x = 0` read `A u̇ = B u`,
//!
//! ```text
//! A = [K 0; 0 M]  (symmetric positive definite),   B = [0 K; −K −G]  (skew-symmetric),
//! ```
//!
//! (Meirovitch, *Computational Methods in Structural Dynamics*, 1980, §4.6; Tisseur &
//! Meerbergen 2001, SIAM Review 43:235, §3.3). With the Cholesky factors `K = L_K L_Kᵀ`,
//! `M = L_M L_Mᵀ` and `v = diag(L_K, L_M)ᵀ u`, the roots are the eigenvalues of the real
//! skew-symmetric
//!
//! ```text
//! S = [0 Pᵀ; −P −W],   P = L_M⁻¹ L_K,   W = L_M⁻¹ G L_M⁻ᵀ,
//! ```
//!
//! (`L_K⁻¹ K = L_Kᵀ`: nothing is divided by `K`), so `iS` is Hermitian: its eigenvalues `θ` are
//! real, the roots `λ = −iθ` lie on the imaginary axis by construction, in pairs `±iω`, and its
//! eigenvectors are orthonormal. A 2n×2n Hermitian solve (tridiagonal reduction and QR) costs
//! about half the general route's real Schur form of the same size with its two sets of vectors,
//! and needs no left vectors: the left vector of the root `iω` is the conjugate of its right
//! vector. The right vector is read from `v`'s lower half, `x ∝ L_M⁻ᵀ v₂` (`v₂ = λ L_Mᵀ x`; a
//! mode's energy is shared between the halves, so neither is small).

use super::bounded::{part, spectral_condition, structured};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side, c64};
use nalgebra::{Complex, DMatrix};

/// The roots `±iω` of a conservative gyroscopic pencil.
#[derive(Debug, Clone)]
pub struct Gyroscopic {
    /// The frequencies `ω > 0` of the roots `iω`, ascending.
    pub frequencies: Vec<f64>,
    /// The right vectors `x` of the roots `iω` (columns, not normalised); `x̄` belongs to `−iω`.
    pub vectors: DMatrix<Complex<f64>>,
    /// The spectral condition numbers of `M` and `K`: every root carries errors of
    /// `ε cond(M)` of the largest before the caller refines it.
    pub mass_condition: f64,
    pub stiffness_condition: f64,
}

/// The roots of `λ²M + λG + K` (see the module documentation). `None` where the route does not
/// apply and the general first-order form must decide: `M` or `K` not symmetric or `G` not
/// skew-symmetric (to 1e-13 of each one's largest entry, as for
/// [`symmetric_definite`](super::symmetric_definite)), `G` zero (the undamped route's), `M` or
/// `K` not positive definite (a rigid-body mode, divergence, flutter), or the Hermitian solve
/// not splitting into `n` roots on each side of zero. The route divides by `M` as the general
/// route's first-order form does: the caller judges its condition.
pub fn gyroscopic(m: &DMatrix<f64>, g: &DMatrix<f64>, k: &DMatrix<f64>) -> Option<Gyroscopic> {
    let n = m.nrows();
    let all = || m.iter().chain(g.iter()).chain(k.iter());
    if n == 0 || g.nrows() != n || k.nrows() != n || all().any(|v| !v.is_finite()) {
        return None;
    }
    if super::amax(g) == 0.0 || !structured(m, 1.0) || !structured(k, 1.0) || !structured(g, -1.0) {
        return None;
    }
    let (fm, fg, fk) = (part(m, 1.0), part(g, -1.0), part(k, 1.0));
    let (mass_condition, stiffness_condition) =
        (spectral_condition(&fm)?, spectral_condition(&fk)?);
    let (lm, lk) = (fm.llt(Side::Lower).ok()?, fk.llt(Side::Lower).ok()?);
    let lm = lm.L();
    // P = L_M⁻¹ L_K.
    let mut p = lk.L().to_owned();
    solve_lower_triangular_in_place(lm, p.as_mut(), Par::Seq);
    // −W = L_M⁻¹ (L_M⁻¹ G)ᵀ (`Gᵀ = −G`), made exactly skew below.
    let mut lg = fg;
    solve_lower_triangular_in_place(lm, lg.as_mut(), Par::Seq);
    let mut w = lg.transpose().to_owned();
    solve_lower_triangular_in_place(lm, w.as_mut(), Par::Seq);
    let i = c64::new(0.0, 1.0);
    // iS, S = [0 Pᵀ; −P −W], with `w` = −W.
    let h = Mat::<c64>::from_fn(2 * n, 2 * n, |r, c| match (r < n, c < n) {
        (true, true) => c64::new(0.0, 0.0),
        (true, false) => i * p[(c - n, r)],
        (false, true) => -i * p[(r - n, c)],
        (false, false) => i * (0.5 * (w[(r - n, c - n)] - w[(c - n, r - n)])),
    });
    let evd = h.self_adjoint_eigen(Side::Lower).ok()?;
    let theta: Vec<f64> = (0..2 * n).map(|j| evd.S().column_vector()[j].re).collect();
    if !(theta[n - 1] < 0.0 && theta[n] > 0.0) {
        return None;
    }
    // The roots iω = −iθ with θ < 0, ascending in ω: columns n−1 down to 0.
    let u = evd.U();
    let order: Vec<usize> = (0..n).rev().collect();
    // x ∝ L_M⁻ᵀ v₂, real and imaginary parts side by side.
    let mut halves = Mat::<f64>::from_fn(n, 2 * n, |r, c| {
        let z = u[(n + r, order[c % n])];
        if c < n { z.re } else { z.im }
    });
    solve_upper_triangular_in_place(lm.transpose(), halves.as_mut(), Par::Seq);
    let vectors = DMatrix::from_fn(n, n, |r, c| {
        Complex::new(halves[(r, c)], halves[(r, n + c)])
    });
    let frequencies: Vec<f64> = order.iter().map(|&j| -theta[j]).collect();
    (frequencies.iter().all(|v| v.is_finite()) && vectors.iter().all(|z| z.is_finite())).then_some(
        Gyroscopic {
            frequencies,
            vectors,
            mass_condition,
            stiffness_condition,
        },
    )
}
