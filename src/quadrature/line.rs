//! One line integral at one speed: the nodes grouped into runs on one branch, interpolated
//! within a run, split where the branch or a mode's character changes, and integrated by
//! Gauss–Legendre against the normal density.

use super::NodeData;
use super::control::OnLine;
use super::roots::{root_in, roots_in};
use super::rules::grid;
use crate::output::{Output, Quantity};
use crate::pair::{self, Carriers};
use crate::tolerance::sigma_of;
use statrs::distribution::{ContinuousCDF, Normal};

/// Where the extrapolated tails end (normal mass outside: 2·10⁻¹⁹).
const TAIL_END: f64 = 9.0;

/// Gauss–Legendre, 5 points on [−1, 1].
pub(super) const GL_X: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683_1,
    0.0,
    0.538_469_310_105_683_1,
    0.906_179_845_938_664,
];
pub(super) const GL_W: [f64; 5] = [
    0.236_926_885_056_189_1,
    0.478_628_670_499_366_5,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
];

/// Sums of one line (or of a rule) at one speed: per output the mass where it is defined and
/// the first two moments about the nominal value; the event masses; the total mass.
#[derive(Debug, Clone, Default)]
pub(super) struct Sums {
    pub mass: f64,
    pub defined: Vec<f64>,
    pub s1: Vec<f64>,
    pub s2: Vec<f64>,
    /// Overdamped per mode, then unstable, then other branch.
    pub events: Vec<f64>,
}

impl Sums {
    pub fn new(outs: usize, modes: usize) -> Sums {
        Sums {
            mass: 0.0,
            defined: vec![0.0; outs],
            s1: vec![0.0; outs],
            s2: vec![0.0; outs],
            events: vec![0.0; modes + 2],
        }
    }

    pub(super) fn add_scaled(&mut self, b: &Sums, w: f64) {
        self.mass += w * b.mass;
        for (x, y) in self
            .defined
            .iter_mut()
            .chain(&mut self.s1)
            .chain(&mut self.s2)
            .chain(&mut self.events)
            .zip(b.defined.iter().chain(&b.s1).chain(&b.s2).chain(&b.events))
        {
            *x += w * y;
        }
    }

    /// Mean and σ of output `o` (shifted back by `shift`).
    pub(super) fn moments(&self, o: usize, shift: f64) -> Option<(f64, f64)> {
        let w = self.defined[o];
        (w > 0.0).then(|| {
            let m1 = self.s1[o] / w;
            (m1 + shift, sigma_of(self.s2[o] / w - m1 * m1))
        })
    }

    pub(super) fn probability(&self, e: usize) -> f64 {
        if self.mass > 0.0 {
            self.events[e] / self.mass
        } else {
            f64::NAN
        }
    }
}

/// Where a line integral collects its weighted output values for the quantiles (per output),
/// and the line's weight.
pub(super) type Atoms<'a> = (&'a mut Vec<Vec<(f64, f64)>>, f64);

/// What a line integral needs at one speed.
pub(super) struct Context<'a> {
    pub store: &'a NodeData,
    pub speed: usize,
    pub outs: &'a [Output],
    pub modes: usize,
    pub shift: &'a [f64],
    /// The nominal branch count here.
    pub branch: u32,
}

/// An interpolant: Lagrange through nodes (positions and carrier rows), on the branch of
/// those nodes.
pub(super) struct Stencil<'a> {
    t: Vec<f64>,
    rows: Vec<&'a [f64]>,
    pub branch: u32,
}

impl Stencil<'_> {
    /// The carriers at `t`.
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (i, (&ti, row)) in self.t.iter().zip(&self.rows).enumerate() {
            let l: f64 = self
                .t
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &tj)| (t - tj) / (ti - tj))
                .product();
            for (o, &c) in out.iter_mut().zip(row.iter()) {
                *o += l * c;
            }
        }
    }
}

impl Context<'_> {
    /// Integrates one line with the nodes at `stride`; with `atoms`, also collects the
    /// weighted output values for the quantiles. Where an output has an expansion along the
    /// line (`control`), its sums are those of the control-variate estimator
    /// ([`super::control`]): `E[q − f₀] + ∫ 1_D (f − q) − 1_{D^c} (q − f₀)` and the same of the
    /// squares, with `D` where the output has a value.
    pub fn line(
        &self,
        li: usize,
        stride: usize,
        control: &[Option<OnLine>],
        mut atoms: Option<Atoms>,
    ) -> Sums {
        let mut sums = Sums::new(self.outs.len(), self.modes);
        for (a, b, st) in self.pieces(li, stride) {
            match st {
                Some(st) => self.piece(&st, (a, b), &mut sums, &mut atoms, control),
                None => undefined(a, b, &mut sums, control),
            }
        }
        // The expansions' exact moments (the lines' weights add up to one).
        for (o, c) in control.iter().enumerate() {
            if let Some(c) = c {
                sums.s1[o] += c.moments.0;
                sums.s2[o] += c.moments.1;
            }
        }
        sums
    }

    /// The line `li` with the nodes at `stride` as pieces `[a, b]` over `[−9, 9]`, each with its
    /// interpolant (`None` where the nodes have no value): within a run of nodes on one branch,
    /// the run's interpolant; where the branch changes between two nodes, each side's up to
    /// the switch point; where a node failed, the other side's up to the middle. The interior
    /// pieces come in order, then the two tails (the end runs' interpolants extrapolated from
    /// ±6 to ±9: the normal mass beyond ±6 is 2·10⁻⁹, but 4·10⁻⁸ of a variance).
    pub fn pieces(&self, li: usize, stride: usize) -> Vec<(f64, f64, Option<Stencil<'_>>)> {
        let data = &self.store.data[li];
        let finest = data.len();
        let w = self.store.width;
        let idx: Vec<usize> = (0..finest).step_by(stride).collect();
        let t: Vec<f64> = idx.iter().map(|&j| grid(finest, j)).collect();
        let node = |k: usize| data[idx[k]].as_ref().expect("swept");
        let sig: Vec<Option<u32>> = (0..idx.len()).map(|k| node(k).branch[self.speed]).collect();
        let row = |k: usize| &node(k).carriers[self.speed * w..(self.speed + 1) * w];
        // Runs of equal signature.
        let mut run_of = vec![(0usize, 0usize); idx.len()];
        let mut start = 0;
        for k in 1..=idx.len() {
            if k == idx.len() || sig[k] != sig[start] {
                for r in run_of.iter_mut().take(k).skip(start) {
                    *r = (start, k - 1);
                }
                start = k;
            }
        }
        let stencil = |from: usize, to: usize| Stencil {
            t: t[from..=to].to_vec(),
            rows: (from..=to).map(row).collect(),
            branch: sig[from].unwrap_or(0),
        };
        // Up to 4 nodes of the run `(r0, r1)` around the interval starting at `k`.
        let around = |k: usize, (r0, r1): (usize, usize)| {
            let len = (r1 - r0 + 1).min(4);
            let from = k.saturating_sub(1).clamp(r0, r1 + 1 - len);
            stencil(from, from + len - 1)
        };
        let mut out = Vec::with_capacity(2 * idx.len() + 2);
        for k in 0..idx.len() - 1 {
            let (a, b) = (t[k], t[k + 1]);
            match (sig[k], sig[k + 1]) {
                (None, None) => out.push((a, b, None)),
                (x, y) if x == y => out.push((a, b, Some(around(k, run_of[k])))),
                (Some(_), None) => {
                    let m = 0.5 * (a + b);
                    let (r0, _) = run_of[k];
                    out.push((a, m, Some(stencil(k.saturating_sub(3).max(r0), k))));
                    out.push((m, b, None));
                }
                (None, Some(_)) => {
                    let m = 0.5 * (a + b);
                    let (_, r1) = run_of[k + 1];
                    out.push((a, m, None));
                    out.push((m, b, Some(stencil(k + 1, (k + 4).min(r1)))));
                }
                (Some(_), Some(_)) => {
                    let (r0, _) = run_of[k];
                    let (_, r1) = run_of[k + 1];
                    let left = stencil(k.saturating_sub(3).max(r0), k);
                    let right = stencil(k + 1, (k + 4).min(r1));
                    let m = self.switch_point(&left, &right, a, b);
                    out.push((a, m, Some(left)));
                    out.push((m, b, Some(right)));
                }
            }
        }
        let last = idx.len() - 1;
        out.push(match sig[0] {
            Some(_) => (-TAIL_END, t[0], Some(stencil(0, run_of[0].1.min(3)))),
            None => (-TAIL_END, t[0], None),
        });
        out.push(match sig[last] {
            Some(_) => (
                t[last],
                TAIL_END,
                Some(stencil(run_of[last].0.max(last.saturating_sub(3)), last)),
            ),
            None => (t[last], TAIL_END, None),
        });
        out
    }

    /// Where the branch changes in `[a, b]`: the zero of the extrapolated `Π p` (det K̂/det M̂,
    /// zero at a static bifurcation) from each side, averaged; the middle if neither has one.
    fn switch_point(&self, left: &Stencil, right: &Stencil, a: f64, b: f64) -> f64 {
        let mut c = vec![0.0; self.store.width];
        // Rigid-body modes (`p` exactly zero on both sides, [`crate::modal::ModeClass::Rigid`])
        // would make the product zero everywhere: they are left out.
        let rigid: Vec<bool> = (0..self.modes)
            .map(|m| {
                [left, right]
                    .iter()
                    .all(|st| st.rows.iter().all(|r| Carriers::new(r).product(m) == 0.0))
            })
            .collect();
        let mut g = |st: &Stencil, t: f64| {
            st.eval(t, &mut c);
            (0..self.modes)
                .filter(|&m| !rigid[m])
                .map(|m| Carriers::new(&c).product(m))
                .product::<f64>()
        };
        let roots: Vec<f64> = [left, right]
            .into_iter()
            .filter_map(|st| root_in(&mut |t| g(st, t), a, b))
            .collect();
        if roots.is_empty() {
            0.5 * (a + b)
        } else {
            roots.iter().sum::<f64>() / roots.len() as f64
        }
    }

    /// Integrates the interpolant `st` over `[a, b]`, split where a mode changes character
    /// (each output less its expansion along the line, where `control` has one).
    fn piece(
        &self,
        st: &Stencil,
        (a, b): (f64, f64),
        sums: &mut Sums,
        atoms: &mut Option<Atoms>,
        control: &[Option<OnLine>],
    ) {
        if b <= a {
            return;
        }
        let mut c = vec![0.0; self.store.width];
        let cuts = self.breakpoints(st, a, b);
        let other = st.branch != self.branch;
        let modes = self.modes;
        // A mode can be unstable between nodes only where one of the stencil's nodes says so:
        // otherwise an excursion of the interpolant is the interpolation's, not the mode's
        // (the sum `s` of a rigid-body mode's roots, its partner alone, jumps between nodes
        // where two such modes trade places, and the interpolant overshoots above 0).
        let may_be_unstable: Vec<bool> = (0..modes)
            .map(|m| {
                st.rows
                    .iter()
                    .map(|r| Carriers::new(r).pair(m))
                    .any(|(s, p)| growth(s, p) > 0.0 || p < 0.0)
            })
            .collect();
        for seg in cuts.windows(2) {
            let ((x0, e0), (x1, e1)) = (seg[0], seg[1]);
            if x1 <= x0 {
                continue;
            }
            let len = x1 - x0;
            // Character on the sub-piece (constant there): from its midpoint.
            st.eval(0.5 * (x0 + x1), &mut c);
            let at = Carriers::new(&c);
            let unstable = at
                .pairs()
                .zip(&may_be_unstable)
                .any(|((s, p), &may)| may && (growth(s, p) > 0.0 || p < 0.0));
            // Overdamped: two real roots of one sign, both negative (`p > 0`); a rigid-body
            // mode (a zero root, `p = 0` exactly) is neither overdamped nor unstable.
            let overdamped: Vec<bool> = (0..modes)
                .map(|m| {
                    let (s, p) = at.pair(m);
                    pair::discriminant(s, p) <= 0.0 && p > 0.0 && growth(s, p) <= 0.0
                })
                .collect();
            for (&x, &wx) in GL_X.iter().zip(&GL_W) {
                // Gauss–Legendre in u ∈ [0, 1]; towards a square-root edge t − edge ∝ u² (both
                // edges: 1 − cos πu), which makes √(t − edge) smooth in u.
                let u = 0.5 + 0.5 * x;
                let (t, dt) = match (e0, e1) {
                    (false, false) => (x0 + len * u, len),
                    (true, false) => (x0 + len * u * u, 2.0 * len * u),
                    (false, true) => (x1 - len * (1.0 - u) * (1.0 - u), 2.0 * len * (1.0 - u)),
                    (true, true) => {
                        let pi = std::f64::consts::PI;
                        (
                            x0 + len * 0.5 * (1.0 - (pi * u).cos()),
                            len * 0.5 * pi * (pi * u).sin(),
                        )
                    }
                };
                let wt = 0.5 * wx * dt * density(t);
                sums.mass += wt;
                for (m, &o) in overdamped.iter().enumerate() {
                    if o {
                        sums.events[m] += wt;
                    }
                }
                if unstable {
                    sums.events[modes] += wt;
                }
                if other {
                    sums.events[modes + 1] += wt;
                }
                st.eval(t, &mut c);
                for (o, out) in self.outs.iter().enumerate() {
                    let v = carrier_value(out, Carriers::new(&c));
                    let q = control[o].map_or(0.0, |e| e.at(t));
                    if !v.is_finite() {
                        sums.s1[o] -= wt * q;
                        sums.s2[o] -= wt * q * q;
                        continue;
                    }
                    let dv = v - self.shift[o];
                    sums.defined[o] += wt;
                    sums.s1[o] += wt * (dv - q);
                    sums.s2[o] += wt * (dv * dv - q * q);
                    if let Some((atoms, lw)) = atoms.as_mut() {
                        atoms[o].push((v, wt * *lw));
                    }
                }
            }
        }
    }

    /// Where `st` is cut on `[a, b]`, with the ends (and whether ω_d has a square-root edge
    /// there): the sign changes of D, p and s of every mode, in order.
    fn breakpoints(&self, st: &Stencil, a: f64, b: f64) -> Vec<(f64, bool)> {
        let mut c = vec![0.0; self.store.width];
        let mut cuts = vec![(a, false), (b, false)];
        for m in 0..self.modes {
            for f in 0..3 {
                let mut h = |t: f64| {
                    st.eval(t, &mut c);
                    let (s, p) = Carriers::new(&c).pair(m);
                    match f {
                        0 => pair::discriminant(s, p),
                        1 => p,
                        _ => growth(s, p),
                    }
                };
                cuts.extend(roots_in(&mut h, a, b).into_iter().map(|r| (r, f == 0)));
            }
        }
        cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
        cuts
    }
}

/// Relative growth rate below which a pair counts as stable (as in [`crate::modal`]: an
/// undamped pair has `s` at rounding level around zero).
const GROWTH_TOL: f64 = 1e-9;

/// The pair's growth rate `Re λ = s/2` less [`GROWTH_TOL`] of its size `√|p|`: positive when
/// the pair is unstable through a complex pair (flutter) or a positive real root.
fn growth(s: f64, p: f64) -> f64 {
    0.5 * s - GROWTH_TOL * p.abs().sqrt()
}

/// An output from the carriers: ω_d = √max(0, p − s²/4), ζ = −s/(2√|p|), |H| (not below 0).
fn carrier_value(o: &Output, c: Carriers) -> f64 {
    match (o.quantity, o.mode) {
        (Quantity::DampedFrequency, Some(m)) => {
            let (s, p) = c.pair(m);
            pair::damped_frequency(s, p)
        }
        (Quantity::DampingRatio, Some(m)) => {
            let (s, p) = c.pair(m);
            pair::damping_ratio(s, p)
        }
        // `f64::max` would turn a node's missing |H| (NaN: a resonance there) into 0.
        (Quantity::TransferMagnitude, _) if c.transfer().is_nan() => f64::NAN,
        (Quantity::TransferMagnitude, _) => c.transfer().max(0.0),
        _ => f64::NAN,
    }
}

pub(super) fn density(t: f64) -> f64 {
    (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Normal mass of `[a, b]`.
pub(super) fn normal_mass(a: f64, b: f64) -> f64 {
    let n = Normal::standard();
    n.cdf(b) - n.cdf(a)
}

/// A stretch `[a, b]` of the line where no output has a value: its normal mass, and the
/// expansions integrated over it (the `1_{D^c} (q − f₀)` terms of the estimator).
fn undefined(a: f64, b: f64, sums: &mut Sums, control: &[Option<OnLine>]) {
    sums.mass += normal_mass(a, b);
    for (o, c) in control.iter().enumerate() {
        if let Some(c) = c {
            let (i1, i2) = c.integrals(a, b);
            sums.s1[o] -= i1;
            sums.s2[o] -= i2;
        }
    }
}
