//! Equations of motion in relative coordinates (Kane / d'Alembert form) and the cut-joint
//! constraints.
//!
//! ```text
//! r(q, q̇, q̈) = Σ_bodies [ J_vᵀ (m a − m g) + J_ωᵀ (I_w α + ω × I_w ω) ] − Q_elements(q, q̇)
//! ```
//!
//! equal to the velocity-transformation form `M* = B_Rᵀ M B_R`, `Q* = B_Rᵀ Q − B_Rᵀ M Ḃ q̇`
//! (Kim & Yoo 2007, eqs. 9–12). Each joint's relative pose over `Dual2` numbers along
//! `q(t) = q + q̇ t + q̈ t²/2` gives its relative velocity and acceleration, which one pass from
//! the root composes into every body's (`motions`); one pass over
//! `Dual` numbers per coordinate, through its own joint alone, gives the partial velocities `J_v = ∂r_cm/∂q_i` and
//! `J_ω = axial(∂A/∂q_i Aᵀ)` as the twist of its joint's child (see [`Partials`]), and the
//! constraint Jacobian `Φ_q`; the projection `r_i = s_iᵀ W_i` pairs that twist with the wrench on
//! the bodies below the joint, accumulated from the leaves (O(n) for all rows).
//! The full equations are `r + Φ_qᵀ λ = Q_drive`, `Φ(q) = 0`.

use super::kinematics::{Pose, poses};
use super::{ForceData, LoadData, System};
use crate::forces::Damps;
use crate::real::{
    D1, D2, M3, Real, V3, axial, axial_tn, cst, lift1, lift2, mul3, mul3_t, mulv, mulv_t,
};
use nalgebra::DMatrix;
use num_dual::{Dual, Dual2};

/// A system lifted once into the scalars of the time pass and of the partial passes.
#[derive(Debug, Clone)]
pub struct Lifted<T: Real> {
    pub base: System<T>,
    pub time: System<D2<T>>,
    pub partial: System<D1<T>>,
}

impl<T: Real> Lifted<T> {
    pub fn new(base: System<T>) -> Self {
        Lifted {
            time: base.map(lift2),
            partial: base.map(lift1),
            base,
        }
    }
}

/// Equations of motion and constraints at one state.
#[derive(Debug, Clone)]
pub struct Dynamics<T: Real> {
    /// `r(q, q̇, q̈)`, one entry per coordinate.
    pub r: Vec<T>,
    /// `Φ(q)`, one entry per constraint equation.
    pub phi: Vec<T>,
    /// `Φ_q`, constraint equations × coordinates.
    pub phi_q: DMatrix<T>,
    /// Force of each component of each force element (N or N·m), in order.
    pub element_force: Vec<T>,
}

impl<T: Real> Dynamics<T> {
    /// `r + Φ_qᵀ λ`: the generalised forces the drives must supply (zero on free coordinates
    /// at a solution).
    pub fn with_multipliers(&self, lambda: &[T]) -> Vec<T> {
        let mut out = self.r.clone();
        for (i, o) in out.iter_mut().enumerate() {
            for (k, l) in lambda.iter().enumerate() {
                *o += self.phi_q[(k, i)] * *l;
            }
        }
        out
    }
}

/// Constraint values `Φ` at the given body poses (the cut joints') and coordinates (the
/// couplers').
pub fn constraint_values<U: Real>(sys: &System<U>, p: &[Pose<U>], q: &[U]) -> Vec<U> {
    let mut out = Vec::with_capacity(sys.m);
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(&ground, |b| &p[b]);
    for c in &sys.constraints {
        let g = &c.geometry;
        c.values(g, pose(g.body1), pose(g.body2), &mut out);
    }
    for c in &sys.couplers {
        let [i, j] = c.coordinates;
        out.push(c.coefficients[0] * q[i] + c.coefficients[1] * q[j] - c.value);
    }
    out
}

/// The redundant equations not imposed ([`crate::model::Constraint::dropped`]) at the given
/// body poses: `(constraint, value)` of each.
pub fn dropped_values<U: Real>(sys: &System<U>, p: &[Pose<U>]) -> Vec<(usize, U)> {
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(&ground, |b| &p[b]);
    let mut out = Vec::new();
    for (k, c) in sys.constraints.iter().enumerate() {
        if c.dropped.is_empty() {
            continue;
        }
        let g = &c.geometry;
        let mut all = Vec::new();
        c.kind.values(g, pose(g.body1), pose(g.body2), &mut all);
        out.extend(c.dropped.iter().map(|&e| (k, all[e])));
    }
    out
}

/// The deformation components of every force element at the given body poses, in order.
pub fn element_deformations<U: Real>(sys: &System<U>, p: &[Pose<U>]) -> Vec<U> {
    let mut out = Vec::new();
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(&ground, |b| &p[b]);
    for e in &sys.forces {
        let g = &e.geometry;
        e.kind
            .deformation(g, pose(g.body1), pose(g.body2), &mut out);
    }
    out
}

/// `Φ(q)` alone (positions only).
pub fn constraints_at<U: Real>(sys: &System<U>, q: &[U]) -> Vec<U> {
    constraint_values(sys, &poses(sys, q), q)
}

/// A screw in global axes at the global origin: a twist `(ω, v)` (a rigid velocity, the
/// velocity of a point `x` being `v + ω × x`), or a wrench `(moment about the origin, force)`.
/// A twist paired with a wrench is the power `ω·N + v·F`.
#[derive(Debug, Clone, Copy)]
pub struct Screw<T: Real> {
    pub w: V3<T>,
    pub v: V3<T>,
}

impl<T: Real> Screw<T> {
    pub fn zero() -> Self {
        let z = V3::from_element(cst::<T>(0.0));
        Screw { w: z, v: z }
    }

    /// `ω·N + v·F`.
    pub fn pair(&self, other: &Screw<T>) -> T {
        self.w.dot(&other.w) + self.v.dot(&other.v)
    }

    /// `self + other · s`.
    fn add_scaled(&mut self, other: &Screw<T>, s: T) {
        self.w += other.w * s;
        self.v += other.v * s;
    }

    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Screw<U> {
        Screw {
            w: self.w.map(f),
            v: self.v.map(f),
        }
    }
}

/// The first-order kinematics at `q` that the projection onto the coordinates needs, O(n) in
/// all (Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §2 and §5.3): a change of
/// coordinate `i` moves the bodies below its joint rigidly together, by the twist `s_i`, so
/// the partial velocities of every body are `J_ω,i = ω_i`, `J_v,i = v_i + ω_i × x_cm` (or zero for
/// the bodies above), and a generalised force is `s_i` paired with the wrench on the bodies
/// below. Force elements and constraint equations enter through their gradient with respect to
/// a twist of each end body. All of it depends on `q` only, so a linearisation in `q̇` and `q̈`
/// computes it once.
#[derive(Debug, Clone)]
pub struct Partials<T: Real> {
    /// `twist[i]`: `s_i`, for the coordinates asked for (`None` for the others).
    pub twist: Vec<Option<Screw<T>>>,
    /// The derivatives of every force element's components (see [`EndPartials`]).
    pub de: Vec<EndPartials<T>>,
    pub phi_q: DMatrix<T>,
    /// Pose of every body at `q`.
    pub pose: Vec<Pose<T>>,
    /// Centre of mass of every body at `q`.
    pub cm: Vec<V3<T>>,
}

impl<T: Real> Partials<T> {
    /// The same partials over another scalar.
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Partials<U> {
        Partials {
            twist: self.twist.iter().map(|s| s.map(|s| s.map(f))).collect(),
            de: self.de.iter().map(|e| e.map(f)).collect(),
            phi_q: self.phi_q.map(f),
            pose: self.pose.iter().map(|p| p.map(f)).collect(),
            cm: self.cm.iter().map(|x| x.map(f)).collect(),
        }
    }

    /// `J_v,i` of body `b` (zero when `b` does not move with coordinate `i`).
    pub fn jv<U: Real>(&self, sys: &System<U>, i: usize, b: usize) -> V3<T> {
        match &self.twist[i] {
            Some(s) if sys.moves(i, b) => s.v + s.w.cross(&self.cm[b]),
            _ => V3::from_element(cst(0.0)),
        }
    }

    /// `J_ω,i` of body `b`.
    pub fn jw<U: Real>(&self, sys: &System<U>, i: usize, b: usize) -> V3<T> {
        match &self.twist[i] {
            Some(s) if sys.moves(i, b) => s.w,
            _ => V3::from_element(cst(0.0)),
        }
    }
}

/// The mass matrix `∂r/∂q̈ = Σ_b (m J_vᵀ J_v + J_ωᵀ I_w J_ω)` for the coordinates `coords`,
/// from partial velocities computed for them (r is linear in q̈ with exactly these
/// coefficients, so no time pass is needed): `M_ik = s_iᵀ I_c s_k` with `I_c` the composite
/// spatial inertia of the bodies both coordinates move (Featherstone's composite-rigid-body
/// algorithm, §6.2), O(n) for the composites and O(1) per entry.
pub fn mass_matrix<T: Real>(sys: &System<D1<T>>, j: &Partials<T>, coords: &[usize]) -> DMatrix<T> {
    let nb = sys.bodies.len();
    // Composite inertia about the origin of each body and those below it: mass, first moment
    // `m x`, and `I_w + m (|x|² 1 − x xᵀ)`.
    let mut mass = vec![cst::<T>(0.0); nb];
    let mut first = vec![V3::from_element(cst::<T>(0.0)); nb];
    let mut second = vec![M3::from_element(cst::<T>(0.0)); nb];
    for (b, body) in sys.bodies.iter().enumerate() {
        let (m, x, a) = (body.mass.re, j.cm[b], &j.pose[b].rot);
        mass[b] = m;
        first[b] = x * m;
        second[b] = mul3_t(&mul3(a, &body.inertia.map(|x| x.re)), a)
            + (M3::identity() * x.dot(&x) - x * x.transpose()) * m;
    }
    for jt in sys.joints.iter().rev() {
        if let Some(p) = jt.parent {
            let c = jt.child;
            let (m, h, i) = (mass[c], first[c], second[c]);
            mass[p] += m;
            first[p] += h;
            second[p] += i;
        }
    }
    let body = |i: usize| sys.joints[sys.coord_joint[i]].child;
    let n = coords.len();
    DMatrix::from_fn(n, n, |r, c| {
        let (i, k) = (coords[r], coords[c]);
        let (bi, bk) = (body(i), body(k));
        let b = if sys.carries(bi, bk) {
            bk
        } else if sys.carries(bk, bi) {
            bi
        } else {
            return cst::<T>(0.0);
        };
        let (Some(si), Some(sk)) = (&j.twist[i], &j.twist[k]) else {
            return cst::<T>(f64::NAN);
        };
        let h = first[b];
        si.v.dot(&sk.v) * mass[b]
            + si.v.dot(&sk.w.cross(&h))
            + si.w.cross(&h).dot(&sk.v)
            + si.w.dot(&mulv(&second[b], &sk.w))
    })
}

/// Partial velocities at `q` for every coordinate; `partial` is the system lifted to `Dual<T>`.
pub fn partials<T: Real>(partial: &System<D1<T>>, q: &[T]) -> Partials<T> {
    let all: Vec<usize> = (0..q.len()).collect();
    partials_for(partial, q, &all)
}

/// `pose` moved by the twist `s` (to first order) as its dual part, from a pose with none.
fn nudged<T: Real>(pose: &Pose<D1<T>>, s: &Screw<T>) -> Pose<D1<T>> {
    let mut out = *pose;
    let trans = pose.trans.map(|c| c.re);
    let d = s.v + s.w.cross(&trans);
    for r in 0..3 {
        out.trans[r].eps = d[r];
    }
    for c in 0..3 {
        let col = s.w.cross(&V3::new(
            pose.rot[(0, c)].re,
            pose.rot[(1, c)].re,
            pose.rot[(2, c)].re,
        ));
        for r in 0..3 {
            out.rot[(r, c)].eps = col[r];
        }
    }
    out
}

/// The unit twist `k`: `0..3` a rotation about global axis `k` through the origin, `3..6` a
/// translation along axis `k − 3`.
fn unit_twist<T: Real>(k: usize) -> Screw<T> {
    let mut s = Screw::zero();
    if k < 3 {
        s.w[k] = cst(1.0);
    } else {
        s.v[k - 3] = cst(1.0);
    }
    s
}

/// The first derivatives of the values `f(pose1, pose2)` of a force element's components or
/// of a cut joint's equations, in whichever of two forms costs fewer dual evaluations (a
/// choice from the tree alone, so the same for every value of the inputs):
///
/// * per coordinate: `∂f/∂q_i` for each coordinate of `coords` that moves an end, both ends
///   moved by its twist at once (shallow trees: a few coordinates);
/// * per end body: the gradient with respect to a twist of that body alone, six evaluations
///   per end, whatever the depth (the coordinates' derivatives are then `s_i` paired with it).
#[derive(Debug, Clone)]
pub enum EndPartials<T: Real> {
    /// For each value, `(coordinate, ∂f/∂q_i)`.
    Coordinates(Vec<Vec<(usize, T)>>),
    /// For each value, `(body, ∂f/∂ξ)`.
    Bodies(Vec<Vec<(usize, Screw<T>)>>),
}

impl<T: Real> EndPartials<T> {
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> EndPartials<U> {
        match self {
            EndPartials::Coordinates(v) => EndPartials::Coordinates(
                v.iter()
                    .map(|l| l.iter().map(|&(i, d)| (i, f(d))).collect())
                    .collect(),
            ),
            EndPartials::Bodies(v) => EndPartials::Bodies(
                v.iter()
                    .map(|l| l.iter().map(|(b, g)| (*b, g.map(f))).collect())
                    .collect(),
            ),
        }
    }

    /// `∂f_k/∂q_i` for every coordinate `i` with a twist, added into `out(k, i)`.
    fn add_columns<U: Real>(
        &self,
        sys: &System<U>,
        twist: &[Option<Screw<T>>],
        mut out: impl FnMut(usize, usize, T),
    ) {
        match self {
            EndPartials::Coordinates(v) => {
                for (k, l) in v.iter().enumerate() {
                    for &(i, d) in l {
                        out(k, i, d);
                    }
                }
            }
            EndPartials::Bodies(v) => {
                for (k, l) in v.iter().enumerate() {
                    for (b, g) in l {
                        for (i, s) in twist.iter().enumerate() {
                            if let Some(s) = s
                                && sys.moves(i, *b)
                            {
                                out(k, i, s.pair(g));
                            }
                        }
                    }
                }
            }
        }
    }
}

/// [`EndPartials`] of `f` (which pushes `values` values) between the bodies `ends`.
fn end_partials<T: Real>(
    sys: &System<D1<T>>,
    p: &[Pose<D1<T>>],
    ends: [Option<usize>; 2],
    twist: &[Option<Screw<T>>],
    values: usize,
    f: impl Fn(&Pose<D1<T>>, &Pose<D1<T>>, &mut Vec<D1<T>>),
) -> EndPartials<T> {
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(ground, |b| p[b]);
    let (x1, x2) = (pose(ends[0]), pose(ends[1]));
    let moves = |i: usize, b: Option<usize>| b.is_some_and(|b| sys.moves(i, b));
    let movers: Vec<usize> = (0..twist.len())
        .filter(|&i| twist[i].is_some() && (moves(i, ends[0]) || moves(i, ends[1])))
        .collect();
    let moving_ends: Vec<usize> = (0..2)
        .filter(|&e| movers.iter().any(|&i| moves(i, ends[e])))
        .collect();
    let mut buf = Vec::with_capacity(values);
    if movers.len() <= 6 * moving_ends.len() {
        let mut out = vec![Vec::with_capacity(movers.len()); values];
        for &i in &movers {
            let s = twist[i].as_ref().expect("a mover has a twist");
            let nudge = |e: usize, x: &Pose<D1<T>>| {
                if moves(i, ends[e]) { nudged(x, s) } else { *x }
            };
            buf.clear();
            f(&nudge(0, &x1), &nudge(1, &x2), &mut buf);
            for (o, v) in out.iter_mut().zip(&buf) {
                o.push((i, v.eps));
            }
        }
        return EndPartials::Coordinates(out);
    }
    let mut out = vec![Vec::with_capacity(2); values];
    for &e in &moving_ends {
        let b = ends[e].expect("a moving end is a body");
        let mut g = vec![Screw::zero(); values];
        for k in 0..6 {
            let u = unit_twist(k);
            buf.clear();
            if e == 0 {
                f(&nudged(&x1, &u), &x2, &mut buf);
            } else {
                f(&x1, &nudged(&x2, &u), &mut buf);
            }
            for (gc, v) in g.iter_mut().zip(&buf) {
                gc.add_scaled(&u, v.eps);
            }
        }
        for (o, gc) in out.iter_mut().zip(g) {
            o.push((b, gc));
        }
    }
    EndPartials::Bodies(out)
}

/// Partial velocities for the coordinates `coords` only (one dual pass of its joint each).
/// Rows of `r` evaluated with them exist for those coordinates only; the others come out NaN.
pub fn partials_for<T: Real>(partial: &System<D1<T>>, q: &[T], coords: &[usize]) -> Partials<T> {
    let n = q.len();
    let mut qi: Vec<D1<T>> = q.iter().map(|&x| lift1(x)).collect();
    let p0 = poses(partial, &qi);
    let mut twist = vec![None; n];
    for &i in coords {
        let j = &partial.joints[partial.coord_joint[i]];
        qi[i] = Dual::new(q[i], cst(1.0));
        let rel = j.kind.relative(&j.geometry, &qi[j.coords.clone()]);
        qi[i] = lift1(q[i]);
        // The relative twist in the parent's axes (`ω_r = axial(Ṙ Rᵀ)`, the translation's rate
        // `ṫ`), turned by the parent's rotation `A_p`: `ω = A_p ω_r`, and the velocity of the
        // point at the origin `v = A_p ṫ − ω × d` with `d` the child's translation.
        let r = rel.rot.map(|c| c.re);
        let w_r = axial(&mul3_t(&rel.rot.map(|c| c.eps), &r));
        let t_d = rel.trans.map(|c| c.eps);
        let (w, t_d) = match j.parent {
            Some(p) => {
                let a_p = p0[p].rot.map(|c| c.re);
                (mulv(&a_p, &w_r), mulv(&a_p, &t_d))
            }
            None => (w_r, t_d),
        };
        let d = p0[j.child].trans.map(|c| c.re);
        twist[i] = Some(Screw {
            w,
            v: t_d - w.cross(&d),
        });
    }
    let de = partial
        .forces
        .iter()
        .map(|e| {
            let g = &e.geometry;
            end_partials(
                partial,
                &p0,
                [g.body1, g.body2],
                &twist,
                e.free.len(),
                |x1, x2, out| e.kind.deformation(g, x1, x2, out),
            )
        })
        .collect();
    let mut phi_q = DMatrix::from_element(partial.m, n, cst::<T>(0.0));
    let mut row = 0;
    for c in &partial.constraints {
        let g = &c.geometry;
        let rows = c.rows();
        end_partials(
            partial,
            &p0,
            [g.body1, g.body2],
            &twist,
            rows,
            |x1, x2, out| c.values(g, x1, x2, out),
        )
        .add_columns(partial, &twist, |k, i, d| phi_q[(row + k, i)] += d);
        row += rows;
    }
    // A coupler's row: its coefficients, at the coordinates whose partials are asked.
    for c in &partial.couplers {
        for (&i, a) in c.coordinates.iter().zip(&c.coefficients) {
            if twist[i].is_some() {
                phi_q[(row, i)] += a.re;
            }
        }
        row += 1;
    }
    Partials {
        twist,
        de,
        phi_q,
        pose: p0.iter().map(|p| p.map(|c| c.re)).collect(),
        cm: p0
            .iter()
            .zip(&partial.bodies)
            .map(|(p, b)| p.apply(&b.cm).map(|c| c.re))
            .collect(),
    }
}

/// A body's velocity and acceleration: angular in its own axes, `ω` and `α` with `Ȧ = A ω̃` and
/// `Ä = A (α̃ + ω̃²)` for its rotation `A`, and the first and second rates `ḋ`, `d̈` of its pose's
/// translation (global axes).
#[derive(Debug, Clone, Copy)]
struct Motion<T: Real> {
    /// `ω`.
    w: V3<T>,
    /// `α`.
    a: V3<T>,
    /// `ḋ`.
    d: V3<T>,
    /// `d̈`.
    dd: V3<T>,
}

/// Every body's [`Motion`] at `(q, q̇, q̈)` from its pose at `q`, in one pass from the root
/// (the forward pass of the recursive Newton–Euler algorithm: Featherstone, *Rigid Body
/// Dynamics Algorithms*, Springer 2008, §5.3, with the angular quantities in the bodies' own
/// axes). Each joint's relative pose `(R, t)` is evaluated over second-order dual numbers in
/// time, alone; its rates `ω_r = axial(RᵀṘ)`, `α_r = axial(RᵀR̈)`, `ṫ`, `ẗ` are composed with
/// the parent's (pose `A_p`):
///
/// ```text
/// ω = Rᵀω_p + ω_r        α = Rᵀα_p + (Rᵀω_p) × ω_r + α_r
/// ḋ = ḋ_p + A_p (ω_p × t + ṫ)
/// d̈ = d̈_p + A_p (α_p × t + ω_p × (ω_p × t) + 2 ω_p × ṫ + ẗ)
/// ```
///
/// Composing whole poses over dual numbers down the tree (`A = A_p R` with its rates) costs
/// twice the operations: 3×3 products of rates where these are 3-vectors.
fn motions<T: Real>(
    l: &Lifted<T>,
    pose: &[Pose<T>],
    q: &[T],
    qd: &[T],
    qdd: &[T],
) -> Vec<Motion<T>> {
    let zero = V3::from_element(cst::<T>(0.0));
    let rest = Motion {
        w: zero,
        a: zero,
        d: zero,
        dd: zero,
    };
    let mut out = vec![rest; l.base.bodies.len()];
    for j in &l.time.joints {
        let qt: Vec<D2<T>> = (j.coords.clone())
            .map(|i| Dual2::new(q[i], qd[i], qdd[i]))
            .collect();
        let rel = j.kind.relative(&j.geometry, &qt);
        let r = rel.rot.map(|c| c.re);
        let (w_r, a_r) = (
            axial_tn(&r, &rel.rot.map(|c| c.v1)),
            axial_tn(&r, &rel.rot.map(|c| c.v2)),
        );
        let t = rel.trans.map(|c| c.re);
        let (td, tdd) = (rel.trans.map(|c| c.v1), rel.trans.map(|c| c.v2));
        let (p, a_p) = match j.parent {
            Some(b) => (out[b], pose[b].rot),
            None => (rest, M3::identity()),
        };
        let w_p = mulv_t(&r, &p.w);
        let spin = p.w.cross(&td);
        out[j.child] = Motion {
            w: w_p + w_r,
            a: mulv_t(&r, &p.a) + w_p.cross(&w_r) + a_r,
            d: p.d + mulv(&a_p, &(p.w.cross(&t) + td)),
            dd: p.dd
                + mulv(
                    &a_p,
                    &(p.a.cross(&t) + p.w.cross(&p.w.cross(&t)) + spin + spin + tdd),
                ),
        };
    }
    out
}

/// The poses with their first rates (dual parts) of the bodies that force elements join (the
/// others as they are, without rates): what the elements' deformations and their rates need.
fn moving_poses<T: Real>(
    sys: &System<T>,
    pose: &[Pose<T>],
    motion: &[Motion<T>],
) -> Vec<Pose<D1<T>>> {
    let mut ends = vec![false; pose.len()];
    for e in &sys.forces {
        for b in [e.geometry.body1, e.geometry.body2].into_iter().flatten() {
            ends[b] = true;
        }
    }
    (pose.iter().zip(motion).zip(ends))
        .map(|((p, m), end)| {
            let zero = cst::<T>(0.0);
            let (rot_d, trans_d) = if end {
                let w = &m.w;
                // Ȧ = A ω̃.
                let wx = M3::new(zero, -w.z, w.y, w.z, zero, -w.x, -w.y, w.x, zero);
                (mul3(&p.rot, &wx), m.d)
            } else {
                (M3::from_element(zero), V3::from_element(zero))
            };
            Pose {
                rot: p.rot.zip_map(&rot_d, Dual::new),
                trans: p.trans.zip_map(&trans_d, Dual::new),
            }
        })
        .collect()
}

/// The torque (ground axes) of an element whose dampers act on the relative angular velocity
/// ([`Damps::RelativeAngularVelocity`]): `R₁ C ω` with `ω = R₁ᵀR₂ ω₂ − ω₁` from the bodies'
/// angular velocities in their own axes and `C` diagonal in body 1's axes. It resists on body 2
/// and drives body 1: the residual `r_i` gains `(R₁ C ω)·(J_ω₂,i − J_ω₁,i) = ∂(½ ωᵀCω)/∂q̇_i`.
fn relative_damping_torque<T: Real>(
    el: &ForceData<T>,
    pose: &[Pose<T>],
    motion: &[Motion<T>],
) -> V3<T> {
    let g = &el.geometry;
    let w2 = match g.body2 {
        Some(b) => mulv(&pose[b].rot, &motion[b].w),
        None => V3::from_element(cst::<T>(0.0)),
    };
    let (w, r1) = match g.body1 {
        Some(b) => (mulv_t(&pose[b].rot, &w2) - motion[b].w, Some(&pose[b].rot)),
        None => (w2, None),
    };
    let cw = V3::new(
        el.damping[0] * w.x,
        el.damping[1] * w.y,
        el.damping[2] * w.z,
    );
    match r1 {
        Some(r1) => mulv(r1, &cw),
        None => cw,
    }
}

/// Evaluates `r(q, q̇, q̈)`, `Φ(q)` and `Φ_q(q)`.
pub fn evaluate<T: Real>(l: &Lifted<T>, q: &[T], qd: &[T], qdd: &[T]) -> Dynamics<T> {
    evaluate_with(l, &partials(&l.partial, q), q, qd, qdd)
}

/// `r` rows for the coordinates `coords` only (others NaN), `Φ`, and the `coords` columns of
/// `Φ_q`: what the equilibrium and linearisation of the free coordinates need.
pub fn evaluate_rows<T: Real>(
    l: &Lifted<T>,
    q: &[T],
    qd: &[T],
    qdd: &[T],
    coords: &[usize],
) -> Dynamics<T> {
    evaluate_with(l, &partials_for(&l.partial, q, coords), q, qd, qdd)
}

/// As [`evaluate`], with the partial velocities at `q` already known.
pub fn evaluate_with<T: Real>(
    l: &Lifted<T>,
    j: &Partials<T>,
    q: &[T],
    qd: &[T],
    qdd: &[T],
) -> Dynamics<T> {
    let sys = &l.base;
    let n = sys.n;
    let motion = motions(l, &j.pose, q, qd, qdd);
    // The wrench of every body's inertia and weight about the origin: the moment about the
    // centre of mass `A (I α + ω × I ω)` with `I` the inertia in the reference configuration.
    let mut wrench = Vec::with_capacity(sys.bodies.len());
    for (b, body) in sys.bodies.iter().enumerate() {
        let (m, pose, x) = (&motion[b], &j.pose[b], j.cm[b]);
        let x0 = body.cm;
        let acc = mulv(&pose.rot, &(m.a.cross(&x0) + m.w.cross(&m.w.cross(&x0)))) + m.dd;
        let force = (acc - sys.gravity) * body.mass;
        let h = mulv(&body.inertia, &m.w);
        let moment = mulv(&pose.rot, &(mulv(&body.inertia, &m.a) + m.w.cross(&h)));
        wrench.push(Screw {
            w: moment + x.cross(&force),
            v: force,
        });
    }
    // The applied loads, against the inertia as the weight is: a force `f` at the point `x`
    // is the wrench `(x × f, f)` about the origin; a follower's components turn with its body.
    for load in &sys.loads {
        let (body, moment, force) = match load {
            LoadData::Force {
                body,
                point,
                force,
                follower,
            } => {
                let pose = &j.pose[*body];
                let x = pose.apply(point);
                let f = if *follower {
                    mulv(&pose.rot, force)
                } else {
                    *force
                };
                (*body, x.cross(&f), f)
            }
            LoadData::Torque {
                body,
                torque,
                follower,
            } => {
                let t = if *follower {
                    mulv(&j.pose[*body].rot, torque)
                } else {
                    *torque
                };
                (*body, t, V3::from_element(cst::<T>(0.0)))
            }
            LoadData::Coordinate { .. } => continue,
        };
        wrench[body].add_scaled(
            &Screw {
                w: moment,
                v: force,
            },
            cst(-1.0),
        );
    }
    // Each element's components over the poses with their rates (the values and their rates),
    // applied to its end bodies as the wrenches whose power on a twist is the element's.
    let mut element_force = Vec::new();
    let deformation = element_deformations(&l.partial, &moving_poses(sys, &j.pose, &motion));
    let mut e = deformation.iter();
    // Derivatives per coordinate, paired with the forces after the projection.
    let mut direct = Vec::new();
    for (el, partials) in sys.forces.iter().zip(&j.de) {
        let first = element_force.len();
        let damps = el.kind.damps();
        for c in 0..el.free.len() {
            let d = e.next().expect("one deformation per component");
            let spring = el.stiffness[c] * (d.re - el.free[c]);
            let f = match damps {
                Damps::DeformationRate => spring + el.damping[c] * d.eps,
                Damps::RelativeAngularVelocity => spring,
            };
            element_force.push(f + el.preload[c]);
        }
        if damps == Damps::RelativeAngularVelocity {
            let torque = relative_damping_torque(el, &j.pose, &motion);
            let g = &el.geometry;
            for (body, sign) in [(g.body2, 1.0), (g.body1, -1.0)] {
                if let Some(b) = body {
                    wrench[b].w += torque * cst::<T>(sign);
                }
            }
        }
        match partials {
            EndPartials::Bodies(g) => {
                for (f, ends) in element_force[first..].iter().zip(g) {
                    for (b, gc) in ends {
                        wrench[*b].add_scaled(gc, *f);
                    }
                }
            }
            EndPartials::Coordinates(_) => direct.push((first, partials)),
        }
    }
    let phi = constraint_values(sys, &j.pose, q);
    // The wrench on each body and those below it (children before parents).
    for jt in sys.joints.iter().rev() {
        if let Some(p) = jt.parent {
            let c = wrench[jt.child];
            wrench[p].add_scaled(&c, cst(1.0));
        }
    }
    // Project onto the coordinates.
    let mut r: Vec<T> = (0..n)
        .map(|i| match &j.twist[i] {
            Some(s) => s.pair(&wrench[sys.joints[sys.coord_joint[i]].child]),
            None => cst::<T>(f64::NAN),
        })
        .collect();
    for (first, partials) in direct {
        partials.add_columns(sys, &j.twist, |k, i, d| {
            r[i] += element_force[first + k] * d;
        });
    }
    for e in &sys.joint_elements {
        r[e.coord] += e.stiffness * (q[e.coord] - e.free) + e.damping * qd[e.coord];
    }
    for load in &sys.loads {
        if let LoadData::Coordinate { coordinate, value } = load {
            r[*coordinate] -= *value;
        }
    }
    Dynamics {
        r,
        phi,
        phi_q: j.phi_q.clone(),
        element_force,
    }
}

/// The equilibrium equations `F(q_R, λ) = [r_R + Φ_Rᵀλ; Φ]` at `q̈ = 0` (Kim & Yoo 2007,
/// eq. 13), for unknowns `q_R` (placed into `q`) and `λ`.
pub fn equilibrium_residual<T: Real>(
    l: &Lifted<T>,
    free: &[usize],
    q: &[T],
    qd: &[T],
    lambda: &[T],
) -> Vec<T> {
    let zero = vec![cst::<T>(0.0); q.len()];
    let d = evaluate_rows(l, q, qd, &zero, free);
    let g = d.with_multipliers(lambda);
    free.iter()
        .map(|&i| g[i])
        .chain(d.phi.iter().copied())
        .collect()
}
