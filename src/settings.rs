//! Run settings as the command line and the Python package take them: one rule each, so that
//! the two front ends accept and refuse the same values for the same reasons. A rule's message
//! leaves the setting unnamed ("must lie in 2..=1000000000 (got 1)"): each front end puts its
//! own spelling in front (`--samples` on the command line, `samples` in Python).

use std::fmt::Display;

pub use crate::threads::{MAX_THREADS, ThreadsError, check as threads};

/// An operating speed or excitation frequency (rad/s): a finite number.
pub fn speed(w: f64) -> Result<f64, String> {
    if w.is_finite() {
        Ok(w)
    } else {
        Err(format!("must be finite (got {w})"))
    }
}

/// Speeds or frequencies given one by one (rad/s): at least one, each finite.
pub fn values(v: Vec<f64>) -> Result<Vec<f64>, String> {
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(format!("{x} is not finite"));
    }
    if v.is_empty() {
        return Err("no values".into());
    }
    Ok(v)
}

/// Largest number of Monte Carlo samples a run may ask for (beyond that the standard error
/// is far below any tolerance's meaning, and the sample index must fit the samplers' 32 bits).
pub const MAX_SAMPLES: usize = 1_000_000_000;

/// A number of Monte Carlo samples: 2 (a σ needs two) to [`MAX_SAMPLES`].
pub fn samples<N: TryInto<usize> + Copy + Display>(n: N) -> Result<usize, String> {
    n.try_into()
        .ok()
        .filter(|n| (2..=MAX_SAMPLES).contains(n))
        .ok_or_else(|| format!("must lie in 2..={MAX_SAMPLES} (got {n})"))
}

/// The quadrature's requested error, relative to the output's σ: in (0, 1).
pub fn quadrature_tolerance(x: f64) -> Result<f64, String> {
    if x > 0.0 && x < 1.0 {
        Ok(x)
    } else {
        Err(format!(
            "must be a relative error in (0, 1), e.g. 1e-3 (got {x})"
        ))
    }
}

/// The most nodes one case's quadrature may sweep: 1 to [`MAX_SAMPLES`] (a rule's first stage
/// is swept whatever is asked: [`crate::quadrature::QuadOptions::nodes`]).
pub fn quadrature_nodes<N: TryInto<usize> + Copy + Display>(n: N) -> Result<usize, String> {
    n.try_into()
        .ok()
        .filter(|n| (1..=MAX_SAMPLES).contains(n))
        .ok_or_else(|| {
            format!("must be a number of nodes in 1..={MAX_SAMPLES}, e.g. 150 (got {n})")
        })
}

/// A target yield: a probability strictly between 0 and 1.
pub fn target_yield(y: f64) -> Result<f64, String> {
    if y > 0.0 && y < 1.0 {
        Ok(y)
    } else {
        Err(format!(
            "must be a probability strictly between 0 and 1, e.g. 0.9973 (got {y})"
        ))
    }
}

/// Samples expected beyond a quantile below which a Monte Carlo of `n` samples cannot bound
/// it at 95 %: with none beyond in `n` draws the chance is `(1 − q)ⁿ ≈ e^{−nq}`, above 2.5 %
/// while `nq < 3.7`.
pub const QUANTILE_SAMPLES: f64 = 3.7;

/// What a Monte Carlo of `n` samples cannot resolve at target yield `y`: `Some(why)` where
/// fewer than [`QUANTILE_SAMPLES`] samples are expected beyond the margin met at it.
pub fn unresolved_target(y: f64, n: usize) -> Option<String> {
    let beyond = n as f64 * y.min(1.0 - y);
    // 10⁻³⁰⁰ and 1 − 10⁻¹² in words a reader takes in.
    let shown = if y < 1e-4 {
        format!("{y:e}")
    } else if 1.0 - y < 1e-4 {
        format!("1 − {:e}", 1.0 - y)
    } else {
        y.to_string()
    };
    (beyond < QUANTILE_SAMPLES).then(|| {
        format!(
            "target yield {shown} with {n} samples: {beyond:.3e} expected beyond the margin met \
             at it, fewer than the {QUANTILE_SAMPLES} a 95 % interval needs; the Monte Carlo's \
             margin there is left unbounded (limits.csv says why)"
        )
    })
}

/// The most speeds an analysis takes. An analysis holds every speed's nominal point, local
/// model and statistics in memory (tens of kilobytes per speed for a small model); 10⁵ is 200
/// times the examples' ranges, and a range beyond it is refused before anything is allocated.
pub const MAX_ANALYSIS_SPEEDS: usize = 100_000;

/// Checks the number of speeds of an analysis (at most [`MAX_ANALYSIS_SPEEDS`]), before they
/// are made.
pub fn analysis_speeds(n: usize) -> Result<(), String> {
    if n > MAX_ANALYSIS_SPEEDS {
        return Err(format!(
            "{n} speeds is more than the {MAX_ANALYSIS_SPEEDS} an analysis takes (a larger step, \
             or several runs over parts of the range)"
        ));
    }
    Ok(())
}

/// The most cells of a table built in memory (the Python package's tables): about 1.5 GB at
/// the peak, strings and Python objects included. The command line streams its sweeps and
/// has no such bound.
pub const MAX_TABLE_CELLS: usize = 20_000_000;

/// Checks that a table of `rows` × `columns` may be built in memory.
pub fn table(rows: usize, columns: usize) -> Result<(), String> {
    let cells = rows.saturating_mul(columns);
    if cells > MAX_TABLE_CELLS {
        return Err(format!(
            "a table of {rows} rows × {columns} columns is more than the {MAX_TABLE_CELLS} cells \
             held in memory; take fewer points, or the command line, which streams its rows to \
             a file (`modaltol sweep … -o FILE`)"
        ));
    }
    Ok(())
}

/// `K/N`: shard `K` of `N` (1-based), as 0-based `k` and `n`.
pub fn shard(spec: &str) -> Result<(usize, usize), String> {
    let bad = || format!("'{spec}': expected K/N with 1 ≤ K ≤ N");
    let (k, n) = spec.split_once('/').ok_or_else(bad)?;
    let k: usize = k.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if k == 0 || k > n {
        return Err(bad());
    }
    Ok((k - 1, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_rule_accepts_its_range_and_refuses_the_rest_saying_why() {
        assert_eq!(speed(1.5), Ok(1.5));
        for w in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(speed(w).unwrap_err().contains("finite"));
        }
        assert!(values(vec![]).is_err());
        assert!(values(vec![1.0, f64::NAN]).is_err());
        assert_eq!(samples(2u64), Ok(2));
        assert_eq!(samples(MAX_SAMPLES), Ok(MAX_SAMPLES));
        for n in [-1i64, 0, 1, MAX_SAMPLES as i64 + 1, i64::MAX] {
            assert!(samples(n).unwrap_err().contains(&n.to_string()), "{n}");
        }
        assert!(quadrature_tolerance(1e-3).is_ok());
        for x in [0.0, 1.0, -1e-3, f64::NAN] {
            assert!(quadrature_tolerance(x).is_err(), "{x}");
        }
        assert_eq!(quadrature_nodes(150u32), Ok(150));
        for n in [-5i64, 0, MAX_SAMPLES as i64 + 1] {
            assert!(
                quadrature_nodes(n).unwrap_err().contains(&n.to_string()),
                "{n}"
            );
        }
        // `0:999999999:1`.
        assert!(
            analysis_speeds(1_000_000_000)
                .unwrap_err()
                .contains("1000000000 speeds")
        );
        assert!(analysis_speeds(MAX_ANALYSIS_SPEEDS).is_ok());
        assert!(table(MAX_TABLE_CELLS, 1).is_ok());
        assert!(table(usize::MAX, 2).is_err());
        assert_eq!(shard("2/8"), Ok((1, 8)));
        for s in ["0/8", "9/8", "1", "a/b", "-1/2"] {
            assert!(shard(s).is_err(), "{s}");
        }
    }
}
