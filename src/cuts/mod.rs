//! Cut joints: constraint equations `Φ(q) = 0` that close the kinematic loops the joint tree
//! leaves open, one file per type. Each type owns its number of scalar equations and writes them
//! once over any [`Real`], from the poses of its two bodies.
//!
//! A cut joint joins a point `point1` of `body1` and a point `point2` of `body2` (either may be
//! ground), given in the reference configuration, with the geometry fields its type uses.
//! Adding a cut-joint type is one file here implementing [`CutType`] and one line in
//! the list `kinds!` (below); the model parser reads the type's name and fields from that trait.

pub mod distance;
pub mod point;
pub mod revolute;

use crate::joints::Use;
use crate::kinds::kinds;
use crate::real::{Real, V3};
use crate::rigid::Pose;

/// Geometry of a cut joint in the reference configuration; `V` is a vector and `X` a number
/// (expressions in the model, values in the mechanics, where `axis` and `axis2` are unit
/// vectors when used).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Geometry<V, X> {
    pub body1: Option<usize>,
    pub point1: V,
    pub body2: Option<usize>,
    pub point2: V,
    pub axis: V,
    pub axis2: V,
    pub length: Option<X>,
}

/// A cut-joint type.
pub trait CutType {
    /// Name in the model file's `type` field.
    const NAME: &'static str;
    /// Number of scalar equations.
    const EQUATIONS: usize;
    /// Use of `point2` (`Optional`: it defaults to `point1`, the two bodies' points coinciding
    /// in the reference configuration), `axis`, `axis2` (`Optional`: the coordinate axis least
    /// aligned with `axis`) and `length` (`Optional`: the points' distance in the reference
    /// configuration).
    const POINT2: Use;
    const AXIS: Use;
    const AXIS2: Use;
    const LENGTH: Use;
    /// Whether the two points must differ in the reference configuration.
    const DISTINCT_POINTS: bool;
    /// Appends the [`CutType::EQUATIONS`] values of `Φ` with the two bodies at poses `x1` and
    /// `x2` (the identity for ground).
    fn equations<T: Real>(g: &Geometry<V3<T>, T>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>);
}

kinds! {
    /// The cut-joint types a model may use.
    pub enum Kind: CutType {
        Distance => distance::Distance,
        Point => point::Point,
        Revolute => revolute::Revolute,
    }
    /// Number of scalar equations.
    fn equations() -> usize = EQUATIONS;
    /// Use of `[point2, axis, axis2, length]`.
    fn uses() -> [Use; 4] = [POINT2, AXIS, AXIS2, LENGTH];
    /// See [`CutType::DISTINCT_POINTS`].
    fn distinct_points() -> bool = DISTINCT_POINTS;
    /// See [`CutType::equations`].
    fn values<T: Real>(g: &Geometry<V3<T>, T>, x1: &Pose<T>, x2: &Pose<T>, out: &mut Vec<T>)
        = equations(g, x1, x2, out);
}
