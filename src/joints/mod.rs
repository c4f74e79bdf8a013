//! Tree joints, one file per type, after pinocchio's joint models: each type owns its number of
//! coordinates (with their units and names) and its relative motion as a function of its
//! coordinates, written once over any [`Real`].
//!
//! A joint connects a parent body (or ground) to a child. Its geometry is given in the
//! reference configuration (where every coordinate is zero): a point `at`, a unit `axis` and a
//! second unit direction `axis2`, each used or not according to the type. The relative motion
//! maps a point of the child in the reference configuration to where the joint moves it in the
//! parent's reference frame; the child's pose is the parent's pose composed with it
//! ([`crate::mechanics::kinematics`]).
//!
//! Adding a joint type is one file here implementing [`JointType`] and one line in
//! the list `kinds!` (below); the model parser reads the type's name, coordinates and geometry fields
//! from that trait and needs no change unless the type brings new fields.

pub mod cylindrical;
pub mod fixed;
pub mod free;
pub mod planar;
pub mod prismatic;
pub mod revolute;
pub mod spherical;
pub mod universal;

use crate::kinds::kinds;
use crate::real::{Real, V3};
use crate::rigid::Pose;

/// Physical unit of a coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Unit {
    /// An angle or a rotation parameter, rad; its generalised force is a torque, N·m.
    Angle,
    /// A translation, m; its generalised force is a force, N.
    Length,
}

impl Unit {
    /// Symbol of the coordinate's unit.
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::Angle => "rad",
            Unit::Length => "m",
        }
    }

    /// Symbol of the unit of the generalised force on the coordinate.
    pub fn force_symbol(self) -> &'static str {
        match self {
            Unit::Angle => "N·m",
            Unit::Length => "N",
        }
    }
}

/// One coordinate of a joint type: the suffix that names it (`joint.suffix`; empty for
/// one-coordinate types, whose coordinate takes the joint's name) and its unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordinateSpec {
    pub suffix: &'static str,
    pub unit: Unit,
}

/// How a joint type uses a geometry field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// The model must give it.
    Required,
    /// The model may give it; the parser supplies a default (`at`: the origin; `axis2`: the
    /// coordinate axis least aligned with `axis`).
    Optional,
    /// Accepted and unused (kept for models written before the field was refused).
    Ignored,
    /// The model must not give it.
    Unused,
}

/// Geometry of a joint in the reference configuration; `V` is a vector of expressions in the
/// model and a [`V3`] in the mechanics, where `axis` and `axis2` are unit vectors when used.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Geometry<V> {
    pub at: V,
    pub axis: V,
    pub axis2: V,
}

/// A joint type.
pub trait JointType {
    /// Name in the model file's `type` field.
    const NAME: &'static str;
    /// Its coordinates, in order.
    const COORDINATES: &'static [CoordinateSpec];
    /// Use of `at`, `axis` and `axis2`.
    const AT: Use;
    const AXIS: Use;
    const AXIS2: Use;
    /// Motion of the child relative to the parent, both in the reference configuration, at the
    /// joint's coordinates `q` (`q.len()` = number of coordinates; the identity at `q = 0`).
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T>;
}

kinds! {
    /// The joint types a model may use.
    pub enum Kind: JointType {
        Revolute => revolute::Revolute,
        Prismatic => prismatic::Prismatic,
        Fixed => fixed::Fixed,
        Universal => universal::Universal,
        Cylindrical => cylindrical::Cylindrical,
        Spherical => spherical::Spherical,
        Planar => planar::Planar,
        Free => free::Free,
    }
    /// Coordinates of a joint of this type.
    fn coordinates() -> &'static [CoordinateSpec] = COORDINATES;
    /// Use of `[at, axis, axis2]`.
    fn uses() -> [Use; 3] = [AT, AXIS, AXIS2];
    /// See [`JointType::relative`].
    fn relative<T: Real>(g: &Geometry<V3<T>>, q: &[T]) -> Pose<T> = relative(g, q);
}

impl Kind {
    /// Number of coordinates.
    pub fn dof(self) -> usize {
        self.coordinates().len()
    }
}

/// The angle coordinate spec with the given suffix.
const fn angle(suffix: &'static str) -> CoordinateSpec {
    CoordinateSpec {
        suffix,
        unit: Unit::Angle,
    }
}

/// The length coordinate spec with the given suffix.
const fn length(suffix: &'static str) -> CoordinateSpec {
    CoordinateSpec {
        suffix,
        unit: Unit::Length,
    }
}
