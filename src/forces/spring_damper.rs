//! Translational spring-damper between two points: its deformation is their distance `ℓ`, so
//! it pulls along the line joining them with the tension `k (ℓ − ℓ0) + c ℓ̇ + f0`. The free
//! length `ℓ0` defaults to the distance in the reference configuration.

use super::{ComponentSpec, ForceType, Geometry};
use crate::joints::{Unit, Use};
use crate::real::{Real, V3};
use crate::rigid::Pose;

pub struct SpringDamper;

impl ForceType for SpringDamper {
    const NAME: &'static str = "spring_damper";
    const COMPONENTS: &'static [ComponentSpec] = &[ComponentSpec {
        suffix: "length",
        unit: Unit::Length,
    }];
    const POINT1: Use = Use::Required;
    const POINT2: Use = Use::Required;
    const AXIS: Use = Use::Unused;
    const DISTINCT_POINTS: bool = true;

    #[inline]
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let d = x2.apply(&g.point2) - x1.apply(&g.point1);
        out.push(d.dot(&d).sqrt());
    }
}
