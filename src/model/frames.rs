//! The frame each coordinate is measured in, and so the frame a mode's frequency is seen from.
//!
//! A joint's coordinates are relative to its parent body. Where a driven rotation (a revolute
//! joint with a `drive`) lies on the path from that body to ground, the parent turns with it,
//! and a mode that lives in those coordinates is seen from the rotating frame: a blade's flap,
//! a governor's sleeve, a pendulum on a spinning shaft. Otherwise the coordinates are measured
//! from ground, and the mode is seen from the fixed frame: a rotor's whirl in a fixed housing
//! (the spin's own joint then comes after the node's translations and tilts, as a meshed
//! shaft's nodes are built). The two differ by the spin: a mode of frequency ω in one frame is
//! seen at ω ± Ω in the other, which is why a Campbell diagram must say which it draws.

use super::Model;
use crate::joints::Unit;

impl Model {
    /// Per coordinate, the driven rotation nearest above its joint that turns the frame it is
    /// measured in (the joint's index), or `None` where it is measured from ground.
    pub fn turned_by(&self) -> Vec<Option<usize>> {
        let tree_joint = |body: usize| self.joints.iter().position(|j| j.child == body);
        let rotates = |j: usize| {
            let joint = &self.joints[j];
            joint.drive.is_some()
                && joint
                    .coords
                    .clone()
                    .any(|c| self.coordinates[c].unit == Unit::Angle)
        };
        // The nearest driven rotation on the path from `body` to ground (bounded by the number
        // of joints, so that a malformed tree cannot loop).
        let above = |mut body: Option<usize>| {
            for _ in 0..=self.joints.len() {
                let j = tree_joint(body?)?;
                if rotates(j) {
                    return Some(j);
                }
                body = self.joints[j].parent;
            }
            None
        };
        self.coordinates
            .iter()
            .map(|c| above(self.joints[c.joint].parent))
            .collect()
    }
}
