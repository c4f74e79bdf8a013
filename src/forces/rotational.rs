//! Rotational spring-damper between two bodies about an axis fixed in body 1 (a torsion
//! spring, a torsional damper or a coupling's twist): its deformation is the angle `θ` by which
//! body 2 has turned relative to body 1 about that axis, and it applies the torque
//! `k (θ − θ0) + c θ̇ + T0` about it, equal and opposite on the two bodies.
//!
//! With `u ⟂ a` (from the coordinate axis least aligned with `a`, chosen as the model is read)
//! and `v = a × u` fixed in body 1 and `R = R₁ᵀR₂` the relative rotation,
//! `cos θ = uᵀR u` and `sin θ = vᵀR u`: exactly the hinge angle for a rotation about `a`, and
//! its projection onto the plane normal to `a` when body 2 also tilts. `θ` is written
//! `2 atan(s / (√(s² + c²) + c))`, without branches (so the recorded program holds it), regular
//! for |θ| < π. `θ0` defaults to zero: the angle as drawn.

use super::{ComponentSpec, ForceType, Geometry};
use crate::joints::{Unit, Use};
use crate::real::{Real, V3, cst};
use crate::rigid::{Pose, perpendicular};

pub struct Rotational;

impl ForceType for Rotational {
    const NAME: &'static str = "rotational_spring_damper";
    const COMPONENTS: &'static [ComponentSpec] = &[ComponentSpec {
        suffix: "angle",
        unit: Unit::Angle,
    }];
    const POINT1: Use = Use::Unused;
    const POINT2: Use = Use::Unused;
    const AXIS: Use = Use::Required;
    const DISTINCT_POINTS: bool = false;

    #[inline]
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let u = perpendicular(&g.axis, &g.reference);
        let v = g.axis.cross(&u);
        let u2 = x2.rot * u;
        let c = (x1.rot * u).dot(&u2);
        let s = (x1.rot * v).dot(&u2);
        let r = (s * s + c * c).sqrt();
        out.push((s / (r + c)).atan() * cst::<T>(2.0));
    }
}
