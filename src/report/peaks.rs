//! `peaks.csv` and the report's table of the transfer function's peaks along the speed
//! ([`crate::peaks`]): each peak's speed and magnitude (none at a resonance: unbounded) with
//! their first-order σ per case, or why a peak could not be located.

use super::opt;
use crate::analyze::Analysis;
use crate::model::Model;

/// Header of `peaks.csv`: the case, the kind (`maximum` or `resonance`), the speed of the peak
/// and its first-order σ (rad/s), |H| at the peak and its σ (in `unit`; empty at a resonance,
/// where it is unbounded), the amplification factor by API 684's half-power method and its σ,
/// the mode at the excitation frequency (a resonance's, 1-based), and why a value is missing.
pub const PEAK_HEADER: [&str; 11] = [
    "case",
    "kind",
    "speed",
    "speed_std",
    "magnitude",
    "magnitude_std",
    "unit",
    "amplification_factor",
    "amplification_factor_std",
    "mode",
    "message",
];

/// Rows of `peaks.csv` (see [`PEAK_HEADER`]): one per peak and case; a peak that could not be
/// located is one row without a case, at the swept speed it was near.
pub fn peak_rows(model: &Model, a: &Analysis) -> Vec<Vec<String>> {
    let unit = (model.analysis.transfer)
        .map(|t| model.transfer_unit(&t))
        .unwrap_or_default();
    let mut rows = Vec::new();
    for row in &a.peaks {
        match row {
            Ok((peak, cases)) => {
                for (case, spread) in a.cases.iter().zip(cases) {
                    let mut why: Vec<&str> =
                        [&spread.speed, &spread.magnitude, &spread.amplification]
                            .iter()
                            .filter_map(|r| r.as_ref().err().map(String::as_str))
                            .collect();
                    why.dedup();
                    rows.push(vec![
                        case.name.clone(),
                        peak.kind.as_str().into(),
                        peak.speed.to_string(),
                        opt(spread.speed.as_ref().ok().map(|s| s.std)),
                        opt(peak.magnitude),
                        opt(spread.magnitude.as_ref().ok().map(|s| s.std)),
                        unit.clone(),
                        opt(peak.amplification.as_ref().ok().map(|a| a.0)),
                        opt(spread.amplification.as_ref().ok().map(|s| s.std)),
                        peak.mode.map_or(String::new(), |k| (k + 1).to_string()),
                        why.join("; "),
                    ]);
                }
            }
            Err(f) => rows.push(vec![
                String::new(),
                String::new(),
                f.near.to_string(),
                String::new(),
                String::new(),
                String::new(),
                unit.clone(),
                String::new(),
                String::new(),
                String::new(),
                f.why.clone(),
            ]),
        }
    }
    rows
}
