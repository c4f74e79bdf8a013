//! Revolute (hinge) cut joint: the points coincide (three equations, in body 1's axes as for
//! the [`super::point`] cut joint) and `axis`, attached to
//! both bodies as it lies in the reference configuration, stays the same line in both (two
//! equations): `(A₂ a)·(A₁ e₁) = 0` and `(A₂ a)·(A₁ e₂) = 0` for unit vectors `e₁`, `e₂`
//! perpendicular to `a` (`e₁` in the plane of `a` and `axis2`). Five equations.

use super::{CutType, Geometry};
use crate::joints::Use;
use crate::real::{Real, V3, mulv};
use crate::rigid::{Pose, perpendicular};

pub struct Revolute;

impl CutType for Revolute {
    const NAME: &'static str = "revolute";
    const EQUATIONS: usize = 5;
    const POINT2: Use = Use::Optional;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Optional;
    const LENGTH: Use = Use::Unused;
    const DISTINCT_POINTS: bool = false;

    #[inline]
    fn equations<T: Real>(g: &Geometry<V3<T>, T>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let d = x1.local(&(x2.apply(&g.point2) - x1.apply(&g.point1)));
        let e1 = perpendicular(&g.axis, &g.axis2);
        let e2 = g.axis.cross(&e1);
        let a2 = mulv(&x2.rot, &g.axis);
        out.extend([
            d.x,
            d.y,
            d.z,
            a2.dot(&mulv(&x1.rot, &e1)),
            a2.dot(&mulv(&x1.rot, &e2)),
        ]);
    }
}
