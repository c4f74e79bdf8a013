//! A mode on the scene: its physical shape (the bodies' displacements and rotations, the
//! ports'), the mechanism posed along it over one period, and the words that describe it (its
//! dominant coordinate, its whirl); see the [`super`] module documentation.

use super::Scene;
use crate::mechanics::System;
use crate::mechanics::dynamics::partials_for;
use crate::mechanics::kinematics::poses;
use crate::modal::C64;
use crate::model::Model;
use crate::real::{V3, lift1};

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

/// The mechanism posed at an equilibrium, where its modes are drawn and described: the model,
/// its system at the point's parameters and speed, the coordinates `q` and the free coordinates
/// the mode shapes are written over.
#[derive(Debug, Clone, Copy)]
pub struct Posed<'a> {
    pub model: &'a Model,
    pub sys: &'a System<f64>,
    pub q: &'a [f64],
    pub free: &'a [usize],
}

/// The mechanism `at` over one period of the mode `v` at amplitude `a`, at `frames` phases
/// `φ = 2πk/frames`: posed at `q + a Re(v e^{iφ})` by the exact kinematics (the reference that
/// a drawing's first-order frames, [`crate::drawing::ModeMotion::frame`], are checked against).
pub fn mode_frames(at: Posed<'_>, v: &[C64], a: f64, frames: usize) -> Vec<Scene> {
    (0..frames)
        .map(|k| {
            let phase = C64::from_polar(1.0, std::f64::consts::TAU * k as f64 / frames as f64);
            let mut qk = at.q.to_vec();
            for (&i, &vi) in at.free.iter().zip(v) {
                qk[i] += a * (vi * phase).re;
            }
            Scene::at(at.model, at.sys, &qk)
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

/// A short description of the mode `v` of the mechanism `at`: its dominant coordinate and,
/// where a driven revolute joint spins at this speed, its whirl about that joint's axis: the
/// orbit of the body that moves most across the axis turns with the spin (`forward whirl`) or
/// against it (`backward whirl`); nothing where the orbit is (nearly) a line. `shape` is the
/// mode's [`physical_shape`].
pub fn describe(at: Posed<'_>, v: &[C64], shape: &PhysicalShape) -> String {
    let Posed {
        model,
        sys,
        q,
        free,
    } = at;
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
        .map(|(v, shape)| {
            let at = Posed {
                model,
                sys: &sys,
                q,
                free,
            };
            describe(at, v, shape)
        })
        .collect()
}
