//! Few Hessian-vector products for a sparse Hessian: the variables coloured so that one
//! product along the sum of a colour's unit vectors gives every entry of their columns.
//!
//! The parameters' own block of the second derivatives (the equilibrium held) is sparse in a
//! real tolerance stack: a spring the harmonic mean of two segments' stiffness couples two
//! variables, a density that multiplies every segment's mass couples with nothing (a mass enters
//! the equations linearly). Its pattern comes from the recorded operations
//! ([`crate::tape::Tape::hessian_pattern`]). Two variables may share a colour where no row has
//! a nonzero in both columns and they are not adjacent (a **distance-2 colouring** of the
//! pattern's graph, Curtis, Powell & Reid 1974; Gebremedhin, Manne & Pothen, *What color is
//! your Jacobian? Graph coloring for computing derivatives*, SIAM Review 47, 2005): then the
//! product along the colour, read at row `a`, is the entry of the one column of that colour
//! that row `a` has. A variable coupled with most others (a global factor that multiplies a
//! nonlinear term of every element: the hub of an arrow) would force every colour apart, so
//! such **hubs** get a product of their own, from which their whole row is read (by symmetry),
//! and are left out of the others' graph: the symmetric direct recovery that star colouring
//! formalises, taken for its most common case (Gebremedhin, Tarafdar, Manne & Pothen, *New
//! acyclic and star coloring algorithms with application to computing Hessians*, SIAM J. Sci.
//! Comput. 29, 2007). The number of hubs is chosen by trying: the fewest products win, and a
//! product per variable where nothing fewer is found (a dense pattern).

/// Each variable's product (its colour's, or its own for a hub) and whether it is a hub.
#[derive(Debug, Clone)]
pub(super) struct Colouring {
    direction: Vec<usize>,
    hub: Vec<bool>,
    adjacent: Vec<Vec<usize>>,
    /// Number of products.
    pub directions: usize,
}

/// Hubs tried at most, and tries without fewer products before giving up.
const MAX_HUBS: usize = 32;
const PATIENCE: usize = 4;

impl Colouring {
    /// The colouring of `nv` variables of which `adjacent(a, b)` (for `a ≠ b`) may have a
    /// nonzero mixed entry.
    pub fn new(nv: usize, adjacent: impl Fn(usize, usize) -> bool) -> Colouring {
        let lists: Vec<Vec<usize>> = (0..nv)
            .map(|a| (0..nv).filter(|&b| b != a && adjacent(a, b)).collect())
            .collect();
        // Largest degree first, for the hubs and for the greedy order.
        let mut order: Vec<usize> = (0..nv).collect();
        order.sort_by_key(|&a| std::cmp::Reverse(lists[a].len()));
        // Every variable a product of its own: the colouring to beat.
        let mut best = ((0..nv).collect::<Vec<_>>(), vec![true; nv], nv);
        let mut stale = 0;
        for hubs in 0..=nv.min(MAX_HUBS) {
            if hubs >= best.2 || stale >= PATIENCE {
                break;
            }
            let mut hub = vec![false; nv];
            for &a in &order[..hubs] {
                hub[a] = true;
            }
            // A distance-2 colouring needs more colours than any vertex has neighbours: where
            // that bound cannot beat the best, the greedy pass (quadratic in the degrees, slow
            // on a dense pattern) is not run.
            let degree = (0..nv)
                .filter(|&a| !hub[a])
                .map(|a| lists[a].iter().filter(|&&b| !hub[b]).count() + 1)
                .max()
                .unwrap_or(0);
            if hubs + degree >= best.2 {
                stale += 1;
                continue;
            }
            let (direction, count) = colour(&lists, &order, &hub);
            if count < best.2 {
                best = (direction, hub, count);
                stale = 0;
            } else {
                stale += 1;
            }
        }
        let (direction, hub, directions) = best;
        Colouring {
            direction,
            hub,
            adjacent: lists,
            directions,
        }
    }

    /// The product (by index) and the variable whose row of it holds entry `(a, b)`, or `None`
    /// where the entry is zero by the pattern.
    pub fn source(&self, a: usize, b: usize) -> Option<(usize, usize)> {
        if self.hub[a] {
            Some((self.direction[a], b))
        } else if self.hub[b] || a == b || self.adjacent[a].binary_search(&b).is_ok() {
            Some((self.direction[b], a))
        } else {
            None
        }
    }

    /// The variables of product `d`.
    pub fn members(&self, d: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.direction.len()).filter(move |&a| self.direction[a] == d)
    }
}

/// Greedy distance-2 colouring of the graph `lists` without the hubs (in `order`), the hubs
/// each a colour of their own after the others: each variable's colour, and the count.
fn colour(lists: &[Vec<usize>], order: &[usize], hub: &[bool]) -> (Vec<usize>, usize) {
    let nv = lists.len();
    let mut colour = vec![usize::MAX; nv];
    // `taken[c] == a + 1`: colour `c` is forbidden for variable `a`.
    let mut taken: Vec<usize> = Vec::new();
    let mut count = 0;
    for &a in order.iter().filter(|&&a| !hub[a]) {
        for &b in lists[a].iter().filter(|&&b| !hub[b]) {
            for c in std::iter::once(b).chain(lists[b].iter().copied()) {
                if !hub[c] && c != a && colour[c] != usize::MAX {
                    taken[colour[c]] = a + 1;
                }
            }
        }
        let free = (0..count).find(|&c| taken[c] != a + 1).unwrap_or(count);
        if free == count {
            count += 1;
            taken.push(0);
        }
        colour[a] = free;
    }
    for a in (0..nv).filter(|&a| hub[a]) {
        colour[a] = count;
        count += 1;
    }
    (colour, count)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every entry of a random sparse symmetric matrix with a dense row and column (an arrow)
    /// recovered exactly from the products along the colours, with fewer products than
    /// columns.
    #[test]
    fn the_products_along_the_colours_give_every_entry() {
        let nv = 30;
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as f64 / (1u64 << 31) as f64
        };
        // A band of two, a few random couplings, and variable 5 coupled with every other (a
        // global factor).
        let mut h = nalgebra::DMatrix::<f64>::zeros(nv, nv);
        for a in 0..nv {
            h[(a, a)] = next() + 0.5;
            for b in a + 1..nv {
                if b <= a + 2 || next() < 0.03 || a == 5 {
                    let v = next() - 0.5;
                    h[(a, b)] = v;
                    h[(b, a)] = v;
                }
            }
            if a != 5 {
                h[(a, 5)] = 0.25 + a as f64;
                h[(5, a)] = h[(a, 5)];
            }
        }
        let colouring = Colouring::new(nv, |a, b| h[(a, b)] != 0.0);
        assert!(
            colouring.directions < nv / 2,
            "{} products for {nv} columns",
            colouring.directions
        );
        let products: Vec<Vec<f64>> = (0..colouring.directions)
            .map(|d| {
                let members: Vec<usize> = colouring.members(d).collect();
                (0..nv)
                    .map(|r| members.iter().map(|&c| h[(r, c)]).sum())
                    .collect()
            })
            .collect();
        for a in 0..nv {
            for b in 0..nv {
                let got = colouring
                    .source(a, b)
                    .map_or(0.0, |(d, row)| products[d][row]);
                assert_eq!(got.to_bits(), h[(a, b)].to_bits(), "({a}, {b})");
            }
        }
    }

    /// A dense pattern keeps a product per variable (every entry read from its own column),
    /// found without the greedy passes; no variables, no products.
    #[test]
    fn a_dense_pattern_keeps_a_product_per_variable() {
        let nv = 400;
        let colouring = Colouring::new(nv, |_, _| true);
        assert_eq!(colouring.directions, nv);
        for (a, b) in [(0, 0), (3, 399), (399, 3), (17, 18)] {
            assert_eq!(colouring.source(a, b), Some((a, b)));
        }
        assert_eq!(Colouring::new(0, |_, _| true).directions, 0);
    }
}
