//! The one scalar trait the mechanics is written against.
//!
//! Every kinematic and dynamic quantity is a function of the coordinates written once, generic
//! over [`Real`]. With `f64` it gives values; with `num_dual::Dual<T>` exact first derivatives;
//! with `num_dual::Dual2<T>` time derivatives along `q(t) = q + q̇ t + q̈ t²/2`; nesting them gives
//! Jacobians of those, and so on. No derivative in the library is written by hand.

use nalgebra::{Matrix3, Vector3};
use num_dual::{Dual, Dual2, DualNum};

/// Scalar usable everywhere in the mechanics: `f64` or any (nested) dual number over `f64`.
pub trait Real: DualNum<Primitive = f64> + Copy + Send + Sync + nalgebra::Scalar {}
impl<T: DualNum<Primitive = f64> + Copy + Send + Sync + nalgebra::Scalar> Real for T {}

/// 3-vector over a [`Real`].
pub type V3<T> = Vector3<T>;
/// 3×3 matrix over a [`Real`].
pub type M3<T> = Matrix3<T>;

/// Scalar carrying one directional derivative over `T`.
pub type D1<T> = Dual<T>;
/// Scalar carrying first and second time derivatives over `T`.
pub type D2<T> = Dual2<T>;

/// Real part (`f64`) of any [`Real`].
pub fn re<T: Real>(x: T) -> f64 {
    x.re()
}

/// The constant `c` as a `T`.
pub fn cst<T: Real>(c: f64) -> T {
    T::from(c)
}

/// Lifts a `T` into the dual number `Dual<T>` with zero derivative.
pub fn lift1<T: Real>(x: T) -> D1<T> {
    Dual::from_re(x)
}

/// Lifts a `T` into `Dual2<T>` with zero time derivatives.
pub fn lift2<T: Real>(x: T) -> D2<T> {
    Dual2::from_re(x)
}

/// Axial vector of the skew-symmetric part of `m`: `w` with `w̃ ≈ (m − mᵀ)/2`.
pub fn axial<T: Real>(m: &M3<T>) -> V3<T> {
    let h = cst::<T>(0.5);
    V3::new(
        (m[(2, 1)] - m[(1, 2)]) * h,
        (m[(0, 2)] - m[(2, 0)]) * h,
        (m[(1, 0)] - m[(0, 1)]) * h,
    )
}

/// `a b` for 3×3 matrices, written out: nalgebra's generic product is slow for dual scalars.
#[inline]
pub fn mul3<T: Real>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    M3::from_fn(|i, j| a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)])
}

/// `a bᵀ` for 3×3 matrices.
#[inline]
pub fn mul3_t<T: Real>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    M3::from_fn(|i, j| a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)])
}

/// `aᵀ x` for a 3×3 matrix and a 3-vector, written out.
#[inline]
pub fn mulv_t<T: Real>(a: &M3<T>, x: &V3<T>) -> V3<T> {
    V3::new(
        a[(0, 0)] * x.x + a[(1, 0)] * x.y + a[(2, 0)] * x.z,
        a[(0, 1)] * x.x + a[(1, 1)] * x.y + a[(2, 1)] * x.z,
        a[(0, 2)] * x.x + a[(1, 2)] * x.y + a[(2, 2)] * x.z,
    )
}

/// `axial(aᵀ b)` (see [`axial`]), from the six entries of `aᵀ b` it reads.
pub fn axial_tn<T: Real>(a: &M3<T>, b: &M3<T>) -> V3<T> {
    // (aᵀ b)_ij = a_·i · b_·j.
    let e =
        |i: usize, j: usize| a[(0, i)] * b[(0, j)] + a[(1, i)] * b[(1, j)] + a[(2, i)] * b[(2, j)];
    let h = cst::<T>(0.5);
    V3::new(
        (e(2, 1) - e(1, 2)) * h,
        (e(0, 2) - e(2, 0)) * h,
        (e(1, 0) - e(0, 1)) * h,
    )
}

/// `a x` for a 3×3 matrix and a 3-vector, written out.
#[inline]
pub fn mulv<T: Real>(a: &M3<T>, x: &V3<T>) -> V3<T> {
    V3::new(
        a[(0, 0)] * x.x + a[(0, 1)] * x.y + a[(0, 2)] * x.z,
        a[(1, 0)] * x.x + a[(1, 1)] * x.y + a[(1, 2)] * x.z,
        a[(2, 0)] * x.x + a[(2, 1)] * x.y + a[(2, 2)] * x.z,
    )
}
