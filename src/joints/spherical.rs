//! Spherical (ball) joint: any rotation about `at`, parametrised by three scaled modified
//! Rodrigues parameters `p = 4 tan(θ/4) n` in the reference configuration's axes
//! ([`crate::rigid::rotation_parameters`]): `x₀ ↦ R(p)(x₀ − at) + at`.
//!
//! The parametrisation is regular for every rotation short of a full turn from the reference
//! configuration, so about any equilibrium reachable in practice; near the reference `p` is the
//! rotation vector `θ n` (to third order), which is why its coordinates are named `rx, ry, rz`
//! and read in rad. Unlike Euler or cardan angles it has no gimbal lock at 90°.

use super::{CoordinateSpec, Geometry, JointType, Use, angle};
use crate::real::{Real, V3};
use crate::rigid::{Pose, rotation_parameters};

pub struct Spherical;

impl JointType for Spherical {
    const NAME: &'static str = "spherical";
    const COORDINATES: &'static [CoordinateSpec] = &[angle("rx"), angle("ry"), angle("rz")];
    const AT: Use = Use::Required;
    const AXIS: Use = Use::Unused;
    const AXIS2: Use = Use::Unused;

    #[inline]
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> {
        let r = rotation_parameters(&V3::new(q[0], q[1], q[2]));
        Pose::about(r, &g.at)
    }
}
