//! Universal (Hooke, cardan) joint: rotation `q₁` (rad) about `axis`, fixed in the parent, then
//! `q₂` about `axis2`, fixed in the child (the cross's second pin), both through `at`:
//! `x₀ ↦ Rot(axis, q₁) Rot(axis2, q₂) (x₀ − at) + at`. The axes need not be perpendicular, only
//! not parallel. It is exactly two revolute joints through one point with a massless body
//! between them.

use super::{CoordinateSpec, Geometry, JointType, Use, angle};
use crate::real::{Real, V3, mul3};
use crate::rigid::{Pose, rotation};

pub struct Universal;

impl JointType for Universal {
    const NAME: &'static str = "universal";
    const COORDINATES: &'static [CoordinateSpec] = &[angle("angle1"), angle("angle2")];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Required;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        let r = mul3(&rotation(&g.axis, q[0]), &rotation(&g.axis2, q[1]));
        Pose::about(r, &g.at)
    }
}
