//! Rigid-body modes: a root that is zero to within the system's own scale (see the module
//! documentation of [`crate::modal`]), found by a Rayleigh quotient of `K̂` on the mode's right
//! vector.

use super::{C64, MAX_MASS_CONDITION_BY_STIFFNESS, Mode, ModeClass, Root};
use crate::linalg;
use nalgebra::{DMatrix, DVector};

/// A mode is rigid where its stiffness is below `ZERO_ROOT²` = 1e-12 of the scale of `K̂`'s
/// terms (see the module documentation): `K̂` formed with a cancellation of up to 4·10³ ε
/// (a spinning cone's two neutral directions came out at 7e-18 and 6e-15 of it), while a mode
/// whose stiffness is a millionth of the largest (soft mounts under a stiff shaft) is 10⁶
/// times above. A double zero root split by rounding lies within `ZERO_ROOT` of the mode's
/// frequency scale `√(K_s/m_x)`.
const ZERO_ROOT: f64 = 1e-6;

/// The test for zero roots (see the module documentation), with the scales computed once.
pub(super) struct RigidTest<'a> {
    m: &'a DMatrix<f64>,
    k: &'a DMatrix<f64>,
    /// `K_s`, the scale of `K̂`'s terms.
    pub(super) stiffness: f64,
    /// No root above this can be zero, whatever its mode's mass: the smaller root of
    /// `m_x λ² + c_x λ + k_x` is at most `√(k_x/m_x)`, and `m_x ≥ λ_min(M̂) ≥ ‖M̂‖/cond(M̂)`
    /// with `cond(M̂)` at most what any route accepts, so that only the lowest modes of a big
    /// model pay for the Rayleigh quotients.
    pub(super) candidate: f64,
}

impl<'a> RigidTest<'a> {
    pub(super) fn new(
        m: &'a DMatrix<f64>,
        c: &DMatrix<f64>,
        k: &'a DMatrix<f64>,
        speed: f64,
    ) -> Self {
        let (nm, nc, nk) = (linalg::amax(m), linalg::amax(c), linalg::amax(k));
        let gyroscopic = if nm > 0.0 { nc * nc / nm } else { 0.0 };
        let stiffness = nk.max(nm * speed * speed).max(gyroscopic);
        let candidate = if nm > 0.0 {
            ZERO_ROOT * (stiffness * MAX_MASS_CONDITION_BY_STIFFNESS / nm).sqrt()
        } else {
            0.0
        };
        RigidTest {
            m,
            k,
            stiffness,
            candidate,
        }
    }

    /// The Rayleigh quotient `|xᴴAx| / xᴴx` of a real matrix.
    pub(super) fn rayleigh(a: &DMatrix<f64>, x: &DVector<C64>) -> f64 {
        let (xr, xi) = (x.map(|z| z.re), x.map(|z| z.im));
        let (ar, ai) = (a * &xr, a * &xi);
        // xᴴAx = xrᵀA xr + xiᵀA xi + i(xrᵀA xi − xiᵀA xr).
        C64::new(xr.dot(&ar) + xi.dot(&ai), xr.dot(&ai) - xi.dot(&ar)).norm() / x.norm_squared()
    }

    /// Is `r` a zero root: within [`RigidTest::candidate`], its vector carrying no stiffness
    /// (`|xᴴK̂x|/xᴴx ≤ ZERO_ROOT² K_s`) and as small as a double zero root splits
    /// (`|λ|² m_x ≤ ZERO_ROOT² K_s`)?
    pub(super) fn zero(&self, r: &Root) -> bool {
        let (l, floor) = (r.lambda.norm(), ZERO_ROOT * ZERO_ROOT * self.stiffness);
        l <= self.candidate
            && Self::rayleigh(self.k, &r.right) <= floor
            && l * l * Self::rayleigh(self.m, &r.right) <= floor
    }

    /// An orthonormal basis (columns) of `K̂`'s null space: its right singular vectors whose
    /// singular values are at most `ZERO_ROOT² K_s`; `None` where the decomposition fails.
    pub(super) fn null_space(&self) -> Option<DMatrix<f64>> {
        let svd = linalg::svd_real(self.k.clone(), false, true)?;
        let vt = svd.v_t?;
        let floor = ZERO_ROOT * ZERO_ROOT * self.stiffness;
        let rows: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&i| svd.singular_values[i] <= floor)
            .collect();
        Some(DMatrix::from_fn(vt.ncols(), rows.len(), |i, j| {
            vt[(rows[j], i)]
        }))
    }

    /// The share of `x`'s squared norm in the span of the orthonormal columns of `null`.
    pub(super) fn share(null: &DMatrix<f64>, x: &DVector<C64>) -> f64 {
        let (xr, xi) = (x.map(|z| z.re), x.map(|z| z.im));
        (null.tr_mul(&xr).norm_squared() + null.tr_mul(&xi).norm_squared()) / x.norm_squared()
    }

    /// The mode as a rigid-body mode if its smaller root is zero: the mode's stiffness
    /// `|xᴴK̂x|/xᴴx` at most `ZERO_ROOT²` of `K_s`. That root is set to zero, and so is the
    /// other where it is as small as a double zero root splits (`|λ|² m_x ≤ ZERO_ROOT² K_s`);
    /// a damped rigid-body mode keeps its decay `−c_x/m_x`.
    pub(super) fn rigid(&self, md: &Mode) -> Option<Mode> {
        let (small, other) = if md.root.lambda.norm() <= md.partner.lambda.norm() {
            (&md.root, &md.partner)
        } else {
            (&md.partner, &md.root)
        };
        let l = small.lambda.norm();
        if l.is_nan() || l > self.candidate {
            return None;
        }
        let floor = ZERO_ROOT * ZERO_ROOT * self.stiffness;
        if Self::rayleigh(self.k, &small.right) > floor {
            return None;
        }
        let lo = other.lambda.norm();
        let double = lo * lo * Self::rayleigh(self.m, &other.right) <= floor;
        let zero = |r: &Root| Root {
            lambda: C64::new(0.0, 0.0),
            ..r.clone()
        };
        Some(Mode {
            root: zero(small),
            partner: if double { zero(other) } else { other.clone() },
            damped_frequency: 0.0,
            natural_frequency: 0.0,
            damping_ratio: f64::NAN,
            class: ModeClass::Rigid,
        })
    }
}
