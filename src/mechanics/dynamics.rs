//! Equations of motion in relative coordinates (Kane / d'Alembert form) and the cut-joint
//! constraints.
//!
//! ```text
//! r(q, q̇, q̈) = Σ_bodies [ J_vᵀ (m a − m g) + J_ωᵀ (I_w α + ω × I_w ω) ] − Q_elements(q, q̇)
//! ```
//!
//! equal to the velocity-transformation form `M* = B_Rᵀ M B_R`, `Q* = B_Rᵀ Q − B_Rᵀ M Ḃ q̇`
//! (Kim & Yoo 2007, eqs. 9–12). One pass over `Dual2` numbers along `q(t) = q + q̇ t + q̈ t²/2`
//! gives every body's velocity and acceleration (`ω̃ = Ȧ Aᵀ`, `α̃ = skew(Ä Aᵀ)`); one pass over
//! `Dual` numbers per coordinate gives the partial velocities `J_v = ∂r_cm/∂q_i` and
//! `J_ω = axial(∂A/∂q_i Aᵀ)`, and in the same pass the constraint Jacobian `Φ_q`.
//! The full equations are `r + Φ_qᵀ λ = Q_drive`, `Φ(q) = 0`.

use super::System;
use super::kinematics::{Pose, poses, update};
use crate::real::{D1, D2, M3, Real, V3, axial, cst, lift1, lift2, mul3, mul3_t, mulv};
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

/// Constraint values `Φ` at the given body poses.
pub fn constraint_values<U: Real>(sys: &System<U>, p: &[Pose<U>]) -> Vec<U> {
    let mut out = Vec::with_capacity(sys.m);
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(&ground, |b| &p[b]);
    for c in &sys.constraints {
        let g = &c.geometry;
        c.kind.values(g, pose(g.body1), pose(g.body2), &mut out);
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
    constraint_values(sys, &poses(sys, q))
}

/// Partial velocities at `q`, one dual pass per coordinate: for coordinate `i`, `J_v` and
/// `J_ω` of every body, `∂ℓ/∂q_i` of every spring-damper, and column `i` of `Φ_q`. They depend
/// on `q` only, so a linearisation in `q̇` and `q̈` computes them once.
#[derive(Debug, Clone)]
pub struct Partials<T: Real> {
    /// `jv[i][b]`: ∂(centre of mass of body b)/∂q_i.
    pub jv: Vec<Vec<V3<T>>>,
    /// `jw[i][b]`: ∂ω_b/∂q̇_i.
    pub jw: Vec<Vec<V3<T>>>,
    /// `de[i][c]`: ∂e_c/∂q_i for every component `c` of every force element, in order.
    pub de: Vec<Vec<T>>,
    pub phi_q: DMatrix<T>,
    /// Rotation of every body at `q`.
    pub rot: Vec<M3<T>>,
}

impl<T: Real> Partials<T> {
    /// The same partials over another scalar.
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Partials<U> {
        Partials {
            jv: self
                .jv
                .iter()
                .map(|v| v.iter().map(|x| x.map(f)).collect())
                .collect(),
            jw: self
                .jw
                .iter()
                .map(|v| v.iter().map(|x| x.map(f)).collect())
                .collect(),
            de: self
                .de
                .iter()
                .map(|v| v.iter().map(|&x| f(x)).collect())
                .collect(),
            phi_q: self.phi_q.map(f),
            rot: self.rot.iter().map(|r| r.map(f)).collect(),
        }
    }
}

/// The mass matrix `∂r/∂q̈ = Σ_b (m J_vᵀ J_v + J_ωᵀ I_w J_ω)` for the coordinates `coords`,
/// from partial velocities computed for them (r is linear in q̈ with exactly these
/// coefficients, so no time pass is needed).
pub fn mass_matrix<T: Real>(sys: &System<D1<T>>, j: &Partials<T>, coords: &[usize]) -> DMatrix<T> {
    let n = coords.len();
    let iw: Vec<M3<T>> = sys
        .bodies
        .iter()
        .zip(&j.rot)
        .map(|(b, a)| mul3_t(&mul3(a, &b.inertia.map(|x| x.re)), a))
        .collect();
    DMatrix::from_fn(n, n, |r, c| {
        let (i, k) = (coords[r], coords[c]);
        let mut s = cst::<T>(0.0);
        for (b, body) in sys.bodies.iter().enumerate() {
            s += j.jv[i][b].dot(&j.jv[k][b]) * body.mass.re
                + j.jw[i][b].dot(&mulv(&iw[b], &j.jw[k][b]));
        }
        s
    })
}

/// Partial velocities at `q` for every coordinate; `partial` is the system lifted to `Dual<T>`.
pub fn partials<T: Real>(partial: &System<D1<T>>, q: &[T]) -> Partials<T> {
    let all: Vec<usize> = (0..q.len()).collect();
    partials_for(partial, q, &all)
}

/// Partial velocities for the coordinates `coords` only (one dual pass each). Rows of `r`
/// evaluated with them exist for those coordinates only; the others come out NaN.
pub fn partials_for<T: Real>(partial: &System<D1<T>>, q: &[T], coords: &[usize]) -> Partials<T> {
    let n = q.len();
    let mut out = Partials {
        jv: Vec::with_capacity(n),
        jw: Vec::with_capacity(n),
        de: Vec::with_capacity(n),
        phi_q: DMatrix::from_element(partial.m, n, cst::<T>(0.0)),
        rot: Vec::new(),
    };
    let mut qi: Vec<D1<T>> = q.iter().map(|&x| lift1(x)).collect();
    // Poses without derivative, once; per coordinate only the bodies below its joint move, so
    // only their poses are recomputed (and restored afterwards).
    let p0 = poses(partial, &qi);
    out.rot = p0.iter().map(|p| p.rot.map(|c| c.re)).collect();
    let mut pp = p0.clone();
    let zero = V3::from_element(cst::<T>(0.0));
    for i in 0..n {
        if !coords.contains(&i) {
            out.jv.push(Vec::new());
            out.jw.push(Vec::new());
            out.de.push(Vec::new());
            continue;
        }
        qi[i] = Dual::new(q[i], cst(1.0));
        update(partial, &qi, &mut pp, partial.subtree[i].iter().copied());
        qi[i] = lift1(q[i]);
        let (mut jv, mut jw) = (vec![zero; pp.len()], vec![zero; pp.len()]);
        for &ji in &partial.subtree[i] {
            let b = partial.joints[ji].child;
            let pose = &pp[b];
            let x = pose.apply(&partial.bodies[b].cm);
            jv[b] = x.map(|c| c.eps);
            let a = pose.rot.map(|c| c.re);
            let ae = pose.rot.map(|c| c.eps);
            jw[b] = axial(&mul3_t(&ae, &a));
        }
        out.jv.push(jv);
        out.jw.push(jw);
        out.de.push(
            element_deformations(partial, &pp)
                .iter()
                .map(|e| e.eps)
                .collect(),
        );
        for (k, c) in constraint_values(partial, &pp).iter().enumerate() {
            out.phi_q[(k, i)] = c.eps;
        }
        for &ji in &partial.subtree[i] {
            let b = partial.joints[ji].child;
            pp[b] = p0[b];
        }
    }
    out
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
    // Time pass: velocities and accelerations of every body.
    let qt: Vec<D2<T>> = (0..n).map(|i| Dual2::new(q[i], qd[i], qdd[i])).collect();
    let pt = poses(&l.time, &qt);
    let mut force = Vec::with_capacity(sys.bodies.len());
    let mut moment = Vec::with_capacity(sys.bodies.len());
    for (b, body) in sys.bodies.iter().enumerate() {
        let x = pt[b].apply(&l.time.bodies[b].cm);
        let acc = x.map(|c| c.v2);
        let a = pt[b].rot.map(|c| c.re);
        let ad = pt[b].rot.map(|c| c.v1);
        let add = pt[b].rot.map(|c| c.v2);
        let omega = axial(&mul3_t(&ad, &a));
        let alpha = axial(&mul3_t(&add, &a));
        let iw = mul3_t(&mul3(&a, &body.inertia), &a);
        force.push((acc - sys.gravity) * body.mass);
        let h = mulv(&iw, &omega);
        moment.push(mulv(&iw, &alpha) + omega.cross(&h));
    }
    // Each element's components over the time pass: the values and their rates.
    let mut element_force = Vec::new();
    let deformation = element_deformations(&l.time, &pt);
    let mut e = deformation.iter();
    for el in &sys.forces {
        for c in 0..el.free.len() {
            let d = e.next().expect("one deformation per component");
            element_force
                .push(el.stiffness[c] * (d.re - el.free[c]) + el.damping[c] * d.v1 + el.preload[c]);
        }
    }
    let phi: Vec<T> = constraint_values(&l.time, &pt)
        .iter()
        .map(|c| c.re)
        .collect();
    // Project onto the partial velocities.
    let mut r: Vec<T> = (0..n)
        .map(|i| {
            if j.jv[i].is_empty() && !sys.bodies.is_empty() {
                return cst::<T>(f64::NAN);
            }
            let mut ri = cst::<T>(0.0);
            for b in 0..sys.bodies.len() {
                ri += j.jv[i][b].dot(&force[b]) + j.jw[i][b].dot(&moment[b]);
            }
            for (f, d) in element_force.iter().zip(&j.de[i]) {
                ri += *f * *d;
            }
            ri
        })
        .collect();
    for e in &sys.joint_elements {
        r[e.coord] += e.stiffness * (q[e.coord] - e.free) + e.damping * qd[e.coord];
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
