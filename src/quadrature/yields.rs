//! The yield by the quadrature: the probability that a design meets every requirement at every
//! speed of its range, each requirement's own, the per-speed probabilities and the worst
//! margins' moments, integrated along the lines of the case's rule.
//!
//! Every node is a whole sweep, so a requirement over a speed range is a property of the node
//! and of the points between nodes: at each speed the carriers are interpolated between nodes
//! exactly as for the moments ([`super::line::Context::pieces`]), and each requirement's margin
//! at each speed is a function of `t` along the line. The line is cut at every boundary of a
//! speed's pieces and into sub-intervals no longer than [`STEP`]; where a margin changes sign
//! across a sub-interval its zero is found by bisection; between those zeros which
//! requirements are met is constant, and the normal mass of each piece is exact. The yield is
//! then a line integral of an indicator with located jumps (the preintegration of Griewank,
//! Kuo, Leövey & Sloan 2018), its error estimated as the moments' are: the node grid against
//! every other node, and the transverse rule against its check.

use super::line::{Context, GL_W, GL_X, Stencil, density, normal_mass};
use super::rules::{Rule, Stage, Transverse};
use super::sums::{ErrorParts, across, sorted_quantile};
use super::{NodeData, Reference};
use crate::model::Requirement;
use crate::requirement::{State, covers, has_margin, margin, reaches};
use rayon::prelude::*;

/// Longest sub-interval of a line (in standard deviations) across which a margin's sign is
/// taken from its ends: a quarter of the finest node spacing.
const STEP: f64 = 0.1875;

/// The yield of one case by the quadrature, with error estimates (absolute).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadYield {
    /// Every requirement met at every speed of its range.
    pub all: (f64, f64),
    /// Per requirement: probability and error.
    pub each: Vec<(f64, f64)>,
    /// Per requirement: the worst margin over its range, mean and σ with their errors, `None`
    /// for a pass-or-fail requirement or where no design has one.
    pub margins: Vec<Option<MarginStat>>,
    /// `[speed][requirement]`: probability of meeting it at that speed and its error; NaN
    /// outside its range.
    pub curves: Vec<Vec<(f64, f64)>>,
    /// `[speed][requirement]`: probability of meeting it at every speed from its range's
    /// start up to that one (beyond the range's end too: the operating range it holds over),
    /// and its error; NaN below the range.
    pub prefix: Vec<Vec<(f64, f64)>>,
}

/// Mean and σ of a requirement's worst margin over its range, with error estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarginStat {
    pub mean: f64,
    pub std: f64,
    pub mean_error: f64,
    pub std_error: f64,
    /// The margin met at the target yield (its `1 − target` quantile, `−∞` where more than
    /// `1 − target` of the designs fail without a margin) and its error estimate.
    pub at_target: f64,
    pub at_target_error: f64,
}

/// The additive sums of one line (or a rule): the mass, the mass meeting everything, per
/// requirement the mass meeting it and the worst margin's defined mass and first two moments
/// about `shift`, per speed and requirement the mass meeting it there and from its range's
/// start up to there; and per requirement the worst margin's weighted atoms (its quantiles).
#[derive(Debug, Clone)]
struct Tally {
    v: Vec<f64>,
    atoms: Vec<Vec<(f64, f64)>>,
}

/// Where each part of a [`Tally`] sits.
#[derive(Clone, Copy)]
struct Layout {
    reqs: usize,
    speeds: usize,
}

impl Layout {
    fn len(&self) -> usize {
        2 + 4 * self.reqs + 2 * self.speeds * self.reqs
    }
    fn mass(&self) -> usize {
        0
    }
    fn all(&self) -> usize {
        1
    }
    fn each(&self, r: usize) -> usize {
        2 + r
    }
    /// Defined mass, first and second moment of requirement `r`'s worst margin.
    fn margin(&self, r: usize, k: usize) -> usize {
        2 + self.reqs + 3 * r + k
    }
    fn curve(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + i * self.reqs + r
    }
    fn prefix(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + (self.speeds + i) * self.reqs + r
    }
}

impl Tally {
    fn new(l: Layout) -> Tally {
        Tally {
            v: vec![0.0; l.len()],
            atoms: vec![Vec::new(); l.reqs],
        }
    }
    fn add_scaled(&mut self, b: &Tally, w: f64) {
        for (x, y) in self.v.iter_mut().zip(&b.v) {
            *x += w * y;
        }
        for (x, y) in self.atoms.iter_mut().zip(&b.atoms) {
            x.extend(y.iter().map(|&(v, wv)| (v, w * wv)));
        }
    }
    /// Requirement `r`'s worst margin at quantile `q` (`None` without atoms).
    fn quantile(&self, r: usize, q: f64) -> Option<f64> {
        let mut a = self.atoms[r].clone();
        if a.is_empty() {
            return None;
        }
        a.sort_by(|x, y| x.0.total_cmp(&y.0));
        let total = a.iter().map(|x| x.1).sum();
        Some(sorted_quantile(&a, total, q))
    }
    fn ratio(&self, l: Layout, k: usize) -> f64 {
        self.v[k] / self.v[l.mass()]
    }
    fn moments(&self, l: Layout, r: usize, shift: f64) -> Option<(f64, f64)> {
        let w = self.v[l.margin(r, 0)];
        (w > 0.0).then(|| {
            let m1 = self.v[l.margin(r, 1)] / w;
            let var = self.v[l.margin(r, 2)] / w - m1 * m1;
            (m1 + shift, var.max(0.0).sqrt())
        })
    }
}

/// What the yield integration needs besides the nodes: the requirements, their nominal
/// worst margins (the shift of the moments) and the target yield (the margin met at it).
pub(super) struct Requirements<'a> {
    pub list: &'a [Requirement],
    pub speeds: &'a [f64],
    pub shift: Vec<f64>,
    pub target: f64,
}

/// The yield at `stage` with its error estimates' parts.
pub(super) fn evaluate_yield(
    store: &NodeData,
    rule: &Rule,
    stage: Stage,
    nominal: &Reference,
    reqs: &Requirements,
) -> (QuadYield, ErrorParts) {
    let l = Layout {
        reqs: reqs.list.len(),
        speeds: store.speeds,
    };
    let (first_level, last_level) = (rule.levels.first, rule.levels.last);
    let stride = 1 << (last_level - stage.level);
    let coarse = stride << 1;
    let check_stride = 1 << (last_level - first_level);
    let transverse = rule.transverse;
    let replicates = match transverse {
        Transverse::Scrambled { replicates } => replicates,
        _ => 1,
    };
    let contexts: Vec<Context> = (0..store.speeds)
        .map(|i| Context {
            store,
            speed: i,
            outs: nominal.outs,
            modes: nominal.modes,
            shift: &[],
            branch: nominal.branches[i] as u32,
        })
        .collect();
    // Per line in use: (line, weight, is check, tallies at stride / coarse / check stride).
    let used: Vec<usize> = (0..rule.lines.len())
        .filter(|&li| rule.uses(&rule.lines[li], stage))
        .collect();
    let per_line: Vec<(usize, Vec<Tally>)> = used
        .par_iter()
        .map(|&li| {
            let line = &rule.lines[li];
            let strides: Vec<usize> = if rule.checks(line, stage) {
                vec![check_stride]
            } else if transverse == Transverse::Tensor {
                vec![stride, coarse, check_stride]
            } else {
                vec![stride, coarse]
            };
            let t = strides
                .iter()
                .map(|&s| line_tally(&contexts, li, s, reqs, l))
                .collect();
            (li, t)
        })
        .collect();
    let mut fine = Tally::new(l);
    let mut rough = Tally::new(l);
    let mut check = Tally::new(l);
    let mut main_at_check = Tally::new(l);
    let mut reps = vec![Tally::new(l); replicates];
    for (li, t) in &per_line {
        let line = &rule.lines[*li];
        let w = rule.weight(line, stage);
        if rule.checks(line, stage) {
            check.add_scaled(&t[0], w);
            continue;
        }
        fine.add_scaled(&t[0], w);
        rough.add_scaled(&t[1], w);
        reps[line.replicate].add_scaled(&t[0], w * replicates as f64);
        if transverse == Transverse::Tensor {
            main_at_check.add_scaled(&t[2], w);
        }
    }
    let across = |f: &dyn Fn(&Tally) -> Option<f64>| -> f64 {
        let e = across(transverse, (&main_at_check, &check), &reps, f);
        if e.is_nan() { f64::INFINITY } else { e }
    };
    let mut parts = ErrorParts::default();
    let mut prob = |k: usize| -> (f64, f64) {
        let p = fine.ratio(l, k);
        let along = 2.0 * (p - rough.ratio(l, k)).abs();
        let cross = across(&|t: &Tally| Some(t.ratio(l, k)));
        parts.along = parts.along.max(along);
        parts.across = parts.across.max(cross);
        let err = along + cross;
        (p, if err.is_finite() { err } else { 1.0 })
    };
    let all = prob(l.all());
    let each: Vec<(f64, f64)> = (0..l.reqs).map(|r| prob(l.each(r))).collect();
    let mut per_speed = |within: fn(&Requirement, f64) -> bool,
                         at: fn(&Layout, usize, usize) -> usize|
     -> Vec<Vec<(f64, f64)>> {
        (0..l.speeds)
            .map(|i| {
                (0..l.reqs)
                    .map(|r| {
                        if within(&reqs.list[r], reqs.speeds[i]) {
                            prob(at(&l, i, r))
                        } else {
                            (f64::NAN, f64::NAN)
                        }
                    })
                    .collect()
            })
            .collect()
    };
    let curves = per_speed(covers, Layout::curve);
    let prefix = per_speed(reaches, Layout::prefix);
    let margins = (0..l.reqs)
        .map(|r| {
            let shift = reqs.shift[r];
            let (mean, std) = fine.moments(l, r, shift)?;
            let (rm, rs) = rough.moments(l, r, shift).unwrap_or((f64::NAN, f64::NAN));
            let cm = across(&|t: &Tally| t.moments(l, r, shift).map(|m| m.0));
            let cs = across(&|t: &Tally| t.moments(l, r, shift).map(|m| m.1));
            let finite = |e: f64| if e.is_finite() { e } else { f64::INFINITY };
            let q = 1.0 - reqs.target;
            let at_target = fine.quantile(r, q).unwrap_or(f64::NAN);
            let rq = rough.quantile(r, q).unwrap_or(f64::NAN);
            let cq = across(&|t: &Tally| t.quantile(r, q));
            Some(MarginStat {
                mean,
                std,
                mean_error: finite(2.0 * (mean - rm).abs() + cm),
                std_error: finite(2.0 * (std - rs).abs() + cs),
                at_target,
                at_target_error: if at_target.is_finite() {
                    finite(2.0 * (at_target - rq).abs() + cq)
                } else {
                    0.0
                },
            })
        })
        .collect();
    (
        QuadYield {
            all,
            each,
            margins,
            curves,
            prefix,
        },
        parts,
    )
}

/// The pieces of one line at every speed, and the requirements' margins at a point of it.
struct LineView<'a> {
    pieces: Vec<Vec<(f64, f64, Option<Stencil<'a>>)>>,
    contexts: &'a [Context<'a>],
    reqs: &'a Requirements<'a>,
    /// Per speed: the requirements it is at or above the range's start of ([`reaches`]).
    active: Vec<Vec<usize>>,
    /// `[speed · requirements + requirement]`: is the speed in the requirement's range?
    covered: Vec<bool>,
}

impl LineView<'_> {
    /// What the requirements read at speed `i` at `t` on piece `at` of that speed (the
    /// carriers interpolated into `c`), `None` where the design has no point there.
    fn state<'c>(&self, t: f64, at: usize, i: usize, c: &'c mut Vec<f64>) -> Option<State<'c>> {
        let ctx = &self.contexts[i];
        let st = self.pieces[i][at].2.as_ref()?;
        c.resize(ctx.store.width, 0.0);
        st.eval(t, c);
        Some(State {
            speed: self.reqs.speeds[i],
            carriers: c,
            modes: ctx.modes,
            same_branch: st.branch == ctx.branch,
        })
    }

    /// The margin of requirement `r` at speed `i` at `t` on piece `at` of that speed.
    fn margin(&self, t: f64, at: usize, i: usize, r: usize, c: &mut Vec<f64>) -> f64 {
        self.state(t, at, i, c)
            .map_or(f64::NEG_INFINITY, |s| margin(&self.reqs.list[r], &s))
    }

    /// The margin of every (speed, requirement) at `t`, `[speed][requirement]` flattened
    /// (+∞ where the speed is below the requirement's range; −∞ where the design has no
    /// point there), the pieces `at[i]` in use at each speed.
    fn margins(&self, t: f64, at: &[usize], out: &mut [f64], c: &mut Vec<f64>) {
        let r = self.reqs.list.len();
        out.iter_mut().for_each(|x| *x = f64::INFINITY);
        for (i, active) in self.active.iter().enumerate() {
            if active.is_empty() {
                continue;
            }
            let state = self.state(t, at[i], i, c);
            for &k in active {
                out[i * r + k] = state
                    .as_ref()
                    .map_or(f64::NEG_INFINITY, |s| margin(&self.reqs.list[k], s));
            }
        }
    }
}

/// The tally of line `li` with the nodes at `stride`.
fn line_tally(
    contexts: &[Context],
    li: usize,
    stride: usize,
    reqs: &Requirements,
    l: Layout,
) -> Tally {
    let nr = reqs.list.len();
    let view = LineView {
        pieces: contexts.iter().map(|c| c.pieces(li, stride)).collect(),
        contexts,
        reqs,
        active: (0..l.speeds)
            .map(|i| {
                (0..nr)
                    .filter(|&k| reaches(&reqs.list[k], reqs.speeds[i]))
                    .collect()
            })
            .collect(),
        covered: reqs
            .speeds
            .iter()
            .flat_map(|&w| reqs.list.iter().map(move |r| covers(r, w)))
            .collect(),
    };
    // Every boundary of every speed's pieces, in order.
    let mut cuts: Vec<f64> = view
        .pieces
        .iter()
        .flat_map(|p| p.iter().flat_map(|x| [x.0, x.1]))
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut tally = Tally::new(l);
    let n = l.speeds * nr;
    let (mut m0, mut m1, mut mm) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut c = Vec::new();
    let mut at = vec![0usize; l.speeds];
    for seg in cuts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        if b <= a {
            continue;
        }
        // The piece of each speed holding this segment.
        let mid = 0.5 * (a + b);
        for (i, p) in view.pieces.iter().enumerate() {
            at[i] = p.iter().position(|x| x.0 <= mid && mid <= x.1).unwrap_or(0);
        }
        let subs = ((b - a) / STEP).ceil().max(1.0) as usize;
        let h = (b - a) / subs as f64;
        view.margins(a, &at, &mut m0, &mut c);
        for j in 0..subs {
            let (x0, x1) = (
                a + h * j as f64,
                if j + 1 == subs {
                    b
                } else {
                    a + h * (j + 1) as f64
                },
            );
            view.margins(x1, &at, &mut m1, &mut c);
            // The zeros of the margins that change sign across [x0, x1].
            let mut zeros = vec![x0, x1];
            for k in 0..n {
                if (m0[k] >= 0.0) != (m1[k] >= 0.0) {
                    let (i, r) = (k / nr, k % nr);
                    let met = |t: f64, c: &mut Vec<f64>| view.margin(t, at[i], i, r, c) >= 0.0;
                    zeros.push(boundary(met, x0, x1, m0[k] >= 0.0, &mut c));
                }
            }
            zeros.sort_by(f64::total_cmp);
            for w in zeros.windows(2) {
                let (y0, y1) = (w[0], w[1]);
                if y1 <= y0 {
                    continue;
                }
                add_piece(&view, &at, y0, y1, &mut tally, l, &mut mm, &mut c);
            }
            std::mem::swap(&mut m0, &mut m1);
        }
    }
    tally
}

/// Where `met` changes from `met0` (at `a`) in `[a, b]`, by bisection to rounding.
fn boundary(
    met: impl Fn(f64, &mut Vec<f64>) -> bool,
    mut a: f64,
    mut b: f64,
    met0: bool,
    c: &mut Vec<f64>,
) -> f64 {
    for _ in 0..64 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if met(m, c) == met0 {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// Adds `[y0, y1]` (where which requirements are met does not change) to `tally`: its mass to
/// what is met at its middle, and the worst margins' moments by 5-point Gauss–Legendre.
#[allow(clippy::too_many_arguments)]
fn add_piece(
    view: &LineView,
    at: &[usize],
    y0: f64,
    y1: f64,
    tally: &mut Tally,
    l: Layout,
    mm: &mut [f64],
    c: &mut Vec<f64>,
) {
    let nr = l.reqs;
    let mass = normal_mass(y0, y1);
    view.margins(0.5 * (y0 + y1), at, mm, c);
    tally.v[l.mass()] += mass;
    let mut all = true;
    for r in 0..nr {
        let (mut met, mut holds) = (true, true);
        for i in 0..l.speeds {
            let ok = mm[i * nr + r] >= 0.0;
            holds &= ok;
            if holds {
                tally.v[l.prefix(i, r)] += mass;
            }
            if !view.covered[i * nr + r] {
                continue;
            }
            if ok {
                tally.v[l.curve(i, r)] += mass;
            } else {
                met = false;
            }
        }
        all &= met;
        if met {
            tally.v[l.each(r)] += mass;
        }
    }
    if all {
        tally.v[l.all()] += mass;
    }
    // The worst margin over each requirement's range.
    for (&x, &wx) in GL_X.iter().zip(&GL_W) {
        let t = y0 + (y1 - y0) * 0.5 * (1.0 + x);
        let wt = 0.5 * wx * (y1 - y0) * density(t);
        view.margins(t, at, mm, c);
        for r in 0..nr {
            if !has_margin(&view.reqs.list[r]) {
                continue;
            }
            let worst = (0..l.speeds)
                .filter(|&i| view.covered[i * nr + r])
                .map(|i| mm[i * nr + r])
                .fold(f64::INFINITY, f64::min);
            tally.atoms[r].push((worst, wt));
            if worst.is_finite() {
                let d = worst - view.reqs.shift[r];
                tally.v[l.margin(r, 0)] += wt;
                tally.v[l.margin(r, 1)] += wt * d;
                tally.v[l.margin(r, 2)] += wt * d * d;
            }
        }
    }
}
