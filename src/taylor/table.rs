//! The Taylor methods' rows: first order (with the variance shares), second order, the
//! invariant method (ω_d), the first-order yield, and their choice for the answer to read where
//! the quadrature gives none ([`Method::Analytic`]).

use super::yields::first_order_rows;
use super::{TaylorResult, TaylorStats};
use crate::output::{Missing, Output};
use crate::propagate::{Study, Tabulate};
use crate::table::{Detail, Method, Row, Tables};
use crate::tolerance::{KINK_SIGMAS, Spread, Stat};

impl Tabulate for TaylorResult {
    fn tabulate(self, study: &Study, case: usize, spread: &Spread, tables: &mut Tables) {
        tables.yields.extend(first_order_rows(study, case, spread));
        for (si, (lm, stats)) in study.locals.iter().zip(self.stats).enumerate() {
            let (Some(lm), Some(stats)) = (lm, stats) else {
                continue;
            };
            for (k, (o, t)) in lm.outputs.iter().zip(stats).enumerate() {
                for row in rows(study.speeds[si], case, o, t) {
                    tables.row(si, k, row);
                }
            }
        }
    }
}

/// The rows of one output: first order, second order, (ω_d) invariant, and the Taylor
/// methods' answer: for ω_d the invariant method within [`KINK_SIGMAS`] σ of a change of class,
/// otherwise second order where it has a value, else first order.
fn rows(speed: f64, case: usize, o: &Output, t: TaylorStats) -> Vec<Row> {
    let row = |stat: &Result<Stat, Missing>, detail| {
        let stat = stat.clone().map(|s| (s.mean, s.std));
        Row::new(speed, case, o, stat, detail)
    };
    let (first, shares) = match t.first_order {
        Ok((st, shares)) => (Ok(st), Some(shares)),
        Err(e) => (Err(e), None),
    };
    let mut rows = vec![
        row(&first, Detail::FirstOrder { shares }),
        row(&t.second_order, Detail::SecondOrder),
    ];
    let mut choice = t
        .second_order
        .map(|st| (Method::SecondOrder, st))
        .or(first.map(|st| (Method::FirstOrder, st)));
    if let Some(inv) = t.invariant {
        rows.push(row(&inv.clone().map(|(st, _)| st), Detail::Invariant));
        if let Ok((st, dst)) = inv
            && (choice.is_err() || dst.mean.abs() < KINK_SIGMAS * dst.std)
        {
            choice = Ok((Method::Invariant, st));
        }
    }
    let (basis, stat) = match choice {
        Ok((m, st)) => (Some(m), Ok(st)),
        Err(e) => (None, Err(e)),
    };
    let quadrature = None;
    rows.push(row(&stat, Detail::Analytic { basis, quadrature }));
    rows
}
