//! The joints as a tree: every body is reached from ground, no joints form a cycle, and the
//! order in which the kinematics visits them (parents before children). Its own stage because
//! it is a property of all the joints together, checked once each joint is valid alone.

use super::joints::Tree;
use super::{Ctx, R};
use crate::model::schema::FileSchema;
use crate::model::{Body, ModelError};

/// The joints from ground outwards; an error for a body no joint has as child, or for joints
/// that form a cycle.
pub(super) fn order(ctx: &Ctx, raw: &FileSchema, bodies: &[Body], tree: &Tree) -> R<Vec<usize>> {
    for (b, c) in tree.child_of.iter().enumerate() {
        if c.is_none() {
            let span = raw.bodies[b].get_ref().name.span();
            return Err(ctx.err(
                span,
                format!(
                    "body '{}' is not connected to ground: no joint has it as child",
                    bodies[b].name
                ),
            ));
        }
    }
    let mut order = Vec::new();
    let mut placed = vec![false; tree.joints.len()];
    let mut frontier: Vec<Option<usize>> = vec![None];
    while let Some(parent) = frontier.pop() {
        for (ji, j) in tree.joints.iter().enumerate() {
            if j.parent == parent && !placed[ji] {
                placed[ji] = true;
                order.push(ji);
                frontier.push(Some(j.child));
            }
        }
    }
    match placed.iter().position(|p| !p) {
        Some(ji) => Err(cycle(ctx, raw, tree, ji)),
        None => Ok(order),
    }
}

/// The error for the cycle that joint `ji`, not reached from ground, lies on or leads to.
fn cycle(ctx: &Ctx, raw: &FileSchema, tree: &Tree, ji: usize) -> ModelError {
    let joints = &tree.joints;
    // Walk up from this joint until a joint repeats: that is the cycle.
    let mut path = vec![ji];
    let mut cur = ji;
    loop {
        let parent_body = joints[cur]
            .parent
            .expect("unplaced joints have a body parent");
        let up = tree.child_of[parent_body].expect("every body has a parent joint");
        if let Some(pos) = path.iter().position(|&x| x == up) {
            let names: Vec<&str> = path[pos..]
                .iter()
                .rev()
                .map(|&k| joints[k].name.as_str())
                .collect();
            let span = raw.joints[up].get_ref().name.span();
            return ctx.err(
                span,
                format!(
                    "the joints form a cycle not connected to ground: {} → {}",
                    names.join(" → "),
                    names[0]
                ),
            );
        }
        path.push(up);
        cur = up;
    }
}
