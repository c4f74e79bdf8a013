//! The parametric multibody system: a [`Model`] instantiated at parameter values and a speed,
//! over any scalar [`Real`].
//!
//! [`System::new`] evaluates every expression once; [`kinematics`] maps coordinates to body
//! poses; [`dynamics`] gives the equations of motion `r(q, q̇, q̈)` and the cut-joint
//! constraints `Φ(q)`. All of it is written once over `T` and differentiated by dual numbers.

pub mod dynamics;
pub mod kinematics;
pub mod ports;

use crate::model::{Field, FieldError, LoadKind, Model};
use crate::real::{M3, Real, V3, cst, mul3, mul3_t};
use crate::rigid::{Pose, perpendicular};
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
/// rates, damping, free values and preloads.
#[derive(Debug, Clone)]
pub struct ForceData<T> {
    pub kind: forces::Kind,
    pub geometry: forces::Geometry<V3<T>>,
    pub stiffness: Vec<T>,
    pub damping: Vec<T>,
    pub free: Vec<T>,
    pub preload: Vec<T>,
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

impl<T: Real> LoadData<T> {
    fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> LoadData<U> {
        match self {
            LoadData::Force {
                body,
                point,
                force,
                follower,
            } => LoadData::Force {
                body: *body,
                point: point.map(f),
                force: force.map(f),
                follower: *follower,
            },
            LoadData::Torque {
                body,
                torque,
                follower,
            } => LoadData::Torque {
                body: *body,
                torque: torque.map(f),
                follower: *follower,
            },
            LoadData::Coordinate { coordinate, value } => LoadData::Coordinate {
                coordinate: *coordinate,
                value: f(*value),
            },
        }
    }
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
    pub constraints: Vec<ConstraintData<T>>,
    pub ports: Vec<PortData<T>>,
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

fn v3<T: Real>(f: &[Field; 3], p: &[T], w: T) -> Result<V3<T>, FieldError> {
    Ok(V3::new(
        f[0].eval(p, w)?,
        f[1].eval(p, w)?,
        f[2].eval(p, w)?,
    ))
}

impl<T: Real> System<T> {
    /// Evaluates every field of `model` at parameter values `p` and operating speed `speed`
    /// (rad/s).
    pub fn new(model: &Model, p: &[T], speed: T) -> Result<System<T>, FieldError> {
        let w = speed;
        let mut bodies = Vec::with_capacity(model.bodies.len());
        for b in &model.bodies {
            let mut inertia = M3::zeros();
            for i in 0..3 {
                for j in 0..3 {
                    inertia[(i, j)] = b.inertia[i][j].eval(p, w)?;
                }
            }
            if let Some([x, y]) = &b.axes {
                // The inertia axes as the columns of R: I = R I_body Rᵀ in global axes.
                let x = direction(x, joints::Use::Required, p, w)?;
                let y = direction(y, joints::Use::Required, p, w)?;
                let y = perpendicular(&x, &y);
                let r = M3::from_columns(&[x, y, x.cross(&y)]);
                inertia = mul3_t(&mul3(&r, &inertia), &r);
            }
            bodies.push(BodyData {
                mass: b.mass.eval(p, w)?,
                inertia,
                cm: v3(&b.cm, p, w)?,
            });
        }
        let mut joints = Vec::with_capacity(model.joints.len());
        let mut joint_elements = Vec::new();
        let mut drive = vec![None; model.coordinates.len()];
        for &ji in &model.order {
            let j = &model.joints[ji];
            let [_, use_axis, use_axis2] = j.kind.uses();
            let g = &j.geometry;
            let geometry = joints::Geometry {
                at: v3(&g.at, p, w)?,
                axis: direction(&g.axis, use_axis, p, w)?,
                axis2: direction(&g.axis2, use_axis2, p, w)?,
            };
            joints.push(JointData {
                kind: j.kind,
                parent: j.parent,
                child: j.child,
                geometry,
                coords: j.coords.clone(),
            });
            if let Some(d) = &j.drive {
                drive[j.coords.start] = Some(d.eval(p, w)?);
            }
            for (k, c) in j.coords.clone().enumerate() {
                if j.stiffness[k].is_some() || j.damping[k].is_some() {
                    let opt = |f: &Option<Field>| f.as_ref().map_or(Ok(cst(0.0)), |f| f.eval(p, w));
                    joint_elements.push(JointElement {
                        coord: c,
                        stiffness: opt(&j.stiffness[k])?,
                        free: j.free[k].eval(p, w)?,
                        damping: opt(&j.damping[k])?,
                    });
                }
            }
        }
        let opt = |f: &Option<Field>| f.as_ref().map_or(Ok(cst(0.0)), |f| f.eval(p, w));
        let mut forces = Vec::with_capacity(model.forces.len());
        for e in &model.forces {
            let [_, _, use_axis] = e.kind.uses();
            let g = &e.geometry;
            let geometry = forces::Geometry {
                body1: g.body1,
                point1: v3(&g.point1, p, w)?,
                body2: g.body2,
                point2: v3(&g.point2, p, w)?,
                axis: direction(&g.axis, use_axis, p, w)?,
                reference: direction(&g.reference, use_axis, p, w)?,
            };
            // Unloaded as drawn unless a free value is given.
            let mut drawn = Vec::new();
            let identity = Pose::identity();
            e.kind
                .deformation(&geometry, &identity, &identity, &mut drawn);
            let free = e
                .free
                .iter()
                .zip(drawn)
                .map(|(f, d)| f.as_ref().map_or(Ok(d), |f| f.eval(p, w)))
                .collect::<Result<_, _>>()?;
            let each = |v: &[Option<Field>]| v.iter().map(opt).collect::<Result<Vec<T>, _>>();
            forces.push(ForceData {
                kind: e.kind,
                stiffness: each(&e.stiffness)?,
                damping: each(&e.damping)?,
                preload: each(&e.preload)?,
                free,
                geometry,
            });
        }
        let mut constraints = Vec::new();
        for c in &model.constraints {
            let [_, use_axis, use_axis2, _] = c.kind.uses();
            let g = &c.geometry;
            constraints.push(ConstraintData {
                kind: c.kind,
                geometry: cuts::Geometry {
                    body1: g.body1,
                    point1: v3(&g.point1, p, w)?,
                    body2: g.body2,
                    point2: v3(&g.point2, p, w)?,
                    axis: direction(&g.axis, use_axis, p, w)?,
                    axis2: direction(&g.axis2, use_axis2, p, w)?,
                    length: g.length.as_ref().map(|f| f.eval(p, w)).transpose()?,
                },
                dropped: c.dropped.clone(),
            });
        }
        let mut ports = Vec::with_capacity(model.ports.len());
        for port in &model.ports {
            ports.push(PortData {
                body: port.body,
                point: v3(&port.point, p, w)?,
                direction: direction(&port.direction, joints::Use::Required, p, w)?,
                rotation: port.rotation,
            });
        }
        let mut loads = Vec::with_capacity(model.loads.len());
        for load in &model.loads {
            loads.push(match &load.kind {
                LoadKind::Force {
                    body,
                    point,
                    force,
                    follower,
                } => LoadData::Force {
                    body: *body,
                    point: v3(point, p, w)?,
                    force: v3(force, p, w)?,
                    follower: *follower,
                },
                LoadKind::Torque {
                    body,
                    torque,
                    follower,
                } => LoadData::Torque {
                    body: *body,
                    torque: v3(torque, p, w)?,
                    follower: *follower,
                },
                LoadKind::Coordinate { coordinate, value } => LoadData::Coordinate {
                    coordinate: *coordinate,
                    value: value.eval(p, w)?,
                },
            });
        }
        let mut couplers = Vec::with_capacity(model.couplers.len());
        for c in &model.couplers {
            couplers.push(CouplerData {
                coordinates: c.coordinates,
                coefficients: [c.coefficients[0].eval(p, w)?, c.coefficients[1].eval(p, w)?],
                value: c.value.eval(p, w)?,
            });
        }
        let span = spans(&joints, model.bodies.len());
        let mut coord_joint = vec![0; model.coordinates.len()];
        for (ji, j) in joints.iter().enumerate() {
            coord_joint[j.coords.clone()].fill(ji);
        }
        Ok(System {
            gravity: v3(&model.gravity, p, w)?,
            bodies,
            joints,
            joint_elements,
            forces,
            constraints,
            ports,
            loads,
            couplers,
            drive,
            coord_joint,
            span,
            n: model.coordinates.len(),
            m: model.n_constraints(),
        })
    }

    /// The same system over another scalar (`f` lifts each number).
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> System<U> {
        let v = |x: &V3<T>| x.map(f);
        System {
            gravity: v(&self.gravity),
            bodies: self
                .bodies
                .iter()
                .map(|b| BodyData {
                    mass: f(b.mass),
                    inertia: b.inertia.map(f),
                    cm: v(&b.cm),
                })
                .collect(),
            joints: self
                .joints
                .iter()
                .map(|j| JointData {
                    kind: j.kind,
                    parent: j.parent,
                    child: j.child,
                    geometry: joints::Geometry {
                        at: v(&j.geometry.at),
                        axis: v(&j.geometry.axis),
                        axis2: v(&j.geometry.axis2),
                    },
                    coords: j.coords.clone(),
                })
                .collect(),
            joint_elements: self
                .joint_elements
                .iter()
                .map(|e| JointElement {
                    coord: e.coord,
                    stiffness: f(e.stiffness),
                    free: f(e.free),
                    damping: f(e.damping),
                })
                .collect(),
            forces: self
                .forces
                .iter()
                .map(|e| {
                    let g = &e.geometry;
                    let each = |v: &[T]| v.iter().map(|&x| f(x)).collect();
                    ForceData {
                        kind: e.kind,
                        geometry: forces::Geometry {
                            body1: g.body1,
                            point1: v(&g.point1),
                            body2: g.body2,
                            point2: v(&g.point2),
                            axis: v(&g.axis),
                            reference: v(&g.reference),
                        },
                        stiffness: each(&e.stiffness),
                        damping: each(&e.damping),
                        free: each(&e.free),
                        preload: each(&e.preload),
                    }
                })
                .collect(),
            constraints: self
                .constraints
                .iter()
                .map(|c| {
                    let g = &c.geometry;
                    ConstraintData {
                        kind: c.kind,
                        geometry: cuts::Geometry {
                            body1: g.body1,
                            point1: v(&g.point1),
                            body2: g.body2,
                            point2: v(&g.point2),
                            axis: v(&g.axis),
                            axis2: v(&g.axis2),
                            length: g.length.map(f),
                        },
                        dropped: c.dropped.clone(),
                    }
                })
                .collect(),
            ports: self
                .ports
                .iter()
                .map(|port| PortData {
                    body: port.body,
                    point: v(&port.point),
                    direction: v(&port.direction),
                    rotation: port.rotation,
                })
                .collect(),
            loads: self.loads.iter().map(|l| l.map(f)).collect(),
            couplers: self
                .couplers
                .iter()
                .map(|c| CouplerData {
                    coordinates: c.coordinates,
                    coefficients: c.coefficients.map(f),
                    value: f(c.value),
                })
                .collect(),
            drive: self.drive.iter().map(|d| d.map(f)).collect(),
            coord_joint: self.coord_joint.clone(),
            span: self.span.clone(),
            n: self.n,
            m: self.m,
        }
    }

    /// Coordinate speeds at steady state: drive speeds on driven coordinates, zero elsewhere.
    pub fn steady_speeds(&self) -> Vec<T> {
        self.drive.iter().map(|d| d.unwrap_or(cst(0.0))).collect()
    }
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

/// A direction field evaluated as a unit vector when the type uses it (`use_`), as given (zero)
/// otherwise. It is scaled by a power of two (exact, no derivative) before the norm, so that
/// neither a huge nor a tiny direction over- or underflows in `a·a`.
fn direction<T: Real>(
    f: &[Field; 3],
    use_: joints::Use,
    p: &[T],
    w: T,
) -> Result<V3<T>, FieldError> {
    let mut a = v3(f, p, w)?;
    if !matches!(use_, joints::Use::Required | joints::Use::Optional) {
        return Ok(a);
    }
    let amax = a.iter().fold(0.0f64, |m, v| m.max(v.re().abs()));
    if amax > 0.0 && amax.is_finite() {
        let e = (amax.log2().floor() as i32 + 1).clamp(-1000, 1000);
        a *= cst::<T>(2f64.powi(-e));
    }
    let n = a.dot(&a).sqrt();
    if !(n.re() > 0.0 && n.re().is_finite()) {
        return Err(FieldError {
            site: f[0].site.clone(),
            error: crate::model::EvalError::DivisionByZero,
        });
    }
    Ok(a / n)
}

/// The depth-first ranges of [`System::span`]: the tree walked from the bodies on ground, each
/// body's children after it. A body that no joint holds carries only itself.
fn spans<T: Real>(joints: &[JointData<T>], bodies: usize) -> Vec<(usize, usize)> {
    let mut children = vec![Vec::new(); bodies];
    let mut roots = Vec::new();
    for j in joints {
        match j.parent {
            Some(p) => children[p].push(j.child),
            None => roots.push(j.child),
        }
    }
    let mut held = vec![false; bodies];
    for j in joints {
        held[j.child] = true;
    }
    roots.extend((0..bodies).filter(|&b| !held[b]));
    let mut span = vec![(0, 0); bodies];
    let mut next = 0;
    // (body, children visited?)
    let mut stack: Vec<(usize, bool)> = roots.iter().rev().map(|&b| (b, false)).collect();
    while let Some((b, done)) = stack.pop() {
        if done {
            span[b].1 = next;
            continue;
        }
        span[b].0 = next;
        next += 1;
        stack.push((b, true));
        stack.extend(children[b].iter().rev().map(|&c| (c, false)));
    }
    span
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
