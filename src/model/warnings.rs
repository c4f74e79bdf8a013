//! Modelling mistakes that load without an error but leave every answer saying less than its
//! author meant: what `check` warns about, each with what to do. None of them is an error, as
//! each can be meant (a structure at rest, an offset toleranced through zero, a requirement
//! over speeds another run analyses).

use super::{Distribution, Model};
use statrs::distribution::{ContinuousCDF, Normal};

impl Model {
    /// The warnings about the model as written, each a sentence that says what is wrong and
    /// what to do:
    ///
    /// * no joint is driven by the speed, where speeds other than 0 are analysed (or none are
    ///   given): every speed is the mechanism at rest;
    /// * a toleranced parameter's band reaches zero (a ±200 % tolerance on a stiffness), with
    ///   the probability of a sample at or beyond it;
    /// * a requirement's operating range lies beyond the `[analysis]` speeds (a range in rpm
    ///   by mistake): the analysis would refuse them ([`Model::check_requirement_speeds`]).
    ///
    /// Designs that cross a physical limit within a case's tolerances (a negative mass) are
    /// [`Model::tolerance_limits`].
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let driven_by_speed = (self.joints.iter())
            .filter_map(|j| j.drive.as_ref())
            .any(|d| d.expr.uses_speed());
        // A structure analysed at rest alone (`speed = "0:0:1"`) means it.
        let turning = (self.analysis.speed).is_none_or(|g| g.speeds().any(|w| w != 0.0));
        if !driven_by_speed && turning {
            out.push(
                "no joint is driven by the speed (no `drive` uses `speed`): at every speed \
                 analysed the mechanism is at rest, and only expressions that use `speed` \
                 change with it; give the spinning joint `drive = \"speed\"`"
                    .to_string(),
            );
        }
        out.extend(self.signs_crossed());
        if let Some(grid) = self.analysis.speed {
            // Its ends decide (a grid is in increasing order).
            let ends: Vec<f64> = grid.speeds().take(1).chain(grid.speeds().last()).collect();
            if let Err(e) = self.check_requirement_speeds(&ends) {
                out.push(format!(
                    "{e} (at the [analysis] speeds {}:{}:{} rad/s, `analyze` refuses to run)",
                    grid.from, grid.to, grid.step
                ));
            }
        }
        out
    }

    /// A warning for each toleranced parameter (its own tolerance, then each case's) whose
    /// band `value ± tolerance` reaches zero, once per parameter and half-width.
    fn signs_crossed(&self) -> Vec<String> {
        let own = (self.parameters.iter().enumerate())
            .filter_map(|(i, p)| p.tolerance.map(|t| (i, t, None)));
        let cases = (self.analysis.cases.iter())
            .flat_map(|c| (c.tolerances.iter()).map(move |&(i, t)| (i, t, Some(c.name.as_str()))));
        let mut seen: Vec<(usize, u64)> = Vec::new();
        let mut out = Vec::new();
        for (i, t, case) in own.chain(cases) {
            let p = &self.parameters[i];
            let h = t.absolute(p.value);
            if p.value == 0.0 || h < p.value.abs() || seen.contains(&(i, h.to_bits())) {
                continue;
            }
            seen.push((i, h.to_bits()));
            let beyond = match p.distribution {
                // The tolerance is 3σ.
                Distribution::Normal => Normal::standard().cdf(-3.0 * p.value.abs() / h),
                Distribution::Uniform => (h - p.value.abs()) / (2.0 * h),
            };
            let whose = case.map_or(String::new(), |c| format!(" in case '{c}'"));
            out.push(format!(
                "parameter '{}' = {} ± {}{whose} reaches zero within its tolerance: {:.3} % of \
                 its {} samples are of the other sign; a mass, stiffness, length or density \
                 cannot be, so give it a tolerance below its value (a percentage below 100 %)",
                p.name,
                p.value,
                h,
                100.0 * beyond,
                match p.distribution {
                    Distribution::Normal => "normal (tolerance = 3σ)",
                    Distribution::Uniform => "uniform",
                },
            ));
        }
        out
    }
}
