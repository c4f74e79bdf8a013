//! A transfer function without a finite value is never a silent blank: in every example, at
//! excitation frequencies from ordinary to beyond floating point and at an undamped mode's
//! own frequency, every sweep, frequency-response and sensitivity row whose |H| is empty says
//! why (a resonance, an overflow), and no row holds an infinity or a NaN.

mod common;

use modaltol::compiled::Compiled;
use modaltol::model::Transfer;
use modaltol::nominal_sweep::NominalSweep;
use modaltol::report::{self, SweepColumns};
use modaltol::sensitivity::{Derivatives, DesignPoint, TransferAt};
use modaltol::sweep::Options;

/// Excitation frequencies (rad/s), or orders of the speed: ordinary, near the square root of
/// the largest float, and beyond it.
const EXCITATIONS: [f64; 7] = [1e-300, 0.5, 7.0, 1e150, 1e155, 1e200, 1e308];

/// Every cell of a row is a finite number or text; a row with an empty `value` cell says why
/// in its `message` cell, and a row without says nothing of a resonance or an overflow.
fn check_row(header: &[String], row: &[String], value: &str, what: &str) -> bool {
    let at = |c: &str| header.iter().position(|h| h == c).unwrap();
    for cell in row {
        assert!(
            !cell.parse::<f64>().is_ok_and(|v| !v.is_finite()),
            "{what}: a non-finite cell in {row:?}"
        );
    }
    let message = &row[at("message")];
    let said = message.contains("resonance") || message.contains("overflow");
    assert_eq!(
        row[at(value)].is_empty(),
        said,
        "{what}: |H| '{}' with message '{message}'",
        row[at(value)]
    );
    message.contains("resonance")
}

/// The examples, and the pendulum without damping (a true undamped resonance).
fn models() -> Vec<(String, Compiled)> {
    let mut out: Vec<(String, Compiled)> = common::EXAMPLES
        .iter()
        .map(|n| (n.to_string(), common::example(n)))
        .collect();
    let undamped = Compiled::from_file_with(
        &common::example_path("rotating_pendulum.toml"),
        &[("c".into(), 0.0)],
    )
    .unwrap();
    out.push(("undamped pendulum".into(), undamped));
    out
}

#[test]
fn an_infinite_transfer_function_says_resonance_or_overflow_in_every_row() {
    let mut resonances = 0;
    for (name, m) in models() {
        let Some(t) = m.model().analysis.transfer else {
            continue;
        };
        let speed = 1.0;
        let pt = common::at(&m, speed, &Options::default());
        // The modes' own frequencies: a resonance where a mode has no damping.
        let mut excitations = EXCITATIONS.to_vec();
        excitations.extend(pt.modes.iter().map(|md| md.natural_frequency));
        let wrt = m.model().toleranced();
        // Sweep rows, with the excitation at `order × speed`.
        for &order in &excitations {
            let cols = SweepColumns {
                transfer: true,
                wrt: wrt.clone(),
            };
            let tf = Transfer { order, ..t };
            let mut study = NominalSweep::new(
                &m,
                Options::default(),
                Some(tf),
                wrt.clone(),
                Derivatives::Exact,
            );
            let (r, extras) = study.step(speed);
            let header = report::sweep_header(m.model(), &cols);
            for row in report::sweep_rows(m.model(), &cols, speed, &r, &extras) {
                let what = format!("{name}: sweep, order {order:e}");
                resonances += check_row(&header, &row, "transfer_magnitude", &what) as usize;
            }
            // The sensitivity table at the same excitation.
            let at = TransferAt::at_speed(&tf, speed);
            if let Ok(s) = DesignPoint::new(&m, &m.model().nominal(), &pt)
                .with_transfer(Some(at))
                .sensitivities(&wrt, Derivatives::Exact)
            {
                let why = report::transfer_defect_at(&pt, Some(&at));
                let shown = report::SensitivityReport {
                    model: m.model(),
                    point: &pt,
                    sensitivity: &s,
                    no_transfer: why,
                };
                let header: Vec<String> = report::SENSITIVITY_HEADER
                    .iter()
                    .map(|h| h.to_string())
                    .collect();
                for row in shown.rows() {
                    let what = format!("{name}: sensitivity, order {order:e}");
                    check_row(&header, &row, "transfer_magnitude", &what);
                }
                let json = shown.json(speed, "ad");
                assert_eq!(
                    json["transfer_magnitude"].is_null(),
                    json["transfer_message"].is_string(),
                    "{name}: sensitivity JSON, order {order:e}: {json}"
                );
            }
        }
        // Frequency-response rows over the same frequencies.
        let rows = DesignPoint::new(&m, &m.model().nominal(), &pt)
            .frequency_response((t.input, t.output), &wrt, excitations.iter().copied())
            .unwrap();
        let header = report::frf_header(m.model(), &wrt);
        for row in report::frf_rows(&pt.linear, &rows) {
            resonances += check_row(&header, &row, "magnitude", &format!("{name}: frf")) as usize;
        }
    }
    assert!(
        resonances > 0,
        "no resonance was met: the test tests less than it says"
    );
}

/// An undamped resonance is a resonance whatever the rounding of its frequency: within a
/// hundred ulps of an undamped mode's natural frequency (where the dynamic stiffness is
/// singular to working precision) every route says "resonance" and gives no |H|, never a
/// finite 10¹⁴; a mode with realistic light damping (ζ from 10⁻⁶) keeps its finite peak,
/// equal to the closed form |H| = 1/(2ζk) of one degree of freedom to 10⁻⁹.
#[test]
fn a_resonance_is_one_whatever_the_rounding_of_its_frequency() {
    let undamped = Compiled::from_file_with(
        &common::example_path("rotating_pendulum.toml"),
        &[("c".into(), 0.0)],
    )
    .unwrap();
    let t = undamped.model().analysis.transfer.unwrap();
    let speed = 1.0;
    let pt = common::at(&undamped, speed, &Options::default());
    let wn = pt.modes[0].natural_frequency;
    let wrt = undamped.model().toleranced();
    let mut near = vec![wn];
    let (mut up, mut down) = (wn, wn);
    for _ in 0..100 {
        up = up.next_up();
        down = down.next_down();
        near.extend([up, down]);
    }
    let rows = DesignPoint::new(&undamped, &undamped.model().nominal(), &pt)
        .frequency_response((t.input, t.output), &wrt, near.iter().copied())
        .unwrap();
    let header = report::frf_header(undamped.model(), &wrt);
    for row in report::frf_rows(&pt.linear, &rows) {
        assert!(
            check_row(&header, &row, "magnitude", "undamped pendulum near ω_n"),
            "{row:?}"
        );
    }
    // The sweep's row at an order that puts the excitation within ulps of ω_n.
    for &w in &near[..21] {
        let tf = Transfer {
            order: w / speed,
            ..t
        };
        let mut study = NominalSweep::new(
            &undamped,
            Options::default(),
            Some(tf),
            wrt.clone(),
            Derivatives::Exact,
        );
        let (r, extras) = study.step(speed);
        let cols = SweepColumns {
            transfer: true,
            wrt: wrt.clone(),
        };
        let header = report::sweep_header(undamped.model(), &cols);
        for row in report::sweep_rows(undamped.model(), &cols, speed, &r, &extras) {
            assert!(
                check_row(&header, &row, "transfer_magnitude", "sweep near ω_n"),
                "{row:?}"
            );
        }
    }
    // Light damping: a finite peak, 1/(2ζ k) at ω = ω_n with k = ω_n² m̂ (one coordinate).
    for zeta in [1e-6, 1e-4, 1e-2] {
        let lin = &pt.linear;
        let (k, m) = (lin.k[(0, 0)], lin.m[(0, 0)]);
        let c = 2.0 * zeta * (k * m).sqrt();
        let mut damped = lin.clone();
        damped.c[(0, 0)] = c;
        let w = (k / m).sqrt();
        let h = modaltol::frf::transfer(&damped, t.input, t.output, w).expect("a finite peak");
        let exact = 1.0 / (c * w);
        assert!(
            (h.magnitude() - exact).abs() <= 1e-9 * exact,
            "ζ = {zeta}: |H| {} against {exact}",
            h.magnitude()
        );
    }
}
