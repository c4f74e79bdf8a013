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
//! and a class: `unstable` if a root has positive real part, else `underdamped` or
//! `overdamped`. All frequencies in rad/s.

use crate::linalg;
use crate::schur::Eigen;
use nalgebra::{Complex, DMatrix, DVector};

/// Complex scalar.
pub type C64 = Complex<f64>;

/// Character of a mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModeClass {
    Underdamped,
    Overdamped,
    Unstable,
}

impl ModeClass {
    pub fn as_str(self) -> &'static str {
        match self {
            ModeClass::Underdamped => "underdamped",
            ModeClass::Overdamped => "overdamped",
            ModeClass::Unstable => "unstable",
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
    #[error(
        "mode {mode} has zero natural frequency (λ₁λ₂ = 0): K̂ is singular, the equilibrium is neutral"
    )]
    ZeroFrequency { mode: usize },
}

/// Relative size below which an imaginary part counts as zero (roots are then real).
const IM_TOL: f64 = 1e-9;
/// Relative size above which a positive real part makes a root unstable.
const RE_TOL: f64 = 1e-10;

/// Solves the damped eigenproblem and groups the roots into modes, sorted by ω_n.
pub fn modes(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
) -> Result<Vec<Mode>, ModalError> {
    let n = m.nrows();
    if m.iter()
        .chain(c.iter())
        .chain(k.iter())
        .any(|v| !v.is_finite())
    {
        return Err(ModalError::NotFinite);
    }
    let sv = linalg::svd(m.clone(), false, false)
        .ok_or(ModalError::NoConvergence { what: "SVD of M̂" })?
        .singular_values;
    let condition = sv.max() / sv.min().max(f64::MIN_POSITIVE);
    if sv.max() == 0.0 || condition > 1e12 {
        return Err(ModalError::SingularMass { condition });
    }
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
    let eig = eigen.values();
    let scale = eig
        .iter()
        .fold(0.0f64, |s, l| s.max(l.norm()))
        .max(f64::MIN_POSITIVE);
    // The left vectors of the first-order form are `[·; Mᵀ y]`.
    let lu_t = m.transpose().lu();
    let mut roots: Vec<Root> = Vec::with_capacity(n + 1);
    for (k, &l0) in eig.iter().enumerate() {
        let snapped = l0.im != 0.0 && l0.im.abs() <= IM_TOL * scale.max(l0.norm());
        let l = if snapped { C64::new(l0.re, 0.0) } else { l0 };
        // A complex root's conjugate is its partner, with conjugate vectors; a pair rounded to
        // two real roots shares the vectors of its first.
        if l.im < 0.0 {
            continue;
        }
        if snapped && l0.im < 0.0 {
            let twin = roots.last().expect("the pair's first root").clone();
            roots.push(Root { lambda: l, ..twin });
            continue;
        }
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
        roots.push(Root {
            lambda: l,
            right: normalize(right),
            left: normalize(left),
        });
    }
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
    // Pair real roots whose right vectors are most alike.
    while real.len() >= 2 {
        let (mut bi, mut bj, mut best) = (0, 1, -1.0);
        for i in 0..real.len() {
            for j in i + 1..real.len() {
                let s = similarity(&real[i].right, &real[j].right);
                if s > best {
                    (bi, bj, best) = (i, j, s);
                }
            }
        }
        let b = real.remove(bj);
        let a = real.remove(bi);
        let (hi, lo) = if a.lambda.re >= b.lambda.re {
            (a, b)
        } else {
            (b, a)
        };
        out.push(make_mode(hi, lo, scale));
    }
    out.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
    for (i, m) in out.iter().enumerate() {
        check_mode(i + 1, m)?;
    }
    Ok(out)
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
    if m.natural_frequency == 0.0 {
        return Err(ModalError::ZeroFrequency { mode });
    }
    if !m.damping_ratio.is_finite() {
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

/// |aᴴ b| / (|a| |b|): 1 for parallel vectors.
pub fn similarity(a: &DVector<C64>, b: &DVector<C64>) -> f64 {
    let d = a.dotc(b).norm();
    d / (a.norm() * b.norm()).max(f64::MIN_POSITIVE)
}

fn make_mode(root: Root, partner: Root, scale: f64) -> Mode {
    let (l1, l2) = (root.lambda, partner.lambda);
    let p = (l1 * l2).re;
    let s = (l1 + l2).re;
    let wn = p.abs().sqrt();
    let zeta = if wn > 0.0 {
        -s / (2.0 * wn)
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
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(n * n);
    for (i, p) in prev.iter().enumerate() {
        for (j, c) in cur.iter().enumerate() {
            pairs.push((similarity(p, c), i, j));
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
