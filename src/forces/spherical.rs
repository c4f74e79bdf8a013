//! Spherical spring-damper between two bodies: the three-axis rotational spring and damper of a
//! ball joint or a free joint (a rubber ball joint, a viscous coupling, a damped gimbal), acting
//! on the relative rotation and the relative angular velocity of body 2 with respect to body 1.
//!
//! The spring measures the relative rotation `R = R₁ᵀR₂` by its scaled modified Rodrigues
//! parameters `p = 4 tan(θ/4) n` ([`crate::rigid::rotation_parameters_of`]), in body 1's axes:
//! the same measure as a ball joint's coordinates, so between a ball joint's parent and child it
//! is the joint's own `stiffness`, and it equals the rotation vector `θ n` to third order
//! (isotropic: a torque `k θ` about the rotation's axis for small `θ`, regular up to `θ = π`).
//! The potential `½ Σ k_c (p_c − p0_c)²` acts through the mechanics' exact generalised forces,
//! as every element's does.
//!
//! The damper acts on the **relative angular velocity** `ω = R₁ᵀ(ω₂ − ω₁)` (body 1's axes; `ω₁`,
//! `ω₂` the bodies' angular velocities in ground axes), not on the rates of a measure of the
//! rotation: the torque `−C ω` on body 2 and `+C ω` on body 1 with `C = diag(c_x, c_y, c_z)` in
//! body 1's axes, the dissipation `½ Σ c_c ω_c²` whatever the rotation. A ball joint's own
//! `damping` acts on its coordinates' rates `ṗ`, which equal `ω` only near the reference
//! (`ṗ = B(p) ω` with `B` of the Rodrigues kinematics: the shipped conical pendulum on its cone
//! at 1.09 rad of tilt has a damping ratio 14 % above the viscous torque's, 21 % at 1.42 rad);
//! this element is the viscous torque (Simscape Multibody's
//! spherical-joint internal mechanics; Exudyn's `RigidBodySpringDamper` with a rotational
//! damping matrix).

use super::{ComponentSpec, Damps, ForceType, Geometry};
use crate::joints::{Unit, Use};
use crate::real::{Real, V3};
use crate::rigid::{Pose, rotation_parameters_of};

pub struct Spherical;

const fn angle(suffix: &'static str) -> ComponentSpec {
    ComponentSpec {
        suffix,
        unit: Unit::Angle,
    }
}

impl ForceType for Spherical {
    const NAME: &'static str = "spherical_spring_damper";
    const COMPONENTS: &'static [ComponentSpec] = &[angle("rx"), angle("ry"), angle("rz")];
    const POINT1: Use = Use::Unused;
    const POINT2: Use = Use::Unused;
    const AXIS: Use = Use::Unused;
    const DISTINCT_POINTS: bool = false;
    const DAMPS: Damps = Damps::RelativeAngularVelocity;

    #[inline]
    fn deformation<T: Real>(_: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>) {
        let p = rotation_parameters_of(&(x1.rot.transpose() * x2.rot));
        out.extend(p.iter().copied());
    }
}
