//! The plan of a forward pass, made once per choice of seeds: which lanes each operation can
//! move ([`Seeding`]), split into blocks of at most [`BLOCK`] lanes, and which tangent row each
//! operation writes (rows shared by operations alive at different times in big programs).
//!
//! [`Tape::forward`] and the compiled passes of [`native`](super::native) run a program along a
//! seeding; making it is kept apart from running it, which happens many times.

use super::packing::Packing;
use super::{Op, Tape, Term};
use std::sync::{Arc, Weak};

impl Tape {
    /// Which lanes of [`Tape::forward`] each operation can move: input `k` moves along lane
    /// `l` for each `(k, l)` in `seeds` (static inputs must not be seeded). Computed once per
    /// choice of seeds; an operation's derivative is only propagated over its lane range.
    /// Derivatives are wanted for the first `differentiated` outputs only: the operations that
    /// only the others need are evaluated without them.
    ///
    /// More than [`BLOCK`] lanes are split into blocks of that many, each a seeding of its own
    /// that [`Tape::forward`] runs in turn: the tangent buffer then holds `BLOCK` lanes of the
    /// operations alive at once, not all the lanes. (A chain's pass keeps every body's pose alive
    /// until the wrenches come back from the tip, and a lane per coordinate: one buffer over
    /// all lanes grows with the square of the number of bodies, about 1 GB at a thousand.) The
    /// values are evaluated once per block; the lane work is the same.
    ///
    /// Lanes that no differentiated output moves along together share a lane of the pass
    /// (`tape::packing`): a banded Jacobian's pass carries the lanes of a band.
    /// The derivatives come back along the lanes asked for.
    pub fn seeding(
        &self,
        seeds: &[(usize, usize)],
        lanes: usize,
        differentiated: usize,
    ) -> Seeding {
        self.seeding_in_groups(seeds, (lanes, 1), differentiated)
    }

    /// [`Tape::seeding`] with the lanes in groups of `group` consecutive lanes, packed as
    /// groups (see `tape::packing`).
    pub fn seeding_in_groups(
        &self,
        seeds: &[(usize, usize)],
        (lanes, group): (usize, usize),
        differentiated: usize,
    ) -> Seeding {
        // Lanes that never meet in a differentiated output share a lane of the pass.
        let packing = self.packing(seeds, (lanes, group), differentiated);
        let packed_seeds;
        let (seeds, lanes) = match &packing {
            Some(p) => {
                packed_seeds = p.seeds(seeds);
                (&packed_seeds[..], p.packed)
            }
            None => (seeds, lanes),
        };
        let mut whole = self.seeding_of(seeds, lanes, differentiated, lanes <= BLOCK);
        if lanes > BLOCK {
            whole.blocks = (0..lanes.div_ceil(BLOCK))
                .map(|b| {
                    let (lo, hi) = (b * BLOCK, (b * BLOCK + BLOCK).min(lanes));
                    let within: Vec<(usize, usize)> = seeds
                        .iter()
                        .filter(|s| (lo..hi).contains(&s.1))
                        .map(|&(k, l)| (k, l - lo))
                        .collect();
                    self.seeding_of(&within, hi - lo, differentiated, true)
                })
                .collect();
        }
        whole.packing = packing;
        whole
    }

    /// A seeding of `lanes` directions, each a combination of inputs: input `k` moves along
    /// lane `l` at rate `w` for each `(k, l, w)` in `directions` (a directional derivative in
    /// each lane, where [`Tape::seeding`] seeds each input at rate one). For a few lanes: no
    /// packing, no blocks, and no compiled pass ([`Tape::compile_forward`] declines it).
    pub fn seeding_along(
        &self,
        directions: &[(usize, usize, f64)],
        lanes: usize,
        differentiated: usize,
    ) -> Seeding {
        assert!(lanes <= BLOCK, "a seeding along directions has few lanes");
        let seeds: Vec<(usize, usize)> = directions.iter().map(|&(k, l, _)| (k, l)).collect();
        let mut seeding = self.seeding_of(&seeds, lanes, differentiated, true);
        let mut weights: Vec<Vec<f64>> = vec![Vec::new(); seeding.input_lanes.len()];
        for &(k, _, w) in directions {
            weights[k].push(w);
        }
        seeding.input_weights = weights;
        seeding
    }

    /// The lanes of each input (by input index) of the seeds `(input, lane)`.
    pub(super) fn input_lanes(&self, seeds: &[(usize, usize)], lanes: usize) -> Vec<Vec<u32>> {
        let inputs = seeds.iter().map(|s| s.0 + 1).max().unwrap_or(0);
        let mut input_lanes = vec![Vec::new(); inputs];
        for &(k, l) in seeds {
            assert!(l < lanes, "a seed's lane is one of the seeding's lanes");
            input_lanes[k].push(l as u32);
        }
        input_lanes
    }

    /// The hull `(first, end)` of the lanes each operation depends on (`(0, 0)`: none), for
    /// the lanes `input_lanes` of the inputs.
    pub(super) fn hulls(&self, input_lanes: &[Vec<u32>]) -> Vec<(u32, u32)> {
        let mut range = vec![(0u32, 0u32); self.ops.len()];
        for (i, op) in self.ops.iter().enumerate().skip(self.n_static) {
            range[i] = match *op {
                Op::Input(k) => input_lanes
                    .get(k as usize)
                    .map_or(&[][..], |v| &v[..])
                    .iter()
                    .fold((u32::MAX, 0), |(lo, hi), &l| (lo.min(l), hi.max(l + 1))),
                op => {
                    let (args, k) = op.operands();
                    // The forward pass reads operands unchecked on this (see `forward_with`).
                    assert!(
                        args[..k].iter().all(|&a| (a as usize) < i),
                        "every operand precedes its operation"
                    );
                    args[..k].iter().fold((u32::MAX, 0), |(lo, hi), &a| {
                        let (l, h) = range[a as usize];
                        if l >= h {
                            (lo, hi)
                        } else {
                            (lo.min(l), hi.max(h))
                        }
                    })
                }
            };
            if range[i].0 >= range[i].1 {
                range[i] = (0, 0);
            }
        }
        range
    }

    /// One block of [`Tape::seeding`] (its tangent rows allocated when `rows`).
    fn seeding_of(
        &self,
        seeds: &[(usize, usize)],
        lanes: usize,
        differentiated: usize,
        rows: bool,
    ) -> Seeding {
        let input_lanes = self.input_lanes(seeds, lanes);
        let mut range = self.hulls(&input_lanes);
        // The operations the differentiated outputs need.
        let live = self.live(&(0..differentiated).collect::<Vec<_>>());
        // As (first lane, width).
        for (r, &live) in range.iter_mut().zip(&live) {
            *r = if live { (r.0, r.1 - r.0) } else { (0, 0) };
        }
        let slots = if rows {
            self.slots(&range, lanes, differentiated)
        } else {
            Slots {
                slot: Vec::new(),
                rows: 0,
                reuse: false,
            }
        };
        Seeding {
            id: Identity::default(),
            seeds: seeds.to_vec(),
            input_lanes,
            input_weights: Vec::new(),
            lanes,
            range,
            differentiated,
            slots,
            blocks: Vec::new(),
            packing: None,
        }
    }

    /// A row of the tangent buffer for every operation with lanes, reused once its last reader
    /// has run (linear-scan allocation; the differentiated outputs keep theirs to the end): the
    /// buffer holds the operations alive at once, not all of them. A chain's pass keeps a few
    /// bodies' operations alive where it records all of them. Returns the rows and their number.
    fn slots(&self, range: &[(u32, u32)], lanes: usize, differentiated: usize) -> Slots {
        let n = self.ops.len();
        // A buffer of one row per operation is kept when small: no clearing on takeover.
        if n * (lanes + CHUNK - 1) <= SMALL_BUFFER {
            return Slots {
                slot: (0..n as u32).collect(),
                rows: n,
                reuse: false,
            };
        }
        // The last reader with lanes of each operation (`usize::MAX`: kept to the end).
        let mut last: Vec<Option<usize>> = vec![None; n];
        for (i, op) in self.ops.iter().enumerate() {
            if range[i].1 > 0 {
                let (args, k) = op.operands();
                for &a in &args[..k] {
                    last[a as usize] = Some(i);
                }
            }
        }
        for o in &self.outputs[..differentiated] {
            if let Term::Node(i, _) = o.term() {
                last[i as usize] = Some(usize::MAX);
            }
        }
        // The operation after which each row is free again (read by nothing: at once).
        let end = |i: usize| match last[i] {
            Some(l) if range[i].1 > 0 && l < n => Some(l),
            None if range[i].1 > 0 => Some(i),
            _ => None,
        };
        // For each operation, the operations whose last reader it is: `ended[start[i]..
        // start[i + 1]]` in increasing order (grouped by a counting sort, not a list each).
        let mut start = vec![0usize; n + 1];
        for i in 0..n {
            if let Some(l) = end(i) {
                start[l + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut ended = vec![0u32; start[n]];
        let mut fill = start.clone();
        for i in 0..n {
            if let Some(l) = end(i) {
                ended[fill[l]] = i as u32;
                fill[l] += 1;
            }
        }
        let mut slot = vec![u32::MAX; n];
        let mut free: Vec<u32> = Vec::new();
        let mut count = 0u32;
        for i in 0..n {
            if range[i].1 > 0 {
                slot[i] = free.pop().unwrap_or_else(|| {
                    count += 1;
                    count - 1
                });
            }
            for &a in &ended[start[i]..start[i + 1]] {
                free.push(slot[a as usize]);
            }
        }
        // The operations without lanes read the zero row after the last.
        for s in &mut slot {
            if *s == u32::MAX {
                *s = count;
            }
        }
        Slots {
            slot,
            rows: count as usize,
            reuse: true,
        }
    }
}

/// Seeds of [`Tape::forward`] with the lane range of every operation.
#[derive(Debug, Clone)]
pub struct Seeding {
    pub(super) id: Identity,
    pub(super) seeds: Vec<(usize, usize)>,
    /// The lanes of each input (by input index; the seeds regrouped).
    pub(super) input_lanes: Vec<Vec<u32>>,
    /// The rate of each of those lanes ([`Tape::seeding_along`]; empty: all one).
    pub(super) input_weights: Vec<Vec<f64>>,
    pub(super) lanes: usize,
    /// First lane and number of lanes of each operation.
    pub(super) range: Vec<(u32, u32)>,
    /// Outputs with derivatives (the first ones).
    pub(super) differentiated: usize,
    pub(super) slots: Slots,
    /// The blocks of at most [`BLOCK`] lanes the lanes are split into (none when they are
    /// that few; then `slots` are this seeding's own rows).
    pub(super) blocks: Vec<Seeding>,
    /// Where the lanes travel in a packed pass (the lanes above are the packed ones).
    pub(super) packing: Option<Packing>,
}

impl Seeding {
    /// Number of lanes (the derivatives' directions; a packed pass carries fewer).
    pub fn lanes(&self) -> usize {
        self.packing.as_ref().map_or(self.lanes, |p| p.lanes)
    }

    /// The seeds `(input, lane)`.
    pub fn seeds(&self) -> &[(usize, usize)] {
        &self.seeds
    }

    /// Do operations alive at different times share tangent rows (in some block)? Big
    /// programs' passes do, small ones keep a row per operation.
    pub fn shares_rows(&self) -> bool {
        self.slots.reuse || self.blocks.iter().any(|b| b.slots.reuse)
    }
}

/// Which seeding a buffer or a compiled pass was made for. A buffer keeps its tangent rows
/// between passes along the same seeding (a row holds zeros where no operation wrote, which
/// only holds for the seeding that wrote it), and a compiled pass runs only on its own: both
/// recognise it by its [`Mark`]. A seeding's copies share its identity (they are the same plan);
/// a mark keeps the identity's allocation alive, so its address is never another seeding's.
/// No process-wide counter is involved.
#[derive(Debug, Clone, Default)]
pub(super) struct Identity(Arc<()>);

/// What a buffer or a compiled pass keeps of the [`Identity`] of its seeding (none: a fresh
/// buffer, or a values-only pass).
#[derive(Debug, Clone, Default)]
pub(super) struct Mark(Weak<()>);

impl Identity {
    /// The mark of this seeding.
    pub(super) fn mark(&self) -> Mark {
        Mark(Arc::downgrade(&self.0))
    }
}

impl Mark {
    /// Was this made for the seeding of identity `id`?
    pub(super) fn is(&self, id: &Identity) -> bool {
        std::ptr::eq(self.0.as_ptr(), Arc::as_ptr(&id.0))
    }
}

/// Lanes are processed in chunks of this many (fixed-size loops the compiler unrolls and
/// vectorises; the lane ranges are mostly 1 to 4 wide).
pub(super) const CHUNK: usize = 4;

/// Most lanes one pass of [`Tape::forward`] carries (see [`Tape::seeding`]).
pub const BLOCK: usize = 256;

/// The tangent rows of a [`Seeding`]'s operations.
#[derive(Debug, Clone)]
pub(super) struct Slots {
    /// Row of each operation; the operations without lanes read row `rows`, which stays zero.
    pub(super) slot: Vec<u32>,
    pub(super) rows: usize,
    /// Rows are shared by operations alive at different times.
    pub(super) reuse: bool,
}

/// Tangent buffers up to this many numbers (8 MB of `f64`) keep one row per operation.
const SMALL_BUFFER: usize = 1 << 20;
