//! The tables of an analysis, as every propagation method fills them: `tolerance.csv`'s rows
//! ([`Row`]), `probabilities.csv`'s ([`ProbabilityRow`]), `yield.csv`'s ([`YieldRow`]) and
//! `sobol.csv`'s ([`SobolIndex`]), collected in [`Tables`].
//!
//! A method's value writes its own rows (its `Tabulate` implementation, next to the method);
//! the tables put them in their order, whatever order the methods ran in, and make the rows a
//! reader should take, [`Method::Analytic`], from the quadrature where it gave a value (see
//! [`Tables::finish`]). Nothing here knows a method's result type: the rows carry the
//! methods' own fields in one enum ([`Detail`]). (In the manner of OpenTURNS's result
//! classes: each algorithm owns its result and how it reads.)

mod method;
mod probability;
mod row;
mod sobol;
mod yield_row;

pub use method::Method;
pub use probability::{Event, ProbabilityRow, wilson};
pub use row::{Detail, McStat, QuadDetail, Row};
pub use sobol::{SobolIndex, Target};
pub use yield_row::{Limit, YieldRow, cpk, reach};

/// Where a row goes: the Monte Carlo's rows after the others (it is the last stage), then by
/// case, speed, output and method.
type Key = (bool, usize, usize, usize, usize);

/// The order of the methods within one output at one speed (and within one case's yields).
const ORDER: [Method; 6] = [
    Method::FirstOrder,
    Method::SecondOrder,
    Method::Invariant,
    Method::Quadrature,
    Method::Analytic,
    Method::MonteCarlo,
];

fn rank(m: Method) -> usize {
    ORDER.iter().position(|&x| x == m).unwrap_or(ORDER.len())
}

/// The tables the methods fill (see the module documentation); [`Tables::finish`] puts them
/// in order.
#[derive(Debug, Default)]
pub struct Tables {
    rows: Vec<(Key, Row)>,
    pub probabilities: Vec<ProbabilityRow>,
    pub yields: Vec<YieldRow>,
    /// Sobol indices per case, and per case the reason where none could be computed.
    pub sobol: Vec<(usize, SobolIndex)>,
    pub sobol_refused: Vec<(usize, String)>,
    /// Per case that ran the quadrature: its rule in words and its number of swept nodes.
    pub quadrature_rules: Vec<(String, usize)>,
    /// Monte Carlo samples evaluated per case.
    pub samples_done: Vec<usize>,
    /// Per case, the Monte Carlo samples whose design is not admissible, by reason:
    /// `(reason, count, first value)`.
    pub inadmissible: Vec<Vec<(String, usize, f64)>>,
}

impl Tables {
    /// Adds `row`, of the output with index `output` at the speed with index `speed`.
    pub fn row(&mut self, speed: usize, output: usize, row: Row) {
        let m = row.method();
        let key = (m == Method::MonteCarlo, row.case, speed, output, rank(m));
        self.rows.push((key, row));
    }

    /// Orders every table and hands over the rows: the Monte Carlo's after the others, then by
    /// case; rows then by speed, output and method (first order, second order, invariant,
    /// quadrature, analytic), yields by method; each method's own order kept within. The
    /// analytic rows become the quadrature's answer where it has one and keep the Taylor
    /// methods' choice elsewhere (see [`Method::Analytic`]).
    pub fn finish(&mut self) -> Vec<Row> {
        let mut rows = std::mem::take(&mut self.rows);
        rows.sort_by_key(|r| r.0);
        let output = |k: &Key| (k.0, k.1, k.2, k.3);
        for group in rows.chunk_by_mut(|a, b| output(&a.0) == output(&b.0)) {
            let answer = group.iter().find_map(|(_, r)| match r.detail {
                Detail::Quadrature(Some(q)) => Some(Row {
                    detail: Detail::Analytic {
                        basis: Some(Method::Quadrature),
                        quadrature: Some(q),
                    },
                    ..r.clone()
                }),
                _ => None,
            });
            if let Some(answer) = answer
                && let Some(slot) = group.iter_mut().find(|r| r.1.method() == Method::Analytic)
            {
                slot.1 = answer;
            }
        }
        let stage = |m: Method| m == Method::MonteCarlo;
        self.probabilities
            .sort_by_key(|p| (stage(p.method), p.case));
        self.yields
            .sort_by_key(|y| (stage(y.method), y.case, rank(y.method)));
        rows.into_iter().map(|r| r.1).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{Missing, Output, Quantity};

    fn out(mode: usize) -> Output {
        Output {
            quantity: Quantity::DampedFrequency,
            mode: Some(mode),
        }
    }

    fn quad(mean: f64) -> (Result<(f64, f64), Missing>, Detail) {
        let q = QuadDetail {
            quantiles: [mean - 1.0, mean, mean + 1.0],
            errors: (1e-6, 1e-6),
            within_request: true,
        };
        (Ok((mean, 0.5)), Detail::Quadrature(Some(q)))
    }

    #[test]
    fn rows_come_out_in_table_order_with_the_quadratures_answer() {
        let mut t = Tables::default();
        let taylor = |m: Option<Method>| Detail::Analytic {
            basis: m,
            quadrature: None,
        };
        // Written method by method, as the methods run: Monte Carlo, quadrature, Taylor.
        let mc = Detail::MonteCarlo(McStat::default());
        t.row(0, 0, Row::new(1.0, 0, &out(0), Ok((9.0, 1.0)), mc));
        let (stat, detail) = quad(2.0);
        t.row(1, 0, Row::new(2.0, 0, &out(0), stat, detail));
        let none = Detail::Quadrature(None);
        t.row(0, 0, Row::new(1.0, 0, &out(0), Err(Missing::NoValue), none));
        for (si, speed) in [(0, 1.0), (1, 2.0)] {
            let first = Detail::FirstOrder { shares: None };
            t.row(si, 0, Row::new(speed, 0, &out(0), Ok((3.0, 1.0)), first));
            let answer = taylor(Some(Method::FirstOrder));
            t.row(si, 0, Row::new(speed, 0, &out(0), Ok((3.0, 1.0)), answer));
        }
        let rows = t.finish();
        let got: Vec<(u64, Method, Option<Method>)> = rows
            .iter()
            .map(|r| (r.speed.to_bits(), r.method(), r.basis()))
            .collect();
        let (w1, w2) = (1f64.to_bits(), 2f64.to_bits());
        let first = Some(Method::FirstOrder);
        assert_eq!(
            got,
            [
                (w1, Method::FirstOrder, None),
                (w1, Method::Quadrature, None),
                (w1, Method::Analytic, first),
                (w2, Method::FirstOrder, None),
                (w2, Method::Quadrature, None),
                (w2, Method::Analytic, Some(Method::Quadrature)),
                (w1, Method::MonteCarlo, None),
            ]
        );
        // Where the quadrature has no value the answer stays the Taylor choice; where it has,
        // the answer is the quadrature's, its quantiles included.
        assert!(rows[2].mean.to_bits() == 3f64.to_bits() && rows[2].quantiles().is_none());
        assert!(rows[5].mean.to_bits() == 2f64.to_bits());
        assert_eq!(rows[5].quantiles(), Some([1.0, 2.0, 3.0]));
        assert_eq!(rows[1].missing, Some(Missing::NoValue));
    }

    #[test]
    fn a_statistic_that_is_not_finite_gives_no_value_and_says_why() {
        let r = Row::new(
            1.0,
            0,
            &out(0),
            Ok((f64::INFINITY, 1.0)),
            Detail::SecondOrder,
        );
        assert!(r.mean.is_nan() && r.std.is_nan());
        assert_eq!(r.missing, Some(Missing::NotFinite));
    }
}
