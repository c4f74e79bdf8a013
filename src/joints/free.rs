//! Free (six-degree-of-freedom) joint: a body floating relative to its parent, held only by
//! force elements (a housing on rubber mounts, a rotor in flexible bearings). Translations
//! `x, y, z` (m) along the reference configuration's axes and a rotation about `at` by the
//! scaled modified Rodrigues parameters `rx, ry, rz` (rad near the reference, as for
//! `spherical`): `x₀ ↦ R(r)(x₀ − at) + at + (x, y, z)`.

use super::{CoordinateSpec, Geometry, JointType, Use, angle, length};
use crate::real::{Real, V3};
use crate::rigid::{Pose, rotation_parameters};

pub struct Free;

impl JointType for Free {
    const NAME: &'static str = "free";
    const COORDINATES: &'static [CoordinateSpec] = &[
        length("x"),
        length("y"),
        length("z"),
        angle("rx"),
        angle("ry"),
        angle("rz"),
    ];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Unused;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        let r = rotation_parameters(&V3::new(q[3], q[4], q[5]));
        Pose::about(r, &g.at).shifted(V3::new(q[0], q[1], q[2]))
    }
}
