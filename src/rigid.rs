//! Rigid motions over any [`Real`]: poses, rotations about an axis, rotations from a vector of
//! rotation parameters.
//!
//! Everything here is branch-free and rational or trigonometric in its inputs, so that dual
//! numbers differentiate it exactly and the recorded [`crate::tape`] never sees a comparison.

use crate::real::{M3, Real, V3, cst, mul3, mulv};

/// Rigid motion from the reference configuration: `x = rot · x₀ + trans`.
#[derive(Debug, Clone, Copy)]
pub struct Pose<T: Real> {
    pub rot: M3<T>,
    pub trans: V3<T>,
}

impl<T: Real> Pose<T> {
    /// Identity (ground, and every body in the reference configuration).
    pub fn identity() -> Self {
        Pose {
            rot: M3::identity(),
            trans: V3::zeros(),
        }
    }

    /// The same motion over another scalar (`f` maps each number).
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Pose<U> {
        Pose {
            rot: self.rot.map(f),
            trans: self.trans.map(f),
        }
    }

    /// Current position of a point given in the reference configuration.
    pub fn apply(&self, x0: &V3<T>) -> V3<T> {
        mulv(&self.rot, x0) + self.trans
    }

    /// A vector of the current configuration in the body's axes: `rotᵀ v`.
    pub fn local(&self, v: &V3<T>) -> V3<T> {
        let r = &self.rot;
        V3::new(
            r[(0, 0)] * v.x + r[(1, 0)] * v.y + r[(2, 0)] * v.z,
            r[(0, 1)] * v.x + r[(1, 1)] * v.y + r[(2, 1)] * v.z,
            r[(0, 2)] * v.x + r[(1, 2)] * v.y + r[(2, 2)] * v.z,
        )
    }

    /// `self ∘ rel`: first `rel`, then `self`.
    pub fn then(&self, rel: &Pose<T>) -> Pose<T> {
        Pose {
            rot: mul3(&self.rot, &rel.rot),
            trans: mulv(&self.rot, &rel.trans) + self.trans,
        }
    }

    /// The rotation `rot` about the point `at`: `x₀ ↦ rot (x₀ − at) + at`.
    pub fn about(rot: M3<T>, at: &V3<T>) -> Pose<T> {
        Pose {
            trans: *at - mulv(&rot, at),
            rot,
        }
    }

    /// The same motion followed by the translation `shift`.
    pub fn shifted(mut self, shift: V3<T>) -> Pose<T> {
        self.trans += shift;
        self
    }
}

/// Rotation by `angle` about the unit vector `a` (Rodrigues' formula):
/// `R = cos q I + sin q [a]× + (1 − cos q) a aᵀ`.
pub fn rotation<T: Real>(a: &V3<T>, angle: T) -> M3<T> {
    let (s, c) = angle.sin_cos();
    let v = cst::<T>(1.0) - c;
    let (x, y, z) = (a.x, a.y, a.z);
    let (xs, ys, zs) = (x * s, y * s, z * s);
    M3::new(
        c + x * x * v,
        x * y * v - zs,
        x * z * v + ys,
        y * x * v + zs,
        c + y * y * v,
        y * z * v - xs,
        z * x * v - ys,
        z * y * v + xs,
        c + z * z * v,
    )
}

/// Rotation from scaled modified Rodrigues parameters `p = 4 tan(θ/4) n` (rotation by `θ` about
/// the unit vector `n`): with `σ = p/4`, `s = σᵀσ`,
///
/// ```text
/// R = I + (4 (1 − s) [σ]× + 8 [σ]×²) / (1 + s)²
/// ```
///
/// (Shuster 1993, "A survey of attitude representations", §6; Schaub & Junkins, *Analytical
/// Mechanics of Space Systems*, §3.8). The map is rational, so exact and branch-free over dual
/// numbers, and regular for every rotation short of a full turn (`θ = 2π`); the scaling makes
/// `p` equal the rotation vector `θ n` up to third order, so the parameters read as angles (rad)
/// near the reference and their small-motion stiffness is a torsional stiffness.
pub fn rotation_parameters<T: Real>(p: &V3<T>) -> M3<T> {
    let sigma = *p * cst::<T>(0.25);
    let s = sigma.dot(&sigma);
    let one = cst::<T>(1.0);
    let d = (one + s) * (one + s);
    let a = cst::<T>(4.0) * (one - s) / d;
    let b = cst::<T>(8.0) / d;
    let (x, y, z) = (sigma.x, sigma.y, sigma.z);
    // [σ]×² = σσᵀ − s I.
    M3::new(
        one + b * (x * x - s),
        b * x * y - a * z,
        b * x * z + a * y,
        b * y * x + a * z,
        one + b * (y * y - s),
        b * y * z - a * x,
        b * z * x - a * y,
        b * z * y + a * x,
        one + b * (z * z - s),
    )
}

/// The scaled modified Rodrigues parameters `p = 4 tan(θ/4) n` of a rotation `R` by `θ < π`,
/// the inverse of [`rotation_parameters`]: with the quaternion's scalar part
/// `w = cos(θ/2) = ½ √(1 + tr R)` and `axial(R) = sin θ n`,
///
/// ```text
/// p = 4 n sin(θ/2) / (1 + cos(θ/2)) = 2 axial(R) / (w (1 + w))
/// ```
///
/// (Shuster 1993, §5–6), branch-free and regular for `θ < π` (where `w > 0`), so exact over
/// dual numbers at the identity too, where the rotation vector `θ n` written as
/// `θ / sin θ · axial(R)` has no derivative.
pub fn rotation_parameters_of<T: Real>(r: &M3<T>) -> V3<T> {
    let one = cst::<T>(1.0);
    let w = (one + r[(0, 0)] + r[(1, 1)] + r[(2, 2)]).sqrt() * cst::<T>(0.5);
    crate::real::axial(r) * (cst::<T>(2.0) / (w * (one + w)))
}

/// A unit vector perpendicular to the unit vector `a`, in the plane of `a` and `hint`
/// (`hint` not parallel to `a`): `normalize(hint − (hint·a) a)`.
pub fn perpendicular<T: Real>(a: &V3<T>, hint: &V3<T>) -> V3<T> {
    let v = *hint - *a * hint.dot(a);
    v / v.dot(&v).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &M3<f64>, b: &M3<f64>, tol: f64) -> bool {
        (a - b).abs().max() <= tol
    }

    #[test]
    fn rotation_parameters_are_the_rotation_by_the_angle_they_encode() {
        for (n, theta) in [
            (V3::new(0.0, 0.0, 1.0), 0.3),
            (V3::new(1.0, 2.0, -0.5).normalize(), 2.9),
            (V3::new(-0.2, 0.1, 0.9).normalize(), -4.0),
            (V3::new(0.6, -0.8, 0.0), 6.0),
        ] {
            let p = n * (4.0 * (theta / 4.0f64).tan());
            assert!(close(&rotation_parameters(&p), &rotation(&n, theta), 1e-14));
        }
        assert!(close(
            &rotation_parameters(&V3::zeros()),
            &M3::identity(),
            0.0
        ));
    }

    #[test]
    fn rotation_parameters_are_the_rotation_vector_to_first_order() {
        // d R/d p_k at p = 0 is [e_k]×, checked by a central difference.
        let h = 1e-6;
        for k in 0..3 {
            let mut e = V3::zeros();
            e[k] = 1.0;
            let d = (rotation_parameters(&(e * h)) - rotation_parameters(&(e * -h))) / (2.0 * h);
            assert!(close(&d, &e.cross_matrix(), 1e-9));
        }
    }

    #[test]
    fn rotation_parameters_of_a_rotation_invert_the_map() {
        for (n, theta) in [
            (V3::new(0.0, 0.0, 1.0), 0.3),
            (V3::new(1.0, 2.0, -0.5).normalize(), 2.9),
            (V3::new(-0.2, 0.1, 0.9).normalize(), -3.0),
            (V3::new(0.6, -0.8, 0.0), 1e-9),
        ] {
            let p = n * (4.0 * (theta / 4.0f64).tan());
            let back = rotation_parameters_of(&rotation(&n, theta));
            assert!(
                (back - p).abs().max() <= 1e-14 * (1.0 + p.norm()),
                "{back} vs {p}"
            );
        }
        // At the identity the derivative along a rotation about e_k is e_k (dual numbers).
        use num_dual::Dual64;
        for k in 0..3 {
            let mut e = V3::<Dual64>::zeros();
            e[k] = Dual64::new(0.0, 1.0);
            let r = rotation_parameters(&e);
            let d = rotation_parameters_of(&r).map(|x| x.eps);
            let mut unit = V3::zeros();
            unit[k] = 1.0;
            assert!((d - unit).abs().max() <= 1e-15, "{d}");
            assert!(
                rotation_parameters_of(&r)
                    .iter()
                    .all(|x| x.re.abs() < 1e-300)
            );
        }
    }
}
