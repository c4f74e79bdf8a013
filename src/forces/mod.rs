//! Force elements: springs and dampers between two bodies, one file per type. Each type owns
//! how it measures its deformation `e` (a few scalar components) from the poses of its two
//! bodies, written once over any [`Real`]; the mechanics does the rest for every type alike.
//!
//! The element acts with the generalised forces of the potential `½ Σ k_c (e_c − e0_c)²` and
//! the dissipation `½ Σ c_c ė_c²`, plus a constant preload `f0_c` on each component:
//!
//! ```text
//! f_c = k_c (e_c − e0_c) + c_c ė_c + f0_c,        r_i += Σ_c f_c ∂e_c/∂q_i
//! ```
//!
//! so the tangent stiffness is symmetric at rest and exact everywhere, whatever the measure.
//! Where the stiffness and damping are given as matrices over the components,
//! `f = K (e − e0) + C ė + f0`: the same virtual work, but a `K` that is not symmetric (a
//! journal bearing's cross-coupling `kxy ≠ kyx`) is a circulatory force, with no potential,
//! and its tangent stiffness is not symmetric either.
//! A type whose dampers act on the relative angular velocity rather than on `ė` says so
//! ([`Damps`]); its springs and preloads act as above.
//! The free value `e0` defaults to the deformation in the reference configuration (the element
//! is unloaded as drawn). An element joins a point `point1` of `body1` and `point2` of `body2`
//! (either body may be ground) given in the reference configuration, with an `axis` where its
//! type uses one.
//!
//! Adding a type is one file here implementing [`ForceType`] and one line in `force_types!`
//! (below); the model parser reads the type's name, components and fields from that trait.

pub mod bearing;
pub mod bushing;
pub mod rotational;
pub mod spherical;
pub mod spring_damper;

use crate::joints::{Unit, Use};
use crate::kinds::kinds;
use crate::real::{Real, V3};
use crate::rigid::Pose;

/// Geometry of a force element in the reference configuration; `V` is a vector (expressions
/// in the model, values in the mechanics, where `axis` is a unit vector when used).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Geometry<V> {
    pub body1: Option<usize>,
    pub point1: V,
    pub body2: Option<usize>,
    pub point2: V,
    pub axis: V,
    /// A direction not parallel to `axis` (the coordinate axis least aligned with it, chosen
    /// as the model is read) from which a type measures angles about `axis`.
    pub reference: V,
}

/// One component of an element's deformation: its name suffix (as in `stiffness` lists and
/// messages) and its unit.
#[derive(Debug, Clone, Copy)]
pub struct ComponentSpec {
    pub suffix: &'static str,
    pub unit: Unit,
}

/// What an element's dampers act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Damps {
    /// The rate of each deformation component, `c_c ė_c` (dissipation `½ Σ c_c ė_c²`).
    DeformationRate,
    /// The angular velocity of body 2 relative to body 1 in body 1's axes,
    /// `ω = R₁ᵀ(ω₂ − ω₁)`: a torque `c_c ω_c` about body 1's axis `c` on body 1 and its opposite
    /// on body 2 (dissipation `½ Σ c_c ω_c²`), for a type with three components.
    RelativeAngularVelocity,
}

/// A force-element type.
pub trait ForceType {
    /// Name in the model file's `type` field.
    const NAME: &'static str;
    /// The components of the deformation, in order (stiffness, damping, free values and
    /// preloads are given per component).
    const COMPONENTS: &'static [ComponentSpec];
    /// Use of `point1`, `point2` (`Optional`: it defaults to `point1`) and `axis`.
    const POINT1: Use;
    const POINT2: Use;
    const AXIS: Use;
    /// Whether the two points must differ in the reference configuration (where the measure
    /// has no derivative at coincident points).
    const DISTINCT_POINTS: bool;
    /// What the dampers act on.
    const DAMPS: Damps = Damps::DeformationRate;
    /// Appends the deformation's components with the two bodies at poses `x1` and `x2` (the
    /// identity for ground).
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>);
}

kinds! {
    /// The force-element types a model may use.
    pub enum Kind: ForceType {
        SpringDamper => spring_damper::SpringDamper,
        Rotational => rotational::Rotational,
        Bushing => bushing::Bushing,
        Spherical => spherical::Spherical,
        Bearing => bearing::Bearing,
    }
    /// See [`ForceType::COMPONENTS`].
    fn components() -> &'static [ComponentSpec] = COMPONENTS;
    /// Use of `[point1, point2, axis]`.
    fn uses() -> [Use; 3] = [POINT1, POINT2, AXIS];
    /// See [`ForceType::DISTINCT_POINTS`].
    fn distinct_points() -> bool = DISTINCT_POINTS;
    /// See [`ForceType::DAMPS`].
    fn damps() -> Damps = DAMPS;
    /// See [`ForceType::deformation`].
    fn deformation<T: Real>(g: &Geometry<V3<T>>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>)
        = deformation(g, x1, x2, out);
}
