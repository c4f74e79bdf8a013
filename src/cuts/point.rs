//! Point (ball, spherical) cut joint: the point `point1` of body 1 and `point2` of body 2
//! coincide, three equations `A₁ᵀ (x₂ − x₁) = 0`, written in body 1's axes so that turning the
//! whole mechanism leaves `Φ` and its multipliers unchanged (a spinning frame then has a steady
//! state). `point2` defaults to `point1` (the points coincide in the reference configuration).

use super::{CutType, Geometry};
use crate::joints::Use;
use crate::real::{Real, V3};
use crate::rigid::Pose;

pub struct Point;

impl CutType for Point {
    const NAME: &'static str = "point";
    const EQUATIONS: usize = 3;
    const POINT2: Use = Use::Optional;
    const AXIS: Use = Use::Unused;
    const AXIS2: Use = Use::Unused;
    const LENGTH: Use = Use::Unused;
    const DISTINCT_POINTS: bool = false;

    #[inline]
    fn equations<T: Real>(g: &Geometry<V3<T>, T>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let d = x1.local(&(x2.apply(&g.point2) - x1.apply(&g.point1)));
        out.extend([d.x, d.y, d.z]);
    }
}
