//! Planar joint: motion in the plane through `at` normal to `axis`. Translations `q₁` along
//! `e₁` (the part of `axis2` perpendicular to `axis`, normalised) and `q₂` along
//! `e₂ = axis × e₁` (m), and rotation `q₃` (rad) about `axis` through the moved point:
//! `x₀ ↦ Rot(axis, q₃)(x₀ − at) + at + q₁ e₁ + q₂ e₂`.

use super::{CoordinateSpec, Geometry, JointType, Use, angle, length};
use crate::real::{Real, V3};
use crate::rigid::{Pose, perpendicular, rotation};

pub struct Planar;

impl JointType for Planar {
    const NAME: &'static str = "planar";
    const COORDINATES: &'static [CoordinateSpec] = &[length("x"), length("y"), angle("angle")];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Optional;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        let e1 = perpendicular(&g.axis, &g.axis2);
        let e2 = g.axis.cross(&e1);
        Pose::about(rotation(&g.axis, q[2]), &g.at).shifted(e1 * q[0] + e2 * q[1])
    }
}
