//! The peaks of a transfer function along the speed and the speeds where they lie, found
//! between the swept speeds, with their exact first derivatives with respect to the design
//! variables: how a rotordynamics engineer reads an unbalance response (the amplitude at each
//! critical speed and the speed itself; API 684's amplification factor and separation margin
//! are read off them; ROSS's `run_unbalance_response` draws the curve they sit on).
//!
//! With `g(Ω, p) = |H|` at the speed `Ω` (the excitation at `order × Ω`, or an unbalance's
//! spin rate):
//!
//! * A **maximum** has `g_Ω = 0 > g_ΩΩ`. Newton on `g_Ω`, with `g_Ω` and `g_ΩΩ` exact from the
//!   linearisation over a hyper-dual number seeded twice along the speed
//!   ([`DesignPoint::linearization_over`]: the equilibrium's move, the drives' rates and the
//!   excitation's frequency move with it), safeguarded by bisection inside the bracket the
//!   swept speeds give (a swept speed above both its neighbours). By the implicit function
//!   theorem on `g_Ω(Ω*, p) = 0` and the envelope theorem,
//!
//!   ```text
//!   dΩ*/dp_a = −g_Ωa / g_ΩΩ,        d g(Ω*, p)/dp_a = g_a
//!   ```
//!
//!   with `g_a` and `g_Ωa` from one hyper-dual pass per variable, seeded along the speed and
//!   `p_a`.
//! * A **resonance**: an undamped mode whose damped frequency meets the excitation's,
//!   `f(Ω) = ω_d(Ω) − ω_e(Ω) = 0`, where |H| is unbounded. It is reported by its speed, never
//!   as a large number: Newton on `f` with `f_Ω` exact (one dual pass along the speed), then
//!   `dΩ_r/dp_a = −f_a / f_Ω`. A mode the load does not excite or the output does not see (the
//!   backward whirl of an isotropic rotor under unbalance) leaves `H` finite where it meets
//!   the excitation: [`crate::frf::transfer`] resolves `H` there, and it is no resonance.
//!
//! A maximum's **amplification factor** `AF = Ω*/(Ω₂ − Ω₁)` (API 684's half-power method:
//! `Ω₁ < Ω* < Ω₂` where |H| falls to the peak's `1/√2`) comes with it: each half-power speed by
//! Newton on `|H| − g*/√2` (bracketed by the nearest swept speed below that level), its
//! derivatives `dΩ_i/dp_a = −(g_a(Ω_i) − g*_a/√2)/g_Ω(Ω_i)`.
//!
//! To first order the σ of the peak, its speed and its amplification factor follow from these
//! gradients ([`crate::tolerance::first_order`]); no step size enters anywhere.
//!
//! # Reference
//! Friswell, Penny, Garvey & Lees, *Dynamics of Rotating Machines* (2010), §3.6 and §6.7 (the
//! unbalance response and its peaks); API Standard 684 (2005), §2.8 (amplification factor and
//! separation margin from the peaks); Nocedal & Wright, *Numerical Optimization* (2006), for
//! the safeguarded Newton step.

use crate::compiled::Compiled;
use crate::frf::{excitation, loads, transfer, transfer_at};
use crate::jet::Jet;
use crate::linearize::Linearization;
use crate::modal::cluster::AS_ONE;
use crate::modal::{C64, SIMPLE_GAP, Smoothness, smoothness};
use crate::model::{Channel, Transfer};
use crate::sensitivity::{DesignPoint, RootDerivatives, Status, mode_derivative};
use crate::sweep::{Options, Point, PointError, point};
use crate::tolerance::{Spread, Stat, first_order, match_modes};
use nalgebra::DMatrix;
use num_dual::{Dual64, HyperDual64};

/// Newton's iterations at most, for a maximum or a resonance.
const ITERATIONS: usize = 60;

/// The residue of a root in the transfer function, relative to the norms it is made of, above
/// which the root is a pole ([`Finder::excited`]); a mode the load or the output is orthogonal
/// to leaves a residue of rounding, about `1e-16`.
const EXCITED: f64 = 1e-8;

/// The relative step in speed at which Newton has converged.
const CONVERGED: f64 = 1e-13;

/// What kind of peak.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PeakKind {
    /// A finite maximum of |H| along the speed.
    Maximum,
    /// An undamped mode at the excitation frequency: |H| is unbounded.
    Resonance,
}

impl PeakKind {
    pub fn as_str(self) -> &'static str {
        match self {
            PeakKind::Maximum => "maximum",
            PeakKind::Resonance => "resonance",
        }
    }
}

/// One peak of the nominal design's transfer function along the speed.
#[derive(Debug, Clone)]
pub struct Peak {
    pub kind: PeakKind,
    /// The speed of the peak (rad/s).
    pub speed: f64,
    /// |H| at the peak (the transfer function's unit; an unbalance's response in m); `None` at
    /// a resonance, where it is unbounded.
    pub magnitude: Option<f64>,
    /// At a resonance, the mode (0-based, as the swept points order them) at the excitation
    /// frequency.
    pub mode: Option<usize>,
    /// `dΩ/dp` per design variable, or why it does not exist.
    pub d_speed: Result<Vec<f64>, String>,
    /// `d|H|/dp` at the peak per design variable (a maximum's), or why it does not exist.
    pub d_magnitude: Result<Vec<f64>, String>,
    /// A maximum's amplification factor `Ω*/(Ω₂ − Ω₁)` by the half-power method of API 684
    /// (`Ω₁ < Ω* < Ω₂` where |H| falls to the peak's `1/√2`) and its derivatives per design
    /// variable, or why there is none (a resonance; a half-power speed beyond the speeds
    /// swept).
    pub amplification: Result<(f64, Vec<f64>), String>,
}

/// A peak that could not be located: near which swept speed, and why.
#[derive(Debug, Clone)]
pub struct PeakFailure {
    pub near: f64,
    pub why: String,
}

/// A peak's first-order mean and σ under one tolerance case (its speed, and its magnitude
/// where it is finite), or why there is none.
#[derive(Debug, Clone)]
pub struct PeakSpread {
    pub speed: Result<Stat, String>,
    pub magnitude: Result<Stat, String>,
    pub amplification: Result<Stat, String>,
}

/// A peak of the nominal design with its first-order spread under each tolerance case (in
/// the order of the cases), or why it could not be located.
pub type PeakRow = Result<(Peak, Vec<PeakSpread>), PeakFailure>;

impl Peak {
    /// The first-order mean and σ of the peak's speed and magnitude under `spread` (over the
    /// design variables the derivatives were taken in).
    pub fn first_order(&self, spread: &Spread) -> PeakSpread {
        let stat = |value: Option<f64>, d: &Result<Vec<f64>, String>| match (value, d) {
            (Some(v), Ok(g)) => Ok(first_order(v, g, spread).0),
            (None, _) => Err("unbounded: a resonance".to_string()),
            (_, Err(why)) => Err(why.clone()),
        };
        PeakSpread {
            speed: stat(Some(self.speed), &self.d_speed),
            magnitude: stat(self.magnitude, &self.d_magnitude),
            amplification: (self.amplification.as_ref())
                .map(|(af, d)| first_order(*af, d, spread).0)
                .map_err(Clone::clone),
        }
    }
}

/// The peaks of the transfer function `transfer` of the design `p` along the swept `points`
/// (in order of speed; `None` where a speed failed), with derivatives with respect to the
/// parameters `wrt`: every resonance between two swept speeds, and every maximum at a swept
/// speed above both its neighbours (the ends of the range are no peaks: the response may rise
/// beyond them), each located between the swept speeds.
pub fn peaks(
    model: &Compiled,
    p: &[f64],
    points: &[Option<Point>],
    transfer: &Transfer,
    wrt: &[usize],
) -> Vec<Result<Peak, PeakFailure>> {
    let g: Vec<Option<f64>> = (points.iter())
        .map(|pt| {
            let pt = pt.as_ref()?;
            let t = crate::sensitivity::TransferAt::at_speed(transfer, pt.speed);
            transfer_fn(&pt.linear, t.input, t.output, t.omega).filter(|v| v.is_finite())
        })
        .collect();
    let finder = Finder {
        model,
        p,
        transfer,
        wrt,
        points,
        g: &g,
    };
    let mut out = Vec::new();
    // Resonances: an undamped mode crossing the excitation frequency between two speeds.
    let mut resonant = vec![false; points.len()];
    for i in 0..points.len().saturating_sub(1) {
        let (Some(a), Some(b)) = (&points[i], &points[i + 1]) else {
            continue;
        };
        for k in crossings(a, b, transfer) {
            match finder.resonance(a, b, k) {
                // A repeated root's members meet the excitation at one speed: one resonance.
                Ok(Some(peak))
                    if out.iter().any(|r: &Result<Peak, PeakFailure>| {
                        r.as_ref().is_ok_and(|q| {
                            (q.speed - peak.speed).abs() <= 1e3 * CONVERGED * peak.speed
                        })
                    }) => {}
                Ok(Some(peak)) => {
                    resonant[i] = true;
                    resonant[i + 1] = true;
                    out.push(Ok(peak));
                }
                Ok(None) => {}
                Err(why) => out.push(Err(PeakFailure { near: a.speed, why })),
            }
        }
    }
    // Maxima at a swept speed above its neighbours, away from the resonances.
    for i in 1..points.len().saturating_sub(1) {
        let (Some(l), Some(c), Some(r)) = (g[i - 1], g[i], g[i + 1]) else {
            continue;
        };
        if resonant[i - 1] || resonant[i] || resonant[i + 1] || !(c > l && c >= r) {
            continue;
        }
        let (Some(a), Some(m), Some(b)) = (&points[i - 1], &points[i], &points[i + 1]) else {
            continue;
        };
        out.push(
            finder
                .maximum((a.speed, b.speed), m)
                .map_err(|why| PeakFailure { near: m.speed, why }),
        );
    }
    out.sort_by(|x, y| {
        let at = |r: &Result<Peak, PeakFailure>| match r {
            Ok(p) => p.speed,
            Err(f) => f.near,
        };
        at(x).total_cmp(&at(y))
    });
    out
}

/// |H| at a point's linearisation.
fn transfer_fn(
    lin: &Linearization<f64>,
    input: Channel,
    output: Channel,
    omega: f64,
) -> Option<f64> {
    transfer(lin, input, output, omega).map(|h| h.magnitude())
}

/// Whether a mode is undamped: its roots on the imaginary axis to rounding.
fn undamped(pt: &Point, k: usize) -> bool {
    let l = pt.modes[k].root.lambda;
    l.im > 0.0 && l.re.abs() <= 1e-9 * l.norm()
}

/// `ω_d − ω_e` of mode `k` at a point (the excitation's frequency `ω_e`).
fn detuning(pt: &Point, k: usize, transfer: &Transfer) -> f64 {
    let we = excitation(&pt.linear, transfer.input, transfer.order * pt.speed);
    pt.modes[k].damped_frequency - we
}

/// The undamped modes (tracked alike at `a` and `b`) whose damped frequency crosses the
/// excitation's between the two points.
fn crossings(a: &Point, b: &Point, transfer: &Transfer) -> Vec<usize> {
    if a.modes.len() != b.modes.len() {
        return Vec::new();
    }
    (0..a.modes.len())
        .filter(|&k| undamped(a, k) && undamped(b, k))
        .filter(|&k| {
            let (fa, fb) = (detuning(a, k, transfer), detuning(b, k, transfer));
            // A zero counts with the positive side, so it is found in one interval only.
            fa.is_finite() && fb.is_finite() && (fa < 0.0) != (fb < 0.0)
        })
        .collect()
}

/// What the searches share: the model, the design, the transfer function and the variables.
struct Finder<'a> {
    model: &'a Compiled,
    p: &'a [f64],
    transfer: &'a Transfer,
    wrt: &'a [usize],
    /// The swept points and |H| at each (`None` where a point failed or |H| has no value).
    points: &'a [Option<Point>],
    g: &'a [Option<f64>],
}

impl Finder<'_> {
    /// The point at `speed`, solved from `near`'s equilibrium and kept on its branch (stable
    /// or not: the peak is the swept points'), its modes in `near`'s order.
    fn solve(&self, speed: f64, near: &Point) -> Result<Point, String> {
        let options = Options {
            no_branch_switch: true,
            ..Options::single()
        };
        let pt = point(self.model, self.p, speed, &near.equilibrium.q, &options)
            .map_err(|e: PointError| format!("at {speed} rad/s: {e}"))?;
        Ok(match_modes(near, pt))
    }

    /// The design's parameters as jets: part `k` of variable `a` (`Some(a)`) seeded by
    /// `part(k)`, the others constant.
    fn seeded<J: Jet>(&self, a: Option<usize>, part: impl Fn(usize) -> f64) -> Vec<J> {
        (self.p.iter().enumerate())
            .map(|(i, &v)| match a {
                Some(a) if self.wrt[a] == i => J::seeded(v, &part),
                _ => J::from(v),
            })
            .collect()
    }

    /// |H| over the jets of `lin`, the excitation at `order × speed`.
    fn magnitude<J: Jet>(&self, lin: &Linearization<J>, speed: J) -> Option<J> {
        let t = self.transfer;
        let omega = speed * J::from(t.order);
        transfer_at(lin, t.input, t.output, omega).map(|h| h.magnitude())
    }

    /// `(g, g_Ω, g_ΩΩ)` at `pt`: one hyper-dual pass seeded twice along the speed.
    fn along_speed(&self, pt: &Point) -> Result<(f64, f64, f64), String> {
        let dp = DesignPoint::new(self.model, self.p, pt);
        let p: Vec<HyperDual64> = self.seeded(None, |_| 0.0);
        let speed = HyperDual64::new(pt.speed, 1.0, 1.0, 0.0);
        let lin = (dp.linearization_over(&p, speed)).map_err(|e| e.to_string())?;
        let g = (self.magnitude(&lin, speed))
            .ok_or_else(|| format!("|H| has no value at {} rad/s", pt.speed))?;
        Ok((g.re, g.eps1, g.eps1eps2))
    }

    /// Newton's iteration on a function of the speed whose root lies in `(lo, hi)`, from
    /// `start`, safeguarded by bisection: `at(pt)` says on which side of `pt` the root lies
    /// (`None`: at it) and gives Newton's next speed where it is to be trusted. The point at
    /// the root to [`CONVERGED`], or `None` after [`ITERATIONS`] steps.
    fn locate(
        &self,
        start: Point,
        (mut lo, mut hi): (f64, f64),
        mut at: impl FnMut(&Point) -> Result<(Option<bool>, Option<f64>), String>,
    ) -> Result<Option<Point>, String> {
        let mut pt = start;
        for _ in 0..ITERATIONS {
            let x = pt.speed;
            let (above, newton) = at(&pt)?;
            match above {
                None => return Ok(Some(pt)),
                Some(true) => lo = x,
                Some(false) => hi = x,
            }
            let next = newton
                .filter(|n| *n > lo && *n < hi)
                .unwrap_or(0.5 * (lo + hi));
            if (next - x).abs() <= CONVERGED * x.abs().max(1.0) || hi - lo <= CONVERGED * hi {
                return Ok(Some(pt));
            }
            pt = self.solve(next, &pt)?;
        }
        Ok(None)
    }

    /// The maximum of |H| inside `bracket`, from the swept point `m` above both its ends.
    fn maximum(&self, bracket: (f64, f64), m: &Point) -> Result<Peak, String> {
        let pt = (self.locate(m.clone(), bracket, |pt| {
            let (_, g1, g2) = self.along_speed(pt)?;
            let above = (g1 != 0.0).then_some(g1 > 0.0);
            Ok((above, (g2 < 0.0).then(|| pt.speed - g1 / g2)))
        }))?
        .ok_or_else(|| {
            format!(
                "the maximum of |H| between {} and {} rad/s did not converge in {ITERATIONS} \
                 Newton steps",
                bracket.0, bracket.1
            )
        })?;
        let (g, _, g2) = self.along_speed(&pt)?;
        // Per variable, one pass seeded along the speed (part 1) and the variable (part 2).
        let dp = DesignPoint::new(self.model, self.p, &pt);
        let mut d_magnitude = Vec::with_capacity(self.wrt.len());
        let mut d_speed = Vec::with_capacity(self.wrt.len());
        for a in 0..self.wrt.len() {
            let p: Vec<HyperDual64> = self.seeded(Some(a), |k| f64::from(u8::from(k == 1)));
            let speed = HyperDual64::new(pt.speed, 1.0, 0.0, 0.0);
            let lin = (dp.linearization_over(&p, speed)).map_err(|e| e.to_string())?;
            let h = (self.magnitude(&lin, speed))
                .ok_or_else(|| format!("|H| has no value at {} rad/s", pt.speed))?;
            d_magnitude.push(h.eps2);
            d_speed.push(-h.eps1eps2 / g2);
        }
        let finite = |v: Vec<f64>, what: &str| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(v)
            } else {
                Err(format!("{what} is not finite"))
            }
        };
        let d_speed = finite(d_speed, "the derivative of the peak's speed");
        let d_magnitude = finite(d_magnitude, "the derivative of the peak");
        let amplification = match (&d_speed, &d_magnitude) {
            (Ok(ds), Ok(dg)) => self.amplification(&pt, (g, dg), ds),
            _ => Err("the peak has no derivative".into()),
        };
        Ok(Peak {
            kind: PeakKind::Maximum,
            speed: pt.speed,
            magnitude: Some(g),
            mode: None,
            d_speed,
            d_magnitude,
            amplification,
        })
    }

    /// API 684's amplification factor `AF = Ω*/(Ω₂ − Ω₁)` of the maximum at `peak` (|H| = `g`,
    /// its derivatives `dg`, those of its speed `ds`), with its derivatives: each half-power
    /// speed `Ω_i` solves `h(Ω) = |H|(Ω) − g/√2 = 0`, so `dΩ_i/dp = −(g_p(Ω_i) − g_p/√2)/g_Ω(Ω_i)`.
    fn amplification(
        &self,
        peak: &Point,
        (g, dg): (f64, &[f64]),
        ds: &[f64],
    ) -> Result<(f64, Vec<f64>), String> {
        let half = g * std::f64::consts::FRAC_1_SQRT_2;
        let below = self.half_power(peak, half, dg, false)?;
        let above = self.half_power(peak, half, dg, true)?;
        let (w, band) = (peak.speed, above.0 - below.0);
        let af = w / band;
        let d = (0..self.wrt.len())
            .map(|a| af * (ds[a] / w - (above.1[a] - below.1[a]) / band))
            .collect();
        Ok((af, d))
    }

    /// The half-power speed on one side of the maximum at `peak` (above it with `up`), where
    /// |H| = `half`, and its derivatives (see [`Finder::amplification`]); bracketed by the
    /// nearest swept speed on that side below `half`.
    fn half_power(
        &self,
        peak: &Point,
        half: f64,
        dg: &[f64],
        up: bool,
    ) -> Result<(f64, Vec<f64>), String> {
        let side = if up { "above" } else { "below" };
        let outside = || {
            format!(
                "|H| does not fall to the peak's 1/√2 {side} it within the speeds swept (the \
                 half-power speed {side} the peak is needed for the amplification factor)"
            )
        };
        let order: Vec<usize> = if up {
            (0..self.points.len()).collect()
        } else {
            (0..self.points.len()).rev().collect()
        };
        let beyond = |s: f64| if up { s > peak.speed } else { s < peak.speed };
        let far = (order.iter().copied())
            .find(|&i| {
                (self.points[i].as_ref()).is_some_and(|pt| beyond(pt.speed))
                    && self.g[i].is_some_and(|v| v < half)
            })
            .ok_or_else(outside)?;
        let far_pt = self.points[far].as_ref().expect("found with a point");
        let bracket = if up {
            (peak.speed, far_pt.speed)
        } else {
            (far_pt.speed, peak.speed)
        };
        let start = self.solve(0.5 * (bracket.0 + bracket.1), far_pt)?;
        // |H| − half rises below the peak and falls above it.
        let pt = (self.locate(start, bracket, |pt| {
            let (v, g1, _) = self.along_speed(pt)?;
            let h = v - half;
            let above = (h != 0.0).then_some((h < 0.0) != up);
            Ok((above, (g1 != 0.0).then(|| pt.speed - h / g1)))
        }))?
        .ok_or_else(|| format!("the half-power speed {side} the peak did not converge"))?;
        let (_, slope, _) = self.along_speed(&pt)?;
        let dp = DesignPoint::new(self.model, self.p, &pt);
        let duals = dp
            .dual_linearizations(self.wrt)
            .map_err(|e| e.to_string())?;
        let t = crate::sensitivity::TransferAt::at_speed(self.transfer, pt.speed);
        let d = (duals.iter().zip(dg))
            .map(|(d, &dga)| {
                let h = transfer(&d.linear, t.input, t.output, t.omega)
                    .ok_or_else(|| format!("|H| has no value at {} rad/s", pt.speed))?;
                Ok(-(h.magnitude().eps - dga * std::f64::consts::FRAC_1_SQRT_2) / slope)
            })
            .collect::<Result<Vec<f64>, String>>()?;
        Ok((pt.speed, d))
    }

    /// The derivative of mode `k`'s `ω_d − ω_e` at `pt` along one direction of the
    /// linearisation `lin` (over dual numbers); `Err` where the mode's root is repeated and the
    /// direction splits it. A repeated root's projection `T` on the direction counts as moving
    /// as one where its split is below the rounding of `T` itself, `ε |λ|` times the
    /// direction's relative size in the pencil (the speed moves a rotor's tilts, not the
    /// translations of a disk at its centre: their `T` is rounding, and not a multiple of the
    /// identity).
    fn detuning_derivative(
        &self,
        pt: &Point,
        k: usize,
        (roots, smooth): (&RootDerivatives, &[Smoothness]),
        lin: &Linearization<Dual64>,
    ) -> Result<f64, String> {
        let eps = |a: &DMatrix<Dual64>| a.map(|v| v.eps);
        let (dm, dc, dk) = (eps(&lin.m), eps(&lin.c), eps(&lin.k));
        let d = roots.along((&dm, &dc, &dk)).swap_remove(k);
        let s = mode_derivative(&pt.modes[k], smooth[k], d, None);
        let dw = if s.status == Status::Ok {
            s.d_damped_frequency
        } else {
            self.member_slope(pt, k, roots, (&dm, &dc, &dk))
                .ok_or_else(|| {
                    format!(
                        "mode {} is a repeated root that the tolerances split at the resonance",
                        k + 1
                    )
                })?
        };
        let we = match self.transfer.input {
            Channel::Unbalance(u) => lin.unbalances.get(u).map_or(0.0, |u| u.spin.eps),
            _ => 0.0,
        };
        Ok(dw - we)
    }

    /// `d ω_d` of mode `k`, a member of a repeated root, along `(M', C', K')` where the
    /// direction moves the root as one to rounding (see [`Finder::detuning_derivative`]).
    fn member_slope(
        &self,
        pt: &Point,
        k: usize,
        roots: &RootDerivatives,
        (dm, dc, dk): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    ) -> Option<f64> {
        let projections = roots.projections((dm, dc, dk));
        let g = (0..projections.len()).find(|&g| roots.members(g).contains(&k))?;
        let t = projections[g].as_ref()?;
        let size = t.nrows() as f64;
        let mean = t.trace() / size;
        let off = (t - DMatrix::<C64>::identity(t.nrows(), t.nrows()) * mean).norm();
        let l = pt.modes[k].root.lambda.norm();
        let lin = &pt.linear;
        let pencil = |m: &DMatrix<f64>, c: &DMatrix<f64>, k: &DMatrix<f64>| {
            l * l * m.norm() + l * c.norm() + k.norm()
        };
        let relative = pencil(dm, dc, dk) / pencil(&lin.m, &lin.c, &lin.k);
        let rounding = 16.0 * f64::EPSILON * l * relative;
        (off <= AS_ONE * t.norm() || off <= rounding).then_some(mean.im)
    }

    /// Where mode `k`'s damped frequency meets the excitation's between the swept points `a`
    /// and `b`: a resonance where |H| has no value there, `None` where it has one (the load
    /// does not excite the mode, or the output does not see it).
    fn resonance(&self, a: &Point, b: &Point, k: usize) -> Result<Option<Peak>, String> {
        let (lo, hi) = (a.speed, b.speed);
        let (fa, fb) = (detuning(a, k, self.transfer), detuning(b, k, self.transfer));
        let rising = fa < 0.0;
        let start = if fa == 0.0 {
            a.clone()
        } else if fb == 0.0 {
            b.clone()
        } else {
            // The secant's root as the start.
            let x = lo + fa / (fa - fb) * (hi - lo);
            self.solve(x, if x - lo < hi - x { a } else { b })?
        };
        let pt = (self.locate(start, (lo, hi), |pt| {
            let f = detuning(pt, k, self.transfer);
            let above = (f != 0.0).then_some((f < 0.0) == rising);
            Ok((above, Some(pt.speed - f / self.speed_slope(pt, k)?)))
        }))?
        .ok_or_else(|| {
            format!(
                "mode {}'s crossing of the excitation frequency between {} and {} rad/s did \
                 not converge in {ITERATIONS} Newton steps",
                k + 1,
                a.speed,
                b.speed
            )
        })?;
        let slope = self.speed_slope(&pt, k)?;
        if !self.excited(&pt, k) {
            return Ok(None);
        }
        // dΩ_r/dp_a = −f_a / f_Ω.
        let smooth = smoothness(&pt.modes);
        let lin = &pt.linear;
        let roots = RootDerivatives::new(&pt.modes, &smooth, (&lin.m, &lin.c, &lin.k));
        let dp = DesignPoint::new(self.model, self.p, &pt);
        let d_speed = (dp.dual_linearizations(self.wrt))
            .map_err(|e| e.to_string())
            .and_then(|duals| {
                (duals.iter())
                    .map(|d| {
                        let fa = self.detuning_derivative(&pt, k, (&roots, &smooth), &d.linear)?;
                        Ok(-fa / slope)
                    })
                    .collect::<Result<Vec<f64>, String>>()
            });
        Ok(Some(Peak {
            kind: PeakKind::Resonance,
            speed: pt.speed,
            magnitude: None,
            mode: Some(k),
            d_speed,
            d_magnitude: Err("unbounded: a resonance".into()),
            amplification: Err("unbounded: a resonance".into()),
        }))
    }

    /// Whether the transfer function has a pole at mode `k`'s root at `pt`: the residue `b_oᵀ
    /// X (Yᵀ(2λM + C)X)⁻¹ Yᵀ b` of the root (its members' right and left vectors `X`, `Y`
    /// where it is repeated) is above rounding, [`EXCITED`], relative to the norms it is made
    /// of. Below it the load does not excite the mode or the output does not see it, and `H`
    /// stays finite through the crossing.
    fn excited(&self, pt: &Point, k: usize) -> bool {
        let lin = &pt.linear;
        let t = self.transfer;
        let omega = excitation(lin, t.input, t.order * pt.speed);
        let Some(b) = loads(lin, t.input, t.output, omega) else {
            return false;
        };
        let lambda = pt.modes[k].root.lambda;
        let members: Vec<&crate::modal::Root> = (pt.modes.iter())
            .flat_map(|m| [&m.root, &m.partner])
            .filter(|r| (r.lambda - lambda).norm() <= SIMPLE_GAP * lambda.norm())
            .collect();
        let n = lin.m.nrows();
        let x = DMatrix::from_fn(n, members.len(), |i, j| members[j].right[i]);
        let y = DMatrix::from_fn(n, members.len(), |i, j| members[j].left[i]);
        let complex = |a: &DMatrix<f64>| a.map(|v| C64::new(v, 0.0));
        let d = y.transpose() * (complex(&lin.m) * (lambda * 2.0) + complex(&lin.c)) * &x;
        let Some(d_inv) = d.try_inverse() else {
            return true;
        };
        let xd = &x * d_inv;
        let bo = nalgebra::DVector::from_iterator(n, b.output.iter().map(|&v| C64::new(v, 0.0)));
        let bi = nalgebra::DVector::from_iterator(
            n,
            (b.re.iter().zip(&b.im)).map(|(&r, &i)| C64::new(r, i)),
        );
        let residue = (bo.transpose() * &xd * (y.transpose() * &bi))[(0, 0)].norm();
        let scale = bo.norm() * bi.norm() * xd.norm() * y.norm();
        residue > EXCITED * scale
    }

    /// `f_Ω`: the derivative of mode `k`'s `ω_d − ω_e` along the speed at `pt`.
    fn speed_slope(&self, pt: &Point, k: usize) -> Result<f64, String> {
        let dp = DesignPoint::new(self.model, self.p, pt);
        let p: Vec<Dual64> = self.seeded(None, |_| 0.0);
        let speed = Dual64::new(pt.speed, 1.0);
        let lin = (dp.linearization_over(&p, speed)).map_err(|e| e.to_string())?;
        let smooth = smoothness(&pt.modes);
        let l = &pt.linear;
        let roots = RootDerivatives::new(&pt.modes, &smooth, (&l.m, &l.c, &l.k));
        let order = match self.transfer.input {
            Channel::Unbalance(_) => 0.0,
            _ => self.transfer.order,
        };
        Ok(self.detuning_derivative(pt, k, (&roots, &smooth), &lin)? - order)
    }
}
