//! One line's tally: the line cut where any requirement's margin changes sign at any speed,
//! each piece's exact normal mass added to what is met on it, and the worst margins' moments
//! by Gauss–Legendre on each piece.

use super::tally::{Layout, Tally};
use super::{Requirements, STEP};
use crate::margins::{State, covers, has_margin, margin, reaches};
use crate::pair::Carriers;
use crate::quadrature::line::{Context, GL_W, GL_X, Stencil, density, normal_mass};

/// The pieces of one line at every speed, and the requirements' margins at a point of it.
pub(super) struct LineView<'a> {
    pieces: Vec<Vec<(f64, f64, Option<Stencil<'a>>)>>,
    contexts: &'a [Context<'a>],
    reqs: &'a Requirements<'a>,
    /// Per speed: the requirements it is at or above the range's start of ([`reaches`]).
    active: Vec<Vec<usize>>,
    /// `[speed · requirements + requirement]`: is the speed in the requirement's range?
    covered: Vec<bool>,
    /// Where each part of a tally sits.
    layout: Layout,
}

impl LineView<'_> {
    /// What the requirements read at speed `i` at `t` on piece `at` of that speed (the
    /// carriers interpolated into `c`), `None` where the design has no point there.
    pub(super) fn state<'c>(
        &self,
        t: f64,
        at: usize,
        i: usize,
        c: &'c mut Vec<f64>,
    ) -> Option<State<'c>> {
        let ctx = &self.contexts[i];
        let st = self.pieces[i][at].2.as_ref()?;
        c.resize(ctx.store.width, 0.0);
        st.eval(t, c);
        Some(State {
            speed: self.reqs.speeds[i],
            carriers: Carriers::new(c),
            same_branch: st.branch == ctx.branch,
        })
    }

    /// Requirement `r`'s margin less its offset (`−∞` stays: no margin at any offset).
    pub(super) fn moved(&self, r: usize, s: &State) -> f64 {
        let m = margin(&self.reqs.list[r], s);
        if m == f64::NEG_INFINITY {
            m
        } else {
            m - self.reqs.offset[r]
        }
    }

    /// The margin of requirement `r` at speed `i` at `t` on piece `at` of that speed.
    pub(super) fn margin(&self, t: f64, at: usize, i: usize, r: usize, c: &mut Vec<f64>) -> f64 {
        self.state(t, at, i, c)
            .map_or(f64::NEG_INFINITY, |s| self.moved(r, &s))
    }

    /// The margin of every (speed, requirement) at `t`, `[speed][requirement]` flattened
    /// (+∞ where the speed is below the requirement's range; −∞ where the design has no
    /// point there), the pieces `at[i]` in use at each speed.
    pub(super) fn margins(&self, t: f64, at: &[usize], out: &mut [f64], c: &mut Vec<f64>) {
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
                    .map_or(f64::NEG_INFINITY, |s| self.moved(k, s));
            }
        }
    }

    /// Adds `[y0, y1]` (where which requirements are met does not change) to `tally`: its mass to
    /// what is met at its middle, and the worst margins' moments by 5-point Gauss–Legendre.
    fn add_piece(
        &self,
        at: &[usize],
        (y0, y1): (f64, f64),
        tally: &mut Tally,
        mm: &mut [f64],
        c: &mut Vec<f64>,
    ) {
        let (view, l) = (self, self.layout);
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
        if !view.reqs.moments {
            return;
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
                if worst.is_finite() {
                    let d = worst - view.reqs.shift[r];
                    tally.v[l.margin(r, 0)] += wt;
                    tally.v[l.margin(r, 1)] += wt * d;
                    tally.v[l.margin(r, 2)] += wt * d * d;
                }
            }
        }
    }
}

/// The tally of line `li` with the nodes at `stride`.
pub(super) fn line_tally(
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
        layout: l,
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
                view.add_piece(&at, (y0, y1), &mut tally, &mut mm, &mut c);
            }
            std::mem::swap(&mut m0, &mut m1);
        }
    }
    tally
}

/// Where `met` changes from `met0` (at `a`) in `[a, b]`, by bisection to rounding.
pub(super) fn boundary(
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
