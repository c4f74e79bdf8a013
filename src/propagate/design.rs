//! One design swept across a study's speeds, as a Monte Carlo sample, a quadrature node and a
//! row of a Sobol design each are: the one sweep of a design the sampling methods make
//! ([`Study::sweep_design`]), read through named readers at each speed ([`DesignAt`]: an
//! output's value, the carriers) and the requirements' margins there ([`Study::margins`]).

use super::Study;
use crate::margins::{self, write_carriers};
use crate::model::Requirement;
use crate::output::Output;
use crate::program::{Tier, Workspace};
use crate::sampling::sample_sweep;
use crate::sensitivity::TransferAt;
use crate::sweep::Point;
use crate::tolerance::value;

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
    /// Sweeps the design `p` across the study's speeds as a sample does
    /// ([`sample_sweep`]: from the nominal point, speed to speed, its modes matched to the
    /// nominal ones): `visit(i, design)` per speed, `None` where the design or the nominal point
    /// failed there. The recorded program's passes run at the caller's tier in its workspace.
    pub fn sweep_design(
        &self,
        p: Vec<f64>,
        run: (Tier, &Workspace),
        mut visit: impl FnMut(usize, Option<&DesignAt>),
    ) {
        sample_sweep(self.model, p, &self.speeds, &self.nominal, run, |i, pts| {
            let at = pts.map(|(nominal, point, switches)| DesignAt {
                nominal,
                point,
                switches,
                same_branch: switches == self.branches[i],
                transfer: self.transfer_at(i),
            });
            visit(i, at.as_ref());
        });
    }

    /// Every requirement's margin at speed `i` of the design `at` (`None` where it failed
    /// there: `−∞`), given to `put(requirement, margin)` for the requirements `within` it
    /// ([`margins::covers`] or [`margins::reaches`]).
    pub fn margins(
        &self,
        i: usize,
        at: Option<&DesignAt>,
        within: fn(&Requirement, f64) -> bool,
        put: impl FnMut(usize, f64),
    ) {
        margins::margins_at(
            &self.model.model().requirements,
            self.speeds[i],
            at.map(|d| (d.point, d.same_branch)),
            self.transfer_at(i),
            within,
            put,
        );
    }
}
