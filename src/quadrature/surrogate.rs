//! Lines between the lines: the carriers interpolated across the lines of a tensor rule, for
//! integrals whose integrand is an indicator (the yield, the probability of a requirement).
//!
//! Along a line the boundary of a set (where a margin changes sign) is located exactly, so the
//! line's mass of the set, `g(y) = P(met | y)`, is exact at the line's transverse point `y`. As
//! a function of `y`, `g` is smooth but can be steep: a boundary crossed obliquely by the line
//! direction gives `g(y) ≈ Φ(a + b y)` with `|b|` as large as the cotangent of the angle
//! between them, which the 3- to 7-point Gauss–Hermite rule integrates to 10⁻³ or worse, and
//! the difference of two such rules does not bound. What is smooth and slowly varying in `y`
//! are the carriers themselves (the pair invariants `s, p` and |H|, on one branch). So the
//! carriers of a tensor rule of order `n` are interpolated across its lines (the tensor
//! Lagrange polynomial through its Gauss–Hermite points, exact for carriers polynomial of
//! degree below `n` in each transverse variable), and the set is integrated along *virtual*
//! lines at the points of a much finer Gauss–Hermite rule, each with its boundary located
//! exactly as on a real line: the surrogate-based failure probability of Li & Xiu (J. Comput.
//! Phys. 229, 2010), with the indicator preintegrated along the line (Griewank, Kuo, Leövey &
//! Sloan 2018). The surrogate converges with the interpolation of the carriers, spectrally
//! where they are smooth.
//!
//! Where the lines disagree at a node (different equilibrium branches, a failed node, a
//! carrier without a value), interpolating across them would mix branches: there the virtual
//! line takes the node of the nearest real line (a piecewise constant surrogate across the
//! lines), and the error estimate (the surrogate of the rule of the order below, and the
//! finer rule against its half) says what that costs.

use super::rules::{Line, Rule, TENSOR_ORDERS};
use super::{NodeData, Sweep};
use crate::linalg::gauss_hermite;

/// Points per transverse dimension of the virtual lines' rule, by the number of transverse
/// dimensions (1 to 3); its check is the rule of half as many points.
pub(super) const VIRTUAL_ORDERS: [usize; 3] = [32, 12, 8];

/// A rule of virtual lines: their transverse points and weights.
pub(super) struct VirtualRule {
    pub points: Vec<(Vec<f64>, f64)>,
}

impl VirtualRule {
    /// The tensor Gauss–Hermite rule of `n` points per dimension in `dims` dimensions.
    pub fn tensor(dims: usize, n: usize) -> VirtualRule {
        let (x, w) = gauss_hermite(n);
        let mut points = vec![(Vec::new(), 1.0)];
        for _ in 0..dims {
            points = points
                .into_iter()
                .flat_map(|(y, wy): (Vec<f64>, f64)| {
                    x.iter().zip(&w).map(move |(&xk, &wk)| {
                        let mut y = y.clone();
                        y.push(xk);
                        (y, wy * wk)
                    })
                })
                .collect();
        }
        VirtualRule { points }
    }

    /// The rule for `dims` transverse dimensions and its check (half the points per
    /// dimension).
    pub fn for_dims(dims: usize) -> (VirtualRule, VirtualRule) {
        let n = VIRTUAL_ORDERS[(dims.max(1) - 1).min(VIRTUAL_ORDERS.len() - 1)];
        (
            VirtualRule::tensor(dims, n),
            VirtualRule::tensor(dims, n / 2),
        )
    }
}

/// The 1-D Lagrange basis through `nodes` at `y`.
fn lagrange(nodes: &[f64], y: f64) -> Vec<f64> {
    (0..nodes.len())
        .map(|k| {
            nodes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != k)
                .map(|(_, &xj)| (y - xj) / (nodes[k] - xj))
                .product()
        })
        .collect()
}

/// The virtual lines at `virt`'s points, interpolated across the lines of `rule` of tensor rank
/// `rank` (the Gauss–Hermite rule of [`TENSOR_ORDERS`]`[rank]` points per dimension) at the
/// nodes of the finest grid taken every `stride`: a [`NodeData`] whose lines are the virtual
/// ones, the other nodes left unswept.
pub(super) fn interpolate(
    store: &NodeData,
    rule: &Rule,
    rank: usize,
    stride: usize,
    virt: &VirtualRule,
) -> NodeData {
    let order = TENSOR_ORDERS[rank];
    let real: Vec<(usize, &Line)> = rule
        .lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.rank == rank)
        .collect();
    let (nodes_1d, _) = gauss_hermite(order);
    let finest = store.data.first().map_or(0, |d| d.len());
    let (width, speeds) = (store.width, store.speeds);
    let data = virt
        .points
        .iter()
        .map(|(y, _)| {
            // The tensor Lagrange weight of each real line at `y`, and the nearest line.
            let basis: Vec<Vec<f64>> = y.iter().map(|&yk| lagrange(&nodes_1d, yk)).collect();
            let weights: Vec<f64> = real
                .iter()
                .map(|(_, l)| {
                    l.y.iter()
                        .enumerate()
                        .map(|(k, &yl)| {
                            let i = nodes_1d
                                .iter()
                                .position(|x| x.to_bits() == yl.to_bits())
                                .expect("a line of the rule sits at its nodes");
                            basis[k][i]
                        })
                        .product()
                })
                .collect();
            let nearest = real
                .iter()
                .map(|(li, l)| {
                    let d: f64 = l.y.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum();
                    (*li, d)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|x| x.0)
                .expect("the rule has lines");
            (0..finest)
                .map(|j| {
                    (j % stride == 0).then(|| {
                        let sweeps: Vec<&Sweep> = real
                            .iter()
                            .map(|(li, _)| store.data[*li][j].as_ref().expect("swept"))
                            .collect();
                        let near = store.data[nearest][j].as_ref().expect("swept");
                        let mut branch = vec![None; speeds];
                        let mut carriers = vec![f64::NAN; speeds * width];
                        for i in 0..speeds {
                            fn row(s: &Sweep, i: usize, width: usize) -> &[f64] {
                                &s.carriers[i * width..(i + 1) * width]
                            }
                            let b0 = sweeps[0].branch[i];
                            let agree = b0.is_some()
                                && sweeps.iter().all(|s| {
                                    s.branch[i] == b0
                                        && row(s, i, width).iter().all(|v| v.is_finite())
                                });
                            let out = &mut carriers[i * width..(i + 1) * width];
                            if agree {
                                branch[i] = b0;
                                out.fill(0.0);
                                for (s, w) in sweeps.iter().zip(&weights) {
                                    for (o, c) in out.iter_mut().zip(row(s, i, width)) {
                                        *o += w * c;
                                    }
                                }
                            } else {
                                branch[i] = near.branch[i];
                                out.copy_from_slice(row(near, i, width));
                            }
                        }
                        Sweep { branch, carriers }
                    })
                })
                .collect()
        })
        .collect();
    NodeData {
        width,
        speeds,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lagrange_basis_reproduces_polynomials_of_lower_degree() {
        let (x, _) = gauss_hermite(5);
        let f = |y: f64| 1.0 - 2.0 * y + 0.5 * y.powi(3) - 0.1 * y.powi(4);
        for y in [-6.0, -1.3, 0.0, 0.7, 4.2] {
            let l = lagrange(&x, y);
            let v: f64 = l.iter().zip(&x).map(|(l, &xk)| l * f(xk)).sum();
            assert!(
                (v - f(y)).abs() < 1e-10 * (1.0 + f(y).abs()),
                "{y}: {v} vs {}",
                f(y)
            );
        }
    }

    #[test]
    fn virtual_rules_integrate_a_steep_sigmoid() {
        // E[Φ(a + b y)] = Φ(a/√(1 + b²)) for a standard normal y.
        use statrs::distribution::{ContinuousCDF, Normal};
        let n = Normal::standard();
        let (a, b) = (1.2, 3.0);
        let (fine, check) = VirtualRule::for_dims(1);
        let e = |r: &VirtualRule| -> f64 {
            r.points.iter().map(|(y, w)| w * n.cdf(a + b * y[0])).sum()
        };
        let exact = n.cdf(a / (1.0 + b * b).sqrt());
        // A sigmoid this steep (b = 3) is what the 32-point rule resolves to 10⁻⁴ (seen:
        // 8.3·10⁻⁵); the carriers it is used on are far smoother than the indicator's mass.
        assert!((e(&fine) - exact).abs() < 1e-4, "{} vs {exact}", e(&fine));
        // The check's distance bounds the fine rule's error.
        assert!((e(&fine) - exact).abs() <= (e(&fine) - e(&check)).abs());
    }
}
