//! Exact sensitivities of the damped modes and transfer functions with respect to design
//! variables, carried through the move of the equilibrium (Kim & Yoo 2007, eqs. 24–27, done with
//! automatic differentiation instead of finite differences, and for non-symmetric systems).
//!
//! For each design variable `b`:
//!
//! 1. equilibrium shift by the implicit function theorem on `F(x, b) = 0`, `x = [q_R; λ]`:
//!    `dx/db = −F_x⁻¹ ∂F/∂b` (`F_x` is Newton's Jacobian at the solution, `∂F/∂b` one dual pass);
//! 2. `M̂', Ĉ', K̂'` from the linearisation evaluated over dual numbers seeded along
//!    `(b, dq*/db, dλ/db)`, which includes the change of the independent-coordinate basis `R`;
//! 3. eigenvalue derivative with right and left vectors (`yᵀ(λ²M̂ + λĈ + K̂) = 0`):
//!
//!    ```text
//!    dλ/db = − yᵀ (λ² M̂' + λ Ĉ' + K̂') x / ( yᵀ (2λ M̂ + Ĉ) x )
//!    ```
//!
//!    then `dω_d = Im dλ` (root with `Im λ > 0`), `dω_n`, `dζ` from the pair invariants
//!    `λ₁λ₂` and `λ₁+λ₂`;
//! 4. `H(jω)` evaluated over the same dual numbers: `d|H| = Re(H̄ dH)/|H|`.
//!
//! Where roots coalesce (a mode changing between underdamped and overdamped) the derivative of
//! ω_d does not exist, nor those of a root repeated in two modes or of a rigid-body mode; such
//! entries carry [`Status::NotDifferentiable`] instead of a number
//! ([`crate::modal::smoothness`] says why).
//! [`finite_difference`] re-runs the whole pipeline at perturbed values as a cross-check.
//!
//! # Reference
//! Kim, Yoo (2007) eq. 24; Adhikari, *Rates of change of eigenvalues and eigenvectors in damped
//! dynamic systems*, AIAA J. 37 (1999).

use crate::compiled::Compiled;
use crate::dual4::Dual4;
use crate::frf::{Complex, transfer};
use crate::implicit;
use crate::jet::Jet;
use crate::linearize::Linearization;
use crate::mechanics::ports::ports_at;
use crate::modal::{C64, Mode, Root, Smoothness, similarities, smoothness};
use crate::model::{Channel, Transfer};
use crate::pair;
use crate::program::{Tier, Workspace};
use crate::sweep::{Options, Point, PointError, point};
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;

/// Whether a derivative exists at this point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Ok,
    /// Roots coalescing or the mode changing class: ω_d (and ζ) are not differentiable here.
    NotDifferentiable,
}

/// Derivatives of one mode with respect to one design variable.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ModeSensitivity {
    pub status: Status,
    pub d_eigen_re: f64,
    pub d_eigen_im: f64,
    pub d_damped_frequency: f64,
    pub d_natural_frequency: f64,
    pub d_damping_ratio: f64,
    /// Derivatives of the pair invariants `λ₁ + λ₂` and `λ₁ λ₂`, smooth even where the roots
    /// coalesce (for one degree of freedom they are `−ĉ/m̂` and `k̂/m̂`, taken from the matrices).
    pub d_sum: f64,
    pub d_product: f64,
}

/// Derivatives with respect to one design variable.
#[derive(Debug, Clone, serde::Serialize)]
pub struct VariableSensitivity {
    /// Parameter index.
    pub param: usize,
    pub modes: Vec<ModeSensitivity>,
    /// d|H|/db and d(arg H)/db, when a transfer function was asked for and the derivative
    /// exists (`None` where `H` passes through zero).
    pub d_transfer_magnitude: Option<f64>,
    pub d_transfer_phase: Option<f64>,
    /// dq*/db for every coordinate.
    pub d_equilibrium: Vec<f64>,
}

/// All sensitivities at one point.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sensitivity {
    /// Nominal |H| and arg H at the excitation frequency.
    pub transfer_magnitude: Option<f64>,
    pub transfer_phase: Option<f64>,
    pub variables: Vec<VariableSensitivity>,
}

/// A transfer function request: coordinates and excitation frequency (rad/s).
#[derive(Debug, Clone, Copy)]
pub struct TransferAt {
    pub input: Channel,
    pub output: Channel,
    pub omega: f64,
}

impl TransferAt {
    /// The model's transfer spec at `speed` (excitation `order × speed`).
    pub fn at_speed(t: &Transfer, speed: f64) -> Self {
        TransferAt {
            input: t.input,
            output: t.output,
            omega: t.order * speed,
        }
    }
}

/// Nominal |H| and arg H at a point.
pub fn nominal_transfer(pt: &Point, t: &TransferAt) -> Option<Complex<f64>> {
    transfer(&pt.linear, t.input, t.output, t.omega)
}

/// Derivatives of a mode from the derivatives of its two roots; `invariants`, when given, are
/// the exact derivatives of `λ₁ + λ₂` and `λ₁ λ₂` (used instead of the roots' sums). `Ok` only
/// where the mode's roots are simple ([`Smoothness::Simple`]: not coalescing, not repeated in
/// another mode, not a rigid-body mode) and the derivatives finite.
fn mode_derivative(
    m: &Mode,
    smooth: Smoothness,
    (d1, d2): (C64, C64),
    invariants: Option<(f64, f64)>,
) -> ModeSensitivity {
    let (l1, l2) = (m.root.lambda, m.partner.lambda);
    let status = if smooth != Smoothness::Simple || !d1.re.is_finite() || !d2.re.is_finite() {
        Status::NotDifferentiable
    } else {
        Status::Ok
    };
    let p = (l1 * l2).re;
    let s = (l1 + l2).re;
    let (ds, dp) = invariants.unwrap_or(((d1 + d2).re, (d1 * l2 + l1 * d2).re));
    let wn = m.natural_frequency;
    let dwn = pair::d_natural_frequency(p, wn, dp);
    let dzeta = pair::d_damping_ratio(s, wn, ds, dwn);
    ModeSensitivity {
        status,
        d_eigen_re: d1.re,
        d_eigen_im: d1.im,
        d_damped_frequency: if l1.im > 0.0 { d1.im } else { 0.0 },
        d_natural_frequency: dwn,
        d_damping_ratio: dzeta,
        d_sum: ds,
        d_product: dp,
    }
}

/// `dλ = −yᵀ(λ²M' + λC' + K')x / yᵀ(2λM + C)x` for one root.
pub fn eigenvalue_derivative(
    lambda: C64,
    x: &DVector<C64>,
    y: &DVector<C64>,
    (m, c): (&DMatrix<f64>, &DMatrix<f64>),
    (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
) -> C64 {
    let b = |a: &DMatrix<f64>| bilinear(y, a, x);
    -(lambda * lambda * b(dm) + lambda * b(dc) + b(dk)) / (lambda * 2.0 * b(m) + b(c))
}

/// `yᵀ A x` for a real `A` (no complex matrix formed).
fn bilinear(y: &DVector<C64>, a: &DMatrix<f64>, x: &DVector<C64>) -> C64 {
    a.column_iter()
        .zip(x.iter())
        .map(|(col, &xj)| {
            col.iter()
                .zip(y.iter())
                .map(|(&v, &yi)| yi * v)
                .sum::<C64>()
                * xj
        })
        .sum()
}

/// [`eigenvalue_derivative`] for all the roots of a point at once. The roots' right vectors
/// are the columns of one matrix, so that a design variable costs three real matrix products
/// (`M'X`, `C'X`, `K'X`, blocked) and O(n) per root, where a root at a time is a pass over
/// three matrices each (memory-bound, and 2n roots); the denominators `yᵀ(2λM + C)x` do not
/// depend on the variable and are computed once. A conjugate partner's derivative is the
/// conjugate, bitwise.
struct RootDerivatives<'a> {
    /// Per mode, its root and the partner (`None` when it is the root's conjugate).
    roots: Vec<(&'a Root, Option<&'a Root>)>,
    /// Real and imaginary parts of the distinct roots' right vectors, as columns.
    xr: DMatrix<f64>,
    xi: DMatrix<f64>,
    /// `yᵀ(2λM + C)x` per distinct root.
    den: Vec<C64>,
}

impl<'a> RootDerivatives<'a> {
    fn new(modes: &'a [Mode], m: &DMatrix<f64>, c: &DMatrix<f64>) -> Self {
        let roots: Vec<(&Root, Option<&Root>)> = modes
            .iter()
            .map(|md| {
                let (r, p) = (&md.root, &md.partner);
                let conjugate = p.lambda == r.lambda.conj()
                    && p.right.iter().zip(&r.right).all(|(a, b)| *a == b.conj())
                    && p.left.iter().zip(&r.left).all(|(a, b)| *a == b.conj());
                (r, (!conjugate).then_some(p))
            })
            .collect();
        let distinct: Vec<&Root> = roots
            .iter()
            .flat_map(|&(r, p)| std::iter::once(r).chain(p))
            .collect();
        let n = m.nrows();
        let xr = DMatrix::from_fn(n, distinct.len(), |i, k| distinct[k].right[i].re);
        let xi = DMatrix::from_fn(n, distinct.len(), |i, k| distinct[k].right[i].im);
        let (mr, mi, cr, ci) = (m * &xr, m * &xi, c * &xr, c * &xi);
        let den = distinct
            .iter()
            .enumerate()
            .map(|(k, r)| {
                (0..n)
                    .map(|i| {
                        let mx = C64::new(mr[(i, k)], mi[(i, k)]);
                        let cx = C64::new(cr[(i, k)], ci[(i, k)]);
                        r.left[i] * (r.lambda * 2.0 * mx + cx)
                    })
                    .sum()
            })
            .collect();
        RootDerivatives { roots, xr, xi, den }
    }

    /// `(dλ_root, dλ_partner)` per mode along `(M', C', K')`.
    fn along(
        &self,
        (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Vec<(C64, C64)> {
        let prod = |a: &DMatrix<f64>| (a * &self.xr, a * &self.xi);
        let ((mr, mi), (cr, ci), (kr, ki)) = (prod(dm), prod(dc), prod(dk));
        let n = dm.nrows();
        let mut k = 0;
        let mut next = |r: &Root| {
            let l = r.lambda;
            let num: C64 = (0..n)
                .map(|i| {
                    let at =
                        |re: &DMatrix<f64>, im: &DMatrix<f64>| C64::new(re[(i, k)], im[(i, k)]);
                    r.left[i] * (l * l * at(&mr, &mi) + l * at(&cr, &ci) + at(&kr, &ki))
                })
                .sum();
            let d = -num / self.den[k];
            k += 1;
            d
        };
        self.roots
            .iter()
            .map(|&(r, p)| {
                let d1 = next(r);
                (d1, p.map_or(d1.conj(), &mut next))
            })
            .collect()
    }
}

/// The linearisation over dual numbers seeded along one design variable, with the equilibrium
/// shift `dq*/db` (all coordinates).
pub struct DualLinearization {
    pub param: usize,
    pub linear: Linearization<Dual64>,
    pub d_equilibrium: Vec<f64>,
}

/// How derivatives are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Derivatives {
    /// Exact, by automatic differentiation through the equilibrium ([`analytic`]).
    #[default]
    Exact,
    /// Central finite differences of the whole pipeline, Richardson-extrapolated
    /// ([`finite_difference`], a cross-check).
    FiniteDifference,
}

/// The sensitivities of the point `pt` (at parameters `p`) to the design variables `wrt`,
/// computed `how`.
pub fn sensitivities(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    wrt: &[usize],
    tf: Option<TransferAt>,
    how: Derivatives,
    workspace: &Workspace,
) -> Result<Sensitivity, PointError> {
    match how {
        Derivatives::Exact => analytic(model, p, pt, wrt, tf, workspace),
        Derivatives::FiniteDifference => finite_difference(model, p, pt, wrt, tf),
    }
}

/// One excitation frequency of a frequency response: `H` and `d|H|/db` for each design
/// variable (`None` where undefined: an undamped resonance, or `H` passing through zero).
#[derive(Debug, Clone)]
pub struct ResponseRow {
    /// Excitation frequency (rad/s).
    pub frequency: f64,
    pub h: Option<Complex<f64>>,
    pub d_magnitude: Vec<Option<f64>>,
}

/// The frequency response from `input` to `output` at the point `pt` over `frequencies`, with
/// the exact derivatives of |H| with respect to the design variables `wrt`.
pub fn frequency_response(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    input: Channel,
    output: Channel,
    wrt: &[usize],
    frequencies: impl Iterator<Item = f64>,
) -> Result<Vec<ResponseRow>, PointError> {
    let duals = dual_linearizations(model, p, pt, wrt, &Workspace::default())?;
    Ok(frequencies
        .map(|f| ResponseRow {
            frequency: f,
            h: transfer(&pt.linear, input, output, f),
            d_magnitude: duals
                .iter()
                .map(|d| {
                    transfer(&d.linear, input, output, f).and_then(|h| transfer_derivative(&h).0)
                })
                .collect(),
        })
        .collect())
}

/// `M̂, Ĉ, K̂` (and `R`) over dual numbers for each design variable in `wrt`: the equilibrium
/// shift by the implicit function theorem, then the linearisation over dual numbers along
/// `(b, dq*/db, dλ/db)`. Three or four variables share one evaluation over [`Dual4`], whose
/// parts are bit for bit one `Dual64` evaluation each; one or two left over take a `Dual64`
/// each (a `Dual4` with unused parts costs them the time and, on a big model, two and a half
/// times a `Dual64`'s buffer).
pub fn dual_linearizations(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    wrt: &[usize],
    workspace: &Workspace,
) -> Result<Vec<DualLinearization>, PointError> {
    let speed = pt.speed;
    let eq = &pt.equilibrium;
    let lu = eq.factor();
    // ∂F/∂p along all the variables in one pass where the model has a recorded program.
    let dp = model.parameter_jacobian(p, speed, (&eq.q, &eq.lambda), wrt, workspace);
    let at = Shift {
        model,
        p,
        pt,
        lu: &lu,
        dp: dp.as_deref(),
        wrt,
        workspace,
    };
    let mut out = Vec::with_capacity(wrt.len());
    for group in wrt.chunks(4) {
        if group.len() > 2 {
            at.linearizations::<Dual4<f64>>(group, &mut out)?;
        } else {
            for b in group.chunks(1) {
                at.linearizations::<Dual64>(b, &mut out)?;
            }
        }
    }
    Ok(out)
}

/// What [`dual_linearizations`] shares between its groups of variables.
struct Shift<'a> {
    model: &'a Compiled,
    p: &'a [f64],
    pt: &'a Point,
    /// Newton's Jacobian at the solution, factorised.
    lu: &'a crate::equilibrium::Factor,
    /// `∂F/∂p` (rows of `F` × the variables), where the model has a recorded program.
    dp: Option<&'a [f64]>,
    /// All the variables (the columns of `dp`).
    wrt: &'a [usize],
    /// Where the recorded program's passes run.
    workspace: &'a Workspace,
}

impl Shift<'_> {
    /// The dual linearisations of the variables `group` (at most `D::PARTS`), direction
    /// `k` along variable `group[k]`, appended to `out`.
    fn linearizations<D: Jet>(
        &self,
        group: &[usize],
        out: &mut Vec<DualLinearization>,
    ) -> Result<(), PointError> {
        let (pt, eq) = (self.pt, &self.pt.equilibrium);
        let (speed, free, nw) = (pt.speed, &pt.linear.free, self.wrt.len());
        let seeded = |values: &[f64], slope: &dyn Fn(usize, usize) -> f64| -> Vec<D> {
            (0..values.len())
                .map(|i| {
                    D::seeded(
                        values[i],
                        |k| if k < group.len() { slope(k, i) } else { 0.0 },
                    )
                })
                .collect()
        };
        let pd = seeded(self.p, &|k, i| if i == group[k] { 1.0 } else { 0.0 });
        let equations = (self.model).at(&pd, D::from(speed), &eq.q, (Tier::Few, self.workspace))?;
        // The shift `[dq_R; dλ]/db = −J⁻¹ ∂F/∂b`: one implicit step from the nominal solution,
        // with `∂F/∂b` from the recorded program where there is one.
        let nf = free.len();
        let mut z: Vec<D> = (free.iter().map(|&i| eq.q[i]))
            .chain(eq.lambda.iter().copied())
            .map(D::from)
            .collect();
        let mut q = seeded(&eq.q, &|_, _| 0.0);
        let singular =
            PointError::Equilibrium(crate::equilibrium::EquilibriumError::SingularJacobian {
                iterations: 0,
            });
        // The columns of `dp` of the group's variables, found once.
        let columns: Vec<usize> = (group.iter())
            .map(|&b| {
                self.wrt
                    .iter()
                    .position(|&w| w == b)
                    .expect("b is a variable")
            })
            .collect();
        implicit::correct(
            &mut z,
            1,
            |z| match self.dp {
                Some(dp) => (0..dp.len() / nw)
                    .map(|r| D::seeded(0.0, |k| columns.get(k).map_or(0.0, |&c| dp[r * nw + c])))
                    .collect(),
                None => {
                    for (k, &i) in free.iter().enumerate() {
                        q[i] = z[k];
                    }
                    equations.residual(&q, &z[nf..])
                }
            },
            |r| self.lu.solve(r),
        )
        .ok_or(singular)?;
        for (k, &i) in free.iter().enumerate() {
            q[i] = z[k];
        }
        let lambda = &z[nf..];
        let dq: Vec<Vec<f64>> = (0..group.len())
            .map(|k| {
                let mut d = vec![0.0; eq.q.len()];
                for &i in free {
                    d[i] = q[i].part(k);
                }
                d
            })
            .collect();
        let linear = equations
            .linearize(&q, lambda, &pt.linear.independent, None)?
            .with_ports(ports_at(self.model.model(), &pd, D::from(speed), &q, free)?);
        for (k, (&b, d_equilibrium)) in group.iter().zip(dq).enumerate() {
            out.push(DualLinearization {
                param: b,
                linear: linear.map(|v| Dual64::new(v.re(), v.part(k))),
                d_equilibrium,
            });
        }
        Ok(())
    }
}

/// d|H|/db and d(arg H)/db from `H` over dual numbers; `None` where the derivative does not
/// exist (`H` passing through zero).
pub fn transfer_derivative(h: &Complex<Dual64>) -> (Option<f64>, Option<f64>) {
    let mag = h.magnitude();
    if mag.re > 0.0 {
        (
            Some(mag.eps).filter(|v| v.is_finite()),
            Some(h.phase().eps).filter(|v| v.is_finite()),
        )
    } else if h.re.eps == 0.0 && h.im.eps == 0.0 {
        // H ≡ 0 to first order: |H| = o(Δb), its derivative is 0; the phase is undefined.
        (Some(0.0), None)
    } else {
        (None, None)
    }
}

/// Exact sensitivities by automatic differentiation through the equilibrium.
pub fn analytic(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    wrt: &[usize],
    tf: Option<TransferAt>,
    workspace: &Workspace,
) -> Result<Sensitivity, PointError> {
    let nominal = tf.and_then(|t| nominal_transfer(pt, &t));
    let mut variables = Vec::with_capacity(wrt.len());
    let roots = RootDerivatives::new(&pt.modes, &pt.linear.m, &pt.linear.c);
    let smooth = smoothness(&pt.modes);
    for DualLinearization {
        param: b,
        linear: lin,
        d_equilibrium: dq,
    } in dual_linearizations(model, p, pt, wrt, workspace)?
    {
        let eps = |a: &DMatrix<Dual64>| a.map(|v| v.eps);
        let (dm, dc, dk) = (eps(&lin.m), eps(&lin.c), eps(&lin.k));
        let (m, c) = (&pt.linear.m, &pt.linear.c);
        // One degree of freedom: λ₁ + λ₂ = −ĉ/m̂ and λ₁λ₂ = k̂/m̂ exactly.
        let invariants = (m.nrows() == 1).then(|| {
            let (m0, c0, k0) = (m[(0, 0)], c[(0, 0)], pt.linear.k[(0, 0)]);
            let ds = -(dc[(0, 0)] * m0 - c0 * dm[(0, 0)]) / (m0 * m0);
            let dp = (dk[(0, 0)] * m0 - k0 * dm[(0, 0)]) / (m0 * m0);
            (ds, dp)
        });
        let modes = (pt.modes.iter().zip(&smooth))
            .zip(roots.along((&dm, &dc, &dk)))
            .map(|((md, &why), d)| mode_derivative(md, why, d, invariants))
            .collect();
        let (dmag, dphase) = match (tf, nominal) {
            (Some(t), Some(_)) => transfer(&lin, t.input, t.output, t.omega)
                .map_or((None, None), |h| transfer_derivative(&h)),
            _ => (None, None),
        };
        variables.push(VariableSensitivity {
            param: b,
            modes,
            d_transfer_magnitude: dmag,
            d_transfer_phase: dphase,
            d_equilibrium: dq,
        });
    }
    Ok(Sensitivity {
        transfer_magnitude: nominal.map(|h| h.magnitude()),
        transfer_phase: nominal.map(|h| h.phase()),
        variables,
    })
}

/// Quantities per mode in [`fd_quantities`].
const NQ: usize = 7;

/// Relative step of the central differences.
const FD_STEP: f64 = 1e-4;

/// Quantities compared by finite differences at one perturbed point: per mode
/// `[Re λ, Im λ, ω_d, ω_n, ζ, λ₁+λ₂, λ₁λ₂]` (modes matched to the nominal ones by shape), then `|H|`,
/// `arg H`, then the coordinates; and whether every mode kept its class.
fn fd_quantities(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    tf: Option<TransferAt>,
    opt: &Options,
) -> Result<(Vec<f64>, bool), PointError> {
    let q = point(model, p, pt.speed, &pt.equilibrium.q, opt)?;
    let mut out = Vec::new();
    let mut same_class = true;
    let s = similarities(&pt.shapes, &q.shapes);
    for (k, m0) in pt.modes.iter().enumerate() {
        let i = (0..q.shapes.len())
            .max_by(|&i, &j| s[(k, i)].total_cmp(&s[(k, j)]))
            .unwrap_or(0);
        let m = &q.modes[i];
        same_class &= m.class == m0.class;
        out.extend([
            m.root.lambda.re,
            m.root.lambda.im,
            m.damped_frequency,
            m.natural_frequency,
            m.damping_ratio,
            (m.root.lambda + m.partner.lambda).re,
            (m.root.lambda * m.partner.lambda).re,
        ]);
    }
    match tf.and_then(|t| nominal_transfer(&q, &t)) {
        Some(h) => out.extend([h.magnitude(), h.phase()]),
        None => out.extend([f64::NAN, f64::NAN]),
    }
    out.extend(q.equilibrium.q.iter().copied());
    Ok((out, same_class))
}

/// Sensitivities by finite differences of the whole pipeline (re-solve the equilibrium,
/// re-linearise, re-solve the modes): central differences at steps `h` and `h/2`,
/// `h = 1e-4 × max(|b|, 1e-3)`, combined by Richardson extrapolation (error O(h⁴)). Modes are
/// matched to the nominal ones by shape. A cross-check, and the paper's method.
pub fn finite_difference(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    wrt: &[usize],
    tf: Option<TransferAt>,
) -> Result<Sensitivity, PointError> {
    let opt = Options {
        independent: Some(pt.linear.independent.clone()),
        no_branch_switch: true,
        ..Default::default()
    };
    let nominal = tf.and_then(|t| nominal_transfer(pt, &t));
    let nm = pt.modes.len();
    let mut variables = Vec::new();
    for &b in wrt {
        let h = FD_STEP * p[b].abs().max(1e-3);
        let mut same = true;
        let mut central = |step: f64| -> Result<Vec<f64>, PointError> {
            let mut pp = p.to_vec();
            pp[b] = p[b] + step;
            let (a, sa) = fd_quantities(model, &pp, pt, tf, &opt)?;
            pp[b] = p[b] - step;
            let (c, sc) = fd_quantities(model, &pp, pt, tf, &opt)?;
            same &= sa && sc;
            Ok(a.iter()
                .zip(&c)
                .map(|(x, y)| (x - y) / (2.0 * step))
                .collect())
        };
        let d1 = central(h)?;
        let d2 = central(0.5 * h)?;
        let d: Vec<f64> = d1
            .iter()
            .zip(&d2)
            .map(|(a, b)| (4.0 * b - a) / 3.0)
            .collect();
        let status = if same {
            Status::Ok
        } else {
            Status::NotDifferentiable
        };
        let modes = (0..nm)
            .map(|k| ModeSensitivity {
                status,
                d_eigen_re: d[NQ * k],
                d_eigen_im: d[NQ * k + 1],
                d_damped_frequency: d[NQ * k + 2],
                d_natural_frequency: d[NQ * k + 3],
                d_damping_ratio: d[NQ * k + 4],
                d_sum: d[NQ * k + 5],
                d_product: d[NQ * k + 6],
            })
            .collect();
        let has_tf = nominal.is_some() && d[NQ * nm].is_finite();
        variables.push(VariableSensitivity {
            param: b,
            modes,
            d_transfer_magnitude: has_tf.then(|| d[NQ * nm]),
            d_transfer_phase: has_tf.then(|| d[NQ * nm + 1]),
            d_equilibrium: d[NQ * nm + 2..].to_vec(),
        });
    }
    Ok(Sensitivity {
        transfer_magnitude: nominal.map(|h| h.magnitude()),
        transfer_phase: nominal.map(|h| h.phase()),
        variables,
    })
}
