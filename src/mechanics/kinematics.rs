//! Tree kinematics: body poses as functions of the joint coordinates.
//!
//! A body's pose maps a point given in the reference configuration to where it is now:
//! `x = A x₀ + d`. Ground is the identity; a child's pose is its parent's composed with the
//! joint's relative motion, itself expressed in the reference configuration:
//!
//! ```text
//! revolute  (axis a through p, angle q):  x₀ ↦ Rot(a, q)(x₀ − p) + p
//! prismatic (axis a, travel q):           x₀ ↦ x₀ + q a
//! fixed:                                  x₀ ↦ x₀
//! ```
//!
//! So `q = 0` everywhere is the reference configuration. Written once over [`Real`]: with dual
//! numbers in time this gives velocities and accelerations, with dual numbers in `q` the partial
//! velocities.

use super::System;
use crate::model::JointKind;
use crate::real::{M3, Real, V3, cst, mul3, mulv};

/// Rigid motion of a body from the reference configuration: `x = rot · x₀ + trans`.
#[derive(Debug, Clone, Copy)]
pub struct Pose<T: Real> {
    pub rot: M3<T>,
    pub trans: V3<T>,
}

impl<T: Real> Pose<T> {
    /// Identity (ground).
    pub fn identity() -> Self {
        Pose {
            rot: M3::identity(),
            trans: V3::zeros(),
        }
    }

    /// Current position of a point given in the reference configuration.
    pub fn apply(&self, x0: &V3<T>) -> V3<T> {
        mulv(&self.rot, x0) + self.trans
    }
}

/// Rotation by `angle` about the unit vector `a` (Rodrigues' formula):
/// `R = cos q I + sin q [a]× + (1 − cos q) a aᵀ`.
pub fn rotation<T: Real>(a: &V3<T>, angle: T) -> M3<T> {
    let (s, c) = angle.sin_cos();
    let v = cst::<T>(1.0) - c;
    let (x, y, z) = (a.x, a.y, a.z);
    let (xs, ys, zs) = (x * s, y * s, z * s);
    M3::new(
        c + x * x * v,
        x * y * v - zs,
        x * z * v + ys,
        y * x * v + zs,
        c + y * y * v,
        y * z * v - xs,
        z * x * v - ys,
        z * y * v + xs,
        c + z * z * v,
    )
}

/// Poses of all bodies at coordinates `q` (ground excluded).
pub fn poses<T: Real>(sys: &System<T>, q: &[T]) -> Vec<Pose<T>> {
    let mut out = vec![Pose::identity(); sys.bodies.len()];
    update(sys, q, &mut out, 0..sys.joints.len());
    out
}

/// Recomputes the children of the joints `which` (indices into `sys.joints`, parents first),
/// leaving the other poses in `out` as they are.
pub fn update<T: Real>(
    sys: &System<T>,
    q: &[T],
    out: &mut [Pose<T>],
    which: impl IntoIterator<Item = usize>,
) {
    for ji in which {
        let j = &sys.joints[ji];
        let parent = j.parent.map_or(Pose::identity(), |p| out[p]);
        let rel = match (j.kind, j.coord) {
            (JointKind::Revolute, Some(c)) => {
                let r = rotation(&j.axis, q[c]);
                Pose {
                    rot: r,
                    trans: j.at - mulv(&r, &j.at),
                }
            }
            (JointKind::Prismatic, Some(c)) => Pose {
                rot: M3::identity(),
                trans: j.axis * q[c],
            },
            _ => Pose::identity(),
        };
        out[j.child] = Pose {
            rot: mul3(&parent.rot, &rel.rot),
            trans: mulv(&parent.rot, &rel.trans) + parent.trans,
        };
    }
}

/// Current position of a point on `body` (`None` = ground) given in the reference configuration.
pub fn point<T: Real>(poses: &[Pose<T>], body: Option<usize>, x0: &V3<T>) -> V3<T> {
    match body {
        Some(b) => poses[b].apply(x0),
        None => *x0,
    }
}
