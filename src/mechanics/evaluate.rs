//! [`System::new`]: every field of a [`Model`] evaluated at parameter values and a speed, item
//! by item; and [`System::map`], the same system over another scalar.

use super::{
    BodyData, ConstraintData, CouplerData, Cross, ForceData, JointData, JointElement, LoadData,
    PortData, System, UnbalanceData,
};
use crate::model::{
    Beam, BeamSection, Body, Constraint, Coupler, Field, FieldError, ForceElement, Load, LoadKind,
};
use crate::model::{Model, Port, SectionProperties, TubeSection};
use crate::real::{M3, Real, V3, cst, mul3, mul3_t};
use crate::rigid::{Pose, perpendicular};
use crate::{beams, cuts, forces, joints};

impl<T: Real> System<T> {
    /// Evaluates every field of `model` at parameter values `p` and operating speed `speed`
    /// (rad/s).
    pub fn new(model: &Model, p: &[T], speed: T) -> Result<System<T>, FieldError> {
        let w = speed;
        let bodies = (model.bodies.iter())
            .map(|b| body(b, p, w))
            .collect::<Result<_, _>>()?;
        let Tree {
            joints,
            joint_elements,
            drive,
        } = tree(model, p, w)?;
        let forces = (model.forces.iter())
            .map(|e| force(e, p, w))
            .collect::<Result<_, _>>()?;
        let beams = (model.beams.iter())
            .map(|b| beam(b, p, w))
            .collect::<Result<_, _>>()?;
        let constraints = (model.constraints.iter())
            .map(|c| constraint(c, p, w))
            .collect::<Result<_, _>>()?;
        let ports = (model.ports.iter())
            .map(|port| port_data(port, p, w))
            .collect::<Result<_, _>>()?;
        let loads = (model.loads.iter())
            .map(|load| load_data(load, p, w))
            .collect::<Result<_, _>>()?;
        let unbalances = (model.unbalances.iter())
            .map(|u| {
                Ok(UnbalanceData {
                    body: u.body,
                    point: v3(&u.point, p, w)?,
                    magnitude: u.magnitude.eval(p, w)?,
                    phase: u.phase.eval(p, w)?,
                })
            })
            .collect::<Result<_, FieldError>>()?;
        let couplers = (model.couplers.iter())
            .map(|c| coupler(c, p, w))
            .collect::<Result<_, _>>()?;
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
            beams,
            constraints,
            ports,
            unbalances,
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
            bodies: (self.bodies.iter())
                .map(|b| BodyData {
                    mass: f(b.mass),
                    inertia: b.inertia.map(f),
                    cm: v(&b.cm),
                })
                .collect(),
            joints: (self.joints.iter())
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
            joint_elements: (self.joint_elements.iter())
                .map(|e| JointElement {
                    coord: e.coord,
                    stiffness: f(e.stiffness),
                    free: f(e.free),
                    damping: f(e.damping),
                })
                .collect(),
            forces: self.forces.iter().map(|e| e.map(f)).collect(),
            beams: self.beams.iter().map(|b| b.map(f)).collect(),
            constraints: self.constraints.iter().map(|c| c.map(f)).collect(),
            ports: (self.ports.iter())
                .map(|port| PortData {
                    body: port.body,
                    point: v(&port.point),
                    direction: v(&port.direction),
                    rotation: port.rotation,
                })
                .collect(),
            unbalances: (self.unbalances.iter())
                .map(|u| UnbalanceData {
                    body: u.body,
                    point: v(&u.point),
                    magnitude: f(u.magnitude),
                    phase: f(u.phase),
                })
                .collect(),
            loads: self.loads.iter().map(|l| l.map(f)).collect(),
            couplers: (self.couplers.iter())
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
}

fn v3<T: Real>(f: &[Field; 3], p: &[T], w: T) -> Result<V3<T>, FieldError> {
    Ok(V3::new(
        f[0].eval(p, w)?,
        f[1].eval(p, w)?,
        f[2].eval(p, w)?,
    ))
}

/// An optional field's value, zero where it is not given.
fn or_zero<T: Real>(f: &Option<Field>, p: &[T], w: T) -> Result<T, FieldError> {
    f.as_ref().map_or(Ok(cst(0.0)), |f| f.eval(p, w))
}

/// A body's mass properties, its inertia turned to global axes where given in its own.
fn body<T: Real>(b: &Body, p: &[T], w: T) -> Result<BodyData<T>, FieldError> {
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
    Ok(BodyData {
        mass: b.mass.eval(p, w)?,
        inertia,
        cm: v3(&b.cm, p, w)?,
    })
}

/// The tree joints (parents before children), their coordinates' springs and dampers, and
/// each coordinate's drive speed.
struct Tree<T> {
    joints: Vec<JointData<T>>,
    joint_elements: Vec<JointElement<T>>,
    drive: Vec<Option<T>>,
}

fn tree<T: Real>(model: &Model, p: &[T], w: T) -> Result<Tree<T>, FieldError> {
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
                joint_elements.push(JointElement {
                    coord: c,
                    stiffness: or_zero(&j.stiffness[k], p, w)?,
                    free: j.free[k].eval(p, w)?,
                    damping: or_zero(&j.damping[k], p, w)?,
                });
            }
        }
    }
    Ok(Tree {
        joints,
        joint_elements,
        drive,
    })
}

/// A force element, unloaded as drawn unless a free value is given.
fn force<T: Real>(e: &ForceElement, p: &[T], w: T) -> Result<ForceData<T>, FieldError> {
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
    let mut drawn = Vec::new();
    let identity = Pose::identity();
    e.kind
        .deformation(&geometry, &identity, &identity, &mut drawn);
    let free = (e.free.iter().zip(drawn))
        .map(|(f, d)| f.as_ref().map_or(Ok(d), |f| f.eval(p, w)))
        .collect::<Result<_, _>>()?;
    let each = |v: &[Option<Field>]| {
        v.iter()
            .map(|f| or_zero(f, p, w))
            .collect::<Result<Vec<T>, _>>()
    };
    let cross = e
        .cross
        .iter()
        .map(|x| {
            Ok(Cross {
                row: x.row,
                col: x.col,
                stiffness: or_zero(&x.stiffness, p, w)?,
                damping: or_zero(&x.damping, p, w)?,
            })
        })
        .collect::<Result<_, FieldError>>()?;
    Ok(ForceData {
        kind: e.kind,
        stiffness: each(&e.stiffness)?,
        damping: each(&e.damping)?,
        preload: each(&e.preload)?,
        free,
        geometry,
        cross,
    })
}

/// A beam element: its reference axes (`e₁` along the chord, `e₂` from the reference
/// direction), length and section properties.
fn beam<T: Real>(b: &Beam, p: &[T], w: T) -> Result<beams::Element<T>, FieldError> {
    let point1 = v3(&b.point1, p, w)?;
    let point2 = v3(&b.point2, p, w)?;
    let chord = point2 - point1;
    let length = chord.dot(&chord).sqrt();
    let e1 = chord / length;
    let e2 = perpendicular(&e1, &v3(&b.reference, p, w)?);
    let axes = M3::from_columns(&[e1, e2, e1.cross(&e2)]);
    let section = section(&b.section, length, p, w)?;
    Ok(beams::Element {
        body1: b.body1,
        point1,
        body2: b.body2,
        point2,
        axes,
        length,
        section,
        beta: (b.damping.as_ref()).map(|f| f.eval(p, w)).transpose()?,
    })
}

/// A beam's section properties. A tube of outer and inner diameter `D`, `d` has
/// `A = π(D² − d²)/4`, `I₂ = I₃ = π(D⁴ − d⁴)/64`, `J = 2I`, and, where no shear coefficient is
/// given, Cowper's (1966, J. Appl. Mech. 33:335) for the hollow circle, `m = d/D`:
/// `κ = 6(1+ν)(1+m²)² / ((7+6ν)(1+m²)² + (20+12ν)m²)`; `φ = 12EI/(κGAL²)` per bending axis.
fn section<T: Real>(
    s: &BeamSection,
    length: T,
    p: &[T],
    w: T,
) -> Result<beams::Section<T>, FieldError> {
    let one = cst::<T>(1.0);
    let l2 = length * length;
    match s {
        BeamSection::Tube(tube) => {
            let TubeSection {
                outer,
                inner,
                youngs,
                shear_modulus,
                poisson,
                density,
                coefficient,
            } = &**tube;
            let (d, di) = (outer.eval(p, w)?, or_zero(inner, p, w)?);
            let (e, rho) = (youngs.eval(p, w)?, density.eval(p, w)?);
            let two = cst::<T>(2.0);
            let (g, nu) = match (shear_modulus, poisson) {
                (Some(g), _) => {
                    let g = g.eval(p, w)?;
                    (g, e / (two * g) - one)
                }
                (None, Some(nu)) => {
                    let nu = nu.eval(p, w)?;
                    (e / (two * (one + nu)), nu)
                }
                (None, None) => unreachable!("validation asks for G or nu"),
            };
            let pi = cst::<T>(std::f64::consts::PI);
            let (d2, di2) = (d * d, di * di);
            let area = pi * (d2 - di2) / cst::<T>(4.0);
            let i = pi * (d2 * d2 - di2 * di2) / cst::<T>(64.0);
            let kappa = match coefficient {
                Some(k) => k.eval(p, w)?,
                None => {
                    let m2 = di2 / d2;
                    let s = (one + m2) * (one + m2);
                    cst::<T>(6.0) * (one + nu) * s
                        / ((cst::<T>(7.0) + cst::<T>(6.0) * nu) * s
                            + (cst::<T>(20.0) + cst::<T>(12.0) * nu) * m2)
                }
            };
            let phi = cst::<T>(12.0) * e * i / (kappa * g * area * l2);
            Ok(beams::Section {
                ea: e * area,
                gj: g * i * two,
                ei: [e * i, e * i],
                phi: [phi, phi],
                rho_a: rho * area,
                rho_i: [rho * i * two, rho * i, rho * i],
            })
        }
        BeamSection::Properties(props) => {
            let SectionProperties {
                ea,
                gj,
                ei,
                kga,
                rho_a,
                rho_i,
            } = &**props;
            let ei = [ei[0].eval(p, w)?, ei[1].eval(p, w)?];
            // Bending about e₂ shears along e₃, and about e₃ along e₂.
            let phi = match kga {
                Some([k2, k3]) => {
                    let (k2, k3) = (k2.eval(p, w)?, k3.eval(p, w)?);
                    let twelve = cst::<T>(12.0);
                    [twelve * ei[0] / (k3 * l2), twelve * ei[1] / (k2 * l2)]
                }
                None => [cst(0.0), cst(0.0)],
            };
            Ok(beams::Section {
                ea: ea.eval(p, w)?,
                gj: gj.eval(p, w)?,
                ei,
                phi,
                rho_a: rho_a.eval(p, w)?,
                rho_i: [
                    rho_i[0].eval(p, w)?,
                    rho_i[1].eval(p, w)?,
                    rho_i[2].eval(p, w)?,
                ],
            })
        }
    }
}

fn constraint<T: Real>(c: &Constraint, p: &[T], w: T) -> Result<ConstraintData<T>, FieldError> {
    let [_, use_axis, use_axis2, _] = c.kind.uses();
    let g = &c.geometry;
    Ok(ConstraintData {
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
    })
}

fn port_data<T: Real>(port: &Port, p: &[T], w: T) -> Result<PortData<T>, FieldError> {
    Ok(PortData {
        body: port.body,
        point: v3(&port.point, p, w)?,
        direction: direction(&port.direction, joints::Use::Required, p, w)?,
        rotation: port.rotation,
    })
}

fn load_data<T: Real>(load: &Load, p: &[T], w: T) -> Result<LoadData<T>, FieldError> {
    Ok(match &load.kind {
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
    })
}

fn coupler<T: Real>(c: &Coupler, p: &[T], w: T) -> Result<CouplerData<T>, FieldError> {
    Ok(CouplerData {
        coordinates: c.coordinates,
        coefficients: [c.coefficients[0].eval(p, w)?, c.coefficients[1].eval(p, w)?],
        value: c.value.eval(p, w)?,
    })
}

impl<T: Real> ForceData<T> {
    fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> ForceData<U> {
        let (g, v) = (&self.geometry, |x: &V3<T>| x.map(f));
        let each = |v: &[T]| v.iter().map(|&x| f(x)).collect();
        ForceData {
            kind: self.kind,
            geometry: forces::Geometry {
                body1: g.body1,
                point1: v(&g.point1),
                body2: g.body2,
                point2: v(&g.point2),
                axis: v(&g.axis),
                reference: v(&g.reference),
            },
            stiffness: each(&self.stiffness),
            damping: each(&self.damping),
            free: each(&self.free),
            preload: each(&self.preload),
            cross: (self.cross.iter())
                .map(|x| Cross {
                    row: x.row,
                    col: x.col,
                    stiffness: f(x.stiffness),
                    damping: f(x.damping),
                })
                .collect(),
        }
    }
}

impl<T: Real> ConstraintData<T> {
    fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> ConstraintData<U> {
        let (g, v) = (&self.geometry, |x: &V3<T>| x.map(f));
        ConstraintData {
            kind: self.kind,
            geometry: cuts::Geometry {
                body1: g.body1,
                point1: v(&g.point1),
                body2: g.body2,
                point2: v(&g.point2),
                axis: v(&g.axis),
                axis2: v(&g.axis2),
                length: g.length.map(f),
            },
            dropped: self.dropped.clone(),
        }
    }
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
