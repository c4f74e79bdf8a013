//! The parametric multibody system: a [`Model`] instantiated at parameter values and a speed,
//! over any scalar [`Real`].
//!
//! [`System::new`] evaluates every expression once; [`kinematics`] maps coordinates to body
//! poses; [`dynamics`] gives the equations of motion `r(q, q̇, q̈)` and the cut-joint
//! constraints `Φ(q)`. All of it is written once over `T` and differentiated by dual numbers.

pub mod dynamics;
mod evaluate;
pub mod kinematics;
pub mod ports;

use crate::model::{FieldError, Model};
use crate::real::{M3, Real, V3, cst};
use crate::rigid::Pose;
use crate::{cuts, forces, joints};
use std::ops::Range;

/// Mass properties of one body, in the reference configuration.
#[derive(Debug, Clone)]
pub struct BodyData<T> {
    pub mass: T,
    /// About the centre of mass, global axes of the reference configuration.
    pub inertia: M3<T>,
    /// Centre of mass in the reference configuration.
    pub cm: V3<T>,
}

/// A tree joint with its geometry in the reference configuration (unit directions).
#[derive(Debug, Clone)]
pub struct JointData<T> {
    pub kind: joints::Kind,
    pub parent: Option<usize>,
    pub child: usize,
    pub geometry: joints::Geometry<V3<T>>,
    /// Indices of its coordinates.
    pub coords: Range<usize>,
}

/// Spring and damper acting on one joint coordinate.
#[derive(Debug, Clone)]
pub struct JointElement<T> {
    pub coord: usize,
    pub stiffness: T,
    pub free: T,
    pub damping: T,
}

/// A force element (geometry in the reference configuration) with its per-component spring
/// rates, damping, free values and preloads, and the off-diagonal terms of its stiffness and
/// damping matrices.
#[derive(Debug, Clone)]
pub struct ForceData<T> {
    pub kind: forces::Kind,
    pub geometry: forces::Geometry<V3<T>>,
    pub stiffness: Vec<T>,
    pub damping: Vec<T>,
    pub free: Vec<T>,
    pub preload: Vec<T>,
    pub cross: Vec<Cross<T>>,
}

/// An off-diagonal term of a force element's stiffness and damping matrices: component
/// `row`'s force per unit of component `col`'s deformation from its free value (`stiffness`)
/// and per unit of its rate (`damping`).
#[derive(Debug, Clone, Copy)]
pub struct Cross<T> {
    pub row: usize,
    pub col: usize,
    pub stiffness: T,
    pub damping: T,
}

#[derive(Debug, Clone)]
pub struct ConstraintData<T> {
    pub kind: cuts::Kind,
    pub geometry: cuts::Geometry<V3<T>, T>,
    /// Its redundant equations, not imposed (see [`crate::model::Constraint::dropped`]).
    pub dropped: Vec<usize>,
}

impl<T: Real> ConstraintData<T> {
    /// The equations imposed (the redundant ones left out) at the poses of its two bodies,
    /// appended to `out`.
    pub fn values<U: Real>(
        &self,
        g: &cuts::Geometry<V3<U>, U>,
        x1: &Pose<U>,
        x2: &Pose<U>,
        out: &mut Vec<U>,
    ) {
        let start = out.len();
        self.kind.values(g, x1, x2, out);
        if !self.dropped.is_empty() {
            let all = out.split_off(start);
            out.extend(
                all.into_iter()
                    .enumerate()
                    .filter(|(k, _)| !self.dropped.contains(k))
                    .map(|(_, v)| v),
            );
        }
    }

    /// How many equations it imposes.
    pub fn rows(&self) -> usize {
        self.kind.equations() - self.dropped.len()
    }
}

/// A port (see [`crate::model::Port`]): a body's point and a unit direction, as drawn.
#[derive(Debug, Clone)]
pub struct PortData<T> {
    pub body: usize,
    pub point: V3<T>,
    pub direction: V3<T>,
    pub rotation: bool,
}

/// An unbalance (see [`crate::model::Unbalance`]) with its numbers evaluated: its point as
/// drawn, `m e` (kg·m) and its phase (rad).
#[derive(Debug, Clone)]
pub struct UnbalanceData<T> {
    pub body: usize,
    pub point: V3<T>,
    pub magnitude: T,
    pub phase: T,
}

/// A coupler `a q₁ + b q₂ = c` (see [`crate::model::Coupler`]) with its numbers evaluated.
#[derive(Debug, Clone)]
pub struct CouplerData<T> {
    pub coordinates: [usize; 2],
    pub coefficients: [T; 2],
    pub value: T,
}

/// An applied load (see [`crate::model::Load`]) with its vectors evaluated: a force at a body's
/// point (reference configuration), a torque on a body, each in ground axes or turning with
/// the body (`follower`), or a generalised force on a coordinate.
#[derive(Debug, Clone)]
pub enum LoadData<T> {
    Force {
        body: usize,
        point: V3<T>,
        force: V3<T>,
        follower: bool,
    },
    Torque {
        body: usize,
        torque: V3<T>,
        follower: bool,
    },
    Coordinate {
        coordinate: usize,
        value: T,
    },
}

/// A model instantiated at one set of parameter values and one speed, over scalar `T`.
#[derive(Debug, Clone)]
pub struct System<T> {
    pub gravity: V3<T>,
    pub bodies: Vec<BodyData<T>>,
    /// Tree joints, parents before children.
    pub joints: Vec<JointData<T>>,
    pub joint_elements: Vec<JointElement<T>>,
    pub forces: Vec<ForceData<T>>,
    /// Beam elements, their sections evaluated.
    pub beams: Vec<crate::beams::Element<T>>,
    pub constraints: Vec<ConstraintData<T>>,
    pub ports: Vec<PortData<T>>,
    pub unbalances: Vec<UnbalanceData<T>>,
    pub loads: Vec<LoadData<T>>,
    pub couplers: Vec<CouplerData<T>>,
    /// Constant speed of each driven coordinate (`None` for free ones).
    pub drive: Vec<Option<T>>,
    /// For each coordinate, its joint (index into `joints`).
    pub coord_joint: Vec<usize>,
    /// For each body, the range of depth-first (pre-order) positions of the bodies it carries,
    /// itself first: body `c` moves with body `b` iff `span[b].0 ≤ span[c].0 < span[b].1` (see
    /// [`System::carries`]).
    pub span: Vec<(usize, usize)>,
    /// Number of coordinates.
    pub n: usize,
    /// Number of constraint equations.
    pub m: usize,
}

/// Coordinate speeds at steady state for the model at parameters `p` and `speed`: drive speeds
/// on driven coordinates, zero elsewhere (as [`System::steady_speeds`], without the rest of the
/// system).
pub fn steady_speeds(model: &Model, p: &[f64], speed: f64) -> Result<Vec<f64>, FieldError> {
    let mut qd = vec![0.0; model.coordinates.len()];
    for j in &model.joints {
        if let Some(d) = &j.drive {
            qd[j.coords.start] = d.eval(p, speed)?;
        }
    }
    Ok(qd)
}

impl<T: Real> System<T> {
    /// Does body `c` move with body `b` (is it `b` or below it)?
    #[inline]
    pub fn carries(&self, b: usize, c: usize) -> bool {
        let (lo, hi) = self.span[b];
        (lo..hi).contains(&self.span[c].0)
    }

    /// Does body `c` move with coordinate `i`?
    #[inline]
    pub fn moves(&self, i: usize, c: usize) -> bool {
        self.carries(self.joints[self.coord_joint[i]].child, c)
    }

    /// Coordinate speeds at steady state: drive speeds on driven coordinates, zero elsewhere.
    pub fn steady_speeds(&self) -> Vec<T> {
        self.drive.iter().map(|d| d.unwrap_or(cst(0.0))).collect()
    }
}

/// Euclidean norm over any [`Real`] (nalgebra's `norm` needs a `RealField`).
pub trait NormDual<T> {
    fn norm_dual(&self) -> T;
}

impl<T: Real> NormDual<T> for V3<T> {
    fn norm_dual(&self) -> T {
        self.dot(self).sqrt()
    }
}
