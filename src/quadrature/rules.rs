//! The rules a case is integrated by: the transverse points of the lines (one line, the
//! Gauss–Hermite tensor rule, scrambled Sobol replicates) and the nested node grids along them.

use statrs::distribution::{ContinuousCDF, Normal};

/// Half-width of the node grid along a line in standard deviations (normal mass outside:
/// 2·10⁻⁹).
const HALF_WIDTH: f64 = 6.0;

/// A case's rule: the transverse rule, its lines, and the node levels along them.
pub(super) struct Rule {
    pub transverse: Transverse,
    pub lines: Vec<Line>,
    pub levels: Levels,
}

impl Rule {
    /// Nodes swept at most: every node of the finest grid on the main lines, the first
    /// level's on the check lines.
    pub fn budget(&self) -> usize {
        let finest = Levels::nodes(self.levels.last);
        self.lines
            .iter()
            .map(|l| {
                if l.check {
                    Levels::nodes(self.levels.first)
                } else {
                    finest
                }
            })
            .sum()
    }

    /// The rule in words, for `d` variables and `swept` nodes.
    pub fn describe(&self, d: usize, swept: usize) -> String {
        let lines = &self.lines;
        format!(
            "{d} variable(s); {}; {} node(s) per line at most; {swept} nodes swept",
            match self.transverse {
                Transverse::Single => "one line".to_string(),
                Transverse::Tensor => format!(
                    "{} lines (3-point Gauss–Hermite tensor, checked by the 2-point rule)",
                    lines.iter().filter(|l| !l.check).count()
                ),
                Transverse::Scrambled { replicates } => format!(
                    "{} lines ({replicates} scrambled Sobol replicates)",
                    lines.len()
                ),
            },
            Levels::nodes(self.levels.last)
        )
    }
}

/// The transverse rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Transverse {
    /// One variable: a single line.
    Single,
    /// Tensor Gauss–Hermite (3 points), checked by the 2-point rule.
    Tensor,
    /// Scrambled Sobol replicates.
    Scrambled { replicates: usize },
}

/// One line: its transverse point and weight; `check` lines belong to the 2-point
/// Gauss–Hermite rule that only checks the transverse error.
#[derive(Debug, Clone)]
pub(super) struct Line {
    pub y: Vec<f64>,
    pub weight: f64,
    pub check: bool,
    pub replicate: usize,
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

/// The rule for `d` variables.
pub(super) fn design(d: usize) -> Rule {
    let (transverse, lines, levels) = design_parts(d);
    Rule {
        transverse,
        lines,
        levels,
    }
}

/// The transverse rule, its lines and the node levels for `d` variables.
fn design_parts(d: usize) -> (Transverse, Vec<Line>, Levels) {
    match d {
        1 => (
            Transverse::Single,
            vec![Line {
                y: Vec::new(),
                weight: 1.0,
                check: false,
                replicate: 0,
            }],
            Levels { first: 5, last: 7 },
        ),
        2..=4 => {
            let mut lines = tensor(
                d - 1,
                &[-3f64.sqrt(), 0.0, 3f64.sqrt()],
                &[1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
                false,
            );
            lines.extend(tensor(d - 1, &[-1.0, 1.0], &[0.5, 0.5], true));
            (Transverse::Tensor, lines, Levels { first: 4, last: 5 })
        }
        _ => {
            let (replicates, per) = (8, 16);
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
                        weight: 1.0 / (replicates * per) as f64,
                        check: false,
                        replicate: r,
                    })
                })
                .collect();
            (
                Transverse::Scrambled { replicates },
                lines,
                Levels { first: 3, last: 4 },
            )
        }
    }
}

/// Tensor product of a 1-D rule in `dims` dimensions.
fn tensor(dims: usize, nodes: &[f64], weights: &[f64], check: bool) -> Vec<Line> {
    let mut lines = vec![Line {
        y: Vec::new(),
        weight: 1.0,
        check,
        replicate: 0,
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
                        check,
                        replicate: 0,
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
        let r3 = tensor(
            2,
            &[-3f64.sqrt(), 0.0, 3f64.sqrt()],
            &[1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
            false,
        );
        let e = |r: &[Line], f: &dyn Fn(&[f64]) -> f64| {
            r.iter().map(|l| l.weight * f(&l.y)).sum::<f64>()
        };
        assert!((e(&r3, &|y| y[0] * y[0] * y[1] * y[1]) - 1.0).abs() < 1e-14);
        assert!((e(&r3, &|y| y[0].powi(4)) - 3.0).abs() < 1e-14);
        let r2 = tensor(2, &[-1.0, 1.0], &[0.5, 0.5], true);
        assert!((e(&r2, &|y| y[1] * y[1]) - 1.0).abs() < 1e-14);
        assert!(r2.iter().all(|l| l.check));
    }
}
