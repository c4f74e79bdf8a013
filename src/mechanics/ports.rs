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

use super::System;
use super::dynamics::partials_for;
use super::kinematics::poses;
use crate::model::{FieldError, Model};
use crate::real::{Real, lift1};

/// The vector of every port over the coordinates `coords`, at `q`.
pub fn port_vectors<T: Real>(sys: &System<T>, q: &[T], coords: &[usize]) -> Vec<Vec<T>> {
    if sys.ports.is_empty() {
        return Vec::new();
    }
    let j = partials_for(&sys.map(lift1), q, coords);
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

/// [`port_vectors`] of `model` at parameters `p`, `speed` and coordinates `q` (nothing to
/// evaluate when the model has no ports).
pub fn ports_at<T: Real>(
    model: &Model,
    p: &[T],
    speed: T,
    q: &[T],
    coords: &[usize],
) -> Result<Vec<Vec<T>>, FieldError> {
    if model.ports.is_empty() {
        return Ok(Vec::new());
    }
    Ok(port_vectors(&System::new(model, p, speed)?, q, coords))
}
