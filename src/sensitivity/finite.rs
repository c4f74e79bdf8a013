//! Sensitivities by finite differences of the whole pipeline: the cross-check, and the paper's
//! method.

use super::{
    DesignPoint, ModeSensitivity, Sensitivity, Status, TransferAt, VariableSensitivity,
    nominal_transfer,
};
use crate::compiled::Compiled;
use crate::modal::match_modes;
use crate::sweep::{Options, Point, PointError, point};

/// Quantities per mode in [`fd_quantities`].
const NQ: usize = 7;

/// Relative step of the central differences.
const FD_STEP: f64 = 1e-4;

/// Quantities compared by finite differences at one perturbed point: per mode
/// `[Re λ, Im λ, ω_d, ω_n, ζ, λ₁+λ₂, λ₁λ₂]` (modes matched to the nominal ones by
/// [`match_modes`]), then `|H|`,
/// `arg H`, then the coordinates; and whether every mode kept its class.
fn fd_quantities(
    model: &Compiled,
    p: &[f64],
    pt: &Point,
    tf: Option<TransferAt>,
    opt: &Options,
) -> Result<(Vec<f64>, bool), PointError> {
    let q = point(model, p, pt.speed, &pt.equilibrium.q, opt)?;
    let mut out = Vec::new();
    let mut same_class = true;
    let order = match_modes(
        (&pt.modes, &pt.shapes, &pt.linear.m_full),
        (&q.modes, &q.shapes),
    );
    for (m0, &i) in pt.modes.iter().zip(&order) {
        let Some(m) = q.modes.get(i) else {
            // No mode of the perturbed point left to match (it has fewer).
            same_class = false;
            out.extend([f64::NAN; NQ]);
            continue;
        };
        same_class &= m.class == m0.class;
        out.extend([
            m.root.lambda.re,
            m.root.lambda.im,
            m.damped_frequency,
            m.natural_frequency,
            m.damping_ratio,
            (m.root.lambda + m.partner.lambda).re,
            (m.root.lambda * m.partner.lambda).re,
        ]);
    }
    match tf.and_then(|t| nominal_transfer(&q, &t)) {
        Some(h) => out.extend([h.magnitude(), h.phase()]),
        None => out.extend([f64::NAN, f64::NAN]),
    }
    out.extend(q.equilibrium.q.iter().copied());
    Ok((out, same_class))
}

impl DesignPoint<'_> {
    /// Sensitivities by finite differences of the whole pipeline (re-solve the equilibrium,
    /// re-linearise, re-solve the modes): central differences at steps `h` and `h/2`,
    /// `h = 1e-4 × max(|b|, 1e-3)`, combined by Richardson extrapolation (error O(h⁴)). Modes are
    /// matched to the nominal ones by shape. A cross-check, and the paper's method.
    pub fn finite_difference(&self, wrt: &[usize]) -> Result<Sensitivity, PointError> {
        let (model, p, pt, tf) = (self.model, self.p, self.point, self.transfer);
        let opt = Options {
            independent: Some(pt.linear.independent.clone()),
            no_branch_switch: true,
            ..Default::default()
        };
        let nominal = tf.and_then(|t| nominal_transfer(pt, &t));
        let nm = pt.modes.len();
        let mut variables = Vec::new();
        for &b in wrt {
            let h = FD_STEP * p[b].abs().max(1e-3);
            let mut same = true;
            let mut central = |step: f64| -> Result<Vec<f64>, PointError> {
                let mut pp = p.to_vec();
                pp[b] = p[b] + step;
                let (a, sa) = fd_quantities(model, &pp, pt, tf, &opt)?;
                pp[b] = p[b] - step;
                let (c, sc) = fd_quantities(model, &pp, pt, tf, &opt)?;
                same &= sa && sc;
                Ok(a.iter()
                    .zip(&c)
                    .map(|(x, y)| (x - y) / (2.0 * step))
                    .collect())
            };
            let d1 = central(h)?;
            let d2 = central(0.5 * h)?;
            let d: Vec<f64> = d1
                .iter()
                .zip(&d2)
                .map(|(a, b)| (4.0 * b - a) / 3.0)
                .collect();
            let status = if same {
                Status::Ok
            } else {
                Status::NotDifferentiable
            };
            let modes = (0..nm)
                .map(|k| ModeSensitivity {
                    status,
                    d_eigen_re: d[NQ * k],
                    d_eigen_im: d[NQ * k + 1],
                    d_damped_frequency: d[NQ * k + 2],
                    d_natural_frequency: d[NQ * k + 3],
                    d_damping_ratio: d[NQ * k + 4],
                    d_sum: d[NQ * k + 5],
                    d_product: d[NQ * k + 6],
                })
                .collect();
            let has_tf = nominal.is_some() && d[NQ * nm].is_finite();
            variables.push(VariableSensitivity {
                param: b,
                modes,
                d_transfer_magnitude: has_tf.then(|| d[NQ * nm]),
                d_transfer_phase: has_tf.then(|| d[NQ * nm + 1]),
                d_equilibrium: d[NQ * nm + 2..].to_vec(),
            });
        }
        Ok(Sensitivity {
            transfer_magnitude: nominal.map(|h| h.magnitude()),
            transfer_phase: nominal.map(|h| h.phase()),
            variables,
        })
    }
}
