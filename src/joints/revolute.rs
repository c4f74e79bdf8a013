//! Revolute joint: rotation by `q` (rad) about `axis` through `at`.

use super::{CoordinateSpec, Geometry, JointType, Use, angle};
use crate::real::{Real, V3};
use crate::rigid::{Pose, rotation};

pub struct Revolute;

impl JointType for Revolute {
    const NAME: &'static str = "revolute";
    const COORDINATES: &'static [CoordinateSpec] = &[angle("")];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        Pose::about(rotation(&g.axis, q[0]), &g.at)
    }
}
