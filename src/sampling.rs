//! What a Monte Carlo sample and a quadrature node share: the map from independent standard
//! normals to a design ([`DesignMap`]), and the sweep of one design across the speeds as a
//! sample follows it counts its branch switches ([`branch_counts`]; the sweep itself is
//! [`crate::propagate::Study::sweep_design`]).
//!
//! Both propagation methods draw or place points in the space of independent standard normals
//! `z`; this module turns them into parameter values and into swept points, so that a node of
//! the quadrature and a sample of the Monte Carlo at the same `z` are the same design on the
//! same branch.

use crate::model::Distribution;
use crate::sweep::Point;
use crate::tolerance::Spread;
use nalgebra::{DMatrix, DVector};

/// The design-variable map of one tolerance case: nominal parameters, the variables, their
/// spread and the Cholesky factor `L` of their correlation.
#[derive(Debug, Clone)]
pub struct DesignMap {
    nominal: Vec<f64>,
    vars: Vec<usize>,
    spread: Spread,
    chol: DMatrix<f64>,
}

impl DesignMap {
    /// The map of the variables `vars` (in the order of `spread`) about the parameters
    /// `nominal`.
    pub fn new(nominal: Vec<f64>, vars: Vec<usize>, spread: Spread) -> DesignMap {
        DesignMap {
            chol: correlation_factor(&spread.correlation),
            nominal,
            vars,
            spread,
        }
    }

    /// The Cholesky factor `L` of the correlation of the normal variables.
    pub fn factor(&self) -> &DMatrix<f64> {
        &self.chol
    }

    /// Parameter values at independent standard normals `z` (and their uniforms `u = Φ(z)`),
    /// one per design variable: a normal variable is `b₀ + σ (L z)ₖ`, a uniform one
    /// `b₀ + √3 σ (2uₖ − 1)` (uniform on ±T; correlations are not applied to uniform
    /// variables). Monte Carlo samples and quadrature nodes both come from here.
    pub fn parameters(&self, z: &[f64], u: &[f64]) -> Vec<f64> {
        let zc = &self.chol * DVector::from_column_slice(z);
        let mut p = self.nominal.clone();
        for (k, &b) in self.vars.iter().enumerate() {
            p[b] += match self.spread.distribution[k] {
                Distribution::Normal => self.spread.sigma[k] * zc[k],
                Distribution::Uniform => self.spread.sigma[k] * 3f64.sqrt() * (2.0 * u[k] - 1.0),
            };
        }
        p
    }
}

/// Cholesky factor of a correlation matrix (the identity where it is not positive definite;
/// the model's validation rejects such matrices).
pub fn correlation_factor(c: &DMatrix<f64>) -> DMatrix<f64> {
    let n = c.nrows();
    c.clone()
        .cholesky()
        .map_or_else(|| DMatrix::identity(n, n), |c| c.l())
}

/// Number of branch switches of the nominal sweep up to each speed, counted as a sample's are
/// ([`crate::propagate::Study::sweep_design`]): from its first point on. Samples start from that point, so a switch
/// made there (from the model's initial guess onto a stable equilibrium, where a sweep starts
/// past a loss of stability) is none of theirs.
pub fn branch_counts(nominal: &[Option<Point>]) -> Vec<usize> {
    let mut started = false;
    nominal
        .iter()
        .scan(0, |n, p| {
            if let Some(p) = p {
                *n += usize::from(started && p.new_branch);
                started = true;
            }
            Some(*n)
        })
        .collect()
}
