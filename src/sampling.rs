//! What a Monte Carlo sample and a quadrature node share: the map from independent standard
//! normals to a design ([`DesignMap`]), and the sweep of one design across the speeds as a
//! sample follows it ([`sample_sweep`], [`branch_counts`]).
//!
//! Both propagation methods draw or place points in the space of independent standard normals
//! `z`; this module turns them into parameter values and into swept points, so that a node of
//! the quadrature and a sample of the Monte Carlo at the same `z` are the same design on the
//! same branch.

use crate::compiled::Compiled;
use crate::equilibrium::Settings;
use crate::model::Distribution;
use crate::program::{Tier, Workspace};
use crate::sweep::{Options, Point, Sweep};
use crate::tolerance::{Spread, match_modes};
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

/// Sweeps the design `p` across `speeds` as a Monte Carlo sample or a quadrature node does:
/// warm-started from the nominal point at the first speed, continued from speed to speed (so
/// that it follows the branch a sweep from the lowest speed follows), its modes matched to the
/// nominal ones by shape. `visit(i, point)` gets, per speed, the nominal point and the sample's
/// with the number of branch switches the sample's sweep made up to there, or `None` where
/// either failed or the sample has another number of modes. The recorded program's passes
/// run at `tier`, chosen by the caller for all its sweeps ([`Tier::for_points`]), in the
/// caller's `workspace` (one per worker thread).
pub fn sample_sweep(
    model: &Compiled,
    p: Vec<f64>,
    speeds: &[f64],
    nominal: &[Option<Point>],
    (tier, workspace): (Tier, &Workspace),
    mut visit: impl FnMut(usize, Option<(&Point, &Point, usize)>),
) {
    // Samples do not report drive forces.
    let options = Options {
        newton: Settings {
            drive_force: false,
            ..Settings::default()
        },
        tier,
        ..Options::default()
    };
    // A design that cannot exist (a negative mass, an indefinite inertia) fails at every speed.
    if model.model().admissible(&p).is_err() {
        for i in 0..speeds.len() {
            visit(i, None);
        }
        return;
    }
    let mut sweep = Sweep::in_workspace(model, p, options, workspace);
    let mut started = false;
    let mut switches = 0;
    for (i, (&w, nom)) in speeds.iter().zip(nominal).enumerate() {
        let pt = nom.as_ref().and_then(|nom| {
            if !started {
                sweep.warm_start(nom);
            }
            let pt = sweep.step(w).ok()?;
            started = true;
            switches += usize::from(pt.new_branch);
            (pt.modes.len() == nom.modes.len()).then(|| (nom, match_modes(nom, pt)))
        });
        visit(i, pt.as_ref().map(|(nom, pt)| (*nom, pt, switches)));
    }
}

/// Number of branch switches of the nominal sweep up to each speed, counted as a sample's are
/// ([`sample_sweep`]): from its first point on. Samples start from that point, so a switch
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
