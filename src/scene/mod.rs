//! The mechanism as it stands at a configuration, for drawing, and its modes as motions of the
//! bodies and ports.
//!
//! A [`Scene`] places every element of the model at the coordinates `q`: each body's centre
//! of mass with the points it is joined at (its joints, cut joints, force elements and ports:
//! drawn as links from the centre of mass), each tree joint at its point with its axes, each cut
//! joint and force element between its two points, each port at its point with its direction,
//! each beam element as its deflected curve ([`CurveMark`]: the cubic Hermite interpolation of
//! its two nodes' points and turned tangents, the element's shape functions without shear).
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

mod modes;

pub use modes::{
    PhysicalShape, Posed, describe, descriptions, frame_of, frame_words, mac, mode_frames,
    physical_shape, physical_shapes,
};

use crate::mechanics::System;
use crate::mechanics::kinematics::poses;
use crate::model::Model;
use crate::real::V3;
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
    /// The body as a solid: its equivalent ellipsoid of inertia, the uniform solid ellipsoid
    /// with the body's mass and inertia about its centre of mass ([`equivalent_ellipsoid`]),
    /// as its shape matrix `S` (m²) in the reference configuration's axes (the columns of
    /// `axes` are those axes turned with the body: `Σ_kl S_kl a_k a_lᵀ` in ground axes). The
    /// ellipsoid is the points `c + y` with `yᵀS⁻¹y ≤ 1`. Zero for a point mass.
    pub solid: [[f64; 3]; 3],
}

impl BodyMark {
    /// How far the body's solid reaches from its centre of mass along the unit direction `d`
    /// (m): `√(dᵀ S_g d)`, `S_g` its shape matrix in ground axes.
    pub fn reach(&self, d: &P3) -> f64 {
        let along: Vec<f64> = (self.axes.iter())
            .map(|a| a[0] * d[0] + a[1] * d[1] + a[2] * d[2])
            .collect();
        let mut q = 0.0;
        for k in 0..3 {
            for l in 0..3 {
                q += self.solid[k][l] * along[k] * along[l];
            }
        }
        q.max(0.0).sqrt()
    }
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

/// A beam element drawn as its curve: `p(ξ) = H₁ a + H₂ L tₐ + H₃ b + H₄ L t_b` over
/// [`CURVE_POINTS`] equally spaced `ξ` from node a to node b, with `a`, `b` the nodes' points,
/// `tₐ`, `t_b` the element's axis as drawn turned with each node's body and `L` its length as
/// drawn (so a straight unstrained element is its chord, and a rigid motion moves the curve
/// rigidly).
#[derive(Debug, Clone, serde::Serialize)]
pub struct CurveMark<P = P3> {
    pub name: String,
    /// The nodes' bodies (`None`: the ground): the curve moves with them.
    pub nodes: [Option<usize>; 2],
    /// `L`, m.
    pub length: f64,
    /// `tₐ`, `t_b`: unit directions, each turned with its node's body.
    pub tangents: [P; 2],
    /// The curve's points, the first and the last at the nodes.
    pub points: Vec<P>,
    /// The radius the element is drawn with (m): `√(2ρJ/ρA)` from its section's mass (the
    /// outer radius of a solid round section), `2√(EI/EA)` where it has none (likewise), zero
    /// where it has neither.
    pub radius: f64,
}

/// The number of points a beam element is drawn through.
pub const CURVE_POINTS: usize = 9;

/// The cubic Hermite functions `[H₁, H₂, H₃, H₄]` at `ξ ∈ [0, 1]` (value at a, slope at a,
/// value at b, slope at b).
pub fn hermite(xi: f64) -> [f64; 4] {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    [
        1.0 - 3.0 * x2 + 2.0 * x3,
        xi - 2.0 * x2 + x3,
        3.0 * x2 - 2.0 * x3,
        x3 - x2,
    ]
}

/// The mechanism placed at one configuration (see the module documentation).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Scene<P = P3> {
    pub bodies: Vec<BodyMark<P>>,
    pub joints: Vec<JointMark<P>>,
    pub cuts: Vec<LinkMark<P>>,
    pub elements: Vec<LinkMark<P>>,
    pub ports: Vec<PortMark<P>>,
    pub beams: Vec<CurveMark<P>>,
}

/// Where a vector of a scene comes from: the body whose pose placed it (`None`: the ground),
/// and whether it is a direction (it turns with the body) or a point (it moves with it); a
/// point of a beam's curve inside the element moves with both nodes (`along`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    pub body: Option<usize>,
    pub direction: bool,
    pub along: Option<Along>,
}

/// A point of beam `beam`'s curve at `ξ`, strictly inside the element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Along {
    pub beam: usize,
    pub xi: f64,
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
    /// force elements: ends; ports: point, direction; beams: tangents, points), so that scenes
    /// of one mechanism map alike.
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
                solid: b.solid,
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
        let beams = (self.beams.iter())
            .map(|c| CurveMark {
                name: c.name.clone(),
                nodes: c.nodes,
                length: c.length,
                tangents: [f(&c.tangents[0]), f(&c.tangents[1])],
                points: c.points.iter().map(&mut *f).collect(),
                radius: c.radius,
            })
            .collect();
        Scene {
            bodies,
            joints,
            cuts,
            elements,
            ports,
            beams,
        }
    }
}

/// The equivalent ellipsoid of inertia of a body of mass `m` and inertia `j` about its centre
/// of mass: the uniform solid ellipsoid with the same mass and the same inertia, as its shape
/// matrix `S = Σ a_k² p_k p_kᵀ` (semi-axes `a_k` along the principal axes `p_k`). Its second
/// moment of mass `∫ y yᵀ dm` is `(m/5) S`, and a body's is `(tr J / 2) I − J`, so
/// `S = (5/m)(tr J / 2 I − J)` with no eigendecomposition. A thin uniform disk of radius `r` is
/// drawn as a flat ellipsoid of radius `r √5/2`; a point mass (or a massless body) as nothing
/// (zero).
pub fn equivalent_ellipsoid(m: f64, j: &crate::real::M3<f64>) -> [[f64; 3]; 3] {
    if !(m > 0.0 && m.is_finite() && j.iter().all(|x| x.is_finite())) {
        return [[0.0; 3]; 3];
    }
    let half_trace = 0.5 * j.trace();
    let mut s = [[0.0; 3]; 3];
    for (r, row) in s.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            let second = if r == c { half_trace } else { 0.0 } - 0.5 * (j[(r, c)] + j[(c, r)]);
            *x = 5.0 / m * second;
        }
    }
    s
}

/// The radius a beam element is drawn with (see [`CurveMark::radius`]).
fn drawn_radius(section: &crate::beams::Section<f64>) -> f64 {
    let r = if section.rho_a > 0.0 {
        (2.0 * section.rho_i[0] / section.rho_a).sqrt()
    } else if section.ea > 0.0 {
        2.0 * (section.ei[0].max(section.ei[1]) / section.ea).sqrt()
    } else {
        0.0
    };
    if r.is_finite() { r } else { 0.0 }
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
        let beams = self.beams.iter().flat_map(|c| c.points.iter().copied());
        bodies.chain(joints).chain(links).chain(ports).chain(beams)
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
            along: None,
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
            along: None,
        },
    }
}

/// The mechanism of `model` (instantiated as `sys`) at coordinates `q`, every vector with the
/// body that placed it (see [`Scene::at`]).
fn placed(model: &Model, sys: &System<f64>, q: &[f64]) -> Scene<Placed> {
    let mut at = Placer {
        model,
        sys,
        pose: poses(sys, q),
        ground: Pose::identity(),
        links: vec![Vec::new(); sys.bodies.len()],
    };
    let joints = at.joints();
    let cuts = at.cuts();
    let elements = at.elements();
    let ports = at.ports();
    let beams = at.beams();
    let pose = &at.pose;
    let bodies = (sys.bodies.iter().zip(&model.bodies).enumerate())
        .map(|(b, (body, mb))| BodyMark {
            name: mb.name.clone(),
            cm: point(Some(b), &pose[b].apply(&body.cm)),
            axes: [0, 1, 2].map(|k| direction(Some(b), &pose[b].rot.column(k).into_owned())),
            links: std::mem::take(&mut at.links[b]),
            solid: equivalent_ellipsoid(body.mass, &body.inertia),
        })
        .collect();
    Scene {
        bodies,
        joints,
        cuts,
        elements,
        ports,
        beams,
    }
}

/// The mechanism being placed: its bodies' poses, and the points each body is linked to so
/// far.
struct Placer<'a> {
    model: &'a Model,
    sys: &'a System<f64>,
    pose: Vec<Pose<f64>>,
    ground: Pose<f64>,
    links: Vec<Vec<Placed>>,
}

impl Placer<'_> {
    fn pose_of(&self, b: Option<usize>) -> &Pose<f64> {
        b.map_or(&self.ground, |b| &self.pose[b])
    }

    /// A point joins body `b` once (a link keeps the anchor of the first point placed there).
    fn attach(&mut self, b: Option<usize>, p: Placed) {
        if let Some(b) = b {
            let l = &mut self.links[b];
            let x = p.x;
            if !l
                .iter()
                .any(|y| (0..3).all(|k| (x[k] - y.x[k]).abs() <= 1e-12 * (1.0 + x[k].abs())))
            {
                l.push(p);
            }
        }
    }

    fn joints(&mut self) -> Vec<JointMark<Placed>> {
        let (model, sys) = (self.model, self.sys);
        let unused = crate::joints::Use::Unused;
        let mut joints = Vec::with_capacity(sys.joints.len());
        for (k, j) in sys.joints.iter().enumerate() {
            let mj = &model.joints[model.order[k]];
            let [at, axis, axis2] = j.kind.uses();
            let child = &self.pose[j.child];
            let at = point(
                Some(j.child),
                &child.apply(if at == unused {
                    &sys.bodies[j.child].cm
                } else {
                    &j.geometry.at
                }),
            );
            let mut axes = Vec::new();
            // An axis a type ignores (a fixed joint's) may be absent: zero, not drawn.
            if axis != unused && j.geometry.axis.norm() > 0.0 {
                axes.push(direction(
                    j.parent,
                    &(self.pose_of(j.parent).rot * j.geometry.axis),
                ));
            }
            if axis2 != unused && j.geometry.axis2.norm() > 0.0 {
                axes.push(direction(Some(j.child), &(child.rot * j.geometry.axis2)));
            }
            self.attach(j.parent, at);
            self.attach(Some(j.child), at);
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
        joints
    }

    fn cuts(&mut self) -> Vec<LinkMark<Placed>> {
        let mut cuts = Vec::with_capacity(self.sys.constraints.len());
        for (c, mc) in self.sys.constraints.iter().zip(&self.model.constraints) {
            let g = &c.geometry;
            let ends = [
                point(g.body1, &self.pose_of(g.body1).apply(&g.point1)),
                point(g.body2, &self.pose_of(g.body2).apply(&g.point2)),
            ];
            self.attach(g.body1, ends[0]);
            self.attach(g.body2, ends[1]);
            cuts.push(LinkMark {
                name: mc.name.clone(),
                kind: c.kind.name(),
                ends,
            });
        }
        cuts
    }

    fn elements(&mut self) -> Vec<LinkMark<Placed>> {
        let (model, sys) = (self.model, self.sys);
        let unused = crate::joints::Use::Unused;
        let mut elements = Vec::with_capacity(sys.forces.len());
        for (e, me) in sys.forces.iter().zip(&model.forces) {
            let g = &e.geometry;
            let [point1, point2, _] = e.kind.uses();
            // Where a type has no points (a torque between two bodies), it joins their centres
            // of mass.
            let end = |b: Option<usize>, used: bool, x: &V3<f64>| match b {
                Some(b) if !used => point(Some(b), &self.pose[b].apply(&sys.bodies[b].cm)),
                None if !used => point(None, &V3::zeros()),
                _ => point(b, &self.pose_of(b).apply(x)),
            };
            let ends = [
                end(g.body1, point1 != unused, &g.point1),
                end(g.body2, point2 != unused, &g.point2),
            ];
            if point1 != unused {
                self.attach(g.body1, ends[0]);
            }
            if point2 != unused {
                self.attach(g.body2, ends[1]);
            }
            elements.push(LinkMark {
                name: me.name.clone(),
                kind: e.kind.name(),
                ends,
            });
        }
        elements
    }

    fn ports(&mut self) -> Vec<PortMark<Placed>> {
        let mut ports = Vec::with_capacity(self.sys.ports.len());
        for (p, mp) in self.sys.ports.iter().zip(&self.model.ports) {
            let pose = &self.pose[p.body];
            let at = point(Some(p.body), &pose.apply(&p.point));
            let direction = direction(Some(p.body), &(pose.rot * p.direction));
            self.attach(Some(p.body), at);
            ports.push(PortMark {
                name: mp.name.clone(),
                at,
                direction,
                rotation: p.rotation,
            });
        }
        ports
    }

    fn beams(&mut self) -> Vec<CurveMark<Placed>> {
        let mut beams = Vec::with_capacity(self.sys.beams.len());
        for (i, (e, mb)) in self.sys.beams.iter().zip(&self.model.beams).enumerate() {
            let nodes = [e.body1, e.body2];
            let ends = [
                self.pose_of(e.body1).apply(&e.point1),
                self.pose_of(e.body2).apply(&e.point2),
            ];
            let axis = e.axes.column(0).into_owned();
            let tangents = [0, 1].map(|k| self.pose_of(nodes[k]).rot * axis);
            let points = (0..CURVE_POINTS)
                .map(|k| {
                    let xi = k as f64 / (CURVE_POINTS - 1) as f64;
                    let h = hermite(xi);
                    let x = ends[0] * h[0]
                        + tangents[0] * (h[1] * e.length)
                        + ends[1] * h[2]
                        + tangents[1] * (h[3] * e.length);
                    match k {
                        0 => point(nodes[0], &ends[0]),
                        _ if k == CURVE_POINTS - 1 => point(nodes[1], &ends[1]),
                        _ => Placed {
                            x: p3(&x),
                            anchor: Anchor {
                                body: None,
                                direction: false,
                                along: Some(Along { beam: i, xi }),
                            },
                        },
                    }
                })
                .collect();
            self.attach(nodes[0], point(nodes[0], &ends[0]));
            self.attach(nodes[1], point(nodes[1], &ends[1]));
            beams.push(CurveMark {
                name: mb.name.clone(),
                nodes,
                length: e.length,
                tangents: [0, 1].map(|k| direction(nodes[k], &tangents[k])),
                points,
                radius: drawn_radius(&e.section),
            });
        }
        beams
    }
}
