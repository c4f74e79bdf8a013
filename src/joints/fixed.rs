//! Fixed joint: no relative motion, no coordinate.

use super::{CoordinateSpec, Geometry, JointType, Use};
use crate::real::{Real, V3};
use crate::rigid::Pose;

pub struct Fixed;

impl JointType for Fixed {
    const NAME: &'static str = "fixed";
    const COORDINATES: &'static [CoordinateSpec] = &[];
    const AT: Use = Use::Ignored;
    const AXIS: Use = Use::Ignored;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(_: &Geometry<V3<T>>, _: &[T]) -> Pose<T> {
        Pose::identity()
    }
}
