//! One pass of the recorded equations at a state: `F`, Newton's Jacobian, the rates and the
//! drive rows, and their shift to other multipliers (`F` is affine in `λ`).

use crate::equations::{Evaluation, Rates};
use crate::linearize::{Linearization, LinearizeError, reduce};
use crate::real::Real;
use crate::tape::Rows;
use nalgebra::DMatrix;

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
    /// with `λ_k` (see [`Linear::shift_multipliers`]). Empty from [`super::Program::linear_over`]:
    /// the sensitivities and Hessians do not shift multipliers, and the 12-arm governor's
    /// twelve 13×13 matrices over dual numbers were 6 % of its sensitivities.
    pub curvature: Vec<DMatrix<S>>,
    /// The driven coordinates' rows of `r + Φ_qᵀλ`: the drive forces at a steady state.
    pub drive: Vec<S>,
    /// `Φ_D`, constraint equations × driven coordinates (how `drive` changes with `λ`).
    pub(super) phi_d: DMatrix<S>,
}

impl<S: Real> Linear<S> {
    /// From a forward pass with [`Program::linear`]'s lanes over the `full` program's outputs
    /// (`F`, then the entries of `Φ_R`), with the constraints' curvature when `curvature`.
    pub(super) fn from_forward(
        mut f: Vec<S>,
        d: &Rows<'_, S>,
        nf: usize,
        m: usize,
        curvature: bool,
    ) -> Self {
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
    pub(super) fn evaluation(self, drive: bool) -> Evaluation<S> {
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
        reduce(free, independent, &phi_r, [self.mass, self.damping, k])
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
    pub(super) fn shift<'h>(
        &mut self,
        delta: &[f64],
        stride: usize,
        row: impl Fn(usize, usize) -> &'h [f64],
    ) {
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
