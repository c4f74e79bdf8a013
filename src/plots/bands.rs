//! Where the band plots mark the paper's first-order method as off: the speeds where its σ is
//! more than 10 % off the quadrature's. Public because the report lists the same speeds.

use super::series;
use crate::analyze::{Analysis, Method};
use crate::tolerance::Quantity;

/// Speeds where first order's σ is more than 10 % off the quadrature's (the quadrature's σ
/// at least 2 % of its largest): `(speed, first-order mean)` there, NaN elsewhere.
pub fn first_order_off(
    a: &Analysis,
    case: usize,
    q: Quantity,
    mode: Option<usize>,
) -> Vec<(f64, f64)> {
    let quad = series(a, case, q, mode, Method::Quadrature);
    let first = series(a, case, q, mode, Method::FirstOrder);
    let largest = quad.iter().map(|r| r.std).fold(0.0f64, f64::max);
    quad.iter()
        .map(|r| {
            let f = first
                .iter()
                .find(|f| f.speed.to_bits() == r.speed.to_bits());
            let off = f.is_some_and(|f| {
                r.std >= 0.02 * largest && ((f.std - r.std).abs() > 0.1 * r.std || f.std.is_nan())
            });
            (
                r.speed,
                if off {
                    f.map_or(f64::NAN, |f| f.mean)
                } else {
                    f64::NAN
                },
            )
        })
        .collect()
}
