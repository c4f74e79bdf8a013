//! One design swept across a study's speeds, as a Monte Carlo sample, a quadrature node and a
//! row of a Sobol design each are: the one sweep of a design the sampling methods make
//! ([`Study::sweep_design`]), read through named readers at each speed ([`DesignAt`]: an
//! output's value, the carriers) and the requirements' margins there ([`Study::margins`]).

use super::Study;
use crate::equilibrium::Settings;
use crate::margins::{self, write_carriers};
use crate::model::Requirement;
use crate::output::Output;
use crate::pair::Carriers;
use crate::program::{Tier, Workspace};
use crate::sensitivity::TransferAt;
use crate::sweep::{Options, Point, Sweep};
use crate::tolerance::{match_modes, value};

/// One design at one speed of a study, where its point solved (see [`Study::sweep_design`]).
#[derive(Clone, Copy)]
pub struct DesignAt<'a> {
    /// The nominal point at this speed, whose modes the design's are matched to.
    pub nominal: &'a Point,
    /// The design's point, its modes in the nominal point's order.
    pub point: &'a Point,
    /// Branch switches of the design's sweep up to this speed.
    pub switches: usize,
    /// Is the design on the nominal design's branch here (as many switches)?
    pub same_branch: bool,
    /// The transfer function at this speed, if the model has one.
    pub transfer: Option<TransferAt>,
}

impl DesignAt<'_> {
    /// The value of output `o` (NaN where it has none).
    pub fn value(&self, o: &Output) -> f64 {
        value(self.point, o, self.transfer).unwrap_or(f64::NAN)
    }

    /// Writes the design's carriers here into `out` ([`crate::pair::Carriers`]).
    pub fn write_carriers(&self, out: &mut [f64]) {
        write_carriers(self.point, self.transfer, out);
    }
}

impl Study<'_> {
    /// Sweeps the design `p` across the study's speeds as a Monte Carlo sample, a quadrature
    /// node and a row of a Sobol design do: warm-started from the nominal point at the first
    /// speed, continued from speed to speed (so that it follows the branch a sweep from the
    /// lowest speed follows), its modes matched to the nominal ones by shape. `visit(i, design)`
    /// gets the design at each speed, `None` where the design or the nominal point failed there
    /// or the design has another number of modes. The recorded program's passes run at `tier`,
    /// chosen by the caller for all its sweeps ([`Tier::for_points`]), in the caller's
    /// `workspace` (one per worker thread).
    pub fn sweep_design(
        &self,
        p: Vec<f64>,
        (tier, workspace): (Tier, &Workspace),
        mut visit: impl FnMut(usize, Option<&DesignAt>),
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
        // A design that cannot exist (a negative mass, an indefinite inertia) fails at every
        // speed.
        if self.model.model().admissible(&p).is_err() {
            for i in 0..self.speeds.len() {
                visit(i, None);
            }
            return;
        }
        let mut sweep = Sweep::in_workspace(self.model, p, options, workspace);
        let mut started = false;
        let mut switches = 0;
        for (i, (&w, nom)) in self.speeds.iter().zip(&self.nominal).enumerate() {
            let pt = nom.as_ref().and_then(|nom| {
                if !started {
                    sweep.warm_start(nom);
                }
                let pt = sweep.step_beside(w, nom).ok()?;
                started = true;
                switches += usize::from(pt.new_branch);
                (pt.modes.len() == nom.modes.len()).then(|| (nom, match_modes(nom, pt)))
            });
            let at = pt.as_ref().map(|(nominal, point)| DesignAt {
                nominal,
                point,
                switches,
                same_branch: switches == self.branches[i],
                transfer: self.transfer_at(i),
            });
            visit(i, at.as_ref());
        }
    }

    /// Every requirement's margin at speed `i` of the design `at` (`None` where it failed
    /// there: `−∞`), given to `put(requirement, margin)` for the requirements `within` it
    /// ([`margins::covers`] or [`margins::reaches`]).
    pub fn margins(
        &self,
        i: usize,
        at: Option<&DesignAt>,
        within: fn(&Requirement, f64) -> bool,
        mut put: impl FnMut(usize, f64),
    ) {
        let speed = self.speeds[i];
        let reqs = &self.model.model().requirements;
        let covering = || reqs.iter().enumerate().filter(|(_, r)| within(r, speed));
        let Some(at) = at else {
            covering().for_each(|(k, _)| put(k, f64::NEG_INFINITY));
            return;
        };
        if covering().next().is_none() {
            return;
        }
        let c = margins::carriers(at.point, at.transfer);
        let state = margins::State {
            speed,
            carriers: Carriers::new(&c),
            same_branch: at.same_branch,
        };
        covering().for_each(|(k, r)| put(k, margins::margin(r, &state)));
    }
}
