//! Exact first and second derivatives of the modal outputs with respect to design variables.
//!
//! Three kinds of forward passes through the equilibrium and the linearisation (the generic
//! mechanics over truncated Taylor numbers; the equilibrium expanded by two chord steps with
//! Newton's Jacobian, factorised once for all, [`crate::implicit::correct`]), then the roots
//! and outputs in closed form:
//!
//! 1. **Per variable** `b_a`: a `Dual2` pass (`b + ε e_a`) gives the matrices' first and
//!    second derivatives along it (`M̂_a`, `M̂_aa`, …, the basis and the ports likewise; first
//!    derivatives only, four variables a pass, where reverse mode gives the second: step 2).
//! 2. **Screening the pairs**: the mixed derivatives of the matrices `M̂_ab` vanish for most
//!    pairs of a real tolerance stack (a mass and a stiffness of two different parts, when the
//!    equilibrium does not move). One `Dual2` pass along a fixed direction `w` with irregular
//!    entries gives `Σ_ab w_a w_b M̂_ab`; where every number of it is zero, every mixed
//!    derivative is (the sum is a polynomial in `w` that vanishes identically only if its
//!    coefficients do: a zero at `w` otherwise is a coincidence of measure zero, Schwartz
//!    1980). Otherwise one hyper-dual pass `(e_a, w)` per variable gives row `a`'s sum
//!    `Σ_b w_b M̂_ab`, and only the pairs of two variables whose rows do not vanish get a
//!    hyper-dual pass `(e_a, e_b)` of their own. So the passes number `p + 1` where the mixed
//!    derivatives vanish, and at most `1 + 2p + p(p−1)/2` where they do not. (With few
//!    variables the screening is shortened where it cannot pay: up to three pairs get their
//!    own passes unscreened, and up to five variables skip the rows' passes.)
//!
//!    Where the coupled pairs are many (a spring the harmonic mean of two segments' stiffness,
//!    one density in every segment, an equilibrium that moves with every variable, arms that
//!    each move a governor's equilibrium), the roots' mixed terms come from reverse mode
//!    instead (`mixed.rs`): per root, forward-over-reverse sweeps of the recorded equations give
//!    `yᵀP_ab x` for every pair, the equilibrium's second-order move eliminated by one adjoint
//!    solve, [`crate::program::BATCH`] Hessian-vector products a sweep. The products are the
//!    fewer of `p` (along each variable's equilibrium move) and the **compressed** set: the
//!    parameters' own block coloured by its pattern from the recorded operations
//!    (`colouring.rs`), plus one product per coordinate the equilibrium moves along. The
//!    diagonal comes with them, so the per-variable passes then need first derivatives only
//!    (four variables a [`Dual4`] pass). The route is chosen by its cost in pair passes
//!    (`SWEEP_LANES`); every route gives the same Hessians to rounding (1.9e-12 relative on the
//!    81-variable blade). On the 40-segment blade at 80/81 variables (`scale_chain local 40 40
//!    --family F`, one point, best of 3, gradients and Hessians): 0.14–0.15 s with
//!    harmonic-mean springs (3 products a root) or a density in every segment (2), 0.29 s with
//!    gravity along the spin axis as well (44), against 1.9, 2.3 and 8.3 s by a pass per pair
//!    and 0.50, 0.55 and 0.60 s by a product per variable. Reverse mode over the recorded
//!    program was chosen over vector hyper-dual lanes, which would still carry `p²` mixed
//!    parts through every coordinate's three lanes; the colouring is applied to the parameters'
//!    block only, because a moving equilibrium couples every pair through the coordinates.
//!    With constraint equations the roots are then taken as the augmented pencil's over the
//!    free coordinates and the multipliers (`augmented.rs`): the recorded equations' own
//!    pencil, whose mixed derivatives need no second derivative of the reduced basis. `H(jω)`
//!    between two free coordinates comes from the same pencil's responses (`transfer.rs`:
//!    its `vᵀP_ab u` is one more contraction beside the roots'); between ports it keeps a
//!    pass per coupled pair, because the ports' vectors' second derivatives are not in the
//!    recorded program. One degree of freedom's invariants come from the roots on this route
//!    where the roots lie apart (`ROOTS_APART`), from the matrices otherwise. The 12-arm
//!    governor with 37 variables (`scale_chain governor`, 13 speeds, best of 3): 0.05 s for
//!    its second-order stage against 0.87 s by a pass per coupled pair; the spinning spatial
//!    four-bar's Hessians 0.37 → 0.18 s.
//! 3. **Roots** (`root.rs`): each simple root's bordered eigen-equations are
//!    factorised once; the root's first and second derivatives follow in closed form from the
//!    matrices' derivatives, one solve per variable and `O(n)` per pair.
//! 4. **Outputs**: ω_d, ζ and the discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4` are the generic maps of
//!    the roots (through the pair invariants, smooth where the roots coalesce), evaluated over
//!    `Dual2` (a variable: its gradient entry and diagonal Hessian entry) or hyper-dual numbers
//!    (a pair: the mixed entry) built from the roots' parts; `H(jω)` is the generic transfer
//!    function over the linearisation's parts. For one degree of freedom the pair invariants
//!    come straight from the matrices (`λ₁+λ₂ = −ĉ/m̂`, `λ₁λ₂ = k̂/m̂`).
//!
//! No step size, no truncation error.
//!
//! # Reference
//! Fike & Alonso (2011), *The development of hyper-dual numbers for exact second-derivative
//! calculations*, AIAA 2011-886; Griewank & Walther, *Evaluating Derivatives* (2008), §15
//! (derivatives of iterative solvers); Walther, *Computing sparse Hessians with automatic
//! differentiation*, ACM TOMS 34 (2008), for exploiting the pairs that vanish; Schwartz, *Fast
//! probabilistic algorithms for verification of polynomial identities*, J. ACM 27 (1980).

mod augmented;
mod cluster;
mod colouring;
mod mixed;
mod root;
mod transfer;

use crate::compiled::Compiled;
use crate::dual4::Dual4;
use crate::equilibrium::Factor;
use crate::frf::{self, transfer};
use crate::implicit;
use crate::jet::Jet;
use crate::linearize::Linearization;
use crate::mechanics::ports::ports_at;
use crate::modal::cluster::{Places, of_modes};
use crate::modal::{C64, Root, Smoothness, smoothness};
use crate::output::{Missing, Output, Quantity};
use crate::pair;
use crate::program::{Tier, Workspace};
use crate::sensitivity::{DesignPoint, TransferAt};
use crate::sweep::{Point, PointError};
use cluster::ClusterTerms;
use colouring::Colouring;
use nalgebra::{Complex, DMatrix};
use num_dual::{Dual2_64, HyperDual64};
use root::{Along, RootTerms, Triple};
use std::rc::Rc;

/// Scalar of the mixed (pair) passes.
type Hd = HyperDual64;

/// How far apart (relative to their size) a single degree of freedom's two roots must lie for
/// its invariants to be taken from them rather than from the matrices: the roots' second
/// derivatives carry rounding amplified by about the inverse square of their gap, so 1e-2
/// keeps it under 1e-12 relative.
const ROOTS_APART: f64 = 1e-2;

/// The cost of a reverse sweep of [`mixed`] in lanes of a pair's pass (a pass carries three
/// lanes a free coordinate): measured on the 40-segment blade (120 lanes), a sweep of eight
/// directions costs 0.3 of a pair's pass (0.7–0.8 against 2.3–2.6 ms).
const SWEEP_LANES: f64 = 36.0;

/// First and second derivatives at one point: per output (as [`crate::output::outputs`]
/// lists them) and per mode for the discriminant `D = λ₁λ₂ − (λ₁+λ₂)²/4`; where an output is
/// not differentiable there (roots coalescing or repeated, a rigid-body mode, `H` through zero),
/// the reason instead.
#[derive(Debug, Clone)]
pub struct Hessians {
    pub gradients: Vec<Result<Vec<f64>, Missing>>,
    pub outputs: Vec<Result<DMatrix<f64>, Missing>>,
    pub discriminant_gradients: Vec<Result<Vec<f64>, Missing>>,
    pub discriminant: Vec<Result<DMatrix<f64>, Missing>>,
}

/// What every pass of one point shares: the point, Newton's Jacobian factorised once, and the
/// working memory of the recorded program's passes.
struct Expansion<'a> {
    model: &'a Compiled,
    lu: Factor,
    pt: &'a Point,
    workspace: &'a Workspace,
}

impl Hessians {
    /// Zero gradients and Hessians in `nv` variables of `outs` outputs and `nm` modes'
    /// discriminants.
    fn zeros(nv: usize, outs: usize, nm: usize) -> Hessians {
        Hessians {
            gradients: vec![Ok(vec![0.0; nv]); outs],
            outputs: vec![Ok(DMatrix::zeros(nv, nv)); outs],
            discriminant_gradients: vec![Ok(vec![0.0; nv]); nm],
            discriminant: vec![Ok(DMatrix::zeros(nv, nv)); nm],
        }
    }
}

/// The derivatives of `M̂`, `Ĉ` and `K̂` along one variable: first (`M, C, K`), then second
/// where taken.
type AlongOne = ([DMatrix<f64>; 3], Option<[DMatrix<f64>; 3]>);

impl Expansion<'_> {
    /// Per variable of `vars`: the matrices' first and second derivatives along it (first
    /// only where `second` is false: then four variables a `Dual4` pass), the augmented
    /// pencil's where `augmented` (`augmented.rs`), the reduced one's otherwise; and the whole
    /// linearisation where more than the roots reads it (`whole`; kept only then: at 160
    /// variables of an 80-segment chain the linearisations would be most of the memory).
    fn along_each(
        &self,
        p: &[f64],
        vars: &[usize],
        (second, whole, augmented): (bool, bool, bool),
    ) -> Result<(Vec<AlongOne>, Vec<Linearization<Dual2_64>>), PointError> {
        let mut singles = Vec::new();
        let mut derivatives = Vec::with_capacity(vars.len());
        if !second {
            for start in (0..vars.len()).step_by(4) {
                let s = self.linearization(&seed::<Dual4<f64>>(p, vars, |b, k| {
                    f64::from(u8::from(b == start + k))
                }))?;
                for k in 0..4.min(vars.len() - start) {
                    derivatives.push((pencil_part(&s, k, augmented), None));
                }
            }
            return Ok((derivatives, singles));
        }
        for a in 0..vars.len() {
            let s = self.linearization(&seed::<Dual2_64>(p, vars, |b, k| {
                f64::from(u8::from(a == b && k == 0))
            }))?;
            derivatives.push((
                pencil_part(&s, 0, augmented),
                Some(pencil_part(&s, 1, augmented)),
            ));
            if whole {
                singles.push(s);
            }
        }
        Ok((derivatives, singles))
    }

    /// The linearisation (ports included) at the parameters `seeded`: the equilibrium expanded
    /// by two chord steps with Newton's Jacobian on `[q_R; λ]`, then the generic linearisation
    /// over the jets, which carries the move of the equilibrium and of the independent basis.
    fn linearization<J: Jet>(&self, seeded: &[J]) -> Result<Linearization<J>, PointError> {
        self.linearization_at(seeded, J::from(self.pt.speed))
    }

    /// [`Expansion::linearization`] at the speed `speed`, a jet itself where the derivatives
    /// along the speed are asked ([`DesignPoint::linearization_over`]).
    fn linearization_at<J: Jet>(
        &self,
        seeded: &[J],
        speed: J,
    ) -> Result<Linearization<J>, PointError> {
        let Expansion {
            model,
            lu,
            pt,
            workspace,
        } = self;
        let eq = &pt.equilibrium;
        let free = &pt.linear.free;
        let nf = free.len();
        let equations = model.at(seeded, speed, (Tier::Few, workspace))?;
        let mut z: Vec<J> = (free.iter().map(|&i| eq.q[i]))
            .chain(eq.lambda.iter().copied())
            .map(J::from)
            .collect();
        let mut q: Vec<J> = eq.q.iter().map(|&v| J::from(v)).collect();
        let mut unpack = |z: &[J]| -> Vec<J> {
            for (k, &i) in free.iter().enumerate() {
                q[i] = z[k];
            }
            q.clone()
        };
        implicit::correct(
            &mut z,
            2,
            |z| equations.residual(&unpack(z), &z[nf..]),
            |r| lu.solve(r),
        )
        .ok_or(PointError::Equilibrium(
            crate::equilibrium::EquilibriumError::SingularJacobian { iterations: 0 },
        ))?;
        let q = unpack(&z);
        let lambda = &z[nf..];
        Ok(equations
            .linearize(&q, lambda, &pt.linear.independent, None)?
            .with_ports(ports_at(model.model(), seeded, speed, &q, free)?))
    }
}

/// The parameters `p` as jets whose part `k` of variable `a` (parameter `vars[a]`) is
/// `part(a, k)`, the other parameters constant.
fn seed<J: Jet>(p: &[f64], vars: &[usize], part: impl Fn(usize, usize) -> f64) -> Vec<J> {
    let mut s: Vec<J> = p.iter().map(|&v| J::from(v)).collect();
    for (a, &i) in vars.iter().enumerate() {
        s[i] = J::seeded(p[i], |k| part(a, k));
    }
    s
}

/// Entry `a` of the screening direction `w`: irregular (a golden-ratio sequence), of one
/// magnitude, alternating in sign. The results do not depend on it: a pair is left out only
/// where its mixed derivatives are zero.
fn screening(a: usize) -> f64 {
    let g = 0.618_033_988_749_895 * (a as f64 + 1.0);
    let w = 0.5 + (g - g.floor());
    if a.is_multiple_of(2) { w } else { -w }
}

/// Is part `k` of every number the roots and the transfer function read (the reduced
/// matrices, the basis, the ports) zero?
fn vanishes<J: Jet>(lin: &Linearization<J>, k: usize) -> bool {
    let zero = |v: &J| v.part(k) == 0.0;
    [&lin.m, &lin.c, &lin.k, &lin.basis]
        .iter()
        .all(|a| a.iter().all(zero))
        && lin.ports.iter().flatten().all(zero)
}

/// Part `k` of a matrix of jets.
fn part<J: Jet>(a: &DMatrix<J>, k: usize) -> DMatrix<f64> {
    a.map(|v| v.part(k))
}

/// Part `k` of the pencil's matrices `(M, C, K)`: the augmented pencil's where `augmented`,
/// the reduced one's otherwise.
fn pencil_part<J: Jet>(lin: &Linearization<J>, k: usize, augmented: bool) -> [DMatrix<f64>; 3] {
    if augmented {
        let [m, c, kk] = [&lin.m_full, &lin.c_full, &lin.k_full].map(|a| part(a, k));
        augmented::matrices([&m, &c, &kk], &part(&lin.phi, k))
    } else {
        [part(&lin.m, k), part(&lin.c, k), part(&lin.k, k)]
    }
}

/// Which variables have mixed second derivatives of the matrices with some other variable
/// (step 2 of the module documentation): none where the pass along `w` has no second part.
fn rows_with_mixed_terms(
    x: &Expansion<'_>,
    p: &[f64],
    vars: &[usize],
    rows: bool,
) -> Result<Vec<bool>, PointError> {
    let nv = vars.len();
    let pairs = nv * nv.saturating_sub(1) / 2;
    if pairs == 0 {
        return Ok(vec![false; nv]);
    }
    // Screening costs a pass and saves the pairs' passes only where they are zero: with up
    // to three pairs (three variables) it cannot save much and, where the pairs do couple
    // (a governor's few variables all move its equilibrium), it costs a pass in seven.
    if pairs <= 3 {
        return Ok(vec![true; nv]);
    }
    let along_w = x.linearization(&seed::<Dual2_64>(p, vars, |a, k| {
        if k == 0 { screening(a) } else { 0.0 }
    }))?;
    if vanishes(&along_w, 1) {
        return Ok(vec![false; nv]);
    }
    // The rows' passes (p of them) pay only where the pairs are many and get passes.
    if !rows || pairs <= 2 * nv {
        return Ok(vec![true; nv]);
    }
    let rows: Vec<bool> = (0..nv)
        .map(|a| {
            let row = x.linearization(&seed::<Hd>(p, vars, |b, k| match k {
                0 => f64::from(u8::from(a == b)),
                1 => screening(b),
                _ => 0.0,
            }))?;
            Ok(!vanishes(&row, 2))
        })
        .collect::<Result<_, PointError>>()?;
    // A pair's mixed term is in both of its rows: one row alone has none.
    Ok(if rows.iter().filter(|&&r| r).count() < 2 {
        vec![false; nv]
    } else {
        rows
    })
}

/// Each wanted root's `yᵀP_ab x` for every pair ([`mixed::pencil_pairs`]).
type PencilPairs = Vec<DMatrix<C64>>;

impl Expansion<'_> {
    /// Which variables' pairs get passes of their own, and each wanted root's mixed terms by
    /// reverse mode where `route` and the costs choose it and `possible` allows it ([`mixed`];
    /// the rows' screening is left out where reverse mode clearly costs less than the pairs).
    fn mixed_route(
        &self,
        p: &[f64],
        vars: &[usize],
        (route, possible): (MixedRoute, bool),
        wanted: Option<&[&Root]>,
    ) -> Result<(Vec<bool>, Option<PencilPairs>), PointError> {
        let (pt, nv) = (self.pt, vars.len());
        // Reverse mode applies to a recorded program, with the roots as its pencil's (`wanted`).
        let applies = possible && wanted.is_some() && self.model.program().is_some();
        let wanted = wanted.unwrap_or_default();
        let unknowns = pt.linear.free.len() + pt.equilibrium.lambda.len();
        // The parameters' own block coloured by its pattern (the products it needs, besides
        // one per coordinate the equilibrium moves along at most).
        let program = (self.model.program()).filter(|_| applies && route != MixedRoute::Passes);
        let colouring = program.map(|program| {
            let pattern = program.parameter_pattern();
            Colouring::new(nv, |a, b| pattern.contains(vars[a], vars[b]))
        });
        let directions = colouring
            .as_ref()
            .map_or(nv, |c| nv.min(c.directions + unknowns));
        let reverse = match route {
            _ if !applies => None,
            MixedRoute::Fastest => {
                Some(reverse_cost(wanted.len(), directions, pt.linear.free.len()))
            }
            MixedRoute::Reverse => Some(0.0),
            MixedRoute::Passes => None,
        };
        let pairs = (nv * nv.saturating_sub(1) / 2) as f64;
        let rows = reverse.is_none_or(|cost| cost >= pairs / 4.0);
        let mixed_rows = rows_with_mixed_terms(self, p, vars, rows)?;
        let flagged = mixed_rows.iter().filter(|&&r| r).count();
        let coupled = (flagged * flagged.saturating_sub(1) / 2) as f64;
        let pairs = match (reverse, colouring) {
            (Some(cost), Some(colouring)) if cost < coupled => {
                mixed::pencil_pairs(self, p, vars, wanted, colouring)?
            }
            _ => None,
        };
        Ok(match pairs {
            Some(pairs) => (vec![false; nv], Some(pairs)),
            None => (mixed_rows, None),
        })
    }
}

/// The cost of the roots' mixed terms by reverse mode in pair passes: per root a gradient
/// sweep and a sweep per [`crate::program::BATCH`] of the `directions` products, a sweep
/// costing [`SWEEP_LANES`] lanes of a pass; and a pass for the equilibrium's moves. (Without
/// the gradient and the moves, a governor's three coupled pairs went to reverse mode at 1.4
/// times their cost.)
fn reverse_cost(roots: usize, directions: usize, nf: usize) -> f64 {
    let sweep = (SWEEP_LANES / (3 * nf.max(1)) as f64).min(1.0);
    (roots * (directions.div_ceil(crate::program::BATCH) + 1)) as f64 * sweep + 1.0
}

/// A root's expansion: a simple root's (`root.rs`), or a repeated root's cluster's, each
/// member's (`cluster.rs`). `None` where the derivative does not exist: a variable, or a pair,
/// that splits the cluster.
trait Expanded {
    fn lambda(&self) -> C64;
    fn first(&self, a: usize) -> Option<C64>;
    fn diagonal(&self, a: usize) -> Option<C64>;
    fn mixed(&self, ab: (usize, usize), second: Option<Triple<'_>>) -> Option<C64>;
}

impl Expanded for RootTerms {
    fn lambda(&self) -> C64 {
        RootTerms::lambda(self)
    }
    fn first(&self, a: usize) -> Option<C64> {
        Some(self.first[a])
    }
    fn diagonal(&self, a: usize) -> Option<C64> {
        Some(self.diagonal[a])
    }
    fn mixed(&self, ab: (usize, usize), second: Option<Triple<'_>>) -> Option<C64> {
        Some(RootTerms::mixed(self, ab, second))
    }
}

impl Expanded for ClusterTerms {
    fn lambda(&self) -> C64 {
        ClusterTerms::lambda(self)
    }
    fn first(&self, a: usize) -> Option<C64> {
        ClusterTerms::first(self, a)
    }
    fn diagonal(&self, a: usize) -> Option<C64> {
        ClusterTerms::diagonal(self, a)
    }
    fn mixed(&self, ab: (usize, usize), second: Option<Triple<'_>>) -> Option<C64> {
        ClusterTerms::mixed(self, ab, second)
    }
}

/// A mode's second root: the first's conjugate (derivatives conjugated), or its own terms.
enum Partner {
    Conjugate,
    Own(Rc<dyn Expanded>),
}

/// A mode's two roots' expansions, or why it has none.
type ModeTerms = Result<(Rc<dyn Expanded>, Partner), Missing>;

/// The roots that need terms of their own as simple roots: each simple mode's root, and its
/// partner where that is not the conjugate, and a repeated mode's roots that are in no
/// cluster (`places`, [`cluster::of_modes`]); and per mode whether the partner is the
/// conjugate.
fn wanted_roots<'p>(
    pt: &'p Point,
    smooth: &[Smoothness],
    places: &Places,
) -> (Vec<&'p Root>, Vec<bool>) {
    let mut wanted: Vec<&Root> = Vec::new();
    let conjugate: Vec<bool> = (pt.modes.iter().zip(smooth).zip(places))
        .map(|((md, &why), &(in_r, in_q))| {
            let conjugate = md.partner_is_conjugate();
            if matches!(why, Smoothness::Simple | Smoothness::Repeated { .. }) {
                if in_r.is_none() {
                    wanted.push(&md.root);
                }
                if !conjugate && in_q.is_none() {
                    wanted.push(&md.partner);
                }
            }
            conjugate
        })
        .collect();
    (wanted, conjugate)
}

/// The roots' terms of every simple or repeated mode, or why the mode's roots have none, in
/// the pencil `nominal` whose roots `wanted` are (the reduced one, or the augmented one:
/// `augmented.rs`); `pairs`, where given, each wanted root's `yᵀP_ab x` for every pair
/// ([`mixed::pencil_pairs`]); `clusters` the repeated roots' clusters' terms, where they have
/// them, at `places`.
fn root_terms(
    smooth: &[Smoothness],
    (nominal, along): (Triple<'_>, &[Along<'_>]),
    (wanted, conjugate, places): (&[&Root], Vec<bool>, &Places),
    pairs: Option<PencilPairs>,
    clusters: &[Option<Rc<ClusterTerms>>],
) -> Vec<ModeTerms> {
    let mut terms = RootTerms::all(wanted, nominal, along, pairs).into_iter();
    let mut take = |place: Option<usize>| -> Option<Rc<dyn Expanded>> {
        match place {
            Some(g) => clusters[g].clone().map(|c| c as Rc<dyn Expanded>),
            None => terms
                .next()
                .flatten()
                .map(|t| Rc::new(t) as Rc<dyn Expanded>),
        }
    };
    (smooth.iter().zip(conjugate).zip(places))
        .enumerate()
        .map(|(i, ((&why, conjugate), &(in_r, in_q)))| {
            if !matches!(why, Smoothness::Simple | Smoothness::Repeated { .. }) {
                return Err(Missing::Mode { mode: i, why });
            }
            let first = take(in_r);
            let partner = if conjugate {
                Some(Partner::Conjugate)
            } else {
                take(in_q).map(Partner::Own)
            };
            first.zip(partner).ok_or(match why {
                Smoothness::Simple => Missing::SingularExpansion { mode: i },
                _ => Missing::Mode { mode: i, why },
            })
        })
        .collect()
}

/// `H` over jets, or why it has none.
type TransferJet<J> = Result<frf::Complex<J>, Missing>;

/// `H` as a jet where a transfer function is asked for: from its value and the parts
/// `parts(terms)` where reverse mode gave its terms (`transfer.rs`), from the linearisation
/// over the same jets otherwise.
fn transfer_jet<J: Jet>(
    tf: Option<TransferAt>,
    lin: Option<&Linearization<J>>,
    terms: Option<&(frf::Complex<f64>, Result<transfer::TransferTerms, Missing>)>,
    parts: impl Fn(&transfer::TransferTerms) -> Vec<C64>,
) -> Option<TransferJet<J>> {
    let t = tf?;
    match (terms, lin) {
        (Some((h, terms)), _) => Some(terms.as_ref().map_err(Clone::clone).map(|terms| {
            let p = parts(terms);
            frf::Complex {
                re: J::seeded(h.re, |k| p[k].re),
                im: J::seeded(h.im, |k| p[k].im),
            }
        })),
        (None, Some(lin)) => {
            Some(transfer(lin, t.input, t.output, t.omega).ok_or(Missing::TransferUnbounded))
        }
        (None, None) => None,
    }
}

/// One root as a complex jet from its value and parts.
fn complex_jet<J: Jet>(l: C64, parts: &[C64]) -> Complex<J> {
    Complex::new(
        J::seeded(l.re, |k| parts[k].re),
        J::seeded(l.im, |k| parts[k].im),
    )
}

/// The outputs `outs` and each mode's discriminant as jets, from the modes' roots as jets
/// (`roots(i)`, or why not), `H` over the same jets where a transfer function is asked for,
/// and, where the model has one degree of freedom and its invariants are taken from the
/// matrices, the linearisation over the same jets.
fn outputs_at<J: Jet>(
    pt: &Point,
    (smooth, outs): (&[Smoothness], &[Output]),
    (lin, h): (Option<&Linearization<J>>, Option<TransferJet<J>>),
    roots: impl Fn(usize) -> Result<(Complex<J>, Complex<J>), Missing>,
) -> Jets<J> {
    let one_dof = pt.linear.m.nrows() == 1;
    // Per mode: ω_d, ζ and D, or why not.
    let mode_values: Vec<[Result<J, Missing>; 3]> = pt
        .modes
        .iter()
        .zip(smooth)
        .enumerate()
        .map(|(i, (md, &why))| {
            // A repeated root's members have values where its cluster moves as one (`roots`
            // says why not otherwise); a rigid-body mode has none.
            if why == Smoothness::Rigid {
                let not = Missing::Mode { mode: i, why };
                return [
                    Err(not.clone()),
                    Err(Missing::RigidDamping { mode: i }),
                    Err(not),
                ];
            }
            // Coalescing roots are not differentiable one by one; their sum and product
            // are, and for one degree of freedom come straight from the matrices.
            let roots = roots(i);
            let invariants = match (one_dof, lin) {
                (true, Some(lin)) => {
                    let (m0, c0, k0) = (lin.m[(0, 0)], lin.c[(0, 0)], lin.k[(0, 0)]);
                    Ok((-c0 / m0, k0 / m0))
                }
                _ => roots.clone().map(|(l1, l2)| ((l1 + l2).re, (l1 * l2).re)),
            };
            let wd = roots.map(|(l1, _)| {
                if md.root.lambda.im > 0.0 {
                    l1.im
                } else {
                    J::from(0.0)
                }
            });
            let zeta = invariants.clone().map(|(s, pr)| pair::damping_ratio(s, pr));
            let d = invariants.map(|(s, pr)| pair::discriminant(s, pr));
            [wd, zeta, d]
        })
        .collect();
    // |H| is not differentiable where H passes through zero, unless H vanishes identically
    // to this order (a transfer that symmetry makes zero): then |H| ≡ 0.
    let h = h.map(|h| {
        let h = h?;
        let zero = [h.re, h.im]
            .iter()
            .all(|v| v.re() == 0.0 && (0..J::PARTS).all(|k| v.part(k) == 0.0));
        if h.magnitude().re() > 0.0 {
            Ok(h.magnitude())
        } else if zero {
            Ok(J::from(0.0))
        } else {
            Err(Missing::TransferZero)
        }
    });
    let outputs = outs
        .iter()
        .map(|o| match (o.quantity, o.mode) {
            (Quantity::DampedFrequency, Some(k)) => mode_values[k][0].clone(),
            (Quantity::DampingRatio, Some(k)) => mode_values[k][1].clone(),
            (Quantity::TransferMagnitude, _) => h.clone().unwrap_or(Err(Missing::NoValue)),
            _ => Err(Missing::NoValue),
        })
        .collect();
    (
        outputs,
        mode_values.into_iter().map(|[_, _, d]| d).collect(),
    )
}

/// The outputs `outs` and each mode's discriminant as jets.
type Jets<J> = (Vec<Result<J, Missing>>, Vec<Result<J, Missing>>);

/// Stores one gradient entry and one Hessian entry (both halves), or the first reason why not.
fn put(
    g: Option<&mut Result<Vec<f64>, Missing>>,
    h: &mut Result<DMatrix<f64>, Missing>,
    (a, b): (usize, usize),
    first: Result<f64, Missing>,
    second: Result<f64, Missing>,
) {
    let finite = |x: Result<f64, Missing>| {
        x.and_then(|x| {
            if x.is_finite() {
                Ok(x)
            } else {
                Err(Missing::NotFinite)
            }
        })
    };
    if let Some(g) = g
        && let Ok(v) = g
    {
        match finite(first) {
            Ok(x) => v[a] = x,
            Err(e) => *g = Err(e),
        }
    }
    if let Ok(m) = h {
        match finite(second) {
            Ok(x) => {
                m[(a, b)] = x;
                m[(b, a)] = x;
            }
            Err(e) => *h = Err(e),
        }
    }
}

/// A root and its parts.
type Parts = (C64, Vec<C64>);

/// The two roots of a mode with the terms `roots` (see [`root_terms`]), their parts given by
/// `parts(terms)` (the partner's the conjugates where it is the root's conjugate); where a
/// part does not exist (a split cluster), the mode's reason `why`.
fn pair(
    roots: &ModeTerms,
    why: Missing,
    parts: &dyn Fn(&dyn Expanded) -> Option<Vec<C64>>,
) -> Result<(Parts, Parts), Missing> {
    let (r, q) = roots.as_ref().map_err(Clone::clone)?;
    let first: Parts = (r.lambda(), parts(r.as_ref()).ok_or(why.clone())?);
    let second: Parts = match q {
        Partner::Conjugate => (first.0.conj(), first.1.iter().map(|z| z.conj()).collect()),
        Partner::Own(q) => (q.lambda(), parts(q.as_ref()).ok_or(why)?),
    };
    Ok((first, second))
}

/// How the roots' mixed second derivatives are taken (the results agree to rounding).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MixedRoute {
    /// Reverse mode where the variables are many and the model has no constraint equations
    /// (`mixed.rs`), a pass per coupled pair otherwise.
    Fastest,
    /// A hyper-dual pass per pair whose mixed derivatives may not vanish: the reference.
    Passes,
    /// Reverse mode wherever it applies, whatever it costs (for comparisons).
    Reverse,
}

impl DesignPoint<'_> {
    /// The linearisation (ports and unbalances included) over the jets `p` and `speed`, seeded
    /// by the caller along any parameters and the speed itself: the equilibrium expanded by two
    /// chord steps, so first derivatives and the second ones of a `Dual2` or hyper-dual seed
    /// are exact (the derivatives along the speed carry the equilibrium's move with it, the
    /// drive's rate and the excitation's frequency).
    pub fn linearization_over<J: Jet>(
        &self,
        p: &[J],
        speed: J,
    ) -> Result<Linearization<J>, PointError> {
        let lent = self.workspace();
        let x = Expansion {
            model: self.model,
            lu: self.point.equilibrium.factor(),
            pt: self.point,
            workspace: &lent,
        };
        x.linearization_at(p, speed)
    }

    /// Gradients and Hessians of `outs` (see [`crate::output::outputs`]) and of each mode's
    /// discriminant with respect to the parameters `vars`, at the design point (see the module
    /// documentation for the passes).
    pub fn hessians(&self, vars: &[usize], outs: &[Output]) -> Result<Hessians, PointError> {
        self.hessians_by(vars, outs, MixedRoute::Fastest)
    }

    /// [`DesignPoint::hessians`] with the roots' mixed terms taken by `route`.
    pub fn hessians_by(
        &self,
        vars: &[usize],
        outs: &[Output],
        route: MixedRoute,
    ) -> Result<Hessians, PointError> {
        let (model, p, pt, tf) = (self.model, self.p, self.point, self.transfer);
        let lent = self.workspace();
        let workspace: &Workspace = &lent;
        let nv = vars.len();
        let nm = pt.modes.len();
        let nf = pt.linear.free.len();
        // Newton's Jacobian, factorised once for every pass (balanced: a model's scale does not
        // cost the chord steps accuracy); the caller's workspace for every pass.
        let x = Expansion {
            model,
            lu: pt.equilibrium.factor(),
            pt,
            workspace,
        };
        let smooth = smoothness(&pt.modes);
        let shared = (smooth.as_slice(), outs);
        let lin = &pt.linear;
        // Repeated roots as clusters (`cluster.rs`), the other roots one by one.
        let (clusters, places) = of_modes(&pt.modes, &smooth, (&lin.m, &lin.c, &lin.k));
        let (wanted, conjugate) = wanted_roots(pt, &smooth, &places);
        // Each cluster's `y_iᵀ·x_j` as a root of its own (`i·k + j`), for reverse mode's
        // contractions `y_iᵀP_ab x_j`.
        let synthetic: Vec<Root> = (clusters.iter().flatten())
            .flat_map(|cl| {
                let k = cl.size();
                (0..k * k).map(move |ij| Root {
                    lambda: cl.lambda,
                    right: cl.right.column(ij % k).into_owned(),
                    left: cl.left.column(ij / k).into_owned(),
                })
            })
            .collect();
        let synthetic_refs: Vec<&Root> = synthetic.iter().collect();
        // Reverse mode can pay only where the pairs outnumber its least cost (one batch of
        // products a root, a transfer function's responses counted as a root).
        let worth = match route {
            MixedRoute::Passes => false,
            MixedRoute::Reverse => true,
            MixedRoute::Fastest => {
                let roots = wanted.len() + synthetic.len() + usize::from(tf.is_some());
                let least = reverse_cost(roots, 1, nf);
                (nv * nv.saturating_sub(1) / 2) as f64 > least
            }
        };
        // The pencil reverse mode contracts: the linearisation's own, or with constraint
        // equations the augmented one over the free coordinates and the multipliers, whose
        // roots' vectors extend the reduced ones' (`augmented.rs`).
        let constrained = !pt.equilibrium.lambda.is_empty();
        let program_nominal = (constrained && worth).then(|| augmented::nominal(lin));
        let nominal: Triple<'_> = match &program_nominal {
            Some([m, c, k]) => (m, c, k),
            None => (&lin.m, &lin.c, &lin.k),
        };
        // |H| between two free coordinates by reverse mode as well (`transfer.rs`), where it is
        // finite.
        let value = tf
            .filter(|_| worth)
            .and_then(|t| transfer(lin, t.input, t.output, t.omega));
        let responses = (tf.zip(value)).and_then(|(t, _)| {
            transfer::Responses::new(nominal, &lin.free, (t.input, t.output), t.omega)
        });
        // The linearisation over jets is needed beyond the roots for a transfer between ports,
        // and for one degree of freedom's invariants unless its roots lie well apart (where
        // they coalesce, the invariants straight from the matrices are smooth and the roots
        // are not); otherwise reverse mode may give the mixed terms.
        let one_dof = lin.m.nrows() == 1;
        let apart = smooth.iter().all(|&s| s == Smoothness::Simple)
            && (pt.modes.iter()).all(|md| {
                (md.root.lambda - md.partner.lambda).norm() >= ROOTS_APART * md.root.lambda.norm()
            });
        let reverse_possible =
            worth && (tf.is_none() || responses.is_some()) && (!one_dof || apart);
        let extended = (constrained && reverse_possible)
            .then(|| augmented::roots(lin, &wanted))
            .flatten();
        let extended: Option<Vec<&Root>> = extended.as_ref().map(|r| r.iter().collect());
        let extended_synthetic = (constrained && reverse_possible)
            .then(|| augmented::roots(lin, &synthetic_refs))
            .flatten();
        let mut program_roots = if constrained {
            (extended.clone())
                .zip(extended_synthetic.as_ref())
                .map(|(mut roots, more)| {
                    roots.extend(more);
                    roots
                })
        } else {
            Some(wanted.iter().chain(&synthetic_refs).copied().collect())
        };
        if let (Some(roots), Some(responses)) = (program_roots.as_mut(), &responses) {
            roots.push(&responses.root);
        }
        let (mixed_rows, mut pairs) =
            x.mixed_route(p, vars, (route, reverse_possible), program_roots.as_deref())?;
        let transfer_pairs = pairs
            .as_mut()
            .and_then(|pairs| responses.as_ref().and_then(|_| pairs.pop()));
        let cluster_pairs = (pairs.as_mut()).map(|p| p.split_off(p.len() - synthetic.len()));
        let whole = (tf.is_some() || one_dof) && pairs.is_none();
        // Where reverse mode gave every root's `yᵀP_ab x`, the diagonal too: the passes along
        // each variable then need first derivatives only, and the roots are taken in the
        // pencil reverse mode contracted.
        let augmented = constrained && pairs.is_some();
        let (derivatives, singles) =
            x.along_each(p, vars, (pairs.is_none() || whole, whole, augmented))?;
        let along: Vec<Along<'_>> = derivatives
            .iter()
            .map(|(d, s)| {
                (
                    (&d[0], &d[1], &d[2]),
                    s.as_ref().map(|s| (&s[0], &s[1], &s[2])),
                )
            })
            .collect();
        let (nominal, roots_in): (Triple<'_>, &[&Root]) = match &extended {
            Some(extended) if augmented => (nominal, extended),
            _ => ((&lin.m, &lin.c, &lin.k), &wanted),
        };
        let transfer_terms =
            (responses.as_ref().zip(transfer_pairs).zip(value)).map(|((responses, pairs), h)| {
                let terms = responses.terms(&along, pairs);
                (h, terms.ok_or(Missing::TransferUnbounded))
            });
        // Each cluster's terms in the pencil the roots are taken in.
        let mut at = 0;
        let cluster_terms: Vec<Option<Rc<ClusterTerms>>> = (clusters.iter())
            .map(|cl| {
                let cl = cl.as_ref().ok()?;
                let k = cl.size();
                let range = at..at + k * k;
                at += k * k;
                let bases = match &extended_synthetic {
                    Some(ext) if augmented => {
                        let ext = &ext[range.clone()];
                        let n = ext[0].right.len();
                        (
                            DMatrix::from_fn(n, k, |r, j| ext[j].right[r]),
                            DMatrix::from_fn(n, k, |r, i| ext[i * k].left[r]),
                        )
                    }
                    _ => (cl.right.clone(), cl.left.clone()),
                };
                let pairs = cluster_pairs.as_ref().map(|p| p[range].to_vec());
                ClusterTerms::new(cl.lambda, bases, nominal, &along, pairs).map(Rc::new)
            })
            .collect();
        let roots = root_terms(
            &smooth,
            (nominal, &along),
            (roots_in, conjugate, &places),
            pairs,
            &cluster_terms,
        );
        let Hessians {
            gradients: mut grad,
            outputs: mut hess,
            discriminant_gradients: mut dgrad,
            discriminant: mut dhess,
        } = Hessians::zeros(nv, outs.len(), nm);
        let pair_of = |i: usize, parts: &dyn Fn(&dyn Expanded) -> Option<Vec<C64>>| {
            pair(
                &roots[i],
                Missing::Mode {
                    mode: i,
                    why: smooth[i],
                },
                parts,
            )
        };
        for a in 0..nv {
            let single = whole.then(|| &singles[a]);
            let h = transfer_jet(tf, single, transfer_terms.as_ref(), |t| {
                vec![t.first[a], t.second[(a, a)]]
            });
            let (o, d) = outputs_at::<Dual2_64>(pt, shared, (single, h), |i| {
                pair_of(i, &|t| Some(vec![t.first(a)?, t.diagonal(a)?]))
                    .map(|((l1, p1), (l2, p2))| (complex_jet(l1, &p1), complex_jet(l2, &p2)))
            });
            for (jets, g, h) in [(&o, &mut grad, &mut hess), (&d, &mut dgrad, &mut dhess)] {
                for (k, v) in jets.iter().enumerate() {
                    let (first, second) = (v.clone().map(|x| x.v1), v.clone().map(|x| x.v2));
                    put(Some(&mut g[k]), &mut h[k], (a, a), first, second);
                }
            }
            for b in a + 1..nv {
                // The matrices' mixed derivatives: their own pass where they may not vanish.
                let mixed: Option<Linearization<Hd>> = if mixed_rows[a] && mixed_rows[b] {
                    Some(x.linearization(&seed::<Hd>(p, vars, |c, k| match k {
                        0 => f64::from(u8::from(c == a)),
                        1 => f64::from(u8::from(c == b)),
                        _ => 0.0,
                    }))?)
                } else {
                    None
                };
                let second = mixed
                    .as_ref()
                    .map(|l| [part(&l.m, 2), part(&l.c, 2), part(&l.k, 2)]);
                let second = second.as_ref().map(|s| (&s[0], &s[1], &s[2]));
                let lin = whole.then(|| {
                    let joined = singles[a].zip(&singles[b], |u, v| Hd::new(u.re, u.v1, v.v1, 0.0));
                    match &mixed {
                        Some(m) => joined.zip(m, |u, v| Hd::new(u.re, u.eps1, u.eps2, v.eps1eps2)),
                        None => joined,
                    }
                });
                let h = transfer_jet(tf, lin.as_ref(), transfer_terms.as_ref(), |t| {
                    vec![t.first[a], t.first[b], t.second[(a, b)]]
                });
                let (o, d) = outputs_at::<Hd>(pt, shared, (lin.as_ref(), h), |i| {
                    pair_of(i, &|t| {
                        Some(vec![t.first(a)?, t.first(b)?, t.mixed((a, b), second)?])
                    })
                    .map(|((l1, p1), (l2, p2))| (complex_jet(l1, &p1), complex_jet(l2, &p2)))
                });
                for (jets, h) in [(&o, &mut hess), (&d, &mut dhess)] {
                    for (k, v) in jets.iter().enumerate() {
                        put(
                            None,
                            &mut h[k],
                            (a, b),
                            Ok(0.0),
                            v.clone().map(|x| x.eps1eps2),
                        );
                    }
                }
            }
        }
        Ok(Hessians {
            gradients: grad,
            outputs: hess,
            discriminant_gradients: dgrad,
            discriminant: dhess,
        })
    }
}
