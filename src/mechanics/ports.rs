//! Ports: the physical degrees of freedom where transfer functions start and end.
//!
//! A translation port at a point `P` of body `b` along a direction `u` (carried by the body)
//! enters the equations as the generalised force `b_i F` of a force `F u` at `P`, and reads the
//! displacement `b_i δq_i` of `P` along `u`, with the same vector
//!
//! ```text
//! b_i = u · ∂x_P/∂q_i = u · (J_v,i + J_ω,i × (x_P − x_cm))        (rigid body: x_P − x_cm = R (P − cm))
//! ```
//!
//! (reciprocity); a rotation port about `u` has `b_i = u · J_ω,i` (a torque in, a small
//! rotation out). With `u = R u₀` at the equilibrium the vectors depend on the coordinates and
//! the parameters like everything else, so derivatives of transfer functions between ports
//! follow the equilibrium's move exactly.
//!
//! An unbalance ([`crate::model::Unbalance`]) is a load of its own kind: a force of amplitude
//! `m e Ω²` turning with its body at the spin rate `Ω = |ω_b|`, across the spin axis `n =
//! ω_b/Ω`: in complex amplitudes `F = m e Ω² e^{iφ} (e₁ − i e₂)`, `e₂ = n × e₁` (ROSS's
//! `_unbalance_force`, with the shaft along `n`). Its generalised force is that of a force at
//! the point, `Re F·b(e₁)`-wise: `Ω² (m e e^{iφ}) (b(e₁) − i b(e₂))`, kept per unit `Ω²` with `Ω`
//! beside it (the excitation frequency). The reference `e₁` only turns the response's phase, so
//! it is any direction across the axis (the coordinate axis least aligned with it). The orbit
//! must be the ground's: the point stands still in the steady motion (on the spin axis of a
//! body whose translations are not coordinates of a frame the spin turns).

use super::System;
use super::dynamics::{BodyPartials, body_partials_for};
use super::kinematics::poses;
use crate::model::{FieldError, Model};
use crate::real::{Real, V3, cst, lift1, re};

/// The vector of every port over the coordinates `coords`, at `q`.
pub fn port_vectors<T: Real>(sys: &System<T>, q: &[T], coords: &[usize]) -> Vec<Vec<T>> {
    if sys.ports.is_empty() {
        return Vec::new();
    }
    let j = body_partials_for(&sys.map(lift1), q, coords);
    let pose = poses(sys, q);
    sys.ports
        .iter()
        .map(|port| {
            let b = port.body;
            let u = pose[b].rot * port.direction;
            let arm = pose[b].rot * (port.point - sys.bodies[b].cm);
            coords
                .iter()
                .map(|&i| {
                    let w = j.jw(sys, i, b);
                    if port.rotation {
                        u.dot(&w)
                    } else {
                        u.dot(&(j.jv(sys, i, b) + w.cross(&arm)))
                    }
                })
                .collect()
        })
        .collect()
}

/// An unbalance's load over the independent (or free) coordinates: `F = Ω² (re + i im)` at
/// the excitation frequency `Ω`, the body's spin rate (all zero where nothing spins).
#[derive(Debug, Clone)]
pub struct UnbalanceLoad<T> {
    pub re: Vec<T>,
    pub im: Vec<T>,
    pub spin: T,
}

impl<T: Real> UnbalanceLoad<T> {
    /// The same load with every number mapped by `f`.
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> UnbalanceLoad<U> {
        UnbalanceLoad {
            re: self.re.iter().map(|&v| f(v)).collect(),
            im: self.im.iter().map(|&v| f(v)).collect(),
            spin: f(self.spin),
        }
    }
}

/// The ports' vectors and the unbalances' loads.
#[derive(Debug, Clone)]
pub struct Vectors<T> {
    pub ports: Vec<Vec<T>>,
    pub unbalances: Vec<UnbalanceLoad<T>>,
}

/// Why an unbalance has no load at an equilibrium.
#[derive(Debug, Clone, thiserror::Error)]
pub enum PortError {
    #[error("{0}")]
    Field(#[from] FieldError),
    #[error(
        "unbalance '{name}': its point is carried round by the spin at {speed} ({why}); an \
         unbalance turns about a point that stands still, on a spinning body's axis"
    )]
    Carried {
        name: String,
        speed: f64,
        why: &'static str,
    },
}

/// The spin `ω_b` of body `b` and the velocity of its centre of mass in the steady motion, from
/// the partials `j` over the `driven` coordinates (among others).
pub fn steady_twist<T: Real, U: Real>(
    sys: &System<U>,
    j: &BodyPartials<T>,
    driven: &[usize],
    rate: impl Fn(usize) -> T,
    b: usize,
) -> (V3<T>, V3<T>) {
    let zero = V3::from_element(cst(0.0));
    driven.iter().fold((zero, zero), |(w, v), &c| {
        (w + j.jw(sys, c, b) * rate(c), v + j.jv(sys, c, b) * rate(c))
    })
}

/// Does body `b` translate by a `free` coordinate of a joint that a spinning drive carries
/// (a rotor written in rotating coordinates, whose orbits are seen from the turning frame)?
pub fn rides_spin<T: Real, U: Real>(
    sys: &System<U>,
    j: &BodyPartials<T>,
    (free, driven): (&[usize], &[usize]),
    spinning: impl Fn(usize) -> bool,
    b: usize,
) -> bool {
    free.iter().any(|&f| {
        let parent = sys.joints[sys.coord_joint[f]].parent;
        j.jv(sys, f, b).map(re).norm() > 0.0
            && parent.is_some_and(|p| {
                (driven.iter()).any(|&d| {
                    spinning(d) && j.jw(sys, d, b).map(re).norm() > 0.0 && sys.moves(d, p)
                })
            })
    })
}

/// Each unbalance's load over the coordinates `coords` at `q` (see the module documentation).
fn unbalance_loads<T: Real>(
    model: &Model,
    sys: &System<T>,
    q: &[T],
    coords: &[usize],
    speed: f64,
) -> Result<Vec<UnbalanceLoad<T>>, PortError> {
    if sys.unbalances.is_empty() {
        return Ok(Vec::new());
    }
    let driven: Vec<usize> = (0..sys.n).filter(|&c| sys.drive[c].is_some()).collect();
    let all: Vec<usize> = coords.iter().chain(&driven).copied().collect();
    let j = body_partials_for(&sys.map(lift1), q, &all);
    let rate = |c: usize| sys.drive[c].unwrap_or(cst(0.0));
    let zero = cst::<T>(0.0);
    let mut out = Vec::with_capacity(sys.unbalances.len());
    for (k, u) in sys.unbalances.iter().enumerate() {
        let b = u.body;
        let (w, v_cm) = steady_twist(sys, &j, &driven, rate, b);
        let x = j.pose[b].apply(&u.point);
        let arm = x - j.pose[b].apply(&sys.bodies[b].cm);
        let spin = w.dot(&w).sqrt();
        let carried = |why| PortError::Carried {
            name: model.unbalances[k].name.clone(),
            speed,
            why,
        };
        if re(spin) == 0.0 {
            out.push(UnbalanceLoad {
                re: vec![zero; coords.len()],
                im: vec![zero; coords.len()],
                spin: zero,
            });
            continue;
        }
        let v = (v_cm + w.cross(&arm)).map(re);
        let size = (x.map(re).norm() + arm.map(re).norm()).max(1e-3);
        if v.norm() > 1e-9 * re(spin) * size {
            return Err(carried("it is off the spin axis, or its body orbits"));
        }
        let spinning = |c: usize| re(rate(c)) != 0.0;
        if rides_spin(sys, &j, (coords, &driven), spinning, b) {
            return Err(carried(
                "its body translates in coordinates of a frame the spin turns: write the rotor's \
                 translations from a frame that does not spin",
            ));
        }
        let n = w / spin;
        let hint = least_aligned(&n.map(re)).map(cst::<T>);
        let e1 = crate::rigid::perpendicular(&n, &hint);
        let e2 = n.cross(&e1);
        let (c, s) = (u.phase.cos() * u.magnitude, u.phase.sin() * u.magnitude);
        let (mut fr, mut fi) = (
            Vec::with_capacity(coords.len()),
            Vec::with_capacity(coords.len()),
        );
        for &i in coords {
            let d = j.jv(sys, i, b) + j.jw(sys, i, b).cross(&arm);
            let (b1, b2) = (e1.dot(&d), e2.dot(&d));
            fr.push(c * b1 + s * b2);
            fi.push(s * b1 - c * b2);
        }
        out.push(UnbalanceLoad {
            re: fr,
            im: fi,
            spin,
        });
    }
    Ok(out)
}

/// The coordinate axis least aligned with `a`.
pub fn least_aligned(a: &V3<f64>) -> V3<f64> {
    let k = (0..3)
        .min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
        .unwrap_or(0);
    let mut e = V3::zeros();
    e[k] = 1.0;
    e
}

/// The ports' vectors ([`port_vectors`]) and the unbalances' loads of `model` at parameters
/// `p`, `speed` and coordinates `q`, over the free coordinates `coords` (nothing to evaluate
/// when the model has neither).
pub fn ports_at<T: Real>(
    model: &Model,
    p: &[T],
    speed: T,
    q: &[T],
    coords: &[usize],
) -> Result<Vectors<T>, PortError> {
    if model.ports.is_empty() && model.unbalances.is_empty() {
        return Ok(Vectors {
            ports: Vec::new(),
            unbalances: Vec::new(),
        });
    }
    let sys = System::new(model, p, speed)?;
    Ok(Vectors {
        ports: port_vectors(&sys, q, coords),
        unbalances: unbalance_loads(model, &sys, q, coords, re(speed))?,
    })
}
