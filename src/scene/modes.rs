//! A mode on the scene: its physical shape (the bodies' displacements and rotations, the
//! ports'), the mechanism posed along it over one period, and the words that describe it (its
//! dominant coordinate, its whirl); see the [`super`] module documentation.

use super::Scene;
use crate::mechanics::System;
use crate::mechanics::dynamics::body_partials_for;
use crate::modal::C64;
use crate::model::Model;
use crate::real::{V3, lift1};
use crate::whirl::Whirl;

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
    let j = body_partials_for(&sys.map(lift1), q, free);
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

/// A short description of the mode `v` over the free coordinates of `model`: its dominant
/// coordinate and its whirl ([`crate::whirl`]), where it has one.
pub fn describe(model: &Model, free: &[usize], v: &[C64], whirl: Option<Whirl>) -> String {
    let Some((k, _)) = v
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
    else {
        return String::new();
    };
    let name = model.coordinates[free[k]].name.clone();
    match whirl {
        Some(w) => format!("{name}, {} whirl", w.as_str()),
        None => name,
    }
}

/// The frame the mode `v` (over the free coordinates `free`) is seen from: the driven rotation
/// that turns its dominant coordinate's frame (`turned`, [`Model::turned_by`]), `None` for the
/// fixed (ground) frame.
pub fn frame_of(turned: &[Option<usize>], free: &[usize], v: &[C64]) -> Option<usize> {
    let (k, _) = (v.iter().enumerate()).max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))?;
    turned[free[k]]
}

/// A mode's frame in words: `rotating (with JOINT)` or `fixed`.
pub fn frame_words(model: &Model, frame: Option<usize>) -> String {
    frame.map_or("fixed".to_string(), |j| {
        format!("rotating (with {})", model.joints[j].name)
    })
}

/// [`describe`] for every mode of the point `pt` of `model` solved with parameters `p` (empty
/// where the model does not evaluate there).
pub fn descriptions(model: &Model, p: &[f64], pt: &crate::sweep::Point) -> Vec<String> {
    let Ok(whirls) = crate::whirl::of_point(model, p, pt) else {
        return Vec::new();
    };
    (pt.shapes.iter().zip(whirls))
        .map(|(v, w)| {
            let v: Vec<C64> = v.iter().copied().collect();
            describe(model, &pt.linear.free, &v, w)
        })
        .collect()
}
