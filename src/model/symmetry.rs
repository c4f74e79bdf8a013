//! Driven coordinates whose value the equilibrium equations cannot depend on, proved from the
//! model's structure rather than tested by evaluating them.
//!
//! A driven coordinate `q_D = Ω t` has a steady state only if the equations `F` of the free
//! coordinates and the constraints do not depend on its value (else the equilibrium drifts as
//! it turns); [`crate::equilibrium`] checks that by evaluating `F` at other values of `q_D`.
//! For the commonest driven joint the check is not needed. Turning a revolute joint on the
//! ground turns everything it carries rigidly about a fixed axis. The equations of motion are
//! invariant under a rotation of the whole world, and the joint's own coordinate enters no row
//! of `F` but its own drive row. So `F` cannot depend on the joint's angle when nothing the joint
//! does not carry sees that part of the world turn: no force element, beam or cut joint joins a
//! carried body to one it does not carry (or to the ground), no load fixed in ground axes acts
//! on a carried body, and gravity is along the axis (or zero). The proof is exact and covers
//! the whole equations of motion, so their linearisation too; where it does not apply, the
//! numerical check runs as before.

use super::Model;
use crate::joints::Kind;

impl Model {
    /// The driven coordinates of revolute joints on the ground whose carried bodies are joined
    /// to nothing else (see the module documentation), with their joints: turning one turns its
    /// part of the mechanism rigidly, alone. Whether gravity lies along the axis depends on the
    /// parameters ([`Model::steady_by_symmetry`]).
    pub fn rigid_spins(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (c, coordinate) in self.coordinates.iter().enumerate() {
            let joint = &self.joints[coordinate.joint];
            if !coordinate.driven || joint.parent.is_some() || joint.kind != Kind::Revolute {
                continue;
            }
            // The bodies the joint carries: its child and, parents first, their children.
            let mut carried = vec![false; self.bodies.len()];
            carried[joint.child] = true;
            for &j in &self.order {
                let j = &self.joints[j];
                if j.parent.is_some_and(|p| carried[p]) {
                    carried[j.child] = true;
                }
            }
            let inside = |b: Option<usize>| b.is_some_and(|b| carried[b]);
            let joins = |b1: Option<usize>, b2: Option<usize>| inside(b1) != inside(b2);
            let alone = !self
                .forces
                .iter()
                .any(|e| joins(e.geometry.body1, e.geometry.body2))
                && !self.beams.iter().any(|b| joins(b.body1, b.body2))
                && !self
                    .constraints
                    .iter()
                    .any(|k| joins(k.geometry.body1, k.geometry.body2))
                // A load fixed in ground axes on a carried body sees it turn.
                && !self.loads.iter().any(|l| match l.kind {
                    super::LoadKind::Force { body, follower, .. }
                    | super::LoadKind::Torque { body, follower, .. } => {
                        !follower && carried[body]
                    }
                    super::LoadKind::Coordinate { .. } => false,
                });
            if alone {
                out.push((c, coordinate.joint));
            }
        }
        out
    }

    /// The driven coordinates on which the equilibrium equations cannot depend at parameters
    /// `p` and `speed`: those of [`Model::rigid_spins`] whose axis is along gravity (or whose
    /// gravity is zero), the cross product of the two as given being exactly zero. A field
    /// that does not evaluate, or an axis that is zero or not finite, proves nothing.
    pub fn steady_by_symmetry(&self, p: &[f64], speed: f64) -> Vec<usize> {
        let eval = |f: &[super::Field; 3]| -> Option<[f64; 3]> {
            let [x, y, z] = f;
            Some([
                x.eval(p, speed).ok()?,
                y.eval(p, speed).ok()?,
                z.eval(p, speed).ok()?,
            ])
        };
        let Some(g) = eval(&self.gravity) else {
            return Vec::new();
        };
        self.rigid_spins()
            .into_iter()
            .filter(|&(_, j)| {
                eval(&self.joints[j].geometry.axis).is_some_and(|a| {
                    if !a.iter().all(|v| v.is_finite()) || a.iter().all(|&v| v == 0.0) {
                        return false;
                    }
                    let cross = [
                        a[1] * g[2] - a[2] * g[1],
                        a[2] * g[0] - a[0] * g[2],
                        a[0] * g[1] - a[1] * g[0],
                    ];
                    cross.iter().all(|&v| v == 0.0)
                })
            })
            .map(|(c, _)| c)
            .collect()
    }
}
