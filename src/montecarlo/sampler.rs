//! The design of each sample: random, Latin hypercube or scrambled Sobol numbers, mapped
//! to the design variables.

use super::McOptions;
use crate::model::Sampling;
use crate::propagate::Study;
use crate::sampling::DesignMap;
use crate::tolerance::Spread;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use statrs::distribution::{ContinuousCDF, Normal};

/// Element `i` of a pseudo-random permutation of `0..len` chosen by `key` (Kensler 2013,
/// *Correlated Multi-Jittered Sampling*, Pixar technical memo 13-01, `permute`): a hash that is
/// a bijection on the next power of two, walked until it lands in range. The Latin hypercube's
/// strata come from it in constant memory, whatever the number of samples (`len ≤ 2³²`).
pub fn permute(mut i: u32, len: u32, key: u32) -> u32 {
    debug_assert!(len > 0 && i < len);
    let p = key;
    let mut w = len.wrapping_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            return ((i as u64 + p as u64) % len as u64) as u32;
        }
    }
}

/// Design-variable values of sample `index` (the study's variables, in the order of the
/// spread).
pub struct Sampler {
    map: DesignMap,
    /// Number of design variables.
    dims: usize,
    opt: McOptions,
    /// Latin hypercube: the key of variable v's permutation of the strata ([`permute`]).
    strata: Vec<u32>,
}

impl Sampler {
    /// The samples of the study's variables under `spread`.
    pub fn new(study: &Study, spread: &Spread, opt: McOptions) -> Sampler {
        let n = study.vars.len();
        // One permutation key per variable, drawn from a stream reserved for it.
        let strata = (0..n)
            .map(|v| {
                let mut rng = ChaCha8Rng::seed_from_u64(opt.seed);
                rng.set_stream(u64::MAX - v as u64);
                rng.random::<u32>()
            })
            .collect();
        Sampler {
            map: DesignMap::new(
                study.model.model().nominal(),
                study.vars.clone(),
                spread.clone(),
            ),
            dims: n,
            opt,
            strata,
        }
    }

    /// Uniform numbers in (0, 1), one per variable, for sample `index`.
    fn uniforms(&self, index: usize) -> Vec<f64> {
        let n = self.dims;
        let clamp = |u: f64| u.clamp(1e-12, 1.0 - 1e-12);
        match self.opt.sampling {
            Sampling::Sobol => (0..n)
                .map(|d| {
                    clamp(
                        sobol_burley::sample(index as u32, d as u32, self.opt.seed as u32) as f64
                            + 0.5 / (1u64 << 24) as f64,
                    )
                })
                .collect(),
            Sampling::Random | Sampling::Lhs => {
                let mut rng = ChaCha8Rng::seed_from_u64(self.opt.seed);
                rng.set_stream(index as u64);
                (0..n)
                    .map(|v| {
                        let u: f64 = rng.random();
                        if self.opt.sampling == Sampling::Lhs {
                            let stratum =
                                permute(index as u32, self.opt.samples as u32, self.strata[v]);
                            clamp((stratum as f64 + u) / self.opt.samples as f64)
                        } else {
                            clamp(u)
                        }
                    })
                    .collect()
            }
        }
    }

    /// All parameter values of sample `index`.
    pub fn parameters(&self, index: usize) -> Vec<f64> {
        let u = self.uniforms(index);
        let normal = Normal::standard();
        let z: Vec<f64> = u.iter().map(|&x| normal.inverse_cdf(x)).collect();
        self.map.parameters(&z, &u)
    }
}
