//! Prismatic joint: translation by `q` (m) along `axis`.

use super::{CoordinateSpec, Geometry, JointType, Use, length};
use crate::real::{M3, Real, V3};
use crate::rigid::Pose;

pub struct Prismatic;

impl JointType for Prismatic {
    const NAME: &'static str = "prismatic";
    const COORDINATES: &'static [CoordinateSpec] = &[length("")];
    const AT: Use = Use::Ignored;
    const AXIS: Use = Use::Required;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        Pose {
            rot: M3::identity(),
            trans: g.axis * q[0],
        }
    }
}
