//! The first and second derivatives of `H(jω)` between two free coordinates where reverse mode
//! gives the roots' mixed terms: without the whole linearisation over hyper-dual numbers per
//! pair.
//!
//! With the pencil `P(λ)` the roots are taken in (`augmented.rs`: the reduced basis drops out,
//! `H = eₒᵀR(RᵀDR)⁻¹Rᵀeᵢ = ẽₒᵀD̃⁻¹ẽᵢ` with `D̃ = P̃(jω)` and `ẽ = [e; 0]`), the responses
//! `u = D̃⁻¹ẽᵢ` and `v = D̃⁻ᵀẽₒ` and per variable `s_a = D̃_aᵀv`, `t_a = D̃⁻¹D̃_a u`:
//!
//! ```text
//! H_a  = −vᵀD̃_a u
//! H_ab = s_aᵀt_b + s_bᵀt_a − vᵀD̃_ab u
//! ```
//!
//! (differentiating `D̃u = ẽᵢ` twice; the unit vectors do not depend on the variables). The
//! contraction `vᵀD̃_ab u` is a root's `yᵀP_ab x` at `λ = jω` with `x = u`, `y = v`, so
//! [`super::mixed::pencil_pairs`] takes it beside the roots'. A port's force and response
//! vectors depend on the coordinates and the parameters; their second derivatives are not in
//! the recorded program, so a transfer between ports keeps its passes.
//!
//! # Reference
//! Griewank & Walther, *Evaluating Derivatives* (2008), §15 (derivatives of linear solves);
//! Adelman & Haftka, *Sensitivity analysis of discrete structural systems*, AIAA J. 24 (1986),
//! for the adjoint response.

use super::root::{Along, Triple, pencil_matrix};
use crate::modal::{C64, Root};
use crate::model::Channel;
use nalgebra::{DMatrix, DVector, Dyn, LU};

/// The responses `u`, `v` of the pencil at `jω` to the unit loads of two free coordinates.
pub struct Responses {
    omega: f64,
    lu: LU<C64, Dyn, Dyn>,
    /// `λ = jω`, `u` as the right vector and `v` as the left: what the mixed terms contract.
    pub root: Root,
}

/// `P(jω) = K − ω²M + jωC` of the matrices `(m, c, k)`.
fn dynamic(triple: Triple<'_>, omega: f64) -> DMatrix<C64> {
    pencil_matrix(C64::new(0.0, omega), triple)
}

impl Responses {
    /// The responses in the pencil `nominal` over `free` (then the multipliers, if `nominal`
    /// has more rows), `None` where a channel is a port or the pencil is singular at `jω`.
    pub fn new(
        nominal: Triple<'_>,
        free: &[usize],
        (input, output): (Channel, Channel),
        omega: f64,
    ) -> Option<Responses> {
        let unit = |c: Channel| -> Option<DVector<C64>> {
            let Channel::Coordinate(c) = c else {
                return None;
            };
            let i = free.iter().position(|&f| f == c)?;
            let mut e = DVector::zeros(nominal.0.nrows());
            e[i] = C64::new(1.0, 0.0);
            Some(e)
        };
        let (ei, eo) = (unit(input)?, unit(output)?);
        let d = dynamic(nominal, omega);
        let lu = d.clone().lu();
        let u = lu.solve(&ei)?;
        let v = d.transpose().lu().solve(&eo)?;
        Some(Responses {
            omega,
            lu,
            root: Root {
                lambda: C64::new(0.0, omega),
                right: u,
                left: v,
            },
        })
    }

    /// `H`'s first derivatives along every variable and what its second derivatives share,
    /// from the variables' derivatives of the pencil (`along`) and `vᵀD̃_ab u` for every pair
    /// (`pairs`); `None` where a solve fails.
    pub fn terms(&self, along: &[Along<'_>], pairs: DMatrix<C64>) -> Option<TransferTerms> {
        let (u, v) = (&self.root.right, &self.root.left);
        let n = u.len();
        let nv = along.len();
        let (mut s, mut t) = (DMatrix::zeros(n, nv), DMatrix::zeros(n, nv));
        let mut first = Vec::with_capacity(nv);
        for (a, &(triple, _)) in along.iter().enumerate() {
            let da = dynamic(triple, self.omega);
            let dau = &da * u;
            first.push(-v.dot(&dau));
            s.column_mut(a).copy_from(&(da.transpose() * v));
            t.column_mut(a).copy_from(&self.lu.solve(&dau)?);
        }
        let st = s.transpose() * t;
        Some(TransferTerms {
            first,
            second: &st + st.transpose() - pairs,
        })
    }
}

/// `H`'s first derivatives and its second derivatives for every pair (see the module
/// documentation).
pub struct TransferTerms {
    pub first: Vec<C64>,
    pub second: DMatrix<C64>,
}
