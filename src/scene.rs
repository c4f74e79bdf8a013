//! The mechanism as it stands at a configuration, for drawing, and its modes as motions of the
//! bodies and ports.
//!
//! A [`Scene`] places every element of the model at the coordinates `q`: each body's centre
//! of mass with the points it is joined at (its joints, cut joints, force elements and ports:
//! drawn as links from the centre of mass), each tree joint at its point with its axes, each cut
//! joint and force element between its two points, each port at its point with its direction.
//! Everything comes from the bodies' poses ([`crate::mechanics::kinematics::poses`]), so what is
//! drawn is what the equations see.
//!
//! A mode's physical shape ([`PhysicalShape`]) maps its complex shape `v` in the free
//! coordinates through the partial velocities at the equilibrium: the displacement of each
//! body's centre of mass `Σ_i J_v,i v_i`, its small rotation `Σ_i J_ω,i v_i` (ground axes), and
//! each port's displacement along its direction (or rotation about it), `bᵀv` with the port's
//! vector `b` of [`crate::mechanics::ports`]. A mode's motion over one period
//! ([`mode_frames`]) poses the mechanism at `q + a Re(v e^{iφ})` by the exact kinematics, so a
//! travelling (whirling) mode moves as it does, with amplitude and phase per coordinate; a
//! drawing animates the same motion to first order from the physical shape, every vector of a
//! scene moving with the body that placed it ([`Scene::anchored`]).

use crate::mechanics::System;
use crate::mechanics::dynamics::partials_for;
use crate::mechanics::kinematics::poses;
use crate::modal::C64;
use crate::model::Model;
use crate::real::{V3, lift1};
use crate::rigid::Pose;

/// A point in ground axes (m).
pub type P3 = [f64; 3];

fn p3(v: &V3<f64>) -> P3 {
    [v.x, v.y, v.z]
}

/// A body: its centre of mass and the points it is joined at. `P` is what stands for a point
/// or a direction ([`P3`] in a scene as drawn; see [`Scene::map`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct BodyMark<P = P3> {
    pub name: String,
    pub cm: P,
    /// Its axes: the ground axes as drawn, turned with the body (the columns of its rotation),
    /// so that a turn about a link's own line shows.
    pub axes: [P; 3],
    /// Where the body is joined (joints, cut joints, force elements, ports), each once.
    pub links: Vec<P>,
}

/// A tree joint at its point, with its axes (unit vectors, ground axes) where its type has them.
#[derive(Debug, Clone, serde::Serialize)]
pub struct JointMark<P = P3> {
    pub name: String,
    pub kind: &'static str,
    pub at: P,
    pub axes: Vec<P>,
    pub parent: String,
    pub child: String,
    /// Driven (turned at the operating speed) rather than free.
    pub driven: bool,
}

/// A cut joint or a force element: its type and its two points.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LinkMark<P = P3> {
    pub name: String,
    pub kind: &'static str,
    pub ends: [P; 2],
}

/// A port at its point, with its direction (unit, ground axes).
#[derive(Debug, Clone, serde::Serialize)]
pub struct PortMark<P = P3> {
    pub name: String,
    pub at: P,
    pub direction: P,
    pub rotation: bool,
}

/// The mechanism placed at one configuration (see the module documentation).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Scene<P = P3> {
    pub bodies: Vec<BodyMark<P>>,
    pub joints: Vec<JointMark<P>>,
    pub cuts: Vec<LinkMark<P>>,
    pub elements: Vec<LinkMark<P>>,
    pub ports: Vec<PortMark<P>>,
}

/// Where a vector of a scene comes from: the body whose pose placed it (`None`: the ground),
/// and whether it is a direction (it turns with the body) or a point (it moves with it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    pub body: Option<usize>,
    pub direction: bool,
}

/// A vector of a scene with its [`Anchor`].
#[derive(Debug, Clone, Copy)]
struct Placed {
    x: P3,
    anchor: Anchor,
}

impl<P> Scene<P> {
    /// The same scene with every vector (point or direction) `p` replaced by `f(p)`, called in
    /// one fixed order (bodies: centre of mass, axes, links; joints: point, axes; cut joints and
    /// force elements: ends; ports: point, direction), so that scenes of one mechanism map
    /// alike.
    pub fn map<Q>(&self, f: &mut impl FnMut(&P) -> Q) -> Scene<Q> {
        let link = |l: &LinkMark<P>, f: &mut dyn FnMut(&P) -> Q| LinkMark {
            name: l.name.clone(),
            kind: l.kind,
            ends: [f(&l.ends[0]), f(&l.ends[1])],
        };
        let bodies = (self.bodies.iter())
            .map(|b| BodyMark {
                name: b.name.clone(),
                cm: f(&b.cm),
                axes: [f(&b.axes[0]), f(&b.axes[1]), f(&b.axes[2])],
                links: b.links.iter().map(&mut *f).collect(),
            })
            .collect();
        let joints = (self.joints.iter())
            .map(|j| JointMark {
                name: j.name.clone(),
                kind: j.kind,
                at: f(&j.at),
                axes: j.axes.iter().map(&mut *f).collect(),
                parent: j.parent.clone(),
                child: j.child.clone(),
                driven: j.driven,
            })
            .collect();
        let cuts = self.cuts.iter().map(|l| link(l, f)).collect();
        let elements = self.elements.iter().map(|l| link(l, f)).collect();
        let ports = (self.ports.iter())
            .map(|p| PortMark {
                name: p.name.clone(),
                at: f(&p.at),
                direction: f(&p.direction),
                rotation: p.rotation,
            })
            .collect();
        Scene {
            bodies,
            joints,
            cuts,
            elements,
            ports,
        }
    }
}

/// The name of body `b` (`None`: the ground).
fn body_name(model: &Model, b: Option<usize>) -> String {
    b.map_or_else(|| "ground".to_string(), |b| model.bodies[b].name.clone())
}

impl Scene {
    /// The mechanism of `model` (instantiated as `sys`) at coordinates `q`.
    pub fn at(model: &Model, sys: &System<f64>, q: &[f64]) -> Scene {
        Scene::anchored(model, sys, q).0
    }

    /// [`Scene::at`], and the [`Anchor`] of every vector in the order of [`Scene::map`].
    pub fn anchored(model: &Model, sys: &System<f64>, q: &[f64]) -> (Scene, Vec<Anchor>) {
        let placed = placed(model, sys, q);
        let mut anchors = Vec::new();
        let scene = placed.map(&mut |p: &Placed| {
            anchors.push(p.anchor);
            p.x
        });
        (scene, anchors)
    }

    /// Every point drawn.
    pub fn points(&self) -> impl Iterator<Item = P3> + '_ {
        let bodies = self
            .bodies
            .iter()
            .flat_map(|b| std::iter::once(b.cm).chain(b.links.iter().copied()));
        let joints = self.joints.iter().map(|j| j.at);
        let links = (self.cuts.iter().chain(&self.elements)).flat_map(|l| l.ends);
        let ports = self.ports.iter().map(|p| p.at);
        bodies.chain(joints).chain(links).chain(ports)
    }

    /// The diagonal of the box around every point drawn, with the origin (m): the scale of the
    /// drawing (1 where everything is at one point).
    pub fn size(&self) -> f64 {
        let mut lo = [0.0f64; 3];
        let mut hi = [0.0f64; 3];
        for x in self.points() {
            for k in 0..3 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let d = ((0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>()).sqrt();
        if d > 0.0 && d.is_finite() { d } else { 1.0 }
    }
}

/// A point placed by body `body`'s pose (`None`: the ground).
fn point(body: Option<usize>, x: &V3<f64>) -> Placed {
    Placed {
        x: p3(x),
        anchor: Anchor {
            body,
            direction: false,
        },
    }
}

/// A direction turned by body `body`'s pose (`None`: the ground).
fn direction(body: Option<usize>, u: &V3<f64>) -> Placed {
    Placed {
        x: p3(u),
        anchor: Anchor {
            body,
            direction: true,
        },
    }
}

/// The mechanism of `model` (instantiated as `sys`) at coordinates `q`, every vector with the
/// body that placed it (see [`Scene::at`]).
fn placed(model: &Model, sys: &System<f64>, q: &[f64]) -> Scene<Placed> {
    let pose = poses(sys, q);
    let ground = Pose::identity();
    let pose_of = |b: Option<usize>| b.map_or(&ground, |b| &pose[b]);
    let mut links: Vec<Vec<Placed>> = vec![Vec::new(); sys.bodies.len()];
    // A point joins body `b` once (a link keeps the anchor of the first point placed there).
    let mut attach = |b: Option<usize>, p: Placed| {
        if let Some(b) = b {
            let l = &mut links[b];
            let x = p.x;
            if !l
                .iter()
                .any(|y| (0..3).all(|k| (x[k] - y.x[k]).abs() <= 1e-12 * (1.0 + x[k].abs())))
            {
                l.push(p);
            }
        }
    };
    let unused = crate::joints::Use::Unused;
    let mut joints = Vec::with_capacity(sys.joints.len());
    for (k, j) in sys.joints.iter().enumerate() {
        let mj = &model.joints[model.order[k]];
        let [at, axis, axis2] = j.kind.uses();
        let child = &pose[j.child];
        let at = point(
            Some(j.child),
            &child.apply(if at == unused {
                &sys.bodies[j.child].cm
            } else {
                &j.geometry.at
            }),
        );
        let mut axes = Vec::new();
        if axis != unused {
            axes.push(direction(
                j.parent,
                &(pose_of(j.parent).rot * j.geometry.axis),
            ));
        }
        if axis2 != unused {
            axes.push(direction(Some(j.child), &(child.rot * j.geometry.axis2)));
        }
        attach(j.parent, at);
        attach(Some(j.child), at);
        joints.push(JointMark {
            name: mj.name.clone(),
            kind: j.kind.name(),
            at,
            axes,
            parent: body_name(model, j.parent),
            child: body_name(model, Some(j.child)),
            driven: j.coords.clone().any(|c| sys.drive[c].is_some()),
        });
    }
    let mut cuts = Vec::with_capacity(sys.constraints.len());
    for (c, mc) in sys.constraints.iter().zip(&model.constraints) {
        let g = &c.geometry;
        let ends = [
            point(g.body1, &pose_of(g.body1).apply(&g.point1)),
            point(g.body2, &pose_of(g.body2).apply(&g.point2)),
        ];
        attach(g.body1, ends[0]);
        attach(g.body2, ends[1]);
        cuts.push(LinkMark {
            name: mc.name.clone(),
            kind: c.kind.name(),
            ends,
        });
    }
    let mut elements = Vec::with_capacity(sys.forces.len());
    for (e, me) in sys.forces.iter().zip(&model.forces) {
        let g = &e.geometry;
        let [point1, point2, _] = e.kind.uses();
        // Where a type has no points (a torque between two bodies), it joins their centres of
        // mass.
        let end = |b: Option<usize>, used: bool, x: &V3<f64>| match b {
            Some(b) if !used => point(Some(b), &pose[b].apply(&sys.bodies[b].cm)),
            None if !used => point(None, &V3::zeros()),
            _ => point(b, &pose_of(b).apply(x)),
        };
        let ends = [
            end(g.body1, point1 != unused, &g.point1),
            end(g.body2, point2 != unused, &g.point2),
        ];
        if point1 != unused {
            attach(g.body1, ends[0]);
        }
        if point2 != unused {
            attach(g.body2, ends[1]);
        }
        elements.push(LinkMark {
            name: me.name.clone(),
            kind: e.kind.name(),
            ends,
        });
    }
    let mut ports = Vec::with_capacity(sys.ports.len());
    for (p, mp) in sys.ports.iter().zip(&model.ports) {
        let at = point(Some(p.body), &pose[p.body].apply(&p.point));
        attach(Some(p.body), at);
        ports.push(PortMark {
            name: mp.name.clone(),
            at,
            direction: direction(Some(p.body), &(pose[p.body].rot * p.direction)),
            rotation: p.rotation,
        });
    }
    let bodies = (sys.bodies.iter().zip(&model.bodies).enumerate())
        .map(|(b, (body, mb))| BodyMark {
            name: mb.name.clone(),
            cm: point(Some(b), &pose[b].apply(&body.cm)),
            axes: [0, 1, 2].map(|k| direction(Some(b), &pose[b].rot.column(k).into_owned())),
            links: std::mem::take(&mut links[b]),
        })
        .collect();
    Scene {
        bodies,
        joints,
        cuts,
        elements,
        ports,
    }
}

/// A mode's shape mapped onto the bodies and ports (see the module documentation), for a shape
/// `v` in the free coordinates: per unit of `v`.
#[derive(Debug, Clone)]
pub struct PhysicalShape {
    /// Per body: the displacement of its centre of mass (m per unit of `v`), ground axes.
    pub displacement: Vec<[C64; 3]>,
    /// Per body: its small rotation (rad per unit of `v`), ground axes.
    pub rotation: Vec<[C64; 3]>,
    /// Per port: the displacement along its direction (m), or the rotation about it (rad).
    pub ports: Vec<C64>,
}

/// The physical shape of the mode shape `v` over the coordinates `free` at `q`.
pub fn physical_shape(sys: &System<f64>, q: &[f64], free: &[usize], v: &[C64]) -> PhysicalShape {
    let mut one = physical_shapes(sys, q, free, std::slice::from_ref(&v));
    one.pop().expect("one shape in, one out")
}

/// [`physical_shape`] of each of `shapes`, the partial velocities evaluated once for all.
pub fn physical_shapes<V: AsRef<[C64]>>(
    sys: &System<f64>,
    q: &[f64],
    free: &[usize],
    shapes: &[V],
) -> Vec<PhysicalShape> {
    let j = partials_for(&sys.map(lift1), q, free);
    let jv: Vec<Vec<V3<f64>>> = (0..sys.bodies.len())
        .map(|b| free.iter().map(|&i| j.jv(sys, i, b)).collect())
        .collect();
    let jw: Vec<Vec<V3<f64>>> = (0..sys.bodies.len())
        .map(|b| free.iter().map(|&i| j.jw(sys, i, b)).collect())
        .collect();
    let pose = &j.pose;
    let zero = [C64::new(0.0, 0.0); 3];
    shapes
        .iter()
        .map(|v| {
            let v = v.as_ref();
            let combine = |rows: &[V3<f64>]| {
                let mut out = zero;
                for (r, &vi) in rows.iter().zip(v) {
                    for k in 0..3 {
                        out[k] += vi * r[k];
                    }
                }
                out
            };
            let displacement: Vec<[C64; 3]> = jv.iter().map(|rows| combine(rows)).collect();
            let rotation: Vec<[C64; 3]> = jw.iter().map(|rows| combine(rows)).collect();
            let ports = sys
                .ports
                .iter()
                .map(|port| {
                    let b = port.body;
                    let u = pose[b].rot * port.direction;
                    let arm = pose[b].rot * (port.point - sys.bodies[b].cm);
                    let along = |x: &[C64; 3]| x[0] * u.x + x[1] * u.y + x[2] * u.z;
                    if port.rotation {
                        along(&rotation[b])
                    } else {
                        let (d, r) = (&displacement[b], &rotation[b]);
                        // d + r × arm.
                        let moved = [
                            d[0] + r[1] * arm.z - r[2] * arm.y,
                            d[1] + r[2] * arm.x - r[0] * arm.z,
                            d[2] + r[0] * arm.y - r[1] * arm.x,
                        ];
                        along(&moved)
                    }
                })
                .collect();
            PhysicalShape {
                displacement,
                rotation,
                ports,
            }
        })
        .collect()
}

/// The mechanism over one period of the mode `v` (over the coordinates `free`) at amplitude
/// `a`, at `frames` phases `φ = 2πk/frames`: posed at `q + a Re(v e^{iφ})` by the exact
/// kinematics (the reference that a drawing's first-order frames,
/// [`crate::drawing::ModeMotion::frame`], are checked against).
pub fn mode_frames(
    model: &Model,
    sys: &System<f64>,
    q: &[f64],
    free: &[usize],
    v: &[C64],
    a: f64,
    frames: usize,
) -> Vec<Scene> {
    (0..frames)
        .map(|k| {
            let phase = C64::from_polar(1.0, std::f64::consts::TAU * k as f64 / frames as f64);
            let mut qk = q.to_vec();
            for (&i, &vi) in free.iter().zip(v) {
                qk[i] += a * (vi * phase).re;
            }
            Scene::at(model, sys, &qk)
        })
        .collect()
}

/// The modal assurance criterion of two shapes over the same coordinates,
/// `|aᴴb|² / ((aᴴa)(bᴴb))` (Allemang 2003, "The modal assurance criterion — twenty years of
/// use and abuse"): 1 for the same shape (any complex scale), 0 for orthogonal ones; 0 where
/// a shape is zero.
pub fn mac(a: &[C64], b: &[C64]) -> f64 {
    let ab: C64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if aa > 0.0 && bb > 0.0 {
        ab.norm_sqr() / (aa * bb)
    } else {
        0.0
    }
}

/// A short description of the mode `v` (over the coordinates `free`, the mechanism at `q`):
/// its dominant coordinate and, where a driven revolute joint spins at this speed, its whirl
/// about that joint's axis: the orbit of the body that moves most across the axis turns with
/// the spin (`forward whirl`) or against it (`backward whirl`); nothing where the orbit is
/// (nearly) a line. `shape` is the mode's [`physical_shape`].
pub fn describe(
    model: &Model,
    sys: &System<f64>,
    q: &[f64],
    free: &[usize],
    v: &[C64],
    shape: &PhysicalShape,
) -> String {
    let Some((k, _)) = v
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
    else {
        return String::new();
    };
    let name = model.coordinates[free[k]].name.clone();
    let pose = poses(sys, q);
    let spin = sys.joints.iter().find_map(|j| {
        let c = j.coords.start;
        let omega = sys.drive.get(c).copied().flatten()?;
        (j.kind == crate::joints::Kind::Revolute && omega != 0.0).then(|| {
            let axis = j
                .parent
                .map_or(j.geometry.axis, |p| pose[p].rot * j.geometry.axis);
            (axis, omega)
        })
    });
    let Some((axis, omega)) = spin else {
        return name;
    };
    let e1 = crate::rigid::perpendicular(&axis, &least_aligned(&axis));
    let e2 = axis.cross(&e1);
    let across = |d: &[C64; 3], e: &V3<f64>| d[0] * e.x + d[1] * e.y + d[2] * e.z;
    let Some((u, w)) = shape
        .displacement
        .iter()
        .map(|d| (across(d, &e1), across(d, &e2)))
        .max_by(|a, b| {
            (a.0.norm_sqr() + a.1.norm_sqr()).total_cmp(&(b.0.norm_sqr() + b.1.norm_sqr()))
        })
    else {
        return name;
    };
    // The orbit Re(u e^{iωt}) e₁ + Re(w e^{iωt}) e₂ turns about the axis with the sign of
    // Im(u w̄); a line where that is small against the orbit's size.
    let turn = (u * w.conj()).im;
    let size = u.norm_sqr() + w.norm_sqr();
    if size == 0.0 || turn.abs() < 0.1 * size {
        return name;
    }
    let forward = (turn > 0.0) == (omega > 0.0);
    format!(
        "{name}, {} whirl",
        if forward { "forward" } else { "backward" }
    )
}

/// The coordinate axis least aligned with `a`.
fn least_aligned(a: &V3<f64>) -> V3<f64> {
    let k = (0..3)
        .min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
        .unwrap_or(0);
    let mut e = V3::zeros();
    e[k] = 1.0;
    e
}

/// [`describe`] for every mode of the point `pt` of `model` solved with parameters `p` (empty
/// where the model does not evaluate there).
pub fn descriptions(model: &Model, p: &[f64], pt: &crate::sweep::Point) -> Vec<String> {
    let Ok(sys) = System::new(model, p, pt.speed) else {
        return Vec::new();
    };
    let (q, free) = (&pt.equilibrium.q, &pt.linear.free);
    let shapes: Vec<Vec<C64>> = (pt.shapes.iter())
        .map(|s| s.iter().copied().collect())
        .collect();
    let physical = physical_shapes(&sys, q, free, &shapes);
    (shapes.iter().zip(&physical))
        .map(|(v, shape)| describe(model, &sys, q, free, v, shape))
        .collect()
}
