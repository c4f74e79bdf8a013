//! Bushing: a linear six-component spring-damper between two body frames at a point (a rubber
//! mount, an elastic coupling, a flexible bearing). Its deformation, in the axes of body 1 (the
//! model's global axes as drawn), is the displacement of body 2's point from body 1's,
//! `d = R₁ᵀ(x₂ − x₁)`, and the relative rotation `φ = axial(R) = (R − Rᵀ)^∨/2` with `R = R₁ᵀR₂`, equal
//! to the rotation vector to first order (`sin θ` times the axis). Each component has its own
//! stiffness and damping, `[x, y, z, rx, ry, rz]` (N/m and N·m/rad; N·s/m and N·m·s/rad).
//! `point2` defaults to `point1`: the two frames coincide as drawn, and the bushing is then
//! unloaded there.

use super::{ComponentSpec, ForceType, Geometry};
use crate::joints::{Unit, Use};
use crate::real::{Real, V3, axial};
use crate::rigid::Pose;

pub struct Bushing;

const fn length(suffix: &'static str) -> ComponentSpec {
    ComponentSpec {
        suffix,
        unit: Unit::Length,
    }
}

const fn angle(suffix: &'static str) -> ComponentSpec {
    ComponentSpec {
        suffix,
        unit: Unit::Angle,
    }
}

impl ForceType for Bushing {
    const NAME: &'static str = "bushing";
    const COMPONENTS: &'static [ComponentSpec] = &[
        length("x"),
        length("y"),
        length("z"),
        angle("rx"),
        angle("ry"),
        angle("rz"),
    ];
    const POINT1: Use = Use::Required;
    const POINT2: Use = Use::Optional;
    const AXIS: Use = Use::Unused;
    const DISTINCT_POINTS: bool = false;

    #[inline]
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let d = x1.local(&(x2.apply(&g.point2) - x1.apply(&g.point1)));
        let phi = axial(&(x1.rot.transpose() * x2.rot));
        out.extend(d.iter().chain(phi.iter()).copied());
    }
}
