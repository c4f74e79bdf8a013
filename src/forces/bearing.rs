//! Bearing: a linear spring-damper holding a shaft's node in its housing, the element
//! rotordynamics writes with the coefficients `kxx, kxy, kyx, kyy` and `cxx, …` (ROSS's
//! `BearingElement`, Friswell et al. 2010 §5.5). Its deformation is the displacement of body 2's
//! point (the journal) from body 1's (the housing; `ground` for a fixed one), in body 1's
//! axes, resolved along the bearing's own directions: `x` along `axis2` (made perpendicular to
//! the shaft's `axis`; by default the coordinate axis least aligned with it, so a shaft along
//! `z` has the global `x`), `y = axis × x` and `z` along `axis` (the axial direction, for a
//! thrust stiffness). Its stiffness and damping are given as numbers per component or as
//! matrices over `[x, y, z]` (a journal bearing's cross-coupled, non-symmetric coefficients),
//! and each coefficient may depend on the speed (an expression of `speed`, or a `[[tables]]`
//! function of it). The element acts in the plane of its journal only through the
//! displacement: it puts no moment on the shaft (give a `bushing` where a bearing holds the
//! tilt too).

use super::{ComponentSpec, ForceType, Geometry};
use crate::joints::{Unit, Use};
use crate::real::{Real, V3};
use crate::rigid::{Pose, perpendicular};

pub struct Bearing;

const fn length(suffix: &'static str) -> ComponentSpec {
    ComponentSpec {
        suffix,
        unit: Unit::Length,
    }
}

impl ForceType for Bearing {
    const NAME: &'static str = "bearing";
    const COMPONENTS: &'static [ComponentSpec] = &[length("x"), length("y"), length("z")];
    const POINT1: Use = Use::Required;
    const POINT2: Use = Use::Optional;
    const AXIS: Use = Use::Required;
    const DISTINCT_POINTS: bool = false;

    #[inline]
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let d = x1.local(&(x2.apply(&g.point2) - x1.apply(&g.point1)));
        let x = perpendicular(&g.axis, &g.reference);
        let y = g.axis.cross(&x);
        out.extend([d.dot(&x), d.dot(&y), d.dot(&g.axis)]);
    }
}
