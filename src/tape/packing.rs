//! Lanes that no differentiated output moves along together share one lane of the pass:
//! compressed forward mode for sparse Jacobians (Curtis, Powell & Reid, *On the estimation of
//! sparse Jacobian matrices*, IMA J. Appl. Math. 13 (1974); Gebremedhin, Manne & Pothen,
//! *What color is your Jacobian?*, SIAM Review 47 (2005), §3: column partitioning by a
//! distance-2 colouring).
//!
//! A beam couples only its two nodes, so a meshed shaft's equations of motion have a banded
//! Jacobian: the row of a node moves along its neighbours' lanes and its own. One pass with a
//! lane per coordinate carries `6 (n + 1)` lanes for `n` elements, most of them zero in every
//! row; nodes three apart never meet in a row, so they can share lanes, and the pass carries
//! the lanes of three nodes whatever `n`.
//!
//! Lanes come in groups (a coordinate's position, velocity and acceleration lanes), coloured
//! together. The lanes an output can move along are bounded by its **lane range**, the hull of
//! the lanes of the inputs it depends on (the forward pass's own bookkeeping, [`Seeding`]). Two
//! groups conflict when some differentiated output's range meets both; every group's conflicts
//! with the groups before it are then one interval (from the first group of the ranges that
//! meet it), and the greedy colouring in group order gives each group the smallest colour that
//! interval leaves free (Gebremedhin et al. §4.1; optimal for a band). The packed pass lays the
//! groups' `t`-th lanes side by side, colour by colour: an operation of the positions alone
//! (most of a beam's) then spans the positions' lanes only. A model whose outputs are dense
//! keeps its lanes as they are (every group its own colour).
//!
//! The packed pass gives the same numbers, bit for bit (up to the sign of a zero): an operation
//! some differentiated output needs depends on lanes inside that output's range, which hold one
//! lane of each colour, so each of its packed lanes carries exactly one of the original lanes'
//! derivatives. The outputs' rows are unpacked after the pass (each lane of an output's range
//! read from its colour; zero outside the range).
//!
//! [`Seeding`]: super::Seeding

use super::{Tape, Term};

/// Where each lane of a seeding travels in its packed pass.
#[derive(Debug, Clone)]
pub(super) struct Packing {
    /// The packed lane of each of the seeding's lanes (`u32::MAX`: a lane no differentiated
    /// output moves along, dropped).
    pub(super) lane: Vec<u32>,
    /// The lane range (first, end) of each differentiated output, in the seeding's lanes.
    pub(super) reach: Vec<(u32, u32)>,
    /// The seeding's lanes (the packed pass carries fewer).
    pub(super) lanes: usize,
    /// The packed pass's lanes.
    pub(super) packed: usize,
}

impl Tape {
    /// The packing of the lanes `seeds` (`(input, lane)`, `lanes` of them, in groups of
    /// `group` consecutive lanes) for the first `differentiated` outputs, where it carries
    /// fewer lanes.
    pub(super) fn packing(
        &self,
        seeds: &[(usize, usize)],
        (lanes, group): (usize, usize),
        differentiated: usize,
    ) -> Option<Packing> {
        assert!(
            group > 0 && lanes.is_multiple_of(group),
            "the lanes come in whole groups"
        );
        let hull = self.hulls(&self.input_lanes(seeds, lanes));
        let reach: Vec<(u32, u32)> = (self.outputs[..differentiated].iter())
            .map(|o| match o.term() {
                Term::Node(i, _) => hull[i as usize],
                Term::Const(_) => (0, 0),
            })
            .collect();
        // The first group each group meets in some output's range (itself if none); groups in
        // no range are moved by no differentiated output.
        let groups = lanes / group;
        let mut first: Vec<usize> = (0..groups).collect();
        let mut covered = vec![false; groups];
        for &(lo, hi) in &reach {
            for g in lo as usize / group..(hi as usize).div_ceil(group) {
                first[g] = first[g].min(lo as usize / group);
                covered[g] = true;
            }
        }
        let mut colour = vec![u32::MAX; groups];
        let mut taken: Vec<bool> = Vec::new();
        let mut colours = 0u32;
        for g in 0..groups {
            if !covered[g] {
                continue;
            }
            taken.clear();
            taken.resize(colours as usize + 1, false);
            for &c in &colour[first[g]..g] {
                if c != u32::MAX {
                    taken[c as usize] = true;
                }
            }
            let c = taken.iter().position(|&t| !t).unwrap_or(taken.len()) as u32;
            colour[g] = c;
            colours = colours.max(c + 1);
        }
        ((colours as usize) < groups).then(|| {
            // The `t`-th lanes of the groups side by side: an operation that depends on the
            // groups' first lanes alone (a coordinate's position, not its rates) spans those.
            let lane = (0..lanes)
                .map(|l| match colour[l / group] {
                    u32::MAX => u32::MAX,
                    c => (l % group) as u32 * colours + c,
                })
                .collect();
            Packing {
                lane,
                reach,
                lanes,
                packed: colours as usize * group,
            }
        })
    }
}

impl Packing {
    /// The seeds moved to their packed lanes (the dropped lanes' seeds left out).
    pub(super) fn seeds(&self, seeds: &[(usize, usize)]) -> Vec<(usize, usize)> {
        seeds
            .iter()
            .filter(|s| self.lane[s.1] != u32::MAX)
            .map(|&(k, l)| (k, self.lane[l] as usize))
            .collect()
    }

    /// Output `k`'s derivatives along the seeding's lanes, from its packed `row`, into `out`
    /// (zeros outside its range).
    pub(super) fn unpack<S: Copy>(&self, k: usize, row: &[S], out: &mut [S]) {
        let (lo, hi) = self.reach[k];
        for l in lo as usize..hi as usize {
            out[l] = row[self.lane[l] as usize];
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::tape::{Forward, record};
    use num_dual::DualNum;

    /// A banded program (each output couples three neighbouring groups of two inputs, as a
    /// beam's node couples its neighbours' positions and rates), one output depending on
    /// nothing: its packed pass carries three groups' lanes, and its Jacobian equals, bit for
    /// bit, the one from a single-lane pass per input (no packing possible there).
    #[test]
    fn a_banded_jacobian_packs_into_three_groups_and_unpacks_exactly() {
        let nodes = 9;
        let x0: Vec<f64> = (0..2 * nodes).map(|k| 0.3 + 0.17 * k as f64).collect();
        let tape = record(&x0, |v| {
            let mut out: Vec<_> = (0..nodes)
                .map(|i| {
                    let (q, r) = (v[2 * i], v[2 * i + 1]);
                    let mut y = q.sin() * r + q * q;
                    if i > 0 {
                        y += v[2 * i - 2] * q - v[2 * i - 1].cos();
                    }
                    if i + 1 < nodes {
                        y += (v[2 * i + 2] - q).exp() * v[2 * i + 3];
                    }
                    y
                })
                .collect();
            out.push(v[0] * 0.0 + 1.5);
            Some(out)
        })
        .expect("records")
        .finish(&(0..=nodes).collect::<Vec<_>>());
        let lanes = 2 * nodes;
        let seeds: Vec<(usize, usize)> = (0..lanes).map(|k| (k, k)).collect();
        let packed = tape.seeding_in_groups(&seeds, (lanes, 2), nodes + 1);
        assert_eq!(packed.packing.as_ref().map(|p| p.packed), Some(6));
        assert_eq!(packed.lanes(), lanes);
        let (values, d) = tape.forward(&[], &x0, &packed, &mut Forward::default());
        for l in 0..lanes {
            let one = tape.seeding(&[(l, 0)], 1, nodes + 1);
            assert!(one.packing.is_none());
            let (v1, d1) = tape.forward(&[], &x0, &one, &mut Forward::default());
            assert_eq!(v1, values);
            for (k, d1) in d1.iter().enumerate() {
                assert_eq!(
                    d[k * lanes + l].to_bits(),
                    d1.to_bits(),
                    "output {k}, lane {l}"
                );
            }
        }
        // Lanes of different groups of a dense program are not packed.
        let dense = record(&x0[..4], |v| Some(vec![v[0] * v[3], v[1] + v[2]]))
            .expect("records")
            .finish(&[0, 1]);
        let s: Vec<(usize, usize)> = (0..4).map(|k| (k, k)).collect();
        assert!(dense.seeding_in_groups(&s, (4, 2), 2).packing.is_none());
    }
}
