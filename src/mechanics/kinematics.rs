//! Tree kinematics: body poses as functions of the joint coordinates.
//!
//! A body's pose maps a point given in the reference configuration to where it is now:
//! `x = A x₀ + d`. Ground is the identity; a child's pose is its parent's composed with the
//! joint's relative motion ([`crate::joints`], one file per joint type), itself expressed in the
//! reference configuration; `q = 0` everywhere is the reference configuration. Written once over
//! [`Real`]: with dual numbers in time this gives velocities and accelerations, with dual numbers
//! in `q` the partial velocities.

use super::System;
use crate::real::Real;
pub use crate::rigid::Pose;

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
        let rel = j.kind.relative(&j.geometry, &q[j.coords.clone()]);
        out[j.child] = match j.parent {
            Some(p) => out[p].then(&rel),
            None => rel,
        };
    }
}
