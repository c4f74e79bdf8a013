//! Roots of a scalar function on an interval: a scan for sign changes refined by bisection
//! (where the pieces of a line integral are split).

/// Sub-points per piece scanned for sign changes.
const SCAN: usize = 8;

/// The roots of `f` in `(a, b)`: sign changes on a scan of [`SCAN`] sub-intervals, refined by
/// bisection to rounding.
pub(super) fn roots_in(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64) -> Vec<f64> {
    // Far from zero at both ends and the middle against the curvature there: no root (the
    // interpolants are low-degree polynomials over one node interval).
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let same = (fa < 0.0) == (fm < 0.0) && (fm < 0.0) == (fb < 0.0);
    if same && fa.abs().min(fm.abs()).min(fb.abs()) > 2.0 * (fa - 2.0 * fm + fb).abs() {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut x0 = a;
    let mut f0 = f(a);
    for k in 1..=SCAN {
        let x1 = a + (b - a) * k as f64 / SCAN as f64;
        let f1 = f(x1);
        if f0.is_finite() && f1.is_finite() && (f0 < 0.0) != (f1 < 0.0) {
            out.push(bisect(f, x0, x1, f0));
        }
        (x0, f0) = (x1, f1);
    }
    out
}

/// One root of `f` in `[a, b]` (the one nearest the middle if several), if any.
pub(super) fn root_in(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64) -> Option<f64> {
    let mid = 0.5 * (a + b);
    roots_in(f, a, b)
        .into_iter()
        .min_by(|x, y| (x - mid).abs().total_cmp(&(y - mid).abs()))
}

fn bisect(f: &mut dyn FnMut(f64) -> f64, mut a: f64, mut b: f64, fa: f64) -> f64 {
    let neg = fa < 0.0;
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if (f(m) < 0.0) == neg {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_are_found_to_rounding() {
        let mut f = |t: f64| (t - 0.3) * (t + 0.7);
        let r = roots_in(&mut f, -1.0, 1.0);
        assert_eq!(r.len(), 2);
        assert!(
            (r[0] + 0.7).abs() < 1e-14 && (r[1] - 0.3).abs() < 1e-14,
            "{r:?}"
        );
    }
}
