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
//! A conservative gyroscopic system (`M̂`, `K̂` symmetric positive definite, `Ĉ` skew-symmetric
//! and nonzero: an undamped rotor on undamped bearings, a spinning mechanism without dampers) is
//! solved from the Hermitian form of [`linalg::gyroscopic`]: its roots on the imaginary axis by
//! construction, its left vectors the conjugates of its right ones, and about half the general
//! route's cost (the Friswell rotor's 84×84 form).
//!
//! One degree of freedom (a governor, a pendulum) is solved in closed form, the same roots,
//! vectors `[1]`, classes and pairing as the first-order form gives, without its 2×2 Schur form.
//!
//! Both routes divide by `M̂` (its Cholesky or LU factor), which costs every root `ε cond(M̂)`;
//! a long chain in joint coordinates has `cond(M̂) ∝ n⁴`. Where `M̂` is ill-conditioned and `K̂`
//! better conditioned, both divide by `K̂` instead and solve for `1/λ` (see
//! [`linalg::symmetric_definite`] and `first_order_modes`).

pub mod cluster;
mod first_order;
mod gyroscopic;
mod pairing;
mod rigid;
mod smoothness;
mod tracking;

pub use smoothness::{SIMPLE_GAP, Smoothness, smoothness};
pub use tracking::{match_modes, match_shapes, permute, similarities, similarity};

use crate::linalg;
use crate::pair;
use first_order::first_order_modes;
use gyroscopic::gyroscopic_modes;
use nalgebra::{Complex, DMatrix, DVector};
use rigid::RigidTest;

/// Complex scalar.
pub type C64 = Complex<f64>;

/// Character of a mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModeClass {
    /// Complex roots with a negative real part: a decaying oscillation.
    Underdamped,
    /// Imaginary roots, their real parts exactly zero: an oscillation no dissipation reaches
    /// (ζ = 0; an undamped or purely gyroscopic system's modes).
    Undamped,
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
            ModeClass::Undamped => "undamped",
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

impl Mode {
    /// Is the partner the root's conjugate, vectors and all (bitwise): its derivatives are
    /// then the root's conjugated.
    pub fn partner_is_conjugate(&self) -> bool {
        let (r, p) = (&self.root, &self.partner);
        p.lambda == r.lambda.conj()
            && p.right.iter().zip(&r.right).all(|(a, b)| *a == b.conj())
            && p.left.iter().zip(&r.left).all(|(a, b)| *a == b.conj())
    }
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

/// Condition number of `M̂` above which the modes are refused where a route divides by `M̂` (a
/// coordinate moves next to no mass: the roots would be rounding): every root then carries
/// errors of `ε cond(M̂)` relative to the largest (1e-4 here).
const MAX_MASS_CONDITION: f64 = 1e12;

/// The same where a route divides by `K̂` instead (`M̂` the worse conditioned; see
/// [`crate::linalg::symmetric_definite`] and [`first_order_modes`]): the low modes keep a few ε
/// whatever `cond(M̂)`, and only the modes that live where `M̂` is nearly singular, the
/// highest, depend on `M̂`'s smallest eigenvalue, itself known to `ε cond(M̂)`. So `M̂` counts
/// as singular where that smallest eigenvalue carries 1 % of rounding (its frequency then
/// 0.5 %): a coordinate moving next to no mass. A chain of a thousand segments in joint
/// coordinates (`cond(M̂)` 3.9e12, growing like n⁴) is within.
const MAX_MASS_CONDITION_BY_STIFFNESS: f64 = 1e-2 / f64::EPSILON;

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
        None => match gyroscopic_modes(m, c, k) {
            Some(out) => out,
            None => first_order_modes(m, c, k, &test)?,
        },
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
        if l1.re == 0.0 && l2.re == 0.0 {
            ModeClass::Undamped
        } else {
            ModeClass::Underdamped
        }
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
    if n > 0.0 && n.is_finite() {
        w / C64::new(n, 0.0)
    } else if z.norm() > 0.0 {
        // The squares under- or overflow (a vector of subnormal or huge components): scaled
        // by its largest component first.
        let w = w.map(|x| x / z.norm());
        let n = w.norm();
        w / C64::new(n, 0.0)
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vector of subnormal or huge components is normalised to unit length (its squares
    /// under- or overflow).
    #[test]
    fn vectors_of_any_scale_normalise_to_unit_length() {
        for s in [1e-310, 1e-200, 1e300] {
            let v = DVector::from_vec(vec![C64::new(3.0 * s, -s), C64::new(0.0, 2.0 * s)]);
            let n = normalize(v);
            assert!((n.norm() - 1.0).abs() < 1e-12, "{s}: {n}");
        }
    }
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

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
            assert!(fast.iter().any(|x| x.class == ModeClass::Undamped));
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
