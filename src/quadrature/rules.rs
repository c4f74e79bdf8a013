//! The rules a case is integrated by: the transverse points of the lines (one line, the
//! Gauss–Hermite tensor rule, scrambled Sobol replicates) and the nested node grids along them.

use crate::linalg::gauss_hermite;
use statrs::distribution::{ContinuousCDF, Normal};

/// Half-width of the node grid along a line in standard deviations (normal mass outside:
/// 2·10⁻⁹).
const HALF_WIDTH: f64 = 6.0;

/// A case's rule: the transverse rule, its lines, the node levels along them and how many
/// lines of each replicate are in use at most.
pub(super) struct Rule {
    pub transverse: Transverse,
    pub lines: Vec<Line>,
    pub levels: Levels,
    /// Lines per replicate: at the start and at most (1 and 1 but for the scrambled rule).
    pub per: (usize, usize),
    /// The most nodes asked for ([`super::QuadOptions::nodes`]; `None`: the rule's own
    /// budget).
    pub asked: Option<usize>,
}

/// How far a rule is refined: the node level along the lines, and the lines per replicate in
/// use (those of rank below it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Stage {
    pub level: usize,
    pub per: usize,
}

impl Rule {
    /// The first stage.
    pub fn first(&self) -> Stage {
        Stage {
            level: self.levels.first,
            per: self.per.0,
        }
    }

    /// Is `line` in use at `stage`?
    pub fn uses(&self, line: &Line, stage: Stage) -> bool {
        match self.transverse {
            Transverse::Tensor => line.rank == stage.per || line.rank + 1 == stage.per,
            _ => line.rank < stage.per,
        }
    }

    /// Does `line` only check the transverse error at `stage` (a line of the tensor rule of the
    /// order below the one in use)?
    pub fn checks(&self, line: &Line, stage: Stage) -> bool {
        self.transverse == Transverse::Tensor && line.rank + 1 == stage.per
    }

    /// The weight of `line` at `stage`: a scrambled replicate's lines share its weight equally.
    pub fn weight(&self, line: &Line, stage: Stage) -> f64 {
        match self.transverse {
            Transverse::Scrambled { replicates } => 1.0 / (replicates * stage.per) as f64,
            _ => line.weight,
        }
    }

    /// Nodes swept at most: every node of the finest grid on the lines of every stage (the
    /// first level's on lines that only check), and at most the nodes asked for, or by
    /// default [`NODE_BUDGET`] for the scrambled rule and [`TENSOR_BUDGET`] for the tensor
    /// rule; never fewer than the first stage's.
    pub fn budget(&self) -> usize {
        let finest = Levels::nodes(self.levels.last);
        let all: usize = self
            .lines
            .iter()
            .map(|l| {
                let main = (self.per.0..=self.per.1).any(|per| {
                    let stage = Stage { level: 0, per };
                    self.uses(l, stage) && !self.checks(l, stage)
                });
                if main {
                    finest
                } else {
                    Levels::nodes(self.levels.first)
                }
            })
            .sum();
        let cap = match (self.asked, self.transverse) {
            (Some(n), _) => n,
            (None, Transverse::Tensor) => TENSOR_BUDGET,
            (None, Transverse::Scrambled { .. }) => NODE_BUDGET,
            (None, Transverse::Single) => all,
        };
        all.min(cap.max(self.nodes(self.first())))
    }

    /// Nodes swept once the rule is refined to `stage` (the lines of earlier stages
    /// included).
    pub fn nodes(&self, stage: Stage) -> usize {
        self.lines
            .iter()
            .map(|l| {
                (self.per.0..=stage.per)
                    .filter(|&per| self.uses(l, Stage { per, ..stage }))
                    .map(|per| {
                        let at = Stage { per, ..stage };
                        Levels::nodes(if self.checks(l, at) {
                            self.levels.first
                        } else {
                            stage.level
                        })
                    })
                    .max()
                    .unwrap_or(0)
            })
            .sum()
    }

    /// The rule in words, for `d` variables, refined to `stage`, `swept` nodes.
    pub fn describe(&self, d: usize, stage: Stage, swept: usize) -> String {
        let lines = &self.lines;
        format!(
            "{d} variable(s); {}; {} node(s) per line; {swept} nodes swept",
            match self.transverse {
                Transverse::Single => "one line".to_string(),
                Transverse::Tensor => format!(
                    "{} lines ({}-point Gauss–Hermite tensor, checked by the {}-point rule)",
                    lines.iter().filter(|l| l.rank == stage.per).count(),
                    TENSOR_ORDERS[stage.per],
                    TENSOR_ORDERS[stage.per - 1]
                ),
                Transverse::Scrambled { replicates } => format!(
                    "{} lines ({replicates} scrambled Sobol replicates of {}; the second-order \
                     expansion as control variate)",
                    replicates * stage.per,
                    stage.per
                ),
            },
            Levels::nodes(stage.level)
        ) + &match self.asked {
            Some(n) if n < self.nodes(self.first()) => format!(
                " (the rule's first stage needs {} nodes, more than the {n} asked for)",
                self.nodes(self.first())
            ),
            _ => String::new(),
        }
    }
}

/// The transverse rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Transverse {
    /// One variable: a single line.
    Single,
    /// Tensor Gauss–Hermite (3 points at first, then 5 and 7), checked by the rule of the order
    /// below.
    Tensor,
    /// Scrambled Sobol replicates.
    Scrambled { replicates: usize },
}

/// One line: its transverse point and weight (a scrambled line's is [`Rule::weight`]); a
/// scrambled line's replicate and its rank in the replicate's sequence, a tensor line's order
/// (the index into [`TENSOR_ORDERS`]).
#[derive(Debug, Clone)]
pub(super) struct Line {
    pub y: Vec<f64>,
    pub weight: f64,
    pub replicate: usize,
    pub rank: usize,
}

/// Node grids along a line: `2^k + 1` points, nested.
#[derive(Debug, Clone, Copy)]
pub(super) struct Levels {
    pub first: usize,
    pub last: usize,
}

impl Levels {
    /// Nodes at level `k` (stride in the finest grid follows).
    pub fn nodes(k: usize) -> usize {
        (1 << k) + 1
    }
}

/// Position of node `j` of an `n`-node grid on `[−6, 6]`.
pub(super) fn grid(n: usize, j: usize) -> f64 {
    -HALF_WIDTH + 2.0 * HALF_WIDTH * j as f64 / (n - 1) as f64
}

/// The rule for `d` variables, sweeping at most `asked` nodes where given (never fewer than
/// its first stage's).
pub(super) fn design(d: usize, asked: Option<usize>) -> Rule {
    let (transverse, lines, levels) = design_parts(d);
    Rule {
        transverse,
        lines,
        levels,
        asked,
        per: match transverse {
            Transverse::Scrambled { .. } => (FIRST_PER_REPLICATE, LINES_PER_REPLICATE),
            Transverse::Tensor => (1, TENSOR_ORDERS.len() - 1),
            Transverse::Single => (1, 1),
        },
    }
}

/// The orders of the tensor Gauss–Hermite rules across the lines with two to four variables:
/// the 3-point rule at first, checked by the 2-point one; where the transverse error is what
/// misses the request, the 5-point rule checked by the 3-point one, then the 7-point rule.
pub(super) const TENSOR_ORDERS: [usize; 4] = [2, 3, 5, 7];

/// Nodes the tensor rule sweeps at most: the default Monte Carlo's samples.
const TENSOR_BUDGET: usize = 3000;

/// Nodes the many-variable rule sweeps at most: a tenth of the default Monte Carlo. Its
/// transverse error falls with the lines as the randomised QMC's does on the residual of the
/// control variate, between `N⁻¹` (smooth) and the Monte Carlo's `N^-½` (modes veering, a
/// change of class across the lines); where the request needs more, the rows say so.
pub(super) const NODE_BUDGET: usize = 300;

/// Scrambled Sobol replicates of the many-variable rule.
const REPLICATES: usize = 8;
/// Lines per replicate at first, and at most (the first 2ᵐ points of a scrambled Sobol
/// sequence are a net: each doubling keeps the lines swept before).
const FIRST_PER_REPLICATE: usize = 2;
const LINES_PER_REPLICATE: usize = 16;

/// The transverse rule, its lines and the node levels for `d` variables.
fn design_parts(d: usize) -> (Transverse, Vec<Line>, Levels) {
    match d {
        1 => (
            Transverse::Single,
            vec![Line {
                y: Vec::new(),
                weight: 1.0,
                replicate: 0,
                rank: 0,
            }],
            Levels { first: 5, last: 7 },
        ),
        2..=4 => {
            let lines = TENSOR_ORDERS
                .iter()
                .enumerate()
                .flat_map(|(order, &n)| {
                    let (x, w) = gauss_hermite(n);
                    tensor(d - 1, &x, &w, order)
                })
                .collect();
            (Transverse::Tensor, lines, Levels { first: 4, last: 5 })
        }
        _ => {
            let (replicates, per) = (REPLICATES, LINES_PER_REPLICATE);
            let normal = Normal::standard();
            let lines = (0..replicates)
                .flat_map(|r| {
                    (0..per).map(move |i| Line {
                        y: (0..d - 1)
                            .map(|k| {
                                let u = sobol_burley::sample(i as u32, k as u32, 0x5eed + r as u32)
                                    as f64
                                    + 0.5 / (1u64 << 24) as f64;
                                normal.inverse_cdf(u.clamp(1e-12, 1.0 - 1e-12))
                            })
                            .collect(),
                        // Depends on the stage: [`Rule::weight`].
                        weight: f64::NAN,
                        replicate: r,
                        rank: i,
                    })
                })
                .collect();
            (
                Transverse::Scrambled { replicates },
                lines,
                Levels { first: 2, last: 4 },
            )
        }
    }
}

/// Tensor product of a 1-D rule in `dims` dimensions, its lines of tensor order `order`.
fn tensor(dims: usize, nodes: &[f64], weights: &[f64], order: usize) -> Vec<Line> {
    let mut lines = vec![Line {
        y: Vec::new(),
        weight: 1.0,
        replicate: 0,
        rank: order,
    }];
    for _ in 0..dims {
        lines = lines
            .into_iter()
            .flat_map(|l| {
                nodes.iter().zip(weights).map(move |(&x, &w)| {
                    let mut y = l.y.clone();
                    y.push(x);
                    Line {
                        y,
                        weight: l.weight * w,
                        replicate: 0,
                        rank: order,
                    }
                })
            })
            .collect();
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tensor_rules_integrate_low_degree_moments() {
        // E[y₁² y₂²] = 1 and E[y₁⁴] = 3 for the 3-point rule; E[y₁²] = 1 for the 2-point rule.
        let rule = |n: usize| {
            let (x, w) = gauss_hermite(n);
            tensor(2, &x, &w, 0)
        };
        let e = |r: &[Line], f: &dyn Fn(&[f64]) -> f64| {
            r.iter().map(|l| l.weight * f(&l.y)).sum::<f64>()
        };
        let r3 = rule(3);
        assert!((e(&r3, &|y| y[0] * y[0] * y[1] * y[1]) - 1.0).abs() < 1e-14);
        assert!((e(&r3, &|y| y[0].powi(4)) - 3.0).abs() < 1e-14);
        assert!((e(&rule(2), &|y| y[1] * y[1]) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn gauss_hermite_rules_are_exact_to_their_degree() {
        // E[y²ᵏ] = (2k − 1)!! up to degree 2n − 1; the 5-point rule in closed form:
        // 0, ±√(5 ∓ √10) with weights 8/15, (7 ± 2√10)/60.
        for n in [2, 3, 5, 7] {
            let (x, w) = gauss_hermite(n);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{n}");
            let mut double_factorial = 1.0;
            for k in 1..n {
                double_factorial *= (2 * k - 1) as f64;
                let m: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(2 * k as i32))
                    .sum();
                assert!(
                    (m / double_factorial - 1.0).abs() < 1e-12,
                    "{n}: degree {}",
                    2 * k
                );
                let odd = |f: fn(f64) -> f64| -> f64 {
                    x.iter()
                        .zip(&w)
                        .map(|(x, w)| w * f(x.powi(2 * k as i32 - 1)))
                        .sum()
                };
                // Zero to rounding of the terms' size.
                assert!(
                    odd(|v| v).abs() < 1e-13 * odd(f64::abs),
                    "{n}: degree {}",
                    2 * k - 1
                );
            }
        }
        let (x, w) = gauss_hermite(5);
        let r10 = 10f64.sqrt();
        assert!(
            (x[3] - (5.0 - r10).sqrt()).abs() < 1e-13 && (x[4] - (5.0 + r10).sqrt()).abs() < 1e-13
        );
        assert!(
            (w[2] - 8.0 / 15.0).abs() < 1e-14 && (w[4] - (7.0 - 2.0 * r10) / 60.0).abs() < 1e-14
        );
    }
}
