//! The additive sums of the yield integration (a line's, a rule's) and where each part of
//! them sits.

/// The additive sums of one line (or a rule): the mass, the mass meeting everything, per
/// requirement the mass meeting it and the worst margin's defined mass and first two moments
/// about `shift`, per speed and requirement the mass meeting it there and from its range's
/// start up to there.
#[derive(Debug, Clone)]
pub(super) struct Tally {
    pub(super) v: Vec<f64>,
}

/// Where each part of a [`Tally`] sits.
#[derive(Clone, Copy)]
pub(super) struct Layout {
    pub(super) reqs: usize,
    pub(super) speeds: usize,
}

impl Layout {
    pub(super) fn len(&self) -> usize {
        2 + 4 * self.reqs + 2 * self.speeds * self.reqs
    }
    pub(super) fn mass(&self) -> usize {
        0
    }
    pub(super) fn all(&self) -> usize {
        1
    }
    pub(super) fn each(&self, r: usize) -> usize {
        2 + r
    }
    /// Defined mass, first and second moment of requirement `r`'s worst margin.
    pub(super) fn margin(&self, r: usize, k: usize) -> usize {
        2 + self.reqs + 3 * r + k
    }
    pub(super) fn curve(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + i * self.reqs + r
    }
    pub(super) fn prefix(&self, i: usize, r: usize) -> usize {
        2 + 4 * self.reqs + (self.speeds + i) * self.reqs + r
    }
}

impl Tally {
    pub(super) fn new(l: Layout) -> Tally {
        Tally {
            v: vec![0.0; l.len()],
        }
    }
    pub(super) fn add_scaled(&mut self, b: &Tally, w: f64) {
        for (x, y) in self.v.iter_mut().zip(&b.v) {
            *x += w * y;
        }
    }
    pub(super) fn ratio(&self, l: Layout, k: usize) -> f64 {
        self.v[k] / self.v[l.mass()]
    }
    pub(super) fn moments(&self, l: Layout, r: usize, shift: f64) -> Option<(f64, f64)> {
        let w = self.v[l.margin(r, 0)];
        (w > 0.0).then(|| {
            let m1 = self.v[l.margin(r, 1)] / w;
            let var = self.v[l.margin(r, 2)] / w - m1 * m1;
            (m1 + shift, var.max(0.0).sqrt())
        })
    }
}
