//! The sweep CSV (`sweep`): one row per speed and mode, with the optional columns of the
//! transfer function and of the derivatives per design variable ([`SweepColumns`]), the
//! equilibrium and the branch. Its own file because its columns vary with the options.

use super::{MODE_COLUMNS, failed_rows, mode_cells, opt, point_message};
use crate::frf::NoTransfer;
use crate::model::Model;
use crate::nominal_sweep::SweepExtras;
use crate::sensitivity::Status as SensStatus;
use crate::sweep::{Point, PointError};
use crate::whirl::Whirl;

/// Optional column groups of the sweep CSV.
#[derive(Debug, Clone, Default)]
pub struct SweepColumns {
    /// Add `transfer_magnitude,transfer_phase`.
    pub transfer: bool,
    /// Design variables (parameter indices) for `d(…)/d(P)` columns; empty: none.
    pub wrt: Vec<usize>,
}

/// Header of the sweep CSV.
pub fn sweep_header(model: &Model, cols: &SweepColumns) -> Vec<String> {
    let mut h: Vec<String> = MODE_COLUMNS.iter().map(|s| s.to_string()).collect();
    h.push("tuning_order".into());
    h.push("whirl".into());
    if cols.transfer {
        h.push("transfer_magnitude".into());
        h.push("transfer_phase".into());
    }
    for &b in &cols.wrt {
        let p = &model.parameters[b].name;
        h.push(format!("d(damped_frequency)/d({p})"));
        h.push(format!("d(natural_frequency)/d({p})"));
        h.push(format!("d(damping_ratio)/d({p})"));
        if cols.transfer {
            h.push(format!("d(transfer_magnitude)/d({p})"));
        }
    }
    if !cols.wrt.is_empty() {
        h.push("sensitivity_status".into());
    }
    h.extend(model.coordinates.iter().map(|c| format!("q:{}", c.name)));
    h.extend(
        model
            .driven()
            .iter()
            .map(|&i| format!("drive:{}", model.coordinates[i].name)),
    );
    h.push("iterations".into());
    h.push("branch".into());
    h.push("message".into());
    h
}

/// Rows of the sweep CSV for one speed: one per mode (a failed speed gets one `failed` row per
/// degree of freedom, with the reason). Derivatives that do not exist are left empty and
/// `sensitivity_status` says `not_differentiable`.
pub fn sweep_rows(
    model: &Model,
    cols: &SweepColumns,
    speed: f64,
    result: &Result<Point, PointError>,
    extras: &SweepExtras,
) -> Vec<Vec<String>> {
    let ncols = sweep_header(model, cols).len();
    match result {
        Ok(p) => p
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let mut r = mode_cells(speed, i, m);
                r.push(opt((speed != 0.0).then(|| m.damped_frequency / speed)));
                let whirl = extras.whirl.get(i).copied().flatten();
                r.push(whirl.map_or("", Whirl::as_str).into());
                if cols.transfer {
                    r.push(opt(extras.transfer.map(|h| h.magnitude())));
                    r.push(opt(extras.transfer.map(|h| h.phase())));
                }
                if !cols.wrt.is_empty() {
                    let mut status = "ok";
                    for (k, _) in cols.wrt.iter().enumerate() {
                        let v = extras.sensitivity.as_ref().map(|s| &s.variables[k]);
                        let ms = v.map(|v| &v.modes[i]);
                        let ok = ms.is_some_and(|m| m.status == SensStatus::Ok);
                        if !ok {
                            status = "not_differentiable";
                        }
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_damped_frequency)));
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_natural_frequency)));
                        r.push(opt(ms.filter(|_| ok).map(|m| m.d_damping_ratio)));
                        if cols.transfer {
                            let d = v.and_then(|v| v.d_transfer_magnitude);
                            if d.is_none() {
                                status = "not_differentiable";
                            }
                            r.push(opt(d));
                        }
                    }
                    r.push(status.into());
                }
                r.extend(p.equilibrium.q.iter().map(|v| v.to_string()));
                r.extend(
                    model
                        .driven()
                        .iter()
                        .map(|&d| p.equilibrium.drive_force[d].to_string()),
                );
                r.push(p.equilibrium.iterations.to_string());
                r.push(p.branch.as_str().into());
                let why = extras.transfer_defect.map(NoTransfer::message);
                r.push(point_message(p, why));
                r
            })
            .collect(),
        Err(e) => failed_rows(model, ncols, speed, e),
    }
}
