//! The speeds at which requirements are judged.
//!
//! A requirement over an operating range `[a, b]` is judged at the analysed speeds inside it
//! ([`crate::margins`]). Judged at a grid alone, a range that falls between two grid
//! points would hold no speed and be met vacuously, and a range whose ends are not grid points
//! would be judged short of them. So the speeds an analysis sweeps are the grid asked for with
//! every requirement's range ends added ([`Model::judged_speeds`]): a range is then judged at its
//! ends and at every grid speed inside, no farther apart than the grid's step. Requirements
//! read the speeds in order (the operating range met runs from a range's start up), so where
//! there are requirements the speeds are put in increasing order.
//!
//! A front end refuses first what the analysis could only answer poorly
//! ([`Model::check_requirement_speeds`]): a range reaching beyond the speeds asked for (a range
//! in rpm by mistake, or a grid that stops short of it) and speeds given out of order.

use super::Model;

/// Two speeds closer than this, relative to `max(1, |speed|)`, are one speed: a grid point
/// computed as `from + i·step` may differ from a range end written in decimals by rounding.
pub const SAME_SPEED: f64 = 1e-9;

/// Are `a` and `b` one speed (see [`SAME_SPEED`])?
pub fn same_speed(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME_SPEED * a.abs().max(b.abs()).max(1.0)
}

impl Model {
    /// The speeds to analyse for the grid `speeds`: unchanged without requirements; else in
    /// increasing order with every requirement's range ends added where the grid has no speed
    /// at them (see the module documentation).
    pub fn judged_speeds(&self, speeds: &[f64]) -> Vec<f64> {
        if self.requirements.is_empty() {
            return speeds.to_vec();
        }
        let mut out = speeds.to_vec();
        out.sort_by(f64::total_cmp);
        out.dedup_by(|a, b| a.to_bits() == b.to_bits());
        let ends = self
            .requirements
            .iter()
            .filter_map(|r| r.speeds)
            .flat_map(|(a, b)| [a, b]);
        for end in ends {
            if !out.iter().any(|&w| same_speed(w, end)) {
                let at = out.partition_point(|&w| w < end);
                out.insert(at, end);
            }
        }
        out
    }

    /// Refuses the speeds `speeds` (as asked for, before [`Model::judged_speeds`]) where the
    /// requirements could not be judged over their ranges: speeds out of increasing order, or a
    /// range reaching beyond the first or last speed. The message names the requirement and
    /// both ranges.
    pub fn check_requirement_speeds(&self, speeds: &[f64]) -> Result<(), String> {
        if self.requirements.is_empty() || speeds.is_empty() {
            return Ok(());
        }
        if speeds.windows(2).any(|w| w[1] <= w[0]) {
            return Err(
                "the model has requirements, which are judged from the start of their range up: \
                 give the speeds in increasing order, each once"
                    .into(),
            );
        }
        let (lo, hi) = (speeds[0], speeds[speeds.len() - 1]);
        for r in &self.requirements {
            let Some((a, b)) = r.speeds else { continue };
            let below = a < lo && !same_speed(a, lo);
            let above = b > hi && !same_speed(b, hi);
            if below || above {
                let rpm = |w: f64| w * 60.0 / std::f64::consts::TAU;
                return Err(format!(
                    "requirement '{}' is judged over {a}–{b} rad/s, beyond the speeds analysed \
                     ({lo}–{hi} rad/s): analyse speeds that cover its range, or correct the \
                     range (speeds are in rad/s: {hi} rad/s is {:.4} rpm)",
                    r.name,
                    rpm(hi)
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::model::{Model, Requirement};
    use crate::requirements::{Kind, stable::Stable};

    fn with_ranges(ranges: &[Option<(f64, f64)>]) -> Model {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/rotating_pendulum.toml");
        let mut m = Model::from_file(&path).expect("the shipped pendulum");
        m.requirements = ranges
            .iter()
            .enumerate()
            .map(|(k, &speeds)| Requirement {
                name: format!("r{k}"),
                kind: Kind::Stable(Stable),
                speeds,
                mode: None,
            })
            .collect();
        m
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn range_ends_are_added_to_the_grid_once_and_in_order() {
        let grid = [0.0, 0.1, 0.2, 0.30000000000000004, 0.4];
        let m = with_ranges(&[Some((0.15, 0.3)), None, Some((0.15, 0.17))]);
        // 0.3 is the grid's 0.30000000000000004 (one speed); 0.15 and 0.17 are added once.
        assert_eq!(
            bits(&m.judged_speeds(&grid)),
            bits(&[0.0, 0.1, 0.15, 0.17, 0.2, 0.30000000000000004, 0.4])
        );
        // Without requirements the grid is untouched, in its order.
        let none = with_ranges(&[]);
        assert_eq!(bits(&none.judged_speeds(&[0.2, 0.1])), bits(&[0.2, 0.1]));
    }

    #[test]
    fn ranges_beyond_the_speeds_and_speeds_out_of_order_are_refused() {
        let m = with_ranges(&[Some((1000.0, 3000.0))]);
        let e = m.check_requirement_speeds(&[0.0, 2.5, 5.0]).unwrap_err();
        assert!(
            e.contains("'r0'") && e.contains("1000–3000") && e.contains("rpm"),
            "{e}"
        );
        let m = with_ranges(&[Some((4.0, 6.0))]);
        assert!(m.check_requirement_speeds(&[0.0, 5.0]).is_err());
        assert!(m.check_requirement_speeds(&[4.0, 6.0]).is_ok());
        assert!(
            m.check_requirement_speeds(&[3.0, 4.5, 6.000000000000001])
                .is_ok()
        );
        let e = m.check_requirement_speeds(&[3.0, 7.0, 5.0]).unwrap_err();
        assert!(e.contains("increasing"), "{e}");
        // A range between two grid speeds is judged (at its ends), not refused.
        let m = with_ranges(&[Some((1.52, 1.58))]);
        assert!(m.check_requirement_speeds(&[1.5, 1.6]).is_ok());
    }
}
