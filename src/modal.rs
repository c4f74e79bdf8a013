//! Damped modal analysis of `M̂ z̈ + Ĉ ż + K̂ z = 0` (Kim & Yoo 2007, eq. 23).
//!
//! Eigenvalues of `(λ² M̂ + λ Ĉ + K̂) x = 0` come from the 2n×2n first-order form
//! `[0 I; −M̂⁻¹K̂ −M̂⁻¹Ĉ]` ([`crate::schur::Eigen`]: the real Schur form); for each, the right vector `x`
//! is read from the form's right eigenvector `[x; λx]`, and the left vector `y`
//! (`yᵀ(λ²M̂ + λĈ + K̂) = 0`) from its left eigenvector `[·; M̂ᵀy]`, both by substitution on the
//! Schur form (O(n²) each, O(n³) in all; faer's blocked `dgeev` from 16 rows on). The 2n roots form n modes: a complex-conjugate pair,
//! or two real roots whose vectors are most alike. Per mode, with roots `λ₁, λ₂`:
//!
//! ```text
//! ω_n = √|λ₁ λ₂|,  ζ = −(λ₁ + λ₂) / (2 ω_n),  ω_d = |Im λ| (0 when the roots are real)
//! ```
//!
//! and a class: `rigid` if a root is zero to within the system's own scale (see below),
//! else `unstable` if a root has positive real part, else `underdamped` or `overdamped`. All
//! frequencies in rad/s.
//!
//! **Rigid-body modes.** A coordinate that no force holds (a rod spinning freely about its own
//! axis on a ball joint, a cone that may precess to any azimuth) gives a zero root, which
//! rounding turns into a tiny number of either sign: a double zero root splits by about
//! `√ε` times the scale of `K̂`'s terms. Read as it stands, that tiny root called such a mode
//! unstable (`+1.6e-7`), underdamped at `2e-6` rad/s, or gave ζ = 5e8. A mode is rigid where
//! its smaller root's right vector `x` carries no stiffness to within the scale at which `K̂`
//! is formed:
//!
//! ```text
//! |xᴴK̂x| / xᴴx ≤ ZERO_ROOT² · K_s,   K_s = max(‖K̂‖, ‖M̂‖ Ω², ‖Ĉ‖² / ‖M̂‖)
//! ```
//!
//! (max-abs norms, Ω the operating speed: `K̂`'s largest entry, the centrifugal terms, the
//! gyroscopic ones; `ZERO_ROOT²` = 1e-12). That root is set to exactly zero, and so is its
//! partner where it is as small as a double zero root splits (`|λ|² m_x ≤ ZERO_ROOT² K_s`,
//! `m_x = |xᴴM̂x|/xᴴx`); a damped rigid-body mode keeps its decay `−c/m`. The test is a
//! Rayleigh quotient, so the eigenvector's own rounding enters squared; it is invariant under
//! scaling all masses, dampers and springs together and under a change of time unit, and
//! holds mode by mode, so that a long chain's low modes (whose frequencies lie decades below its
//! highest) stay what they are, and a pendulum with a hinge damper is unstable from 3·10⁻¹²
//! rad/s past its bifurcation on (its slow root `−k/c` is not mistaken for a zero one). A
//! rigid mode has ω_d = ω_n = 0, an undefined damping ratio (NaN here, an empty cell or `–` in
//! the outputs), and counts neither as unstable nor in any stability statement.
//!
//! An undamped, non-gyroscopic system (`Ĉ = 0` exactly, `M̂` and `K̂` symmetric: a blade
//! flapping, a chain of pendulums in one plane) is solved as the n×n symmetric-definite pencil
//! `K̂ x = ω² M̂ x` instead ([`linalg::symmetric_definite`]): the same modes to rounding, about
//! twenty times fewer operations, and no rounding that could give a stiff chain's highest
//! modes a spurious positive real part (the first-order form `M̂⁻¹K̂` of a 320-segment blade
//! spans ten decades).
//!
//! One degree of freedom (a governor, a pendulum) is solved in closed form, the same roots,
//! vectors `[1]`, classes and pairing as the first-order form gives, without its 2×2 Schur form.
//!
//! Both routes divide by `M̂` (its Cholesky or LU factor), which costs every root `ε cond(M̂)`;
//! a long chain in joint coordinates has `cond(M̂) ∝ n⁴`. Where `M̂` is ill-conditioned and `K̂`
//! better conditioned, both divide by `K̂` instead and solve for `1/λ` (see
//! [`linalg::symmetric_definite`] and `first_order_modes`).

use crate::linalg;
use crate::pair;
use crate::schur::Eigen;
use nalgebra::{Complex, DMatrix, DVector, Dyn, LU};

/// Complex scalar.
pub type C64 = Complex<f64>;

/// Character of a mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModeClass {
    Underdamped,
    Overdamped,
    Unstable,
    /// A zero root (see the module documentation): no frequency, no damping ratio, neither
    /// stable nor unstable.
    Rigid,
}

impl ModeClass {
    pub fn as_str(self) -> &'static str {
        match self {
            ModeClass::Underdamped => "underdamped",
            ModeClass::Overdamped => "overdamped",
            ModeClass::Unstable => "unstable",
            ModeClass::Rigid => "rigid",
        }
    }
}

/// One root of the pencil with its right and left vectors (in the independent coordinates).
#[derive(Debug, Clone)]
pub struct Root {
    pub lambda: C64,
    pub right: DVector<C64>,
    pub left: DVector<C64>,
}

/// A mode: two roots and the derived quantities.
#[derive(Debug, Clone)]
pub struct Mode {
    /// The reported root: `Im λ > 0` when underdamped, else the real root with larger real
    /// part (the slower decay, or the divergence).
    pub root: Root,
    /// The other root (the conjugate, or the second real root).
    pub partner: Root,
    /// ω_d (rad/s), 0 when the roots are real.
    pub damped_frequency: f64,
    /// ω_n = √|λ₁λ₂| (rad/s).
    pub natural_frequency: f64,
    /// ζ = −(λ₁+λ₂)/(2ω_n).
    pub damping_ratio: f64,
    pub class: ModeClass,
}

/// Why the modal solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModalError {
    #[error(
        "the reduced mass matrix M̂ is singular (condition {condition:.3e}): a coordinate moves no mass or inertia, e.g. a massless body or a rod spinning about its own axis"
    )]
    SingularMass { condition: f64 },
    #[error("non-finite entries in M̂, Ĉ or K̂ (an input value overflows)")]
    NotFinite,
    #[error(
        "M̂, Ĉ and K̂ span more than double precision (the scale of their terms, max(‖K̂‖, ‖M̂‖Ω², ‖Ĉ‖²/‖M̂‖), overflows): an input value is out of scale"
    )]
    ScaleOverflow,
    #[error(
        "the eigenvalue solver did not converge ({what}; M̂, Ĉ, K̂ span more than double precision can resolve)"
    )]
    NoConvergence { what: &'static str },
    #[error(
        "mode {mode}: {what} is not a finite number (λ = {re:e} {im:+e}i): the matrices' scales overflow double precision"
    )]
    NotFiniteMode {
        mode: usize,
        what: &'static str,
        re: f64,
        im: f64,
    },
}

/// Relative size below which an imaginary part counts as zero (roots are then real).
const IM_TOL: f64 = 1e-9;
/// Relative size above which a positive real part makes a root unstable.
const RE_TOL: f64 = 1e-10;

/// Solves the damped eigenproblem and groups the roots into modes, sorted by ω_n (rigid-body
/// modes first). `speed` is the operating speed (rad/s): its centrifugal terms `‖M̂‖Ω²` are
/// part of the scale against which a root counts as zero (see the module documentation).
pub fn modes(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
    speed: f64,
) -> Result<Vec<Mode>, ModalError> {
    if m.iter()
        .chain(c.iter())
        .chain(k.iter())
        .any(|v| !v.is_finite())
    {
        return Err(ModalError::NotFinite);
    }
    let undamped = c
        .iter()
        .all(|&v| v == 0.0)
        .then(|| undamped_modes(m, k))
        .flatten();
    let test = RigidTest::new(m, c, k, speed);
    if !(test.stiffness.is_finite() && test.candidate.is_finite()) {
        return Err(ModalError::ScaleOverflow);
    }
    let mut out = match undamped {
        Some(out) => out,
        None if m.nrows() == 1 => scalar_modes(m[(0, 0)], c[(0, 0)], k[(0, 0)])?,
        None => first_order_modes(m, c, k, &test)?,
    };
    for md in &mut out {
        if let Some(rigid) = test.rigid(md) {
            *md = rigid;
        }
    }
    out.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
    for (i, m) in out.iter().enumerate() {
        check_mode(i + 1, m)?;
    }
    Ok(out)
}

/// The modes of an undamped, non-gyroscopic system (`Ĉ = 0`, `M̂` and `K̂` symmetric, `M̂`
/// positive definite): from `K̂ x = μ M̂ x` ([`linalg::symmetric_definite`]), each `μ > 0` a
/// pair `±i√μ` and each `μ < 0` the real pair `±√−μ` (unstable), with real vectors, each its
/// own left vector. `None` where the general route must decide: the matrices are not of that
/// form, `M̂` is as ill-conditioned as [`first_order_modes`] refuses, or a root is as close to
/// zero as the first-order form's rounding (a neutral mode, which that route classes).
fn undamped_modes(m: &DMatrix<f64>, k: &DMatrix<f64>) -> Option<Vec<Mode>> {
    let d = linalg::symmetric_definite(m, k)?;
    let limit = if d.by_stiffness {
        MAX_MASS_CONDITION_BY_STIFFNESS
    } else {
        MAX_MASS_CONDITION
    };
    if d.mass_condition > limit {
        return None;
    }
    let scale = d
        .values
        .iter()
        .fold(0.0f64, |s, mu| s.max(mu.abs().sqrt()))
        .max(f64::MIN_POSITIVE);
    if d.values.iter().any(|mu| mu.abs().sqrt() <= IM_TOL * scale) {
        return None;
    }
    let modes = d
        .values
        .iter()
        .zip(d.vectors.column_iter())
        .map(|(&mu, x)| {
            let x = normalize(x.map(|v| C64::new(v, 0.0)));
            let root = |lambda| Root {
                lambda,
                right: x.clone(),
                left: x.clone(),
            };
            let w = mu.abs().sqrt();
            if mu > 0.0 {
                make_mode(root(C64::new(0.0, w)), root(C64::new(0.0, -w)), scale)
            } else {
                make_mode(root(C64::new(w, 0.0)), root(C64::new(-w, 0.0)), scale)
            }
        })
        .collect();
    Some(modes)
}

/// A mode is rigid where its stiffness is below `ZERO_ROOT²` = 1e-12 of the scale of `K̂`'s
/// terms (see the module documentation): `K̂` formed with a cancellation of up to 4·10³ ε
/// (a spinning cone's two neutral directions came out at 7e-18 and 6e-15 of it), while a mode
/// whose stiffness is a millionth of the largest (soft mounts under a stiff shaft) is 10⁶
/// times above. A double zero root split by rounding lies within `ZERO_ROOT` of the mode's
/// frequency scale `√(K_s/m_x)`.
const ZERO_ROOT: f64 = 1e-6;

/// The test for zero roots (see the module documentation), with the scales computed once.
struct RigidTest<'a> {
    m: &'a DMatrix<f64>,
    k: &'a DMatrix<f64>,
    /// `K_s`, the scale of `K̂`'s terms.
    stiffness: f64,
    /// No root above this can be zero, whatever its mode's mass: the smaller root of
    /// `m_x λ² + c_x λ + k_x` is at most `√(k_x/m_x)`, and `m_x ≥ λ_min(M̂) ≥ ‖M̂‖/cond(M̂)`
    /// with `cond(M̂)` at most what any route accepts, so that only the lowest modes of a big
    /// model pay for the Rayleigh quotients.
    candidate: f64,
}

impl<'a> RigidTest<'a> {
    fn new(m: &'a DMatrix<f64>, c: &DMatrix<f64>, k: &'a DMatrix<f64>, speed: f64) -> Self {
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
    fn rayleigh(a: &DMatrix<f64>, x: &DVector<C64>) -> f64 {
        let (xr, xi) = (x.map(|z| z.re), x.map(|z| z.im));
        let (ar, ai) = (a * &xr, a * &xi);
        // xᴴAx = xrᵀA xr + xiᵀA xi + i(xrᵀA xi − xiᵀA xr).
        C64::new(xr.dot(&ar) + xi.dot(&ai), xr.dot(&ai) - xi.dot(&ar)).norm() / x.norm_squared()
    }

    /// Is `r` a zero root: within [`RigidTest::candidate`], its vector carrying no stiffness
    /// (`|xᴴK̂x|/xᴴx ≤ ZERO_ROOT² K_s`) and as small as a double zero root splits
    /// (`|λ|² m_x ≤ ZERO_ROOT² K_s`)?
    fn zero(&self, r: &Root) -> bool {
        let (l, floor) = (r.lambda.norm(), ZERO_ROOT * ZERO_ROOT * self.stiffness);
        l <= self.candidate
            && Self::rayleigh(self.k, &r.right) <= floor
            && l * l * Self::rayleigh(self.m, &r.right) <= floor
    }

    /// An orthonormal basis (columns) of `K̂`'s null space: its right singular vectors whose
    /// singular values are at most `ZERO_ROOT² K_s`; `None` where the decomposition fails.
    fn null_space(&self) -> Option<DMatrix<f64>> {
        let svd = linalg::svd(self.k.clone(), false, true)?;
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
    fn share(null: &DMatrix<f64>, x: &DVector<C64>) -> f64 {
        let (xr, xi) = (x.map(|z| z.re), x.map(|z| z.im));
        (null.tr_mul(&xr).norm_squared() + null.tr_mul(&xi).norm_squared()) / x.norm_squared()
    }

    /// The mode as a rigid-body mode if its smaller root is zero: the mode's stiffness
    /// `|xᴴK̂x|/xᴴx` at most `ZERO_ROOT²` of `K_s`. That root is set to zero, and so is the
    /// other where it is as small as a double zero root splits (`|λ|² m_x ≤ ZERO_ROOT² K_s`);
    /// a damped rigid-body mode keeps its decay `−c_x/m_x`.
    fn rigid(&self, md: &Mode) -> Option<Mode> {
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

/// Condition number of `M̂` above which the modes are refused where a route divides by `M̂` (a
/// coordinate moves next to no mass: the roots would be rounding): every root then carries
/// errors of `ε cond(M̂)` relative to the largest (1e-4 here).
const MAX_MASS_CONDITION: f64 = 1e12;

/// The same where a route divides by `K̂` instead (`M̂` the worse conditioned; see
/// [`linalg::symmetric_definite`] and [`first_order_modes`]): the low modes keep a few ε
/// whatever `cond(M̂)`, and only the modes that live where `M̂` is nearly singular, the
/// highest, depend on `M̂`'s smallest eigenvalue, itself known to `ε cond(M̂)`. So `M̂` counts
/// as singular where that smallest eigenvalue carries 1 % of rounding (its frequency then
/// 0.5 %): a coordinate moving next to no mass. A chain of a thousand segments in joint
/// coordinates (`cond(M̂)` 3.9e12, growing like n⁴) is within.
const MAX_MASS_CONDITION_BY_STIFFNESS: f64 = 1e-2 / f64::EPSILON;

/// The modes from the 2n×2n first-order form (any `M̂`, `Ĉ`, `K̂`; see the module
/// documentation), unsorted.
///
/// The form divides by `M̂`, so every root carries errors of `ε cond(M̂)` of the largest: a
/// long chain in joint coordinates (`cond(M̂) ∝ n⁴`) with joint damping had its first frequency
/// 4e-5 off at 480 segments, and at 160 its vectors overflowed. Where `M̂` is ill-conditioned
/// and `K̂` better conditioned, the roles swap: the roots `μ = 1/λ` of `μ²K̂ + μĈ + M̂` (the
/// same equation divided by `λ²`, with the same right and left vectors) come from the form
/// `[0 I; −K̂⁻¹M̂ −K̂⁻¹Ĉ]`, exact for the low modes whatever `cond(M̂)`. `M̂` then counts as
/// singular as on the symmetric route (its smallest eigenvalue carrying 1 % of rounding).
fn first_order_modes(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
    rigid: &RigidTest,
) -> Result<Vec<Mode>, ModalError> {
    let form = FirstOrderForm::new(m, c, k)?;
    let (roots, scale) = form.roots()?;
    Ok(pair_roots(roots, scale, rigid))
}

/// The condition number `σ_max/σ_min` of `a` (infinite where `a` is zero, `σ_min` floored at
/// the smallest normal number); `what` names the decomposition where it fails.
fn condition_of(a: &DMatrix<f64>, what: &'static str) -> Result<f64, ModalError> {
    let sv = linalg::svd(a.clone(), false, false)
        .ok_or(ModalError::NoConvergence { what })?
        .singular_values;
    Ok(if sv.max() == 0.0 {
        f64::INFINITY
    } else {
        sv.max() / sv.min().max(f64::MIN_POSITIVE)
    })
}

/// [`first_order_modes`]'s first-order form `[0 I; −M̂⁻¹K̂ −M̂⁻¹Ĉ]` (or, `swapped`, the form
/// `[0 I; −K̂⁻¹M̂ −K̂⁻¹Ĉ]` of `μ = 1/λ`) with its eigendecomposition.
struct FirstOrderForm<'a> {
    /// The number of coordinates (the form has twice as many rows).
    n: usize,
    /// The matrix the form divides by: `M̂`, or `K̂` where `swapped`.
    divisor: &'a DMatrix<f64>,
    /// `cond(M̂)`, for the errors.
    condition: f64,
    /// The form is of `μ²K̂ + μĈ + M̂` (its roots are `1/λ`).
    swapped: bool,
    eigen: Eigen,
}

impl<'a> FirstOrderForm<'a> {
    /// The form of `(λ²M̂ + λĈ + K̂) x = 0`, divided by `K̂` where `M̂` is the worse conditioned
    /// (above [`linalg::WELL_CONDITIONED`] and within [`MAX_MASS_CONDITION_BY_STIFFNESS`]),
    /// else by `M̂`, refused above [`MAX_MASS_CONDITION`]; and its eigendecomposition.
    fn new(
        m: &'a DMatrix<f64>,
        c: &DMatrix<f64>,
        k: &'a DMatrix<f64>,
    ) -> Result<FirstOrderForm<'a>, ModalError> {
        let n = m.nrows();
        let condition = condition_of(m, "SVD of M̂")?;
        // By K̂ where M̂ is the worse conditioned (see [`first_order_modes`]).
        let swapped = condition > linalg::WELL_CONDITIONED
            && condition <= MAX_MASS_CONDITION_BY_STIFFNESS
            && condition_of(k, "SVD of K̂")? < condition;
        if !swapped && condition > MAX_MASS_CONDITION {
            return Err(ModalError::SingularMass { condition });
        }
        let (m, k) = if swapped { (k, m) } else { (m, k) };
        let lu = m.clone().lu();
        let mk = lu.solve(k).ok_or(ModalError::SingularMass { condition })?;
        let mc = lu.solve(c).ok_or(ModalError::SingularMass { condition })?;
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -mk[(i, j)];
                a[(n + i, n + j)] = -mc[(i, j)];
            }
        }
        let eigen = Eigen::new(a).ok_or(ModalError::NoConvergence {
            what: "eigenvalues of the first-order form",
        })?;
        Ok(FirstOrderForm {
            n,
            divisor: m,
            condition,
            swapped,
            eigen,
        })
    }

    /// The roots `λ` with `Im λ ≥ 0` (a pair snapped to the real axis, `|Im| ≤ IM_TOL` of the
    /// form's scale, gives both), with their vectors, and the scale of the roots
    /// (`max|λ|` of the form, `1/min|μ|` where `swapped`).
    fn roots(&self) -> Result<(Vec<Root>, f64), ModalError> {
        let (n, swapped) = (self.n, self.swapped);
        let eig = self.eigen.values();
        let form_scale = eig
            .iter()
            .fold(0.0f64, |s, l| s.max(l.norm()))
            .max(f64::MIN_POSITIVE);
        let scale = if swapped {
            // The roots are 1/μ.
            1.0 / eig
                .iter()
                .fold(f64::INFINITY, |s, l| s.min(l.norm()))
                .max(f64::MIN_POSITIVE)
        } else {
            form_scale
        };
        // The left vectors of the first-order form are `[·; Mᵀ y]`.
        let lu_t = self.divisor.transpose().lu();
        let mut roots: Vec<Root> = Vec::with_capacity(n + 1);
        for (k, &l0) in eig.iter().enumerate() {
            let snapped = l0.im != 0.0 && l0.im.abs() <= IM_TOL * form_scale.max(l0.norm());
            let l = if snapped { C64::new(l0.re, 0.0) } else { l0 };
            // A complex root's conjugate is its partner, with conjugate vectors; a pair rounded
            // to two real roots shares the vectors of its first.
            if l.im < 0.0 {
                continue;
            }
            if snapped && l0.im < 0.0 {
                let twin = roots.last().expect("the pair's first root").clone();
                let lambda = if swapped { 1.0 / l } else { l };
                roots.push(Root { lambda, ..twin });
                continue;
            }
            roots.push(self.root(k, l, &lu_t)?);
        }
        Ok((roots, scale))
    }

    /// The root of the form's eigenvalue `k`, at `l` (snapped), with its right vector from the
    /// form's `[x; λx]` (the half with the smaller rounding) and its left vector `y` from the
    /// form's `[·; Mᵀy]` (`lu_t` factorises `Mᵀ`); where `swapped`, `λ = 1/μ`, kept with
    /// `Im λ ≥ 0`.
    fn root(&self, k: usize, l: C64, lu_t: &LU<f64, Dyn, Dyn>) -> Result<Root, ModalError> {
        let (n, eigen, condition) = (self.n, &self.eigen, self.condition);
        // `[x; λx]`: the half that carries x with the smaller rounding.
        let right = if l.norm() <= 1.0 {
            eigen.right(k, l, 0..n)
        } else {
            eigen.right(k, l, n..2 * n) / l
        };
        let w2 = eigen.left(k, l, n..2 * n);
        let left = lu_t
            .solve(&w2.map(|z| z.re))
            .zip(lu_t.solve(&w2.map(|z| z.im)))
            .map(|(re, im)| re.zip_map(&im, C64::new))
            .ok_or(ModalError::SingularMass { condition })?;
        let root = Root {
            lambda: l,
            right: normalize(right),
            left: normalize(left),
        };
        // A root μ of μ²K̂ + μĈ + M̂ is λ = 1/μ with the same vectors; for Im μ > 0 that has
        // Im λ < 0, so its conjugate (vectors conjugated) is kept.
        Ok(if self.swapped && l.im > 0.0 {
            Root {
                lambda: 1.0 / l.conj(),
                right: root.right.map(|z| z.conj()),
                left: root.left.map(|z| z.conj()),
            }
        } else if self.swapped {
            Root {
                lambda: 1.0 / l,
                ..root
            }
        } else {
            root
        })
    }
}

/// The modes of the roots with `Im λ ≥ 0` ([`FirstOrderForm::roots`]): each complex root with
/// its conjugate, in the roots' order, then the real roots paired ([`pair_real_roots`]).
fn pair_roots(roots: Vec<Root>, scale: f64, rigid: &RigidTest) -> Vec<Mode> {
    let mut out = Vec::new();
    let mut real: Vec<Root> = Vec::new();
    for r in roots {
        if r.lambda.im > 0.0 {
            let conj = Root {
                lambda: r.lambda.conj(),
                right: r.right.map(|z| z.conj()),
                left: r.left.map(|z| z.conj()),
            };
            out.push(make_mode(r, conj, scale));
        } else if r.lambda.im == 0.0 {
            real.push(r);
        }
    }
    pair_real_roots(real, scale, rigid, &mut out);
    out
}

/// Pairs the real roots `real` into modes (pushed onto `out`), the larger real part first in
/// each: zero roots with decays of `K̂`'s null space first, then by the similarity of their
/// right vectors (see the comment within).
fn pair_real_roots(real: Vec<Root>, scale: f64, rigid: &RigidTest, out: &mut Vec<Mode>) {
    // Pair real roots whose right vectors are most alike: greedily, the most alike pair of
    // those left first. Where several directions are held by nothing (a rod spinning about its
    // own axis on a cone that may precess), rounding often gives their zero roots one shared
    // vector (a pair snapped to the real axis), more alike to each other than to the
    // directions' decays `−c/m`, whose vectors lie in `K̂`'s null space too: each zero root
    // is paired with such a decay first (each rigid direction is one mode, its zero and its
    // decay), so that two zeros and two decays do not make a double-zero rigid mode and a
    // spurious overdamped one.
    let rights: Vec<DVector<C64>> = real.iter().map(|r| r.right.clone()).collect();
    let s = similarities(&rights, &rights);
    let zero: Vec<bool> = real.iter().map(|r| rigid.zero(r)).collect();
    let decay: Vec<bool> = match zero
        .iter()
        .any(|&z| z)
        .then(|| rigid.null_space())
        .flatten()
    {
        Some(null) => (real.iter().zip(&zero))
            .map(|(r, &z)| !z && RigidTest::share(&null, &r.right) >= 0.5)
            .collect(),
        None => vec![false; real.len()],
    };
    // 1 for a zero root and a decay of the null space, else 0.
    let rank = |a: usize, b: usize| u8::from((zero[a] && decay[b]) || (zero[b] && decay[a]));
    let mut pairs: Vec<(usize, usize)> = (0..real.len())
        .flat_map(|i| (i + 1..real.len()).map(move |j| (i, j)))
        .collect();
    // Stable: equal similarities in the order of the roots.
    pairs.sort_by(|&(a, b), &(c, d)| {
        rank(c, d)
            .cmp(&rank(a, b))
            .then(s[(c, d)].total_cmp(&s[(a, b)]))
    });
    let mut real: Vec<Option<Root>> = real.into_iter().map(Some).collect();
    for (i, j) in pairs {
        if real[i].is_none() || real[j].is_none() {
            continue;
        }
        let (a, b) = (real[i].take(), real[j].take());
        let (a, b) = (a.expect("unpaired"), b.expect("unpaired"));
        let (hi, lo) = if a.lambda.re >= b.lambda.re {
            (a, b)
        } else {
            (b, a)
        };
        out.push(make_mode(hi, lo, scale));
    }
}

/// [`first_order_modes`] for one degree of freedom, in closed form: the roots of
/// `M̂λ² + Ĉλ + K̂ = 0` with the vectors `[1]` (right and left, as that route normalises them),
/// snapped, paired and classed as there. A one-degree-of-freedom point (a governor, a pendulum,
/// the 12-arm governor) spent about a sixth of its time in that route's SVD, LU and Schur form
/// of a 2×2 matrix. The larger root comes from the quadratic formula with the sign that adds,
/// the smaller from the product of the roots `K̂/M̂`, so that neither cancels.
fn scalar_modes(m: f64, c: f64, k: f64) -> Result<Vec<Mode>, ModalError> {
    // A 1×1 `M̂` has condition 1, or is singular.
    if m == 0.0 {
        return Err(ModalError::SingularMass {
            condition: f64::INFINITY,
        });
    }
    let (half, product) = (-0.5 * (c / m), k / m);
    // λ = half ± √(half² − product).
    let disc = half * half - product;
    let (l1, l2) = if disc < 0.0 {
        let im = (-disc).sqrt();
        (C64::new(half, im), C64::new(half, -im))
    } else {
        let big = half + disc.sqrt().copysign(half);
        let small = if big == 0.0 { 0.0 } else { product / big };
        (C64::new(big, 0.0), C64::new(small, 0.0))
    };
    let scale = l1.norm().max(l2.norm()).max(f64::MIN_POSITIVE);
    let one = DVector::from_element(1, C64::new(1.0, 0.0));
    let root = |lambda| Root {
        lambda,
        right: one.clone(),
        left: one.clone(),
    };
    let mode = if l1.im != 0.0 && l1.im.abs() > IM_TOL * scale.max(l1.norm()) {
        make_mode(root(l1), root(l2), scale)
    } else {
        // Real roots (a complex pair within rounding of the axis snaps to a double root),
        // the one with the larger real part reported.
        let (a, b) = if l1.im != 0.0 {
            (C64::new(l1.re, 0.0), C64::new(l1.re, 0.0))
        } else if l1.re >= l2.re {
            (l1, l2)
        } else {
            (l2, l1)
        };
        make_mode(root(a), root(b), scale)
    };
    Ok(vec![mode])
}

/// A mode is reported only with finite roots, vectors and derived quantities: an overflow
/// anywhere makes the point fail with the reason, never a NaN or ∞ in a result.
fn check_mode(mode: usize, m: &Mode) -> Result<(), ModalError> {
    let l = m.root.lambda;
    let bad = |what| ModalError::NotFiniteMode {
        mode,
        what,
        re: l.re,
        im: l.im,
    };
    let finite = |z: &C64| z.re.is_finite() && z.im.is_finite();
    if !finite(&m.root.lambda) || !finite(&m.partner.lambda) {
        return Err(bad("an eigenvalue"));
    }
    if !m.natural_frequency.is_finite() || !m.damped_frequency.is_finite() {
        return Err(bad("the natural frequency"));
    }
    if m.class != ModeClass::Rigid && !m.damping_ratio.is_finite() {
        return Err(bad("the damping ratio"));
    }
    for v in [
        &m.root.right,
        &m.root.left,
        &m.partner.right,
        &m.partner.left,
    ] {
        if !v.iter().all(finite) {
            return Err(bad("a mode shape"));
        }
    }
    Ok(())
}

/// Whether a mode's roots are differentiable functions of the system's parameters at a point,
/// and if not, why. Derivatives (first-order sensitivities, the Taylor methods' gradients and
/// Hessians) exist for a root exactly where it is simple; one test for all of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Smoothness {
    /// Both roots are simple: every quantity of the mode is differentiable.
    Simple,
    /// The mode's two roots coincide (it is changing between underdamped and overdamped): ω_d
    /// has a kink there; the pair's sum and product stay smooth.
    Coalescing,
    /// A root coincides with a root of another mode (0-based index), as two modes of a
    /// symmetric rotor at rest do: neither is differentiable.
    Repeated { other: usize },
    /// A rigid-body mode (a zero root): no frequency or damping ratio to differentiate.
    Rigid,
}

impl std::fmt::Display for Smoothness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Smoothness::Simple => write!(f, "its roots are simple"),
            Smoothness::Coalescing => write!(
                f,
                "its two roots coincide (it is changing between underdamped and overdamped)"
            ),
            Smoothness::Repeated { other } => {
                write!(
                    f,
                    "a root of it is repeated in mode {} (a double root)",
                    other + 1
                )
            }
            Smoothness::Rigid => write!(f, "it is a rigid-body mode (a zero root)"),
        }
    }
}

/// Relative distance below which two roots count as one: `|λ − μ| ≤ SIMPLE_GAP · max(|λ|, |μ|)`.
/// The roots carry rounding of about `ε cond`; their derivatives grow like the inverse of
/// the gap, so that within a millionth they would carry more rounding than information.
pub const SIMPLE_GAP: f64 = 1e-6;

/// Each mode's [`Smoothness`] among all the roots of `modes`: scale-invariant (relative gaps
/// only), so that scaling every mass, damper and spring of a model leaves it unchanged.
pub fn smoothness(modes: &[Mode]) -> Vec<Smoothness> {
    let close = |a: C64, b: C64| (a - b).norm() <= SIMPLE_GAP * a.norm().max(b.norm());
    let roots = |m: &Mode| [m.root.lambda, m.partner.lambda];
    modes
        .iter()
        .enumerate()
        .map(|(i, md)| {
            if md.class == ModeClass::Rigid {
                return Smoothness::Rigid;
            }
            let repeated = modes.iter().enumerate().find(|(j, other)| {
                *j != i
                    && other.class != ModeClass::Rigid
                    && roots(md)
                        .iter()
                        .any(|&a| roots(other).iter().any(|&b| close(a, b)))
            });
            match repeated {
                Some((other, _)) => Smoothness::Repeated { other },
                None if close(md.root.lambda, md.partner.lambda) => Smoothness::Coalescing,
                None => Smoothness::Simple,
            }
        })
        .collect()
}

/// |aᴴ b| / (|a| |b|): 1 for parallel vectors.
pub fn similarity(a: &DVector<C64>, b: &DVector<C64>) -> f64 {
    let d = a.dotc(b).norm();
    d / (a.norm() * b.norm()).max(f64::MIN_POSITIVE)
}

/// [`similarity`] of every vector of `a` (rows) with every vector of `b` (columns), all of one
/// length, with each norm computed once; from 16 384 multiply-adds on (`PRODUCTS_FROM`), the
/// normalised vectors' products `Aᴴ B` by four real matrix products. Pairing and tracking
/// compare every mode with every mode; one [`similarity`] call each made that O(n³) with the
/// norms recomputed in every call (a 480-segment chain with overdamped modes spent a minute
/// pairing its real roots).
pub fn similarities(a: &[DVector<C64>], b: &[DVector<C64>]) -> DMatrix<f64> {
    let len = a.iter().chain(b).next().map_or(0, |v| v.len());
    let inverse_norms = |v: &[DVector<C64>]| -> Vec<f64> {
        v.iter()
            .map(|x| {
                let n = x.norm();
                if n > 0.0 { 1.0 / n } else { 0.0 }
            })
            .collect()
    };
    let (sa, sb) = (inverse_norms(a), inverse_norms(b));
    if a.len() * b.len() * len < PRODUCTS_FROM {
        return DMatrix::from_fn(a.len(), b.len(), |i, j| {
            a[i].dotc(&b[j]).norm() * sa[i] * sb[j]
        });
    }
    let parts = |v: &[DVector<C64>], scale: &[f64]| {
        (
            DMatrix::from_fn(len, v.len(), |i, j| v[j][i].re * scale[j]),
            DMatrix::from_fn(len, v.len(), |i, j| v[j][i].im * scale[j]),
        )
    };
    let ((ar, ai), (br, bi)) = (parts(a, &sa), parts(b, &sb));
    // Transposed first: `*` runs the blocked product, `tr_mul` a dot product per entry.
    let (ar, ai) = (ar.transpose(), ai.transpose());
    let re = &ar * &br + &ai * &bi;
    let im = &ar * &bi - &ai * &br;
    re.zip_map(&im, f64::hypot)
}

/// Size (vectors × vectors × length) from which [`similarities`] multiplies matrices: below,
/// setting the products up costs more than they save (a one-mode model's tracking took 0.4 µs
/// a speed by products, 0.05 µs by dot products).
const PRODUCTS_FROM: usize = 1 << 14;

fn make_mode(root: Root, partner: Root, scale: f64) -> Mode {
    let (l1, l2) = (root.lambda, partner.lambda);
    let p = (l1 * l2).re;
    let s = (l1 + l2).re;
    let wn = pair::natural_frequency(p);
    let zeta = if wn > 0.0 {
        // `+ 0.0`: an undamped mode's ζ is 0, not −0.
        pair::damping_ratio(s, p) + 0.0
    } else {
        f64::INFINITY.copysign(-s)
    };
    let unstable = l1.re.max(l2.re) > RE_TOL * scale.max(1e-300);
    let class = if unstable {
        ModeClass::Unstable
    } else if l1.im != 0.0 {
        ModeClass::Underdamped
    } else {
        ModeClass::Overdamped
    };
    Mode {
        damped_frequency: l1.im.abs(),
        natural_frequency: wn,
        damping_ratio: zeta,
        class,
        root,
        partner,
    }
}

/// Scales to unit norm with the largest entry real and positive (a fixed phase).
fn normalize(v: DVector<C64>) -> DVector<C64> {
    let (imax, _) = v.iter().enumerate().fold((0, -1.0), |acc, (i, z)| {
        if z.norm() > acc.1 { (i, z.norm()) } else { acc }
    });
    let z = v[imax];
    let phase = if z.norm() > 0.0 {
        z.conj() / z.norm()
    } else {
        C64::new(1.0, 0.0)
    };
    let w = v * phase;
    let n = w.norm();
    if n > 0.0 { w / C64::new(n, 0.0) } else { w }
}

/// `items` in the order `order` (a permutation of their indices).
pub fn permute<T>(items: Vec<T>, order: &[usize]) -> Vec<T> {
    let mut items: Vec<Option<T>> = items.into_iter().map(Some).collect();
    order
        .iter()
        .map(|&i| items[i].take().expect("a permutation"))
        .collect()
}

/// For each reference mode shape, the index of the most similar shape of `cur` (as many; greedy on the
/// largest similarity first): tracks modes across speeds and matches a sample's modes to the
/// nominal ones.
pub fn match_shapes(prev: &[DVector<C64>], cur: &[DVector<C64>]) -> Vec<usize> {
    let n = prev.len();
    let s = similarities(prev, cur);
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(n * cur.len());
    for i in 0..n {
        for j in 0..cur.len() {
            pairs.push((s[(i, j)], i, j));
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out = vec![usize::MAX; n];
    let mut used = vec![false; n];
    for (_, i, j) in pairs {
        if out[i] == usize::MAX && !used[j] {
            out[i] = j;
            used[j] = true;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn all_similarities_at_once_agree_with_each_pair() {
        // Both routes (dot products, and matrix products for many long vectors) against each
        // pair's `|xᴴy|/(|x||y|)`, with a zero vector (similar to nothing), a parallel pair and
        // vectors of very different sizes.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (len, extra) in [(9, 1), (64, 20)] {
            let mut v = |scale: f64| {
                DVector::from_fn(len, |_, _| {
                    C64::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale
                })
            };
            let mut a: Vec<DVector<C64>> = vec![v(1.0), v(1e-150), DVector::zeros(len), v(1e150)];
            let mut b: Vec<DVector<C64>> =
                vec![v(3.0), a[0].map(|z| z * C64::new(0.0, -2.0)), v(1e-9)];
            for _ in 0..extra {
                a.push(v(1.0));
                b.push(v(0.5));
            }
            assert_eq!(
                a.len() * b.len() * len >= PRODUCTS_FROM,
                len == 64,
                "the two cases take the two routes"
            );
            let s = similarities(&a, &b);
            assert_eq!(s.shape(), (a.len(), b.len()));
            for (i, x) in a.iter().enumerate() {
                for (j, y) in b.iter().enumerate() {
                    let (nx, ny) = (x.norm(), y.norm());
                    let pairwise = if nx > 0.0 {
                        (x / C64::from(nx)).dotc(&(y / C64::from(ny))).norm()
                    } else {
                        0.0
                    };
                    assert!((s[(i, j)] - pairwise).abs() < 1e-14, "{len}: {i} {j}");
                }
            }
            assert!((s[(0, 1)] - 1.0).abs() < 1e-15);
            assert!(
                s.row(2).iter().all(|&v| v == 0.0),
                "a zero vector is similar to nothing"
            );
        }
    }

    /// A random symmetric positive definite `M` and a symmetric `K` with some negative
    /// eigenvalues (unstable modes), both of size n.
    fn pencil(n: usize, seed: u64) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut r = |n| DMatrix::<f64>::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
        let a = r(n);
        let m = &a * a.transpose() + DMatrix::identity(n, n) * 0.5;
        let b = r(n);
        let k = (&b + b.transpose()) * 20.0 + DMatrix::identity(n, n) * 30.0;
        (m, k)
    }

    /// Where `K̂` is no better conditioned than `M̂`, both routes divide by `M̂`, and an `M̂` of
    /// condition 1e13 is refused as singular (the 1 % limit is for the routes that divide by
    /// `K̂`); with a well-conditioned `K̂` the same `M̂` is solved, its low mode exactly.
    #[test]
    fn the_relaxed_mass_condition_holds_only_where_k_is_the_divisor() {
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1e-13]));
        let stiff = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1e-14]));
        for c in [DMatrix::zeros(2, 2), DMatrix::identity(2, 2) * 1e-20] {
            assert!(
                matches!(
                    modes(&m, &c, &stiff, 0.0),
                    Err(ModalError::SingularMass { .. })
                ),
                "cond(K̂) 1e14 with Ĉ = {c}"
            );
        }
        let k = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0]));
        let out = modes(&m, &DMatrix::zeros(2, 2), &k, 0.0).expect("solved by K̂");
        assert!((out[0].natural_frequency - 2.0).abs() < 1e-14);
    }

    /// One degree of freedom in closed form against the first-order form's Schur route:
    /// underdamped, overdamped (the small root from the product, where the quadratic formula
    /// would cancel), unstable by a negative `K̂` or `Ĉ`, and scales of `M̂` far from one. Away
    /// from critical damping (a double root, known only to √ε by either route) the roots agree
    /// to rounding, with the same classes and the vectors `[1]`.
    #[test]
    fn one_degree_of_freedom_in_closed_form_agrees_with_the_first_order_form() {
        let one = |v: f64| DMatrix::from_element(1, 1, v);
        let mut compared = 0;
        for m in [1.0f64, 2.5e-3, 7e4, -3.0] {
            for c in [-3.0f64, -1e-7, 1e-7, 0.1, 2.0, 40.0, 1e4] {
                for k in [-5.0f64, 1e-6, 1.0, 100.0, 1e6] {
                    let (half, product) = (-0.5 * c / m, k / m);
                    if (half * half - product).abs() < 1e-6 * (half * half).max(product.abs()) {
                        continue;
                    }
                    let fast = scalar_modes(m, c, k).expect("solved");
                    let (mm, cc, kk) = (one(m), one(c), one(k));
                    let test = RigidTest::new(&mm, &cc, &kk, 0.0);
                    let general = first_order_modes(&mm, &cc, &kk, &test).expect("solved");
                    assert_eq!((fast.len(), general.len()), (1, 1));
                    let (a, b) = (&fast[0], &general[0]);
                    let scale = a.root.lambda.norm().max(a.partner.lambda.norm());
                    for (x, y) in [(&a.root, &b.root), (&a.partner, &b.partner)] {
                        assert!(
                            (x.lambda - y.lambda).norm() <= 1e-12 * scale,
                            "m {m} c {c} k {k}: {} against {}",
                            x.lambda,
                            y.lambda
                        );
                        for v in [&x.right, &x.left, &y.right, &y.left] {
                            assert!((v[0] - C64::new(1.0, 0.0)).norm() < 1e-15);
                        }
                        let residual = x.lambda * x.lambda * m + x.lambda * c + k;
                        assert!(residual.norm() <= 1e-12 * (m.abs() * scale * scale + k.abs()));
                    }
                    assert_eq!(a.class, b.class, "m {m} c {c} k {k}");
                    // The Schur route's roots carry ε‖A‖ absolutely, so its small root of an
                    // overdamped pair (and ω_n, ζ through it) ε·scale/|λ_small| relatively.
                    let small = a.root.lambda.norm().min(a.partner.lambda.norm());
                    let tol = 1e-13 * scale / small.max(f64::MIN_POSITIVE);
                    let rel = |u: f64, v: f64| (u - v).abs() <= tol * u.abs().max(1e-300);
                    assert!(
                        rel(a.natural_frequency, b.natural_frequency),
                        "m {m} c {c} k {k}"
                    );
                    let zeta = a.damping_ratio.abs().max(1.0);
                    assert!((a.damping_ratio - b.damping_ratio).abs() <= tol * zeta);
                    assert!((a.damped_frequency - b.damped_frequency).abs() <= 1e-12 * scale);
                    // The closed form's own roots to rounding: their product and sum.
                    let (l1, l2) = (a.root.lambda, a.partner.lambda);
                    assert!(((l1 * l2).re - k / m).abs() <= 1e-15 * (k / m).abs());
                    assert!(((l1 + l2).re + c / m).abs() <= 1e-15 * scale);
                    compared += 1;
                }
            }
        }
        assert!(compared > 100, "{compared}");
        // Critical damping: a double root, reported as one overdamped mode of equal roots.
        let out = modes(&one(2.0), &one(4.0), &one(2.0), 0.0).expect("solved");
        assert_eq!(out[0].class, ModeClass::Overdamped);
        assert_eq!(out[0].root.lambda, C64::new(-1.0, 0.0));
        assert_eq!(out[0].partner.lambda, C64::new(-1.0, 0.0));
        // A singular mass is refused as by the first-order form; a zero stiffness is a
        // rigid-body mode (its damped root −ĉ/m̂ kept as the partner).
        assert!(matches!(
            modes(&one(0.0), &one(1.0), &one(1.0), 0.0),
            Err(ModalError::SingularMass { .. })
        ));
        let rigid = modes(&one(1.0), &one(1.0), &one(0.0), 0.0).expect("solved");
        assert_eq!(rigid[0].class, ModeClass::Rigid);
        assert_eq!(rigid[0].root.lambda, C64::new(0.0, 0.0));
        assert_eq!(rigid[0].partner.lambda, C64::new(-1.0, 0.0));
        assert_eq!(rigid[0].natural_frequency.to_bits(), 0f64.to_bits());
        assert!(rigid[0].damping_ratio.is_nan());
    }

    /// The undamped route against the first-order form: the same modes (frequencies, class,
    /// shapes), and each mode satisfying `(λ²M + K) x = 0` with `x` its own left vector.
    #[test]
    fn undamped_modes_agree_with_the_first_order_form() {
        for (n, seed) in [(5, 1), (12, 2), (30, 3)] {
            let (m, k) = pencil(n, seed);
            let c = DMatrix::zeros(n, n);
            let mut fast = undamped_modes(&m, &k).expect("symmetric definite");
            let mut general =
                first_order_modes(&m, &c, &k, &RigidTest::new(&m, &c, &k, 0.0)).unwrap();
            for v in [&mut fast, &mut general] {
                v.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
            }
            assert_eq!(fast.len(), n);
            assert!(fast.iter().any(|x| x.class == ModeClass::Unstable));
            assert!(fast.iter().any(|x| x.class == ModeClass::Underdamped));
            let scale = k.amax() + m.amax();
            for (a, b) in fast.iter().zip(&general) {
                let w = a.natural_frequency;
                assert!(
                    (w - b.natural_frequency).abs() <= 1e-10 * (1.0 + w),
                    "{w} vs {b:?}"
                );
                assert_eq!(a.class, b.class, "n = {n}, ω = {w}");
                assert!((a.damped_frequency - b.damped_frequency).abs() <= 1e-10 * (1.0 + w));
                assert!(a.damping_ratio.abs() <= 0.0, "ζ = {}", a.damping_ratio);
                assert!(similarity(&a.root.right, &b.root.right) > 1.0 - 1e-9);
                assert!(similarity(&a.root.left, &b.root.left) > 1.0 - 1e-9);
                let l = a.root.lambda;
                let x = &a.root.right;
                let mc = m.map(|v| C64::new(v, 0.0));
                let kc = k.map(|v| C64::new(v, 0.0));
                let r = (&mc * x) * (l * l) + &kc * x;
                assert!(
                    r.norm() <= 1e-11 * scale * (1.0 + l.norm_sqr()),
                    "{}",
                    r.norm()
                );
            }
            // With `M` and `K` passed to `modes`, the undamped route is the one taken.
            let out = modes(&m, &c, &k, 0.0).unwrap();
            assert!(out.iter().all(|x| x.damping_ratio == 0.0));
        }
    }

    /// Only the undamped, non-gyroscopic, symmetric pencil takes that route.
    #[test]
    fn the_undamped_route_refuses_other_pencils() {
        let (m, k) = pencil(6, 4);
        let mut asymmetric = k.clone();
        asymmetric[(0, 1)] += 1e-9 * k.amax();
        assert!(undamped_modes(&m, &asymmetric).is_none());
        let mut indefinite = m.clone();
        indefinite[(0, 0)] = -1.0;
        assert!(undamped_modes(&indefinite, &k).is_none());
        // A damped pencil goes to the first-order form: its damping ratios are not zero.
        let c = DMatrix::identity(6, 6) * 0.3;
        assert!(
            modes(&m, &c, &k, 0.0)
                .unwrap()
                .iter()
                .all(|x| x.damping_ratio != 0.0)
        );
    }
}
