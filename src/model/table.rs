//! Tabulated functions of one argument (`[[tables]]`): a bearing's coefficients measured at a
//! few speeds, called in any expression as `name(speed)`.
//!
//! A table is interpolated by the shape-preserving piecewise cubic Hermite interpolant (PCHIP;
//! Fritsch & Carlson 1980, with the slopes of Fritsch & Butland 1984 as SciPy's
//! `PchipInterpolator` takes them): it never overshoots the data (a stiffness tabulated
//! positive stays positive), it is continuous with its first derivative, so the sensitivities
//! and the speed derivatives through it exist everywhere, and beyond the table it continues as
//! the straight line of its end slope. This is what ROSS (3.1) does with a bearing's
//! coefficient tables, so the same table gives the same rotor in both. Two points give the
//! straight line through them.
//!
//! The second derivative jumps at the knots (PCHIP is C¹, not C²); at a knot the Hessian
//! through a table takes the side above it. A table called with an argument that depends only
//! on the speed (the usual case) reaches no parameter, and no Hessian sees it.
//!
//! The interpolant is evaluated without a branch on the argument, so the recorded program of
//! the equations holds it at every speed: with `u_k = clamp(x, x_k, x_{k+1}) − x_k`, written
//! `(|x − x_k| − |x − x_{k+1}| + h_k)/2`, the value is
//!
//! ```text
//! S(x) = y_0 + d_0 min(x − x_0, 0) + Σ_k u_k (d_k + u_k (α_k + u_k β_k)) + d_n max(x − x_n, 0)
//! ```
//!
//! each interval's cubic increment from its left knot (its full rise `y_{k+1} − y_k` once `x`
//! is past it), with no cancellation between terms larger than the data.

use crate::real::{Real, cst};

/// The most points a table takes: each call of it records a few operations per interval.
pub const MAX_POINTS: usize = 1000;

/// A table's two lists: the argument's values and the function's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Column {
    X,
    Y,
}

/// A tabulated function with its interpolant's coefficients.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Table {
    pub name: String,
    /// The argument's values, strictly increasing.
    pub x: Vec<f64>,
    /// The function's values.
    pub y: Vec<f64>,
    /// The interpolant's slope at each knot.
    slope: Vec<f64>,
}

impl Table {
    /// The table of `y` at `x`; else the list at fault and what is wrong with it (fewer than
    /// two points, lists of different lengths, a value that is not finite, an argument not
    /// strictly increasing).
    pub fn new(name: &str, x: Vec<f64>, y: Vec<f64>) -> Result<Table, (Column, String)> {
        if x.len() != y.len() {
            let e = format!(
                "x has {} values and y {}: give one value of y per x",
                x.len(),
                y.len()
            );
            return Err((Column::Y, e));
        }
        if x.len() < 2 {
            return Err((Column::X, "a table needs at least two points".into()));
        }
        if x.len() > MAX_POINTS {
            let e = format!(
                "{} points; a table takes at most {MAX_POINTS} (every call evaluates each interval)",
                x.len()
            );
            return Err((Column::X, e));
        }
        if let Some((i, v)) = (x.iter().chain(&y).enumerate()).find(|(_, v)| !v.is_finite()) {
            let (list, name, at) = if i < x.len() {
                (Column::X, "x", i)
            } else {
                (Column::Y, "y", i - x.len())
            };
            return Err((list, format!("{name}[{at}] = {v} is not finite")));
        }
        if let Some(k) = (1..x.len()).find(|&k| x[k] <= x[k - 1]) {
            let e = format!(
                "x must increase strictly, but x[{k}] = {} follows x[{}] = {}",
                x[k],
                k - 1,
                x[k - 1]
            );
            return Err((Column::X, e));
        }
        let slope = pchip_slopes(&x, &y);
        Ok(Table {
            name: name.to_string(),
            x,
            y,
            slope,
        })
    }

    /// The interpolant at `x` (see the module documentation), over any [`Real`].
    pub fn eval<T: Real>(&self, x: T) -> T {
        let (xs, ys, d) = (&self.x, &self.y, &self.slope);
        let n = xs.len() - 1;
        let half = cst::<T>(0.5);
        let below = x - cst::<T>(xs[0]);
        let above = x - cst::<T>(xs[n]);
        let mut s = cst::<T>(ys[0])
            + (below - below.abs()) * half * cst::<T>(d[0])
            + (above + above.abs()) * half * cst::<T>(d[n]);
        for k in 0..n {
            let h = xs[k + 1] - xs[k];
            let m = (ys[k + 1] - ys[k]) / h;
            let alpha = (3.0 * m - 2.0 * d[k] - d[k + 1]) / h;
            let beta = (d[k] + d[k + 1] - 2.0 * m) / (h * h);
            let u = ((x - cst::<T>(xs[k])).abs() - (x - cst::<T>(xs[k + 1])).abs() + cst::<T>(h))
                * half;
            s += u * (cst::<T>(d[k]) + u * (cst::<T>(alpha) + u * cst::<T>(beta)));
        }
        s
    }
}

/// PCHIP's slopes at the knots: zero where the data turn (or are flat) on either side, else
/// the weighted harmonic mean of the neighbouring secants; at the ends the one-sided
/// three-point estimate, held to the shape (Fritsch & Butland 1984; SciPy's
/// `PchipInterpolator`). Two points: the secant at both.
fn pchip_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let m: Vec<f64> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / h[k]).collect();
    if n == 2 {
        return vec![m[0], m[0]];
    }
    let mut d = vec![0.0; n];
    for k in 1..n - 1 {
        if m[k - 1] * m[k] > 0.0 {
            let w1 = 2.0 * h[k] + h[k - 1];
            let w2 = h[k] + 2.0 * h[k - 1];
            d[k] = (w1 + w2) / (w1 / m[k - 1] + w2 / m[k]);
        }
    }
    let end = |h0: f64, h1: f64, m0: f64, m1: f64| {
        let d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
        if d.signum() != m0.signum() || m0 == 0.0 {
            0.0
        } else if m0.signum() != m1.signum() && d.abs() > 3.0 * m0.abs() {
            3.0 * m0
        } else {
            d
        }
    };
    d[0] = end(h[0], h[1], m[0], m[1]);
    d[n - 1] = end(h[n - 2], h[n - 3], m[n - 2], m[n - 3]);
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{Dual2_64, Dual64};

    #[test]
    fn reproduces_the_data_a_line_and_extends_by_the_end_slopes() {
        let t = Table::new("t", vec![0.0, 1.0, 3.0, 4.0], vec![1.0, 2.0, 2.5, 5.0]).unwrap();
        for (x, y) in t.x.iter().zip(&t.y) {
            assert!((t.eval(*x) - y).abs() <= 1e-15 * y.abs().max(1.0));
        }
        // Monotone data stay monotone between the knots (no overshoot).
        let mut last = t.eval(0.0f64);
        for i in 1..=400 {
            let v = t.eval(4.0 * i as f64 / 400.0);
            assert!(v >= last - 1e-15, "not monotone at {i}");
            last = v;
        }
        // A line is reproduced exactly, inside and beyond.
        let line = Table::new("l", vec![0.0, 2.0, 5.0, 9.0], vec![1.0, 5.0, 11.0, 19.0]).unwrap();
        for x in [-3.0f64, 0.5, 2.0, 4.2, 9.0, 12.0] {
            assert!(
                (line.eval(x) - (1.0 + 2.0 * x)).abs() <= 1e-14 * 25.0,
                "{x}"
            );
        }
        // Beyond the ends: the straight line of the end slope.
        let (lo, hi) = (t.slope[0], t.slope[3]);
        assert!((t.eval(-2.0f64) - (1.0 - 2.0 * lo)).abs() <= 1e-14);
        assert!((t.eval(6.0f64) - (5.0 + 2.0 * hi)).abs() <= 1e-14);
    }

    #[test]
    fn slopes_are_scipys_pchip() {
        // scipy.interpolate.PchipInterpolator(x, y).derivative()(x) (SciPy 1.18.1):
        // [1.25, 0.42857142857142855, 0.5, 3.25]; by hand: secants 1, 0.25, 2.5; interior
        // harmonic means with weights (2h_k + h_{k−1}, h_k + 2h_{k−1}): 9/(5 + 16) = 3/7 and
        // 9/(16 + 2) = 1/2; ends ((2h₀ + h₁)m₀ − h₀m₁)/(h₀ + h₁): 3.75/3 and 9.75/3.
        let t = Table::new("t", vec![0.0, 1.0, 3.0, 4.0], vec![1.0, 2.0, 2.5, 5.0]).unwrap();
        let want = [1.25, 3.0 / 7.0, 0.5, 3.25];
        for (a, b) in t.slope.iter().zip(want) {
            assert!((a - b).abs() <= 1e-15, "{a} vs {b}");
        }
        // SciPy's values between the knots: p(2.0) = 2.23214286, p(0.3) = 1.37275.
        assert!((t.eval(2.0f64) - 2.232142857142857).abs() <= 1e-12);
        assert!((t.eval(0.3f64) - 1.37275).abs() <= 1e-12);
        // A turning point gets a zero slope (SciPy: [2, 0, −2]), and an end estimate more
        // than three secants steep where the data turn is held to three (SciPy: 3).
        let peak = Table::new("p", vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 0.0]).unwrap();
        for (a, b) in peak.slope.iter().zip([2.0, 0.0, -2.0]) {
            assert!((a - b).abs() <= 1e-15, "{a} vs {b}");
        }
        let steep = Table::new("s", vec![0.0, 1.0, 1.1], vec![0.0, 1.0, 0.0]).unwrap();
        assert!((steep.slope[0] - 3.0).abs() <= 1e-15);
    }

    #[test]
    fn first_and_second_derivatives_are_the_pieces_own() {
        let t = Table::new("t", vec![0.0, 1.0, 3.0, 4.0], vec![1.0, 2.0, 2.5, 5.0]).unwrap();
        // Inside interval 1 ([1, 3]), the Hermite cubic written out.
        let (x0, h, y0, y1, d0, d1) = (1.0, 2.0, 2.0, 2.5, t.slope[1], t.slope[2]);
        let cubic = |x: f64| {
            let s = (x - x0) / h;
            let h00 = 2.0 * s.powi(3) - 3.0 * s * s + 1.0;
            let h10 = s.powi(3) - 2.0 * s * s + s;
            let h01 = -2.0 * s.powi(3) + 3.0 * s * s;
            let h11 = s.powi(3) - s * s;
            h00 * y0 + h10 * h * d0 + h01 * y1 + h11 * h * d1
        };
        for x in [1.3, 2.0, 2.9] {
            let v = t.eval(Dual2_64::new(x, 1.0, 0.0));
            // Central differences of a cubic: the second is exact but for rounding.
            let (e1, e2) = (1e-5, 1e-3);
            let fd1 = (cubic(x + e1) - cubic(x - e1)) / (2.0 * e1);
            let fd2 = (cubic(x + e2) - 2.0 * cubic(x) + cubic(x - e2)) / (e2 * e2);
            assert!((v.re - cubic(x)).abs() <= 1e-14);
            assert!((v.v1 - fd1).abs() <= 1e-8, "{} vs {fd1}", v.v1);
            assert!((v.v2 - fd2).abs() <= 1e-8, "{} vs {fd2}", v.v2);
        }
        // At a knot the slope is the knot's, from either side.
        for k in 0..4 {
            let v = t.eval(Dual64::new(t.x[k], 1.0));
            assert!((v.eps - t.slope[k]).abs() <= 1e-14, "knot {k}");
        }
    }

    #[test]
    fn bad_tables_are_refused_with_the_reason() {
        let e = |x: Vec<f64>, y: Vec<f64>| Table::new("t", x, y).unwrap_err().1;
        assert!(e(vec![0.0, 2.0, 1.0], vec![1.0; 3]).contains("x[2] = 1 follows x[1] = 2"));
        assert!(e(vec![0.0, 0.0], vec![1.0; 2]).contains("increase strictly"));
        assert!(e(vec![0.0], vec![1.0]).contains("at least two points"));
        let many: Vec<f64> = (0..=MAX_POINTS).map(|i| i as f64).collect();
        assert!(e(many.clone(), many).contains("1001 points; a table takes at most 1000"));
        assert!(e(vec![0.0, 1.0], vec![1.0]).contains("one value of y per x"));
        assert!(e(vec![0.0, 1.0], vec![1.0, f64::NAN]).contains("y[1] = NaN is not finite"));
    }
}
