//! The partial velocities: one pass over `Dual` numbers per coordinate, through its own joint
//! alone, gives the twist of its joint's child (`J_v = ∂r_cm/∂q_i`, `J_ω = axial(∂A/∂q_i Aᵀ)`),
//! the elements' deformation rates and the constraint Jacobian `Φ_q` ([`Partials`]), and from
//! them the mass matrix.

use crate::mechanics::System;
use crate::mechanics::kinematics::{Pose, poses};
use crate::real::{D1, M3, Real, V3, axial, cst, lift1, mul3, mul3_t, mulv};
use nalgebra::DMatrix;
use num_dual::Dual;

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
    pub(super) fn add_scaled(&mut self, other: &Screw<T>, s: T) {
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
    /// The bodies' poses and partial velocities.
    pub body: BodyPartials<T>,
    /// The derivatives of every force element's components (see [`EndPartials`]).
    pub de: Vec<EndPartials<T>>,
    pub phi_q: DMatrix<T>,
    /// Every beam's deformation derivatives and slices (see [`BeamPartials`]).
    pub beams: Vec<BeamPartials<T>>,
}

/// The bodies' part of [`Partials`]: their poses, centres of mass and the twists of the
/// coordinates asked for, all that the partial velocities `J_v`, `J_ω` of a body need (mode
/// shapes' motions, whirl, ports), without the elements' and beams' derivatives.
#[derive(Debug, Clone)]
pub struct BodyPartials<T: Real> {
    /// `twist[i]`: `s_i`, for the coordinates asked for (`None` for the others).
    pub twist: Vec<Option<Screw<T>>>,
    /// Pose of every body at `q`.
    pub pose: Vec<Pose<T>>,
    /// Centre of mass of every body at `q`.
    pub cm: Vec<V3<T>>,
}

/// A beam's first-order kinematics at `q`: the derivatives of its deformation components
/// ([`EndPartials`]), and for each slice ([`crate::beams::SLICES`]) its pose and the twist it
/// takes from each unit twist of each end body (`(body, [T u₀, …, T u₅])`: `u₀…u₂` rotations
/// about the global axes through the origin, `u₃…u₅` translations along them), so that a
/// wrench `W` on the slice acts on the end body as the wrench whose `k`-th component is
/// `T u_k · W`.
#[derive(Debug, Clone)]
pub struct BeamPartials<T: Real> {
    pub elastic: EndPartials<T>,
    pub slices: Vec<SlicePartials<T>>,
}

/// One slice of a beam: see [`BeamPartials`].
#[derive(Debug, Clone)]
pub struct SlicePartials<T: Real> {
    pub pose: Pose<T>,
    pub ends: Vec<(usize, [Screw<T>; 6])>,
}

impl<T: Real> BeamPartials<T> {
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> BeamPartials<U> {
        BeamPartials {
            elastic: self.elastic.map(f),
            slices: (self.slices.iter())
                .map(|s| SlicePartials {
                    pose: s.pose.map(f),
                    ends: (s.ends.iter())
                        .map(|(b, t)| (*b, t.map(|x| x.map(f))))
                        .collect(),
                })
                .collect(),
        }
    }
}

impl<T: Real> SlicePartials<T> {
    /// The slice's twist when its end bodies move with the twist `s` where `moves(body)`.
    pub fn twist(&self, s: &Screw<T>, moves: impl Fn(usize) -> bool) -> Screw<T> {
        let mut out = Screw::zero();
        for (b, t) in &self.ends {
            if moves(*b) {
                for (k, tk) in t.iter().enumerate() {
                    let c = if k < 3 { s.w[k] } else { s.v[k - 3] };
                    out.add_scaled(tk, c);
                }
            }
        }
        out
    }

    /// The wrench on each end body of the wrench `w` on the slice, added into `out`.
    pub fn transmit(&self, w: &Screw<T>, out: &mut [Screw<T>]) {
        for (b, t) in &self.ends {
            for (k, tk) in t.iter().enumerate() {
                let c = tk.pair(w);
                if k < 3 {
                    out[*b].w[k] += c;
                } else {
                    out[*b].v[k - 3] += c;
                }
            }
        }
    }
}

impl<T: Real> Partials<T> {
    /// The same partials over another scalar.
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Partials<U> {
        Partials {
            body: self.body.map(f),
            de: self.de.iter().map(|e| e.map(f)).collect(),
            phi_q: self.phi_q.map(f),
            beams: self.beams.iter().map(|b| b.map(f)).collect(),
        }
    }
}

impl<T: Real> BodyPartials<T> {
    /// The same over another scalar.
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> BodyPartials<U> {
        BodyPartials {
            twist: self.twist.iter().map(|s| s.map(|s| s.map(f))).collect(),
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
        let (m, x, a) = (body.mass.re, j.body.cm[b], &j.body.pose[b].rot);
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
    let mut out = DMatrix::from_fn(n, n, |r, c| {
        let (i, k) = (coords[r], coords[c]);
        let (bi, bk) = (body(i), body(k));
        let b = if sys.carries(bi, bk) {
            bk
        } else if sys.carries(bk, bi) {
            bi
        } else {
            return cst::<T>(0.0);
        };
        let (Some(si), Some(sk)) = (&j.body.twist[i], &j.body.twist[k]) else {
            return cst::<T>(f64::NAN);
        };
        let h = first[b];
        si.v.dot(&sk.v) * mass[b]
            + si.v.dot(&sk.w.cross(&h))
            + si.w.cross(&h).dot(&sk.v)
            + si.w.dot(&mulv(&second[b], &sk.w))
    });
    add_slices(sys, j, coords, &mut out);
    out
}

/// The beams' slices' part of the mass matrix: `Σ tᵢᵀ I_s t_k` over the slices, `tᵢ` the
/// slice's twist from coordinate `i` and `I_s` its spatial inertia about the origin.
fn add_slices<T: Real>(
    sys: &System<D1<T>>,
    j: &Partials<T>,
    coords: &[usize],
    out: &mut DMatrix<T>,
) {
    for (beam, bp) in sys.beams.iter().zip(&j.beams) {
        for (slice, &(_, w)) in bp.slices.iter().zip(&crate::beams::SLICES) {
            let (m, inertia) = beam.slice_inertia(w);
            let (m, inertia) = (m.re, inertia.map(|x| x.re));
            let (a, x) = (&slice.pose.rot, slice.pose.trans);
            let h = x * m;
            let second = mul3_t(&mul3(a, &inertia), a)
                + (M3::identity() * x.dot(&x) - x * x.transpose()) * m;
            // The slice's twist from each coordinate that moves one of its ends.
            let twists: Vec<(usize, Screw<T>)> = (coords.iter().enumerate())
                .filter_map(|(r, &i)| {
                    let s = j.body.twist[i].as_ref()?;
                    let moved = |b: usize| sys.moves(i, b);
                    slice
                        .ends
                        .iter()
                        .any(|(b, _)| moved(*b))
                        .then(|| (r, slice.twist(s, moved)))
                })
                .collect();
            for (r, ti) in &twists {
                for (c, tk) in &twists {
                    out[(*r, *c)] += ti.v.dot(&tk.v) * m
                        + ti.v.dot(&tk.w.cross(&h))
                        + ti.w.cross(&h).dot(&tk.v)
                        + ti.w.dot(&mulv(&second, &tk.w));
                }
            }
        }
    }
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
///   Values that a common rigid motion of both ends leaves unchanged (a beam's deformations)
///   have opposite gradients at the two ends: six evaluations in all.
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
    pub(super) fn add_columns<U: Real>(
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

/// The mechanism at `q` as [`end_partials`] reads it: the system, its bodies' poses and each
/// coordinate's twist (`None` for the coordinates whose partials are not asked).
struct Moving<'a, T: Real> {
    sys: &'a System<D1<T>>,
    poses: &'a [Pose<D1<T>>],
    twist: &'a [Option<Screw<T>>],
}

/// [`EndPartials`] of `f` (which pushes `values` values) between the bodies `ends`; `objective`:
/// `f` is unchanged by a common rigid motion of both ends.
fn end_partials<T: Real>(
    at: &Moving<'_, T>,
    ends: [Option<usize>; 2],
    values: usize,
    objective: bool,
    f: impl Fn(&Pose<D1<T>>, &Pose<D1<T>>, &mut Vec<D1<T>>),
) -> EndPartials<T> {
    let Moving {
        sys,
        poses: p,
        twist,
    } = *at;
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
    // Values that a common rigid motion of both ends leaves unchanged have opposite gradients
    // at the two ends: six evaluations give both.
    let paired = objective && moving_ends.len() == 2;
    let per_body = if paired { 6 } else { 6 * moving_ends.len() };
    let mut buf = Vec::with_capacity(values);
    if movers.len() <= per_body {
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
    let evaluated = if paired {
        &moving_ends[1..]
    } else {
        &moving_ends[..]
    };
    for &e in evaluated {
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
            if paired {
                let mut opposite = Screw::zero();
                opposite.add_scaled(&gc, cst(-1.0));
                o.push((ends[0].expect("a moving end is a body"), opposite));
            }
            o.push((b, gc));
        }
    }
    EndPartials::Bodies(out)
}

/// The bodies' poses (dual parts zero: what the elements' partials are evaluated at) and their
/// [`BodyPartials`] for the coordinates `coords` (one dual pass of each one's joint).
fn moving_bodies<T: Real>(
    partial: &System<D1<T>>,
    q: &[T],
    coords: &[usize],
) -> (Vec<Pose<D1<T>>>, BodyPartials<T>) {
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
    let body = BodyPartials {
        twist,
        pose: p0.iter().map(|p| p.map(|c| c.re)).collect(),
        cm: p0
            .iter()
            .zip(&partial.bodies)
            .map(|(p, b)| p.apply(&b.cm).map(|c| c.re))
            .collect(),
    };
    (p0, body)
}

/// The bodies' partial velocities for the coordinates `coords` ([`BodyPartials`]): what a
/// mode's motions need, without the force elements, constraints and beams of
/// [`partials_for`].
pub fn body_partials_for<T: Real>(
    partial: &System<D1<T>>,
    q: &[T],
    coords: &[usize],
) -> BodyPartials<T> {
    moving_bodies(partial, q, coords).1
}

/// Partial velocities for the coordinates `coords` only (one dual pass of its joint each).
/// Rows of `r` evaluated with them exist for those coordinates only; the others come out NaN.
pub fn partials_for<T: Real>(partial: &System<D1<T>>, q: &[T], coords: &[usize]) -> Partials<T> {
    let n = q.len();
    let (p0, body) = moving_bodies(partial, q, coords);
    let at = Moving {
        sys: partial,
        poses: &p0,
        twist: &body.twist,
    };
    let de = partial
        .forces
        .iter()
        .map(|e| {
            let g = &e.geometry;
            end_partials(
                &at,
                [g.body1, g.body2],
                e.free.len(),
                false,
                |x1, x2, out| e.kind.deformation(g, x1, x2, out),
            )
        })
        .collect();
    let beams = (partial.beams.iter())
        .map(|b| beam_partials(&at, b))
        .collect();
    let mut phi_q = DMatrix::from_element(partial.m, n, cst::<T>(0.0));
    let mut row = 0;
    for c in &partial.constraints {
        let g = &c.geometry;
        let rows = c.rows();
        end_partials(&at, [g.body1, g.body2], rows, false, |x1, x2, out| {
            c.values(g, x1, x2, out)
        })
        .add_columns(partial, &body.twist, |k, i, d| phi_q[(row + k, i)] += d);
        row += rows;
    }
    // A coupler's row: its coefficients, at the coordinates whose partials are asked.
    for c in &partial.couplers {
        for (&i, a) in c.coordinates.iter().zip(&c.coefficients) {
            if body.twist[i].is_some() {
                phi_q[(row, i)] += a.re;
            }
        }
        row += 1;
    }
    Partials {
        body,
        de,
        phi_q,
        beams,
    }
}

/// A beam's [`BeamPartials`] at the poses of `at`. The element at six unit twists of an end
/// body ([`crate::beams::Local`] over dual numbers) gives both the deformations' gradient and,
/// through [`crate::beams::SliceMap`], every slice's twist: a common rigid motion of both ends
/// moves every value rigidly with it (the element frame is objective), so with two moving ends
/// only the second is evaluated, the first end's gradient being the opposite and a slice's
/// twist from its unit twist `u` being `u` less its twist from `u` of the second.
fn beam_partials<T: Real>(at: &Moving<'_, T>, b: &crate::beams::Element<D1<T>>) -> BeamPartials<T> {
    let id = |x: D1<T>| x;
    let re = |x: D1<T>| x.re;
    let ground = Pose::identity();
    let pose = |e: Option<usize>| e.map_or(ground, |e| at.poses[e]);
    let (x1, x2) = (pose(b.body1), pose(b.body2));
    let here = b.local(id, &x1, &x2).map(re);
    let maps: Vec<_> = (crate::beams::SLICES.iter())
        .map(|&(xi, _)| b.slice_map(re, &here, xi))
        .collect();
    let mut slices: Vec<SlicePartials<T>> = (crate::beams::SLICES.iter())
        .map(|&(xi, _)| SlicePartials {
            pose: b.slice(re, &here, xi),
            ends: Vec::with_capacity(2),
        })
        .collect();
    let values = crate::beams::COMPONENTS;
    let mut elastic: Vec<Vec<_>> = (0..values).map(|_| Vec::with_capacity(2)).collect();
    let both = b.body1.is_some() && b.body2.is_some();
    let mut buf = Vec::with_capacity(values);
    for (end, body) in [b.body1, b.body2].into_iter().enumerate() {
        let Some(body) = body else { continue };
        if both && end == 0 {
            continue;
        }
        let mut gradient = vec![Screw::zero(); values];
        let mut twists = vec![[Screw::zero(); 6]; slices.len()];
        for k in 0..6 {
            let u = unit_twist(k);
            let local = if end == 0 {
                b.local(id, &nudged(&x1, &u), &x2)
            } else {
                b.local(id, &x1, &nudged(&x2, &u))
            };
            buf.clear();
            b.deformations(id, &local, &mut buf);
            for (g, v) in gradient.iter_mut().zip(&buf) {
                g.add_scaled(&u, v.eps);
            }
            let rate = crate::beams::LocalRate::of(&local);
            for (t, m) in twists.iter_mut().zip(&maps) {
                let (w, x) = m.motion(&rate);
                t[k] = Screw {
                    w,
                    v: x - w.cross(&m.centre),
                };
            }
        }
        for (o, g) in elastic.iter_mut().zip(gradient) {
            if let (true, Some(first)) = (both, b.body1) {
                let mut opposite = Screw::zero();
                opposite.add_scaled(&g, cst(-1.0));
                o.push((first, opposite));
            }
            o.push((body, g));
        }
        for (s, t) in slices.iter_mut().zip(twists) {
            if let (true, Some(first)) = (both, b.body1) {
                let of_first: [Screw<T>; 6] = std::array::from_fn(|k| {
                    let mut f = unit_twist(k);
                    f.add_scaled(&t[k], cst(-1.0));
                    f
                });
                s.ends.push((first, of_first));
            }
            s.ends.push((body, t));
        }
    }
    BeamPartials {
        elastic: EndPartials::Bodies(elastic),
        slices,
    }
}
