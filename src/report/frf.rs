//! The frequency-response table of `frf`: `H` at each excitation frequency, its derivatives per
//! design variable, and why `H` has no value where it has none. Its own file: it is the one
//! table indexed by excitation frequency rather than by speed and mode.

use super::{message, opt};
use crate::frf::{NoTransfer, transfer_defect};
use crate::linearize::Linearization;
use crate::model::Model;
use crate::sensitivity::ResponseRow;

/// Header of the frequency-response table (`frf`): excitation frequency, |H|, arg H, its real
/// and imaginary parts, then `d(magnitude)/d(P)` per design variable, then `message` (why `H`
/// has no value, where it has none).
pub fn frf_header(model: &Model, wrt: &[usize]) -> Vec<String> {
    let mut header: Vec<String> = ["frequency", "magnitude", "phase", "real", "imag"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(
        wrt.iter()
            .map(|&b| format!("d(magnitude)/d({})", model.parameters[b].name)),
    );
    header.push("message".into());
    header
}

/// Rows of the frequency-response table (see [`frf_header`]) of the linearisation `lin`:
/// empty cells where `H` or a derivative does not exist, and where `H` has no finite value,
/// the reason ([`transfer_defect`]: a resonance, an overflow).
pub fn frf_rows(lin: &Linearization<f64>, rows: &[ResponseRow]) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| {
            let mut row = vec![r.frequency.to_string()];
            let why = transfer_defect(lin, r.frequency, r.h.as_ref());
            let h = r.h.filter(|_| why.is_none());
            row.extend([
                opt(h.map(|h| h.magnitude())),
                opt(h.map(|h| h.phase())),
                opt(h.map(|h| h.re)),
                opt(h.map(|h| h.im)),
            ]);
            row.extend(r.d_magnitude.iter().map(|&v| opt(v)));
            row.push(message([why.map(NoTransfer::message)]));
            row
        })
        .collect()
}
