//! The results of `sensitivity` at one speed: the CSV rows (derivatives per unit and as
//! elasticities), the JSON document and the text table. Together because they show one
//! [`Sensitivity`] and share what is left empty where a derivative does not exist.

use super::{fixed, message, opt};
use crate::frf::{NoTransfer, excitation, transfer_defect};
use crate::model::Model;
use crate::sensitivity::{Sensitivity, Status as SensStatus, TransferAt, nominal_transfer};
use crate::sweep::Point;
use serde_json::{Value, json};
use std::fmt::Write;

/// The elasticity `(b/f)·df/db`: the relative change of `f` per relative change of `b`; none
/// where `f` is zero (an undamped mode's ζ, an overdamped mode's ω_d).
pub fn elasticity(b: f64, f: f64, df_db: f64) -> Option<f64> {
    let e = b / f * df_db;
    (f != 0.0 && e.is_finite()).then_some(e)
}

/// Header of the sensitivity table (`sensitivity --format csv`): one row per mode and design
/// variable, the derivatives per unit of the variable (`d_…`) and normalised (`elasticity_…`,
/// [`elasticity`]), then `message` (why |H| has no value, where it has none).
pub const SENSITIVITY_HEADER: [&str; 19] = [
    "speed",
    "mode",
    "status",
    "damped_frequency",
    "natural_frequency",
    "damping_ratio",
    "transfer_magnitude",
    "parameter",
    "value",
    "sensitivity_status",
    "d_damped_frequency",
    "d_natural_frequency",
    "d_damping_ratio",
    "d_transfer_magnitude",
    "elasticity_damped_frequency",
    "elasticity_natural_frequency",
    "elasticity_damping_ratio",
    "elasticity_transfer_magnitude",
    "message",
];

/// Why the transfer function `t` has no finite value at the point `pt`, where it has none.
pub fn transfer_defect_at(pt: &Point, t: Option<&TransferAt>) -> Option<NoTransfer> {
    t.and_then(|t| {
        let omega = excitation(&pt.linear, t.input, t.omega);
        transfer_defect(&pt.linear, omega, nominal_transfer(pt, t).as_ref())
    })
}

/// The result of `sensitivity` at one point, as its CSV rows, JSON document and text table
/// show it: the model, the point, its sensitivities, and why |H| has no value where it has none
/// ([`transfer_defect_at`]).
#[derive(Debug, Clone, Copy)]
pub struct SensitivityReport<'a> {
    pub model: &'a Model,
    pub point: &'a Point,
    pub sensitivity: &'a Sensitivity,
    pub no_transfer: Option<NoTransfer>,
}

impl SensitivityReport<'_> {
    /// Rows of the sensitivity table (see [`SENSITIVITY_HEADER`]); derivatives that do not exist
    /// are empty and `sensitivity_status` says `not_differentiable`; `message` says why |H|
    /// has no value, where it has none.
    pub fn rows(&self) -> Vec<Vec<String>> {
        let SensitivityReport {
            model,
            point: pt,
            sensitivity: s,
            no_transfer: transfer,
        } = *self;
        let mut rows = Vec::new();
        for (i, m) in pt.modes.iter().enumerate() {
            for v in &s.variables {
                let b = model.parameters[v.param].value;
                let ms = &v.modes[i];
                let ok = ms.status == SensStatus::Ok;
                let d = |x: f64| ok.then_some(x);
                let dh = v.d_transfer_magnitude;
                let el = |f: f64, df: Option<f64>| df.and_then(|df| elasticity(b, f, df));
                rows.push(vec![
                    pt.speed.to_string(),
                    (i + 1).to_string(),
                    m.class.as_str().to_string(),
                    m.damped_frequency.to_string(),
                    m.natural_frequency.to_string(),
                    opt(Some(m.damping_ratio)),
                    opt(s.transfer_magnitude),
                    model.parameters[v.param].name.clone(),
                    b.to_string(),
                    if ok { "ok" } else { "not_differentiable" }.to_string(),
                    opt(d(ms.d_damped_frequency)),
                    opt(d(ms.d_natural_frequency)),
                    opt(d(ms.d_damping_ratio)),
                    opt(dh),
                    opt(el(m.damped_frequency, d(ms.d_damped_frequency))),
                    opt(el(m.natural_frequency, d(ms.d_natural_frequency))),
                    opt(el(m.damping_ratio, d(ms.d_damping_ratio))),
                    opt(s.transfer_magnitude.and_then(|h| el(h, dh))),
                    message([transfer.map(NoTransfer::message)]),
                ]);
            }
        }
        rows
    }

    /// The `sensitivity` result at `speed` (derivatives by `method`) as JSON.
    pub fn json(&self, speed: f64, method: &str) -> Value {
        let SensitivityReport {
            model,
            point: pt,
            sensitivity: s,
            no_transfer: transfer,
        } = *self;
        let vars: Vec<Value> = s
            .variables
            .iter()
            .map(|v| {
                let p = &model.parameters[v.param];
                json!({
                    "parameter": p.name, "value": p.value,
                    "d_transfer_magnitude": v.d_transfer_magnitude, "d_transfer_phase": v.d_transfer_phase,
                    "d_equilibrium": model.coordinates.iter().zip(&v.d_equilibrium).map(|(c, d)| json!({"name": c.name, "value": d})).collect::<Vec<_>>(),
                    "modes": v.modes.iter().enumerate().map(|(i, m)| {
                        let ok = m.status == SensStatus::Ok;
                        json!({"mode": i + 1, "status": m.status,
                               "d_damped_frequency": ok.then_some(m.d_damped_frequency),
                               "d_natural_frequency": ok.then_some(m.d_natural_frequency),
                               "d_damping_ratio": ok.then_some(m.d_damping_ratio),
                               "d_eigen_re": m.d_eigen_re, "d_eigen_im": m.d_eigen_im})
                    }).collect::<Vec<_>>(),
                })
            })
            .collect();
        json!({
            "model": model.name, "speed": speed, "derivatives": method,
            "units": {"frequency": "rad/s", "derivative": "quantity unit per parameter unit"},
            "modes": pt.modes.iter().enumerate().map(|(i, m)| json!({"mode": i + 1, "status": m.class.as_str(),
                "damped_frequency": m.damped_frequency, "natural_frequency": m.natural_frequency, "damping_ratio": m.damping_ratio})).collect::<Vec<_>>(),
            "transfer_magnitude": s.transfer_magnitude.filter(|_| transfer.is_none()),
            "transfer_phase": s.transfer_phase.filter(|_| transfer.is_none()),
            "transfer_message": transfer.map(NoTransfer::message),
            "variables": vars,
        })
    }

    /// The `sensitivity` result at `speed` (derivatives by `method`) as a text table.
    pub fn table(&self, speed: f64, method: &str) -> String {
        let SensitivityReport {
            model,
            point: pt,
            sensitivity: s,
            no_transfer: transfer,
        } = *self;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "model: {}    speed: {speed:?} rad/s    derivatives: {method}",
            model.name
        );
        if let Some(why) = transfer {
            let _ = writeln!(out, "transfer: {}", why.message());
        } else if let (Some(h), Some(ph)) = (s.transfer_magnitude, s.transfer_phase) {
            let _ = writeln!(out, "transfer |H| = {h:.8e}, arg H = {ph:.6} rad");
        }
        for (i, m) in pt.modes.iter().enumerate() {
            let _ = writeln!(
                out,
                "\nmode {} ({}): ω_d = {:.8} rad/s, ω_n = {:.8} rad/s, ζ = {}",
                i + 1,
                m.class.as_str(),
                m.damped_frequency,
                m.natural_frequency,
                fixed(m.damping_ratio, 6)
            );
            let pw = s
                .variables
                .iter()
                .map(|v| model.parameters[v.param].name.chars().count())
                .max()
                .unwrap_or(0)
                .max(14);
            let _ = writeln!(
                out,
                "  {:<pw$} {:>16} {:>16} {:>16} {:>16}",
                "parameter", "dω_d/dP", "dω_n/dP", "dζ/dP", "d|H|/dP"
            );
            for v in &s.variables {
                let ms = &v.modes[i];
                let f = |x: f64| {
                    if ms.status == SensStatus::Ok {
                        format!("{x:>16.8e}")
                    } else {
                        format!("{:>16}", "n/a")
                    }
                };
                let dh = v
                    .d_transfer_magnitude
                    .map_or(format!("{:>16}", "-"), |x| format!("{x:>16.8e}"));
                let _ = writeln!(
                    out,
                    "  {:<pw$} {} {} {} {dh}",
                    model.parameters[v.param].name,
                    f(ms.d_damped_frequency),
                    f(ms.d_natural_frequency),
                    f(ms.d_damping_ratio)
                );
            }
            if s.variables
                .iter()
                .any(|v| v.modes[i].status != SensStatus::Ok)
            {
                let _ = writeln!(
                    out,
                    "  n/a: roots coalescing or the mode changes class here; ω_d is not differentiable"
                );
            }
        }
        out
    }
}
