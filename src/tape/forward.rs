//! Forward mode: a program's values and the first derivatives of its outputs along several
//! directions (lanes) at once, in one pass along a [`Seeding`].
//!
//! The pass keeps each operation's value and, in a tangent row, its derivatives along the lanes
//! it can move; the chain rule is applied chunk by chunk over those lanes ([`Lanes`]). The
//! derivatives are read where the pass left them ([`Rows`]).

use super::seeding::{CHUNK, Mark};
use super::{BLOCK, Op, Seeding, Tape, Term};
use crate::real::Real;
use std::borrow::Cow;

impl Tape {
    /// Forward mode with several directions (lanes) at once: values of every output and first
    /// derivatives of the seeding's differentiated outputs along its directions. Returns the
    /// outputs' values and those derivatives (`differentiated × lanes`, row-major). The local
    /// derivative of each elementary function comes from evaluating it over a dual number; the
    /// lanes carry the chain rule.
    pub fn forward<S: Real>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &mut Forward<S>,
    ) -> (Vec<S>, Vec<S>) {
        let (values, rows) = self.forward_rows(fixed, x, seeding, work);
        let mut derivs = Vec::with_capacity(rows.len() * rows.lanes);
        for k in 0..rows.len() {
            derivs.extend_from_slice(rows.row(k));
        }
        (values, derivs)
    }

    /// [`Tape::forward`], the derivatives read where the pass left them (copying them out
    /// took about 2 of the 30 µs of the 12-arm governor's exact evaluation, `perf`).
    pub fn forward_rows<'w, S: Real>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &'w mut Forward<S>,
    ) -> (Vec<S>, Rows<'w, S>) {
        let (values, rows) = if !seeding.blocks.is_empty() {
            let (nd, lanes) = (seeding.differentiated, seeding.lanes);
            let mut derivs = vec![S::from(0.0); nd * lanes];
            let mut values = Vec::new();
            for (b, block) in seeding.blocks.iter().enumerate() {
                let (v, d) = self.forward(fixed, x, block, work);
                let (lo, w) = (b * BLOCK, block.lanes);
                for r in 0..nd {
                    derivs[r * lanes + lo..r * lanes + lo + w]
                        .copy_from_slice(&d[r * w..(r + 1) * w]);
                }
                values = v;
            }
            let rows = Rows {
                start: (0..nd).map(|r| r * lanes).collect(),
                lanes,
                tan: Cow::Owned(derivs),
            };
            (values, rows)
        } else {
            let stride = seeding.lanes + CHUNK - 1;
            #[cfg(target_arch = "x86_64")]
            let avx2 = std::arch::is_x86_feature_detected!("avx2");
            #[cfg(not(target_arch = "x86_64"))]
            let avx2 = false;
            if avx2 {
                // SAFETY: the processor has AVX2, just checked.
                #[cfg(target_arch = "x86_64")]
                unsafe {
                    forward_avx2(self, fixed, x, seeding, work, stride)
                };
            } else {
                self.forward_pass(fixed, x, seeding, work, stride);
            }
            self.read_outputs(&work.val, &work.tan, seeding, stride)
        };
        (values, rows.unpacked(seeding))
    }

    /// The pass of [`Tape::forward_rows`] with rows shared or not (inlined into each
    /// instruction set's copy).
    #[inline(always)]
    fn forward_pass<S: Real>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &mut Forward<S>,
        stride: usize,
    ) {
        if seeding.slots.reuse {
            self.forward_with::<S, true>(fixed, x, seeding, work, stride);
        } else {
            self.forward_with::<S, false>(fixed, x, seeding, work, stride);
        }
    }

    /// [`Tape::forward`] with rows shared or not (two compiled loops: the small programs'
    /// one keeps no bookkeeping of shared rows). Inlined into each instruction set's copy.
    #[inline(always)]
    fn forward_with<S: Real, const REUSE: bool>(
        &self,
        fixed: &[S],
        x: &[S],
        seeding: &Seeding,
        work: &mut Forward<S>,
        stride: usize,
    ) {
        let ns = self.n_static;
        let zero = S::from(0.0);
        // Every operation writes its value below: no clearing.
        work.val.resize(self.ops.len(), zero);
        work.val[..ns].copy_from_slice(&fixed[..ns]);
        // A row holds zeros outside what its operation wrote (`dirty`); a row taken over by
        // another operation is cleared where the new one does not write.
        let rows = seeding.slots.rows + 1;
        if !work.seeding.is(&seeding.id) || work.tan.len() != rows * stride {
            work.tan.clear();
            work.tan.resize(rows * stride, zero);
            work.dirty.clear();
            work.dirty.resize(rows, (0, 0));
            work.seeding = seeding.id.mark();
        }
        // What the unchecked reads and writes below rely on, besides every operand preceding its
        // operation (kept by the tape's constructors, asserted when a seeding is made) and the
        // lanes' ranges lying within the lanes (asserted there too).
        assert!(
            seeding.range.len() == self.ops.len()
                && (REUSE || seeding.slots.rows == self.ops.len())
                && stride == seeding.lanes + CHUNK - 1,
            "a seeding of this program"
        );
        let (val, tan, dirty) = (&mut work.val, &mut work.tan, &mut work.dirty);
        for (i, op) in self.ops.iter().enumerate().skip(ns) {
            let (lo, w) = seeding.range[i];
            let at = if REUSE {
                seeding.slots.slot[i]
            } else {
                i as u32
            };
            if REUSE && w > 0 {
                take_row(tan, &mut dirty[at as usize], at as usize * stride, (lo, w));
            }
            let lanes = Lanes::<REUSE> {
                stride,
                at: at as usize,
                lo: lo as usize,
                width: w as usize,
                slot: &seeding.slots.slot,
            };
            let v = step(*op, &lanes, (val, tan), x, seeding);
            // SAFETY: `i` is an operation's index and `val` holds one value for each.
            unsafe { *val.get_unchecked_mut(i) = v };
        }
    }

    /// The outputs' values and where the differentiated outputs' lanes are after a forward
    /// pass (a constant output's in the zero row after the last).
    pub(super) fn read_outputs<'w, S: Real>(
        &self,
        val: &[S],
        tan: &'w [S],
        seeding: &Seeding,
        stride: usize,
    ) -> (Vec<S>, Rows<'w, S>) {
        let zero_row = seeding.slots.rows * stride;
        let mut start = Vec::with_capacity(seeding.differentiated);
        let values = (self.outputs.iter().enumerate())
            .map(|(k, o)| {
                let (value, row) = match o.term() {
                    Term::Const(c) => (S::from(c), zero_row),
                    Term::Node(i, _) => {
                        let i = i as usize;
                        (val[i], seeding.slots.slot[i] as usize * stride)
                    }
                };
                if k < seeding.differentiated {
                    start.push(row);
                }
                value
            })
            .collect();
        (
            values,
            Rows {
                start,
                lanes: seeding.lanes,
                tan: Cow::Borrowed(tan),
            },
        )
    }
}

/// [`Tape::forward_pass`] compiled for AVX2: the lane loops' chunks of four `f64` are one
/// instruction each instead of two. No multiply–add is contracted (Rust contracts none, and
/// FMA is not enabled), so the results are the baseline's to the bit.
///
/// # Safety
/// The processor must have AVX2 (checked by the caller).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn forward_avx2<S: Real>(
    tape: &Tape,
    fixed: &[S],
    x: &[S],
    seeding: &Seeding,
    work: &mut Forward<S>,
    stride: usize,
) {
    tape.forward_pass(fixed, x, seeding, work, stride);
}

/// The derivatives of a forward pass's differentiated outputs (see [`Tape::forward_rows`]):
/// output `k`'s lanes are `row(k)`.
pub struct Rows<'w, S: Clone> {
    /// Where each output's lanes start in `tan`.
    start: Vec<usize>,
    lanes: usize,
    tan: Cow<'w, [S]>,
}

impl<'w, S: Clone> Rows<'w, S> {
    /// The rows of a packed pass along its seeding's lanes (as they are where not packed).
    pub(super) fn unpacked(self, seeding: &Seeding) -> Rows<'w, S>
    where
        S: Real,
    {
        let Some(p) = &seeding.packing else {
            return self;
        };
        let mut tan = vec![S::from(0.0); self.len() * p.lanes];
        for (k, out) in tan.chunks_exact_mut(p.lanes).enumerate() {
            p.unpack(k, self.row(k), out);
        }
        Rows {
            start: (0..self.len()).map(|k| k * p.lanes).collect(),
            lanes: p.lanes,
            tan: Cow::Owned(tan),
        }
    }

    /// Number of differentiated outputs.
    pub fn len(&self) -> usize {
        self.start.len()
    }

    /// Are there none?
    pub fn is_empty(&self) -> bool {
        self.start.is_empty()
    }

    /// The lanes of output `k`.
    pub fn row(&self, k: usize) -> &[S] {
        &self.tan[self.start[k]..self.start[k] + self.lanes]
    }
}

/// Scalars too wide to move a chunk of lanes as one array ([`crate::dual4::Dual4`], 40 bytes:
/// three operands' chunks are 480 bytes, which the compiler copies through memory, eight times
/// the time of the pass lane by lane). `f64` and `Dual64` keep their chunks.
const fn wide<S>() -> bool {
    std::mem::size_of::<S>() > 16
}

/// Takes over the row at `row` of `tan` for an operation that writes the lanes `(lo, w)`
/// (`w > 0`): clears what the row's last operation wrote (`dirty`) outside what the new one
/// writes, and records what it writes.
#[inline(always)]
fn take_row<S: Real>(tan: &mut [S], dirty: &mut (usize, usize), row: usize, (lo, w): (u32, u32)) {
    let (lo, w) = (lo as usize, w as usize);
    let written = if w == 1 {
        (lo, lo + 1)
    } else {
        (lo, lo + w.div_ceil(CHUNK) * CHUNK)
    };
    if dirty.0 < written.0 || dirty.1 > written.1 {
        tan[row + dirty.0..row + dirty.1].fill(S::from(0.0));
    }
    *dirty = written;
}

/// One operation of the forward pass: writes its tangents over `lanes` into `tan` from its
/// operands' and returns its value (`val` holds every operation's before it, `x` the inputs).
#[inline(always)]
fn step<S: Real, const REUSE: bool>(
    op: Op,
    lanes: &Lanes<'_, REUSE>,
    (val, tan): (&[S], &mut [S]),
    x: &[S],
    seeding: &Seeding,
) -> S {
    let zero = S::from(0.0);
    let stride = lanes.stride;
    // An operand's value. SAFETY: `val` holds a value for every operation (resized by the
    // caller) and an operand precedes its operation, so it is in bounds and written already.
    macro_rules! v {
        ($a:expr) => {
            unsafe { *val.get_unchecked($a as usize) }
        };
    }
    match op {
        Op::Input(k) => {
            lanes.map(tan, [], |[]| zero);
            if lanes.width > 0 {
                let weights = seeding.input_weights.get(k as usize);
                for (j, &l) in seeding.input_lanes[k as usize].iter().enumerate() {
                    let w = weights.map_or(1.0, |w| w[j]);
                    tan[lanes.at * stride + l as usize] = S::from(w);
                }
            }
            x[k as usize]
        }
        Op::Const(c) => {
            lanes.map(tan, [], |[]| zero);
            S::from(c)
        }
        Op::Add(a, b) => {
            lanes.map(tan, [a, b], |[x, y]| x + y);
            v!(a) + v!(b)
        }
        Op::Sub(a, b) => {
            lanes.map(tan, [a, b], |[x, y]| x - y);
            v!(a) - v!(b)
        }
        Op::Mul(a, b) => {
            let (va, vb) = (v!(a), v!(b));
            lanes.map(tan, [a, b], |[x, y]| x * vb + va * y);
            va * vb
        }
        Op::Neg(a) => {
            lanes.map(tan, [a], |[x]| -x);
            -v!(a)
        }
        Op::AddC(a, c) => {
            lanes.map(tan, [a], |[x]| x);
            v!(a) + c
        }
        Op::MulC(a, c) => {
            lanes.map(tan, [a], |[x]| x * c);
            v!(a) * c
        }
        Op::MulAdd(a, b, c) => {
            let (va, vb, vc) = (v!(a), v!(b), v!(c));
            lanes.map(tan, [a, b, c], |[x, y, z]| x * vb + va * y + z);
            va * vb + vc
        }
        Op::MulSub(a, b, c) => {
            let (va, vb, vc) = (v!(a), v!(b), v!(c));
            lanes.map(tan, [a, b, c], |[x, y, z]| x * vb + va * y - z);
            va * vb - vc
        }
        Op::SubMul(a, b, c) => {
            let (va, vb, vc) = (v!(a), v!(b), v!(c));
            lanes.map(tan, [a, b, c], |[x, y, z]| z - (x * vb + va * y));
            vc - va * vb
        }
        op => {
            // Division and the functions: local partials from a dual evaluation.
            let (v, da, db) = op.partials(val);
            match (op.args(), da, db) {
                ([Some(a), Some(b), _], Some(da), Some(db)) => {
                    lanes.map(tan, [a, b], |[x, y]| da * x + db * y)
                }
                ([Some(a), _, _], Some(da), _) => lanes.map(tan, [a], |[x]| da * x),
                _ => lanes.map(tan, [], |[]| zero),
            }
            v
        }
    }
}

/// The lanes one operation of [`Tape::forward`] writes: `width` lanes from `lo` of tangent row
/// `at`, in rows of `stride` (the lanes plus room for the last chunk); `slot` gives each
/// operation's row.
struct Lanes<'a, const REUSE: bool> {
    stride: usize,
    at: usize,
    lo: usize,
    width: usize,
    slot: &'a [u32],
}

impl<const REUSE: bool> Lanes<'_, REUSE> {
    /// `out[l] = f([arg[l] for arg in args])` over the operation's lanes, a single lane alone
    /// and wider ranges in whole chunks. A chunk's lanes beyond the range are outside every
    /// operand's range too, so they are written with zeros (the derivatives there) and the
    /// zero invariant of [`Forward`] holds. An operand's row is never the operation's own (it
    /// is freed after the operation's row is taken).
    #[inline(always)]
    fn map<S: Copy, const K: usize>(&self, tan: &mut [S], args: [u32; K], f: impl Fn([S; K]) -> S) {
        let chunks = self.width.div_ceil(CHUNK) * CHUNK;
        let (base, out) = if REUSE {
            let base = args.map(|a| self.slot[a as usize] as usize * self.stride + self.lo);
            let out = self.at * self.stride + self.lo;
            // Raw reads and writes: this loop indexed through slices spends twice the time
            // (the 12-arm governor's exact evaluation with shared rows 95–113 µs, with these
            // 65–68 µs). One check per operation keeps it in bounds.
            assert!(
                out + chunks <= tan.len() && base.iter().all(|&b| b + chunks <= tan.len()),
                "a forward pass's lanes stay in their rows"
            );
            (base, out)
        } else {
            // One row per operation: an operand's row is its index, below the operation's own.
            // In bounds without a check: `forward_with` asserted a row per operation and one
            // zero row, every operand precedes its operation, and a range of lanes rounded up
            // to whole chunks ends within the row's `stride = lanes + CHUNK − 1`.
            (
                args.map(|a| a as usize * self.stride + self.lo),
                self.at * self.stride + self.lo,
            )
        };
        let p = tan.as_mut_ptr();
        if self.width == 1 {
            // SAFETY: in bounds as said above; no reference into `tan` is alive.
            unsafe { std::ptr::write(p.add(out), f(base.map(|b| std::ptr::read(p.add(b))))) };
            return;
        }
        let mut k = 0;
        if wide::<S>() {
            // Lane by lane (see [`wide`]): lane `j` of the output is written after lane `j` of
            // every operand is read, so an operand sharing the output's row is still read
            // before it changes.
            while k < self.width {
                for j in k..k + CHUNK {
                    // SAFETY: as for the chunks below, one element at a time.
                    let value = f(base.map(|b| unsafe { std::ptr::read(p.add(b + j)) }));
                    unsafe { std::ptr::write(p.add(out + j), value) };
                }
                k += CHUNK;
            }
            return;
        }
        while k < self.width {
            // SAFETY: every chunk read and written lies in `tan` (as said above) and is
            // aligned as `S` is (an array has its element's alignment); no reference into
            // `tan` is alive meanwhile, and each chunk is copied out before the output's is
            // written, so an operand sharing the output's row would still read its old values.
            let chunk: [[S; CHUNK]; K] =
                base.map(|b| unsafe { std::ptr::read(p.add(b + k).cast::<[S; CHUNK]>()) });
            let value: [S; CHUNK] = std::array::from_fn(|j| f(chunk.map(|c| c[j])));
            unsafe { std::ptr::write(p.add(out + k).cast::<[S; CHUNK]>(), value) };
            k += CHUNK;
        }
    }
}

/// Scratch space of [`Tape::forward`].
#[derive(Debug, Clone)]
pub struct Forward<S> {
    pub(super) val: Vec<S>,
    pub(super) tan: Vec<S>,
    /// The lanes each tangent row's last operation wrote (zeros elsewhere).
    dirty: Vec<(usize, usize)>,
    /// The [`Seeding`] the buffer was last used with.
    pub(super) seeding: Mark,
}

impl<S> Default for Forward<S> {
    fn default() -> Self {
        Forward {
            val: Vec::new(),
            tan: Vec::new(),
            dirty: Vec::new(),
            seeding: Mark::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tape::record;
    use num_dual::DualNum;

    /// The AVX2 copy of the pass gives the baseline copy's bits, values and lanes, on a program
    /// with products, quotients, fused operations and elementary functions over many lanes.
    #[test]
    fn every_instruction_set_passes_to_the_same_bits() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let n = 11;
            let x0: Vec<f64> = (0..n).map(|k| 0.4 + 0.23 * k as f64).collect();
            let tape = record(&x0, |v| {
                let out = (0..n)
                    .map(|i| {
                        let (a, b) = (v[i], v[(i + 3) % n]);
                        a * b.sin() + (a / (b + 2.0)).exp() - a.sqrt() * b * v[(i + 5) % n]
                    })
                    .collect();
                Some(out)
            })
            .expect("records")
            .finish(&(0..n).collect::<Vec<_>>());
            let seeds: Vec<(usize, usize)> = (0..n).map(|k| (k, k)).collect();
            let seeding = tape.seeding(&seeds, n, n);
            let stride = seeding.lanes + CHUNK - 1;
            let (mut base, mut wide) = (Forward::default(), Forward::default());
            tape.forward_pass(&[], &x0, &seeding, &mut base, stride);
            // SAFETY: the processor has AVX2, just checked.
            unsafe { forward_avx2(&tape, &[], &x0, &seeding, &mut wide, stride) };
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&base.val), bits(&wide.val));
            assert_eq!(bits(&base.tan), bits(&wide.tan));
            assert!(base.tan.iter().filter(|&&t| t != 0.0).count() > n);
        }
    }
}
