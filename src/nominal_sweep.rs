//! A speed sweep with, at every speed, the transfer function and the sensitivities asked for:
//! what the `sweep` command writes, one speed at a time, for any front end.

use crate::compiled::Compiled;
use crate::frf::{Complex, NoTransfer, transfer_defect};
use crate::model::Transfer;
use crate::sensitivity::{Derivatives, DesignPoint, Sensitivity, TransferAt, nominal_transfer};
use crate::sweep::{Options, Point, PointError, Sweep};
use crate::whirl::{self, Whirl};

/// Transfer function and sensitivities at one speed, for the optional sweep columns.
#[derive(Debug, Clone, Default)]
pub struct SweepExtras {
    pub transfer: Option<Complex<f64>>,
    /// Why the transfer function asked for has no finite value, where it has none.
    pub transfer_defect: Option<NoTransfer>,
    pub sensitivity: Option<Sensitivity>,
    /// Each mode's whirl ([`crate::whirl`]; empty where the model has no spinning part or
    /// does not evaluate).
    pub whirl: Vec<Option<Whirl>>,
}

/// A sweep at the nominal parameters (continuation from speed to speed, see [`Sweep`]) with
/// its extras.
pub struct NominalSweep<'a> {
    model: &'a Compiled,
    sweep: Sweep<'a>,
    transfer: Option<Transfer>,
    wrt: Vec<usize>,
    derivatives: Derivatives,
}

impl<'a> NominalSweep<'a> {
    /// A sweep of `model` with `options`; at each speed the transfer function `transfer`
    /// (excited at its order times the speed) and the sensitivities to the design variables
    /// `wrt` (none when empty), computed `derivatives`.
    pub fn new(
        model: &'a Compiled,
        options: Options,
        transfer: Option<Transfer>,
        wrt: Vec<usize>,
        derivatives: Derivatives,
    ) -> Self {
        NominalSweep {
            sweep: Sweep::new(model, model.model().nominal(), options),
            model,
            transfer,
            wrt,
            derivatives,
        }
    }

    /// The point at `speed` and its extras. A point whose sensitivities fail fails with their
    /// reason.
    pub fn step(&mut self, speed: f64) -> (Result<Point, PointError>, SweepExtras) {
        let mut result = self.sweep.step(speed);
        let mut extras = SweepExtras::default();
        if let Ok(pt) = &result {
            let p = self.model.model().nominal();
            extras.whirl = whirl::of_point(self.model.model(), &p, pt).unwrap_or_default();
            let t = self.transfer.map(|t| TransferAt::at_speed(&t, speed));
            extras.transfer = t.and_then(|t| nominal_transfer(pt, &t));
            extras.transfer_defect =
                t.and_then(|t| transfer_defect(&pt.linear, t.omega, extras.transfer.as_ref()));
            if !self.wrt.is_empty() {
                let (wrt, how, workspace) = (&self.wrt, self.derivatives, self.sweep.workspace());
                let at = DesignPoint::new(self.model, &p, pt)
                    .with_transfer(t)
                    .with_workspace(workspace);
                match at.sensitivities(wrt, how) {
                    Ok(s) => extras.sensitivity = Some(s),
                    Err(e) => result = Err(e),
                }
            }
        }
        (result, extras)
    }
}
