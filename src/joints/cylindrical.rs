//! Cylindrical joint: rotation `q₁` (rad) about `axis` through `at` and translation `q₂` (m)
//! along it: `x₀ ↦ Rot(axis, q₁)(x₀ − at) + at + q₂ axis`.

use super::{CoordinateSpec, Geometry, JointType, Use, angle, length};
use crate::real::{Real, V3};
use crate::rigid::{Pose, rotation};

pub struct Cylindrical;

impl JointType for Cylindrical {
    const NAME: &'static str = "cylindrical";
    const COORDINATES: &'static [CoordinateSpec] = &[angle("angle"), length("slide")];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        Pose::about(rotation(&g.axis, q[0]), &g.at).shifted(g.axis * q[1])
    }
}
