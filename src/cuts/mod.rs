//! Cut joints: constraint equations `Φ(q) = 0` that close the kinematic loops the joint tree
//! leaves open, one file per type. Each type owns its number of scalar equations and writes them
//! once over any [`Real`], from the poses of its two bodies.
//!
//! A cut joint joins a point `point1` of `body1` and a point `point2` of `body2` (either may be
//! ground), given in the reference configuration, with the geometry fields its type uses.
//! Adding a cut-joint type is one file here implementing [`CutType`] and one line in
//! `cut_types!` (below); the model parser reads the type's name and fields from that trait.

pub mod distance;
pub mod point;
pub mod revolute;

use crate::joints::Use;
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

/// Declares the cut-joint types: the enum [`Kind`] and its dispatch to each type's [`CutType`].
macro_rules! cut_types {
    ($($variant:ident => $ty:path),* $(,)?) => {
        /// The cut-joint types a model may use.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
        pub enum Kind {
            $($variant),*
        }

        impl Kind {
            /// Every type, in the order they are listed to users.
            pub const ALL: &[Kind] = &[$(Kind::$variant),*];

            /// Name in the model file.
            pub fn name(self) -> &'static str {
                match self {
                    $(Kind::$variant => <$ty as CutType>::NAME),*
                }
            }

            /// Number of scalar equations.
            pub fn equations(self) -> usize {
                match self {
                    $(Kind::$variant => <$ty as CutType>::EQUATIONS),*
                }
            }

            /// Use of `[point2, axis, axis2, length]`.
            pub fn uses(self) -> [Use; 4] {
                match self {
                    $(Kind::$variant => [
                        <$ty as CutType>::POINT2,
                        <$ty as CutType>::AXIS,
                        <$ty as CutType>::AXIS2,
                        <$ty as CutType>::LENGTH,
                    ]),*
                }
            }

            /// See [`CutType::DISTINCT_POINTS`].
            pub fn distinct_points(self) -> bool {
                match self {
                    $(Kind::$variant => <$ty as CutType>::DISTINCT_POINTS),*
                }
            }

            /// See [`CutType::equations`].
            #[inline]
            pub fn values<T: Real>(
                self,
                g: &Geometry<V3<T>, T>,
                x1: &Pose<T>,
                x2: &Pose<T>,
                out: &mut Vec<T>,
            ) {
                match self {
                    $(Kind::$variant => <$ty as CutType>::equations(g, x1, x2, out)),*
                }
            }
        }
    };
}

cut_types! {
    Distance => distance::Distance,
    Point => point::Point,
    Revolute => revolute::Revolute,
}
