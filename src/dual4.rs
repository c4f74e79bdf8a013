//! [`Dual4`]: a dual number with four independent first-order parts, so that one evaluation
//! gives four directional derivatives.
//!
//! The sensitivities differentiate the linearisation along one direction per design variable
//! (the parameter and the equilibrium's shift with it). Over [`num_dual::Dual64`] that is one
//! pass of the recorded program per variable, each recomputing the same values and paying the
//! same per-operation dispatch, which costs most of a pass. Over `Dual4` four variables share
//! one pass: each operation's value and dispatch once, and four derivative parts. (A
//! `num_dual::DualSVec64<4>` does the same with its parts in an optional vector, whose branches
//! and generic arithmetic cost what the passes save: see `docs/benchmarks.md`.)
//!
//! Each part follows exactly the arithmetic of a `Dual64`'s `eps` (num-dual's own macros
//! implement the functions, and the product and quotient rules below are written as num-dual
//! writes them), so part `k` of a `Dual4` result is bit for bit the `Dual64` result along
//! direction `k`.

// num-dual's macros call each other unqualified: all of them in scope.
use num_dual::{
    DualNum, DualNumFloat, DualStruct, chain_rule, first, forward_binop, impl_add_sub_rem,
    impl_assign_ops, impl_comparisons, impl_derivatives, impl_dual, impl_dual_struct,
    impl_first_derivatives, impl_float_const, impl_from_f, impl_from_primitive, impl_inv,
    impl_iterator, impl_neg, impl_num, impl_scalar_op, impl_signed, impl_zero_one, second, third,
    zeroth,
};
use num_traits::{FloatConst, FromPrimitive, Inv, Num, One, Signed, Zero};
use std::fmt;
use std::iter::{Product, Sum};
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// A value and four first derivatives of it, along four independent directions.
#[derive(Copy, Clone, Debug)]
pub struct Dual4<T> {
    pub re: T,
    pub e0: T,
    pub e1: T,
    pub e2: T,
    pub e3: T,
}

impl<T> Dual4<T> {
    #[inline]
    pub fn new(re: T, e0: T, e1: T, e2: T, e3: T) -> Self {
        Dual4 { re, e0, e1, e2, e3 }
    }
}

impl<T: Zero> Dual4<T> {
    /// A constant: all four derivatives zero.
    #[inline]
    pub fn from_re(re: T) -> Self {
        Self::new(re, T::zero(), T::zero(), T::zero(), T::zero())
    }
}

impl<T: Copy> Dual4<T> {
    /// The value and its derivatives as an array `[e0, e1, e2, e3]`.
    #[inline]
    pub fn parts(&self) -> [T; 4] {
        [self.e0, self.e1, self.e2, self.e3]
    }

    /// From a value and its four derivatives.
    #[inline]
    pub fn from_parts(re: T, [e0, e1, e2, e3]: [T; 4]) -> Self {
        Self::new(re, e0, e1, e2, e3)
    }
}

/* chain rule */
impl<T: DualNum> Dual4<T> {
    #[inline]
    fn chain_rule(&self, f0: T, f1: T) -> Self {
        Self::new(
            f0,
            self.e0.clone() * f1.clone(),
            self.e1.clone() * f1.clone(),
            self.e2.clone() * f1.clone(),
            self.e3.clone() * f1,
        )
    }
}

/* product rule */
#[allow(clippy::suspicious_arithmetic_impl)] // the product rule is a sum
impl<T: DualNum> Mul<&Dual4<T>> for &Dual4<T> {
    type Output = Dual4<T>;
    #[inline]
    fn mul(self, other: &Dual4<T>) -> Self::Output {
        let part = |a: &T, b: &T| a.clone() * other.re.clone() + b.clone() * self.re.clone();
        Dual4::new(
            self.re.clone() * other.re.clone(),
            part(&self.e0, &other.e0),
            part(&self.e1, &other.e1),
            part(&self.e2, &other.e2),
            part(&self.e3, &other.e3),
        )
    }
}

/* quotient rule */
#[allow(clippy::suspicious_arithmetic_impl)] // the quotient rule has products
impl<T: DualNum> Div<&Dual4<T>> for &Dual4<T> {
    type Output = Dual4<T>;
    #[inline]
    fn div(self, other: &Dual4<T>) -> Dual4<T> {
        let inv = other.re.recip();
        let part = |a: &T, b: &T| {
            (a.clone() * other.re.clone() - b.clone() * self.re.clone()) * inv.clone() * inv.clone()
        };
        Dual4::new(
            self.re.clone() * inv.clone(),
            part(&self.e0, &other.e0),
            part(&self.e1, &other.e1),
            part(&self.e2, &other.e2),
            part(&self.e3, &other.e3),
        )
    }
}

impl<T: DualNum> fmt::Display for Dual4<T> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} + [{}, {}, {}, {}]ε",
            self.re, self.e0, self.e1, self.e2, self.e3
        )
    }
}

impl_first_derivatives!(Dual4, [e0, e1, e2, e3]);
impl_dual!(Dual4, [e0, e1, e2, e3]);
