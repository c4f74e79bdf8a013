//! Distance cut joint: `|x₂ − x₁| = L` between two points (a massless rod with ball joints at
//! both ends), written `Φ = ½ (dᵀd − L²)` with `d = x₂ − x₁` so that it is polynomial in the
//! poses. One equation; `length` defaults to the points' distance in the reference
//! configuration.

use super::{CutType, Geometry};
use crate::joints::Use;
use crate::real::{Real, V3, cst};
use crate::rigid::Pose;

pub struct Distance;

impl CutType for Distance {
    const NAME: &'static str = "distance";
    const EQUATIONS: usize = 1;
    const POINT2: Use = Use::Required;
    const AXIS: Use = Use::Unused;
    const AXIS2: Use = Use::Unused;
    const LENGTH: Use = Use::Optional;
    const DISTINCT_POINTS: bool = true;

    #[inline]
    fn equations<T: Real>(g: &Geometry<V3<T>, T>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let length = g.length.unwrap_or_else(|| {
            let d0 = g.point2 - g.point1;
            d0.dot(&d0).sqrt()
        });
        let d = x2.apply(&g.point2) - x1.apply(&g.point1);
        out.push((d.dot(&d) - length * length) * cst::<T>(0.5));
    }
}
