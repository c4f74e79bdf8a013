//! Redundant cut-joint equations: the rows of the constraint Jacobian `Φ_R` (over the free
//! coordinates) that are combinations of the others at the reference configuration, found by
//! elimination with complete pivoting ([`crate::linalg::dependent_rows_after`], the cut joints'
//! rows before the couplers', so that a coupler repeating them is found, and refused) and
//! dropped. A planar
//! loop closed by a `point` or `revolute` cut (whose out-of-plane equations vanish identically)
//! and overconstrained mobile loops (Bricard's) then count their degrees of freedom from the
//! rank, as Adams and Simscape Multibody do; that the rank stays the same at each equilibrium
//! is checked there ([`crate::sweep`]: a dropped equation must still hold).
//!
//! At the reference configuration (every coordinate 0) each body's pose is the identity, and
//! moving coordinate `i` alone moves the bodies its joint carries by the joint's relative pose:
//! the column `∂Φ/∂q_i` is the dual part of the cut equations with those bodies at
//! `Rel_i(ε)` (exact, dual numbers). Fields are evaluated at the nominal parameters and speed 0.

use super::Mechanism;
use crate::model::{Constraint, Coupler, Field};
use crate::real::V3;
use crate::rigid::Pose;
use nalgebra::DMatrix;
use num_dual::Dual64;

/// Per constraint, its equations (indices within it) that are redundant at the reference
/// configuration, and the couplers (their equations follow) that are; `None` where a field does
/// not evaluate there (nothing is dropped then).
#[allow(clippy::type_complexity)]
pub(super) fn redundant(
    mech: &Mechanism,
    constraints: &[Constraint],
    couplers: &[Coupler],
    p: &[f64],
) -> Option<(Vec<Vec<usize>>, Vec<usize>)> {
    let coordinates = mech.coordinates;
    let free: Vec<usize> = (0..coordinates.len())
        .filter(|&i| !coordinates[i].driven)
        .collect();
    let coordinate_joint: Vec<usize> = coordinates.iter().map(|c| c.joint).collect();
    let cut_rows: usize = constraints.iter().map(|c| c.kind.equations()).sum();
    let m = cut_rows + couplers.len();
    if m == 0 {
        return Some((vec![Vec::new(); constraints.len()], Vec::new()));
    }
    let mut phi = DMatrix::zeros(m, free.len());
    for (k, c) in couplers.iter().enumerate() {
        for (&i, f) in c.coordinates.iter().zip(&c.coefficients) {
            if let Some(col) = free.iter().position(|&x| x == i) {
                phi[(cut_rows + k, col)] = f.eval(p, 0.0).ok()?;
            }
        }
    }
    for (col, &i) in free.iter().enumerate() {
        let (carried, moved) = moved_by(mech, coordinate_joint[i], i, p)?;
        let identity = Pose::identity();
        let pose = |b: Option<usize>| {
            if b.is_some_and(|b| carried[b]) {
                &moved
            } else {
                &identity
            }
        };
        let mut row = 0;
        for c in constraints {
            let out = cut_values(c, p, pose(c.geometry.body1), pose(c.geometry.body2))?;
            for (k, v) in out.iter().enumerate() {
                phi[(row + k, col)] = v.eps;
            }
            row += c.kind.equations();
        }
    }
    // Relative to the largest entry (rounding leaves an identically zero row at ~1e-16 of
    // it); nothing is dropped where an entry is not finite.
    if phi.iter().any(|x| !x.is_finite()) {
        return None;
    }
    // The cut joints' equations weighed first: a coupler that repeats them (or is only tangent
    // to their loop) is the equation reported, not one of theirs dropped for it.
    let dependent = crate::linalg::dependent_rows_after(&phi, cut_rows);
    let coupled: Vec<usize> = dependent
        .iter()
        .filter(|&&r| r >= cut_rows)
        .map(|&r| r - cut_rows)
        .collect();
    let mut out = vec![Vec::new(); constraints.len()];
    let mut start = 0;
    for (k, c) in constraints.iter().enumerate() {
        let n = c.kind.equations();
        out[k] = dependent
            .iter()
            .filter(|&&r| (start..start + n).contains(&r))
            .map(|&r| r - start)
            .collect();
        start += n;
    }
    Some((out, coupled))
}

/// The bodies joint `ji` carries (its child and, parents first, their children) and its
/// relative pose with coordinate `i` moved by `ε` (the others at 0); `None` where a field does
/// not evaluate.
fn moved_by(mech: &Mechanism, ji: usize, i: usize, p: &[f64]) -> Option<(Vec<bool>, Pose<Dual64>)> {
    let Mechanism {
        joints,
        order,
        bodies,
        ..
    } = *mech;
    let joint = &joints[ji];
    let mut carried = vec![false; bodies];
    carried[joint.child] = true;
    for &j in order {
        if joints[j].parent.is_some_and(|b| carried[b]) {
            carried[joints[j].child] = true;
        }
    }
    let [_, use_axis, use_axis2] = joint.kind.uses();
    let g = &joint.geometry;
    let geometry = crate::joints::Geometry {
        at: vector(&g.at, p)?,
        axis: direction(&g.axis, use_axis, p)?,
        axis2: direction(&g.axis2, use_axis2, p)?,
    };
    let q: Vec<Dual64> = joint
        .coords
        .clone()
        .map(|c| Dual64::new(0.0, if c == i { 1.0 } else { 0.0 }))
        .collect();
    Some((carried, joint.kind.relative(&geometry, &q)))
}

/// The equations of cut joint `c` with its bodies at `x1` and `x2`; `None` where a field does
/// not evaluate.
fn cut_values(
    c: &Constraint,
    p: &[f64],
    x1: &Pose<Dual64>,
    x2: &Pose<Dual64>,
) -> Option<Vec<Dual64>> {
    let [_, use_axis, use_axis2, _] = c.kind.uses();
    let g = &c.geometry;
    let geometry = crate::cuts::Geometry {
        body1: g.body1,
        point1: vector(&g.point1, p)?,
        body2: g.body2,
        point2: vector(&g.point2, p)?,
        axis: direction(&g.axis, use_axis, p)?,
        axis2: direction(&g.axis2, use_axis2, p)?,
        length: match &g.length {
            Some(f) => Some(Dual64::from(f.eval(p, 0.0).ok()?)),
            None => None,
        },
    };
    let mut out = Vec::new();
    c.kind.values(&geometry, x1, x2, &mut out);
    Some(out)
}

fn vector(f: &[Field; 3], p: &[f64]) -> Option<V3<Dual64>> {
    let [x, y, z] = f;
    Some(V3::new(
        Dual64::from(x.eval(p, 0.0).ok()?),
        Dual64::from(y.eval(p, 0.0).ok()?),
        Dual64::from(z.eval(p, 0.0).ok()?),
    ))
}

/// A unit direction where the type uses one (as the mechanics normalises it), else as given.
fn direction(f: &[Field; 3], use_: crate::joints::Use, p: &[f64]) -> Option<V3<Dual64>> {
    let a = vector(f, p)?;
    if !matches!(
        use_,
        crate::joints::Use::Required | crate::joints::Use::Optional
    ) {
        return Some(a);
    }
    let n = a.map(|x| x.re).norm();
    (n > 0.0 && n.is_finite()).then(|| a / Dual64::from(n))
}
