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
use crate::real::{M3, Real, V3, cst};

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
        self.rot * x0 + self.trans
    }
}

/// Rotation by `angle` about the unit vector `a` (Rodrigues' formula).
pub fn rotation<T: Real>(a: &V3<T>, angle: T) -> M3<T> {
    let (s, c) = angle.sin_cos();
    let one = cst::<T>(1.0);
    let k = M3::new(
        cst(0.0),
        -a.z,
        a.y,
        a.z,
        cst(0.0),
        -a.x,
        -a.y,
        a.x,
        cst(0.0),
    );
    M3::identity() * c + k * s + (a * a.transpose()) * (one - c)
}

/// Poses of all bodies at coordinates `q` (ground excluded).
pub fn poses<T: Real>(sys: &System<T>, q: &[T]) -> Vec<Pose<T>> {
    let mut out = vec![Pose::identity(); sys.bodies.len()];
    for j in &sys.joints {
        let parent = j.parent.map_or(Pose::identity(), |p| out[p]);
        let rel = match (j.kind, j.coord) {
            (JointKind::Revolute, Some(c)) => {
                let r = rotation(&j.axis, q[c]);
                Pose {
                    rot: r,
                    trans: j.at - r * j.at,
                }
            }
            (JointKind::Prismatic, Some(c)) => Pose {
                rot: M3::identity(),
                trans: j.axis * q[c],
            },
            _ => Pose::identity(),
        };
        out[j.child] = Pose {
            rot: parent.rot * rel.rot,
            trans: parent.rot * rel.trans + parent.trans,
        };
    }
    out
}

/// Current position of a point on `body` (`None` = ground) given in the reference configuration.
pub fn point<T: Real>(poses: &[Pose<T>], body: Option<usize>, x0: &V3<T>) -> V3<T> {
    match body {
        Some(b) => poses[b].apply(x0),
        None => *x0,
    }
}
