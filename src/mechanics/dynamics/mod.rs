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

mod partials;

pub use partials::{
    BeamPartials, BodyPartials, EndPartials, Partials, Screw, SlicePartials, body_partials_for,
    mass_matrix, partials, partials_for,
};

use super::kinematics::{Pose, poses};
use super::{ForceData, LoadData, System};
use crate::forces::Damps;
use crate::real::{D1, D2, M3, Real, V3, axial_tn, cst, lift1, lift2, mul3, mulv, mulv_t};
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
/// angular velocities in their own axes and `C` in body 1's axes. It resists on body 2 and
/// drives body 1: the residual `r_i` gains `(R₁ C ω)·(J_ω₂,i − J_ω₁,i)`, which for a symmetric
/// `C` is `∂(½ ωᵀCω)/∂q̇_i`.
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
    let mut cw = V3::new(
        el.damping[0] * w.x,
        el.damping[1] * w.y,
        el.damping[2] * w.z,
    );
    for x in &el.cross {
        cw[x.row] += x.damping * w[x.col];
    }
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
    let motion = motions(l, &j.body.pose, q, qd, qdd);
    let mut wrench = inertia_wrenches(sys, j, &motion);
    subtract_loads(sys, j, &mut wrench);
    let (element_force, mut direct) = element_forces(l, j, &motion, &mut wrench);
    let rates = beam_inertia(l, j, &motion, &mut wrench);
    let beam_force = beam_forces(sys, j, &rates, &mut wrench);
    let phi = constraint_values(sys, &j.body.pose, q);
    // The wrench on each body and those below it (children before parents).
    for jt in sys.joints.iter().rev() {
        if let Some(p) = jt.parent {
            let c = wrench[jt.child];
            wrench[p].add_scaled(&c, cst(1.0));
        }
    }
    // Project onto the coordinates.
    let mut r: Vec<T> = (0..n)
        .map(|i| match &j.body.twist[i] {
            Some(s) => s.pair(&wrench[sys.joints[sys.coord_joint[i]].child]),
            None => cst::<T>(f64::NAN),
        })
        .collect();
    for (first, partials) in direct.drain(..) {
        partials.add_columns(sys, &j.body.twist, |k, i, d| {
            r[i] += element_force[first + k] * d;
        });
    }
    for (b, f) in j.beams.iter().zip(&beam_force) {
        if let EndPartials::Coordinates(_) = &b.elastic {
            b.elastic
                .add_columns(sys, &j.body.twist, |k, i, d| r[i] += f[k] * d);
        }
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

/// The wrench of every body's inertia and weight about the origin: the moment about the
/// centre of mass `A (I α + ω × I ω)` with `I` the inertia in the reference configuration.
fn inertia_wrenches<T: Real>(
    sys: &System<T>,
    j: &Partials<T>,
    motion: &[Motion<T>],
) -> Vec<Screw<T>> {
    let mut wrench = Vec::with_capacity(sys.bodies.len());
    for (b, body) in sys.bodies.iter().enumerate() {
        let (m, pose, x) = (&motion[b], &j.body.pose[b], j.body.cm[b]);
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
    wrench
}

/// The beams' slices' inertia and weight ([`crate::beams`]), each slice's wrench carried to
/// its elements' end bodies ([`SlicePartials::transmit`]). The element is evaluated over
/// second-order dual numbers in time from its end bodies' poses and their rates
/// (`Ȧ = A ω̃`, `Ä = A (α̃ + ω̃²)`). Its frame's angular velocity and acceleration in its own
/// axes, `Ω_e = axial(R_eᵀ Ṙ_e)` and `Ω̇_e = axial(R_eᵀ R̈_e)`, are taken once; a slice turned
/// by `Q` from the frame then has, in its section's axes (where its inertia is diagonal),
///
/// ```text
/// Ω = Qᵀ Ω_e + Ω_Q,   Ω̇ = Qᵀ Ω̇_e − Ω_Q × Qᵀ Ω_e + Ω̇_Q,   Ω_Q = axial(Qᵀ Q̇), Ω̇_Q = axial(Qᵀ Q̈)
/// ```
///
/// (from `(R_e Q)ᵀ (R_e Q)˙ = Qᵀ Ω̃_e Q + Ω̃_Q` and `Q̇ᵀ = −Ω̃_Q Qᵀ`), and the moment about its
/// centre is `R_e Q (D Ω̇ + Ω × D Ω)`: no product of two rotations over the duals per slice.
/// Returns the deformation rates `ė` of each damped beam (from the same pass).
fn beam_inertia<T: Real>(
    l: &Lifted<T>,
    j: &Partials<T>,
    motion: &[Motion<T>],
    wrench: &mut [Screw<T>],
) -> Vec<Option<Vec<T>>> {
    let sys = &l.base;
    let moving = |b: Option<usize>| -> Pose<D2<T>> {
        let Some(b) = b else {
            return Pose::identity();
        };
        let (p, m) = (&j.body.pose[b], &motion[b]);
        let wx = skew(&m.w);
        let rd = mul3(&p.rot, &wx);
        let rdd = mul3(&p.rot, &(skew(&m.a) + mul3(&wx, &wx)));
        Pose {
            rot: M3::from_fn(|r, c| Dual2::new(p.rot[(r, c)], rd[(r, c)], rdd[(r, c)])),
            trans: V3::from_fn(|r, _| Dual2::new(p.trans[r], m.d[r], m.dd[r])),
        }
    };
    let id = |x: D2<T>| x;
    let mut rates = Vec::with_capacity(sys.beams.len());
    for ((beam, time), bp) in sys.beams.iter().zip(&l.time.beams).zip(&j.beams) {
        let here = time.local(id, &moving(beam.body1), &moving(beam.body2));
        rates.push(beam.beta.is_some().then(|| {
            let mut e = Vec::with_capacity(crate::beams::COMPONENTS);
            time.deformations(id, &here, &mut e);
            e.iter().map(|c| c.v1).collect()
        }));
        let frame = here.frame.map(|c| c.re);
        let (frame_w, frame_a) = (
            axial_tn(&frame, &here.frame.map(|c| c.v1)),
            axial_tn(&frame, &here.frame.map(|c| c.v2)),
        );
        let (mass, principal) = beam.section_inertia();
        for (slice, &(xi, w)) in bp.slices.iter().zip(&crate::beams::SLICES) {
            let (centre, q) = time.section(id, &here, xi);
            let qr = q.map(|c| c.re);
            let carried = mulv_t(&qr, &frame_w);
            let own = axial_tn(&qr, &q.map(|c| c.v1));
            let omega = carried + own;
            let alpha =
                mulv_t(&qr, &frame_a) - own.cross(&carried) + axial_tn(&qr, &q.map(|c| c.v2));
            let w = cst::<T>(w);
            let (m, d) = (mass * w, principal * w);
            let h = V3::new(d.x * omega.x, d.y * omega.y, d.z * omega.z);
            let local = V3::new(d.x * alpha.x, d.y * alpha.y, d.z * alpha.z) + omega.cross(&h);
            let moment = mulv(&frame, &mulv(&qr, &local));
            let x = centre.map(|c| c.re);
            let force = (centre.map(|c| c.v2) - sys.gravity) * m;
            let w = Screw {
                w: moment + x.cross(&force),
                v: force,
            };
            slice.transmit(&w, wrench);
        }
    }
    rates
}

/// `[v]×`.
fn skew<T: Real>(v: &V3<T>) -> M3<T> {
    let z = cst::<T>(0.0);
    M3::new(z, -v.z, v.y, v.z, z, -v.x, -v.y, v.x, z)
}

/// The beams' component forces `f_c = k_c (e_c + β ė_c)` (the elements are unloaded as drawn;
/// `rates`: each damped beam's `ė`), applied to their end bodies where their derivatives are
/// per body; the rest are added per coordinate by the caller. Returns each beam's component
/// forces.
fn beam_forces<T: Real>(
    sys: &System<T>,
    j: &Partials<T>,
    rates: &[Option<Vec<T>>],
    wrench: &mut [Screw<T>],
) -> Vec<[T; crate::beams::COMPONENTS]> {
    let id = |x: T| x;
    let ground = Pose::identity();
    let pose = |b: Option<usize>| b.map_or(&ground, |b| &j.body.pose[b]);
    let mut out = Vec::with_capacity(sys.beams.len());
    let mut e = Vec::with_capacity(crate::beams::COMPONENTS);
    for ((beam, bp), rate) in sys.beams.iter().zip(&j.beams).zip(rates) {
        e.clear();
        beam.deformations(
            id,
            &beam.local(id, pose(beam.body1), pose(beam.body2)),
            &mut e,
        );
        let f = beam.forces(&e, rate.as_deref());
        if let EndPartials::Bodies(g) = &bp.elastic {
            for (fc, ends) in f.iter().zip(g) {
                for (b, gc) in ends {
                    wrench[*b].add_scaled(gc, *fc);
                }
            }
        }
        out.push(f);
    }
    out
}

/// The applied loads, against the inertia as the weight is: a force `f` at the point `x` is
/// the wrench `(x × f, f)` about the origin; a follower's components turn with its body.
/// (A load on a coordinate enters its row directly.)
fn subtract_loads<T: Real>(sys: &System<T>, j: &Partials<T>, wrench: &mut [Screw<T>]) {
    for load in &sys.loads {
        let (body, moment, force) = match load {
            LoadData::Force {
                body,
                point,
                force,
                follower,
            } => {
                let pose = &j.body.pose[*body];
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
                    mulv(&j.body.pose[*body].rot, torque)
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
}

/// Each element's components over the poses with their rates (the values and their rates),
/// applied to its end bodies as the wrenches whose power on a twist is the element's: the
/// components' forces, and the elements whose derivatives are per coordinate (the first
/// component's index and the partials), paired with the forces after the projection.
fn element_forces<'j, T: Real>(
    l: &Lifted<T>,
    j: &'j Partials<T>,
    motion: &[Motion<T>],
    wrench: &mut [Screw<T>],
) -> (Vec<T>, Vec<(usize, &'j EndPartials<T>)>) {
    let sys = &l.base;
    let mut element_force = Vec::new();
    let deformation = element_deformations(&l.partial, &moving_poses(sys, &j.body.pose, motion));
    // Derivatives per coordinate, paired with the forces after the projection.
    let mut direct = Vec::new();
    for (el, partials) in sys.forces.iter().zip(&j.de) {
        let first = element_force.len();
        let d = &deformation[first..first + el.free.len()];
        let damps = el.kind.damps();
        // The dampers on the deformation's rates (else on the relative angular velocity).
        let rates = damps == Damps::DeformationRate;
        for (c, dc) in d.iter().enumerate() {
            let spring = el.stiffness[c] * (dc.re - el.free[c]);
            let f = if rates {
                spring + el.damping[c] * dc.eps
            } else {
                spring
            };
            element_force.push(f + el.preload[c]);
        }
        for x in &el.cross {
            let spring = x.stiffness * (d[x.col].re - el.free[x.col]);
            element_force[first + x.row] += if rates {
                spring + x.damping * d[x.col].eps
            } else {
                spring
            };
        }
        if damps == Damps::RelativeAngularVelocity {
            let torque = relative_damping_torque(el, &j.body.pose, motion);
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
    (element_force, direct)
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
