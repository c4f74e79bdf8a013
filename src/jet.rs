//! Truncated Taylor numbers read and written part by part: the one interface the exact
//! derivatives use over every scalar that carries them.
//!
//! The sensitivities seed one direction per design variable ([`num_dual::Dual64`], or four at
//! once in a [`Dual4`]); the Hessians seed a variable's gradient and diagonal entry
//! ([`num_dual::Dual2_64`]) or a pair's mixed entry ([`num_dual::HyperDual64`]). All of them
//! are a value and a few parts, and the implicit corrections ([`crate::implicit`]) work on those
//! parts one at a time, so one trait serves them all.

use crate::dual4::Dual4;
use crate::real::Real;
use num_dual::{Dual2_64, Dual64, HyperDual64};

/// A value and `PARTS` further parts (derivatives), each an `f64`.
pub trait Jet: Real {
    /// Number of parts besides the value.
    const PARTS: usize;

    /// The value `re` with part `k` equal to `part(k)`.
    fn seeded(re: f64, part: impl Fn(usize) -> f64) -> Self;

    /// Part `k` (`0 ≤ k < PARTS`).
    fn part(&self, k: usize) -> f64;

    /// Sets part `k` to `v`.
    fn set_part(&mut self, k: usize, v: f64);
}

/// One first derivative: `eps`.
impl Jet for Dual64 {
    const PARTS: usize = 1;

    fn seeded(re: f64, part: impl Fn(usize) -> f64) -> Self {
        Dual64::new(re, part(0))
    }

    fn part(&self, _: usize) -> f64 {
        self.eps
    }

    fn set_part(&mut self, _: usize, v: f64) {
        self.eps = v;
    }
}

/// Four independent first derivatives: `e0 … e3`.
impl Jet for Dual4<f64> {
    const PARTS: usize = 4;

    fn seeded(re: f64, part: impl Fn(usize) -> f64) -> Self {
        Dual4::from_parts(re, std::array::from_fn(part))
    }

    fn part(&self, k: usize) -> f64 {
        self.parts()[k]
    }

    fn set_part(&mut self, k: usize, v: f64) {
        *[&mut self.e0, &mut self.e1, &mut self.e2, &mut self.e3][k] = v;
    }
}

/// A first and a second derivative along one direction: `v1`, `v2`.
impl Jet for Dual2_64 {
    const PARTS: usize = 2;

    fn seeded(re: f64, part: impl Fn(usize) -> f64) -> Self {
        Dual2_64::new(re, part(0), part(1))
    }

    fn part(&self, k: usize) -> f64 {
        [self.v1, self.v2][k]
    }

    fn set_part(&mut self, k: usize, v: f64) {
        *[&mut self.v1, &mut self.v2][k] = v;
    }
}

/// Two first derivatives and their mixed second one: `eps1`, `eps2`, `eps1eps2`.
impl Jet for HyperDual64 {
    const PARTS: usize = 3;

    fn seeded(re: f64, part: impl Fn(usize) -> f64) -> Self {
        HyperDual64::new(re, part(0), part(1), part(2))
    }

    fn part(&self, k: usize) -> f64 {
        [self.eps1, self.eps2, self.eps1eps2][k]
    }

    fn set_part(&mut self, k: usize, v: f64) {
        *[&mut self.eps1, &mut self.eps2, &mut self.eps1eps2][k] = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every scalar's parts read back what was seeded and written, and `seeded` leaves the
    /// value alone.
    fn round_trip<J: Jet>() {
        let mut x = J::seeded(1.5, |k| k as f64 + 2.0);
        assert_eq!(x.re().to_bits(), 1.5f64.to_bits());
        for k in 0..J::PARTS {
            assert_eq!(x.part(k).to_bits(), (k as f64 + 2.0).to_bits());
            x.set_part(k, -(k as f64));
            assert_eq!(x.part(k).to_bits(), (-(k as f64)).to_bits());
        }
    }

    #[test]
    fn every_jet_reads_back_its_parts() {
        round_trip::<Dual64>();
        round_trip::<Dual4<f64>>();
        round_trip::<Dual2_64>();
        round_trip::<HyperDual64>();
    }

    #[test]
    fn a_seeded_product_carries_the_product_rule_in_each_part() {
        let a = Dual4::<f64>::seeded(2.0, |k| k as f64);
        let b = Dual4::<f64>::seeded(3.0, |_| 1.0);
        let c = a * b;
        for k in 0..4 {
            assert_eq!(c.part(k).to_bits(), (3.0 * k as f64 + 2.0).to_bits());
        }
    }
}
