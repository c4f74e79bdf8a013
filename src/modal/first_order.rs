//! The modes of any `M̂`, `Ĉ`, `K̂` from the 2n×2n first-order form, dividing by `M̂` or, where
//! `M̂` is the worse conditioned, by `K̂` (see the module documentation of [`crate::modal`]).

use super::pairing::pair_roots;
use super::rigid::RigidTest;
use super::{
    C64, IM_TOL, MAX_MASS_CONDITION, MAX_MASS_CONDITION_BY_STIFFNESS, ModalError, Mode, Root,
    normalize,
};
use crate::linalg;
use crate::schur::Eigen;
use nalgebra::{DMatrix, Dyn, LU};

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
pub(super) fn first_order_modes(
    m: &DMatrix<f64>,
    c: &DMatrix<f64>,
    k: &DMatrix<f64>,
    rigid: &RigidTest,
) -> Result<Vec<Mode>, ModalError> {
    let form = FirstOrderForm::new(m, c, k)?;
    let (mut roots, scale) = form.roots()?;
    if conservative_gyroscopic(m, c, k) {
        onto_the_axis(&mut roots);
    }
    Ok(pair_roots(roots, scale, rigid))
}

/// Relative asymmetry (of `M̂`, `K̂`) or symmetry (of `Ĉ`) below which the pencil counts as
/// conservative gyroscopic: rounding of the derivatives that form them, far below any physical
/// damping or circulatory force.
const STRUCTURE_TOL: f64 = 1e-10;

/// Is the pencil conservative and gyroscopic: `M̂`, `K̂` symmetric, `Ĉ` skew-symmetric (an
/// undamped rotor, a spinning mechanism without dampers), each to [`STRUCTURE_TOL`] of its
/// largest entry?
fn conservative_gyroscopic(m: &DMatrix<f64>, c: &DMatrix<f64>, k: &DMatrix<f64>) -> bool {
    let within = |a: &DMatrix<f64>, b: DMatrix<f64>| b.amax() <= STRUCTURE_TOL * a.amax();
    within(m, m - m.transpose()) && within(k, k - k.transpose()) && within(c, c + c.transpose())
}

/// The roots of a conservative gyroscopic pencil lie symmetric about the imaginary axis
/// (`λ`, `−λ̄` are both roots: its Hamiltonian structure; Tisseur & Meerbergen 2001, SIAM
/// Review 43:235, §3.3), so a root off the axis (flutter) comes with its mirror image as another
/// root. A complex root whose mirror `−λ̄` is farther from every other root than from itself
/// lies on the axis, and its real part is the unstructured solver's rounding (2e-8 of |λ|
/// on a stiff undamped rotor, read as flutter): it is set to zero. A true flutter pair
/// (two roots mirror images of each other) and real roots (divergence) are left as they are.
fn onto_the_axis(roots: &mut [Root]) {
    let lambdas: Vec<C64> = roots.iter().map(|r| r.lambda).collect();
    for (i, root) in roots.iter_mut().enumerate() {
        let l = root.lambda;
        if l.im == 0.0 || l.re == 0.0 {
            continue;
        }
        let mirror = C64::new(-l.re, l.im);
        let alone = (lambdas.iter().enumerate())
            .filter(|&(j, _)| j != i)
            .all(|(_, o)| (o - mirror).norm() > (l - mirror).norm());
        if alone {
            root.lambda.re = 0.0;
        }
    }
}

/// The condition number `σ_max/σ_min` of `a` (infinite where `a` is zero, `σ_min` floored at
/// the smallest normal number); `what` names the decomposition where it fails.
fn condition_of(a: &DMatrix<f64>, what: &'static str) -> Result<f64, ModalError> {
    let sv = linalg::svd_real(a.clone(), false, false)
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
pub(super) struct FirstOrderForm<'a> {
    /// The number of coordinates (the form has twice as many rows).
    n: usize,
    /// The matrix the form divides by: `M̂`, or `K̂` where `swapped`.
    divisor: &'a DMatrix<f64>,
    /// `cond(M̂)`, for the errors.
    condition: f64,
    /// The pencil itself, `[M̂, Ĉ, K̂]`, where the roots are refined.
    pencil: [&'a DMatrix<f64>; 3],
    /// The roots `λ` of the form's eigenvalues (`1/μ` where `swapped`), for the gaps
    /// [`FirstOrderForm::refined`] reads.
    lambdas: Vec<C64>,
    /// The form is of `μ²K̂ + μĈ + M̂` (its roots are `1/λ`).
    swapped: bool,
    eigen: Eigen,
}

impl<'a> FirstOrderForm<'a> {
    /// The form of `(λ²M̂ + λĈ + K̂) x = 0`, divided by `K̂` where `M̂` is the worse conditioned
    /// (above [`linalg::WELL_CONDITIONED`] and within [`MAX_MASS_CONDITION_BY_STIFFNESS`]),
    /// else by `M̂`, refused above [`MAX_MASS_CONDITION`]; and its eigendecomposition.
    pub(super) fn new(
        m: &'a DMatrix<f64>,
        c: &'a DMatrix<f64>,
        k: &'a DMatrix<f64>,
    ) -> Result<FirstOrderForm<'a>, ModalError> {
        let n = m.nrows();
        let pencil = [m, c, k];
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
        let lambdas = (eigen.values().into_iter())
            .map(|v| if swapped { 1.0 / v } else { v })
            .collect();
        Ok(FirstOrderForm {
            n,
            divisor: m,
            condition,
            pencil,
            lambdas,
            swapped,
            eigen,
        })
    }

    /// The roots `λ` with `Im λ ≥ 0` (a pair snapped to the real axis, `|Im| ≤ IM_TOL` of the
    /// form's scale, gives both), with their vectors, refined on the pencil
    /// ([`FirstOrderForm::refine`]), and the scale of the roots
    /// (`max|λ|` of the form, `1/min|μ|` where `swapped`).
    pub(super) fn roots(&self) -> Result<(Vec<Root>, f64), ModalError> {
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
        // The roots to refine (a pair rounded to two real roots: its first only).
        let mut refine: Vec<bool> = Vec::with_capacity(n + 1);
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
                refine.push(false);
                continue;
            }
            roots.push(self.root(k, l, &lu_t)?);
            refine.push(true);
        }
        self.refine(&mut roots, &refine);
        Ok((roots, scale))
    }

    /// The roots marked in `which` with `λ` moved by one Newton step on the pencil along their
    /// vectors (the two-sided Rayleigh quotient; Lancaster 1966, *Lambda-Matrices and
    /// Vibrating Systems*, §7.2): `λ − yᵀP(λ)x / yᵀP′(λ)x`, `P(λ) = λ²M̂ + λĈ + K̂`. The Schur
    /// form's roots carry the form's rounding, `ε cond(M̂)` of the largest root: a stiff rotor's
    /// low whirl roots were 1.5e-8 off and an undamped gyroscopic system's roots left the
    /// imaginary axis by 2e-8 of their size, read as flutter. The step's error is the product
    /// of the vectors' errors, so the root becomes that of the pencil to its own rounding. A
    /// real root stays real. A root with another within `1e-4 |λ|` (a repeated root, whose left
    /// and right vectors need not belong together: the step then moved a double root off the
    /// imaginary axis) is left as the form gives it, and so is one whose step exceeds
    /// `1e-6 |λ|`. The products `M̂x`, `Ĉx`, `K̂x` of all the roots are three real matrix
    /// products (the vectors' real and imaginary parts side by side), not three complex ones per
    /// root: at 96 beam elements those took a tenth of a modal point.
    fn refine(&self, roots: &mut [Root], which: &[bool]) {
        let apart = |lambda: C64| {
            (self.lambdas.iter())
                .filter(|&&v| (v - lambda).norm() > 0.0 && (v.conj() - lambda).norm() > 0.0)
                .all(|v| (v - lambda).norm() > 1e-4 * lambda.norm())
        };
        let chosen: Vec<usize> = (0..roots.len())
            .filter(|&j| which[j] && apart(roots[j].lambda))
            .collect();
        let (n, r) = (self.n, chosen.len());
        if r == 0 {
            return;
        }
        let x = DMatrix::from_fn(n, 2 * r, |i, j| {
            let z = roots[chosen[j % r]].right[i];
            if j < r { z.re } else { z.im }
        });
        let [mx, cx, kx] = self.pencil.map(|a| a * &x);
        let column = |p: &DMatrix<f64>, j: usize, i: usize| C64::new(p[(i, j)], p[(i, r + j)]);
        for (j, &at) in chosen.iter().enumerate() {
            let root = &mut roots[at];
            let (l, y) = (root.lambda, &root.left);
            let (mut residual, mut slope) = (C64::new(0.0, 0.0), C64::new(0.0, 0.0));
            for i in 0..n {
                let (m, c, k) = (column(&mx, j, i), column(&cx, j, i), column(&kx, j, i));
                residual += y[i] * (m * (l * l) + c * l + k);
                slope += y[i] * (m * (l * 2.0) + c);
            }
            let mut step = residual / slope;
            if l.im == 0.0 {
                step.im = 0.0;
            }
            if step.is_finite() && step.norm() <= 1e-6 * l.norm() {
                root.lambda = l - step;
            }
        }
    }

    /// The root of the form's eigenvalue `k`, at `l` (snapped), with its right vector from the
    /// form's `[x; λx]` (the half with the smaller rounding) and its left vector `y` from the
    /// form's `[·; Mᵀy]` (`lu_t` factorises `Mᵀ`); where `swapped`, `λ = 1/μ`, kept with
    /// `Im λ ≥ 0`.
    pub(super) fn root(
        &self,
        k: usize,
        l: C64,
        lu_t: &LU<f64, Dyn, Dyn>,
    ) -> Result<Root, ModalError> {
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
