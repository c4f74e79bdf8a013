//! Newton's system balanced (forces against lengths) and factorised, once per Jacobian: the
//! factorisation the solve, the steady-state check, the sensitivities and the Hessians share.

use super::Equilibrium;
use crate::linalg::Lu;
use nalgebra::{DMatrix, DVector};

/// Newton's system `J = [K Φ_Rᵀ; Φ_R 0]` balanced: its rows are forces (the free coordinates'
/// residuals) and lengths (the constraints), its unknowns coordinates and multipliers (forces
/// per constraint unit). Scaling every mass, spring and damper of a model by a factor scales
/// `K` and `λ` by it and leaves `Φ_R` alone, so that the blocks drift apart: a spatial four-bar
/// scaled by 1e-9 had its force rows below the constraints' rounding and Newton stalled at a
/// residual of 1.5e-10. With the force scale `α = 2^round(log₂(‖K‖/‖Φ_R‖))` (`‖Φ_R‖ := 1`
/// without constraints) the balanced system
///
/// ```text
/// J' = D_r J D_c = [K/α Φ_Rᵀ; Φ_R 0],   F' = D_r F = [F_r/α; Φ],   x = D_c x',
/// D_r = diag(I/α, I), D_c = diag(I, αI)
/// ```
///
/// has blocks of one size whatever the model's scale, and its tolerances (steps, rounding
/// floors, the line search's norm, the steady-state check) are the same for a model and its
/// scaled copy. A power of two scales exactly: without constraints `J' = J/α` and the steps
/// are `J`'s to the bit.
#[derive(Debug, Clone, Copy)]
pub struct Balance {
    nf: usize,
    /// The force scale α (a power of two).
    pub alpha: f64,
}

impl Balance {
    /// The balance of Newton's Jacobian `jac` with `nf` free coordinates (its first `nf` rows
    /// and columns).
    pub fn of(jac: &DMatrix<f64>, nf: usize) -> Balance {
        let n = jac.nrows();
        let block = |r: std::ops::Range<usize>, c: std::ops::Range<usize>| {
            r.flat_map(|i| c.clone().map(move |j| (i, j)))
                .fold(0.0f64, |s, (i, j)| s.max(jac[(i, j)].abs()))
        };
        let k = block(0..nf, 0..nf);
        let phi = if n > nf { block(nf..n, 0..nf) } else { 1.0 };
        let ratio = k / phi;
        let alpha = if ratio.is_finite() && ratio > 0.0 {
            2f64.powi((ratio.log2().round() as i32).clamp(-1000, 1000))
        } else {
            1.0
        };
        Balance { nf, alpha }
    }

    /// `J' = D_r J D_c`.
    pub fn jacobian(&self, j: &DMatrix<f64>) -> DMatrix<f64> {
        let mut j = j.clone();
        if self.alpha.to_bits() != 1f64.to_bits() {
            let nf = self.nf;
            for c in 0..j.ncols() {
                for r in 0..j.nrows() {
                    if r < nf && c < nf {
                        j[(r, c)] /= self.alpha;
                    } else if r >= nf && c >= nf {
                        j[(r, c)] *= self.alpha;
                    }
                }
            }
        }
        j
    }

    /// `max |J'|` without forming `J'`.
    pub fn amax(&self, j: &DMatrix<f64>) -> f64 {
        let (n, nf, a) = (j.nrows(), self.nf, self.alpha);
        (0..j.ncols())
            .flat_map(|c| (0..n).map(move |r| (r, c)))
            .fold(0.0f64, |s, (r, c)| {
                let v = j[(r, c)].abs();
                s.max(if r < nf && c < nf {
                    v / a
                } else if r >= nf && c >= nf {
                    v * a
                } else {
                    v
                })
            })
    }

    /// `max |F'|` without forming `F'`.
    pub fn norm(&self, f: &[f64]) -> f64 {
        let nf = self.nf;
        f.iter().enumerate().fold(0.0f64, |s, (i, v)| {
            s.max(if i < nf {
                v.abs() / self.alpha
            } else {
                v.abs()
            })
        })
    }

    /// `F' = D_r F`.
    pub fn residual(&self, f: &[f64]) -> Vec<f64> {
        let mut f = f.to_vec();
        f[..self.nf].iter_mut().for_each(|v| *v /= self.alpha);
        f
    }

    /// `x = D_c x'`: the unknowns (or a step) from the balanced ones.
    pub fn unknowns(&self, mut x: Vec<f64>) -> Vec<f64> {
        x[self.nf..].iter_mut().for_each(|v| *v *= self.alpha);
        x
    }
}

/// Newton's Jacobian factorised balanced ([`Balance`]), for Newton's steps and the
/// sensitivities' and Hessians' implicit steps alike.
///
/// Where a coordinate is held by nothing (a rod spinning freely about its own axis, a cone that
/// may precess to any azimuth: a rigid-body mode) the equilibria form a continuum and `J` is
/// singular, exactly or to rounding. Partial pivoting then divides rounding by rounding: its
/// steps threw the free coordinate about by O(1), or it failed outright. Such a `J` is solved
/// in the least-squares sense instead, by its singular value decomposition truncated at
/// [`RANK_TOLERANCE`]: the minimum-norm step, which moves nothing along the continuum (where
/// the modes do not change, by the symmetry that makes it) and is the Newton step elsewhere
/// (Gauss–Newton for an underdetermined system; Nocedal & Wright §10.3).
#[derive(Debug, Clone)]
pub struct Factor {
    balance: Balance,
    solver: Solver,
}

/// How a [`Factor`] solves.
#[derive(Debug, Clone)]
pub(super) enum Solver {
    Lu(Lu),
    /// `J'⁺ = V Σ⁺ Uᵀ` with the singular values below the tolerance dropped: `(V Σ⁺, U)`.
    Pseudo(DMatrix<f64>, DMatrix<f64>),
}

/// Singular values of the balanced Jacobian below this fraction of the largest count as zero:
/// the same 1e-12 below which a mode's stiffness counts as zero ([`crate::modal`]'s
/// `ZERO_ROOT²`).
pub const RANK_TOLERANCE: f64 = 1e-12;

/// LU pivots below this fraction of the largest send a factorisation to the singular value
/// decomposition (which then decides the rank): pivots overestimate the smallest singular value
/// by at most a modest factor on the matrices met here, so this catches every rank deficiency
/// at [`RANK_TOLERANCE`] and costs a well-conditioned `J` nothing.
const PIVOT_TOLERANCE: f64 = 1e-10;

impl Factor {
    /// Factorises Newton's Jacobian `jac` (`nf` free coordinates, the rest multipliers).
    pub fn new(jac: &DMatrix<f64>, nf: usize) -> Factor {
        Factor::with(Balance::of(jac, nf), jac)
    }

    /// Factorises `jac` with the balance `balance` (Newton keeps one through a solve).
    pub(super) fn with(balance: Balance, jac: &DMatrix<f64>) -> Factor {
        let j = balance.jacobian(jac);
        let lu = Lu::new(j.clone());
        let solver = if lu.pivot_ratio() > PIVOT_TOLERANCE {
            Solver::Lu(lu)
        } else {
            Self::pseudo(j, balance.nf).map_or(Solver::Lu(lu), |(vs, u)| Solver::Pseudo(vs, u))
        };
        Factor { balance, solver }
    }

    /// `(V Σ⁺, U)` of `j` (`nf` free coordinates), the singular values below
    /// [`RANK_TOLERANCE`] of the largest dropped; `None` where the decomposition fails, or
    /// where a dropped direction moves the multipliers rather than the coordinates: redundant
    /// cut joints, which the solve reports by name rather than solving around.
    fn pseudo(j: DMatrix<f64>, nf: usize) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let svd = crate::linalg::svd_real(j, true, true)?;
        let (u, vt) = (svd.u?, svd.v_t?);
        let top = svd.singular_values.max();
        if !top.is_finite() {
            return None;
        }
        let mut vs = vt.transpose();
        for (k, &sv) in svd.singular_values.iter().enumerate() {
            if sv > RANK_TOLERANCE * top {
                vs.column_mut(k).scale_mut(1.0 / sv);
            } else {
                let coordinates = vs.column(k).rows(0, nf).norm_squared();
                if coordinates < 0.5 {
                    return None;
                }
                vs.column_mut(k).fill(0.0);
            }
        }
        Some((vs, u))
    }

    /// Is `J` rank-deficient (solved in the least-squares sense)?
    pub fn singular(&self) -> bool {
        matches!(self.solver, Solver::Pseudo(..))
    }

    /// `x` with `J x = b` (the minimum-norm least-squares `x` where `J` is rank-deficient), or
    /// `None` where an exactly singular `J` could not be decomposed.
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let b = self.balance.residual(b);
        let x = match &self.solver {
            Solver::Lu(lu) => lu.solve(&b)?,
            Solver::Pseudo(vs, u) => {
                let y = u.tr_mul(&DVector::from_vec(b));
                (vs * y).as_slice().to_vec()
            }
        };
        Some(self.balance.unknowns(x))
    }
}

impl Equilibrium {
    /// Newton's Jacobian at the solution, factorised ([`Factor`]).
    pub fn factor(&self) -> Factor {
        Factor::new(&self.jacobian, self.jacobian.nrows() - self.lambda.len())
    }
}
