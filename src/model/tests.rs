//! Model files: parsing and validation, against hand-written expectations.

use super::{Sampling, SpeedRange};

/// Each sampling scheme's name is the one serde writes (shard files, summaries) and reads
/// back as that scheme; an unknown name is none; a model file with one is refused naming
/// the schemes.
#[test]
fn sampling_names_are_one_spelling_everywhere() {
    for s in Sampling::ALL {
        assert_eq!(
            serde_json::to_string(&s).unwrap(),
            format!("{:?}", s.name())
        );
        assert_eq!(Sampling::named(s.name()), Some(s));
    }
    assert_eq!(Sampling::named("Sobol"), None);
    assert_eq!(Sampling::names(false), "random, lhs or sobol");
    assert_eq!(Sampling::names(true), "\"random\", \"lhs\" or \"sobol\"");
    let text = include_str!("../../examples/rotating_pendulum.toml")
        .replace("sampling = \"random\"", "sampling = \"halton\"");
    let e = super::Model::from_str(&text, "p.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("analysis sampling 'halton': expected random, lhs or sobol"),
        "{e}"
    );
}

#[test]
fn speeds_are_the_decimal_grid_points() {
    let r = SpeedRange::parse("0:10:0.05").unwrap();
    assert_eq!(r.len(), 201);
    for (i, w) in r.speeds().enumerate() {
        // The double nearest to the decimal i·0.05, so it prints with at most 2 places.
        let decimal: f64 = format!("{}.{:02}", i / 20, (i % 20) * 5).parse().unwrap();
        assert!(w.to_bits() == decimal.to_bits(), "{i}: {w} vs {decimal}");
        assert!(w.to_string().split('.').nth(1).is_none_or(|d| d.len() <= 2));
    }
    let r = SpeedRange::parse("9.5:10:0.05").unwrap();
    assert_eq!(r.at(7).to_string(), "9.85");
    assert_eq!(
        SpeedRange::parse("0:1:0.1").unwrap().at(3).to_string(),
        "0.3"
    );
    let r = SpeedRange::parse("-1.25:1:0.25").unwrap();
    assert_eq!(r.at(5).to_string(), "0");
    // Not a short decimal: `from + i·step` as before.
    let third = 1.0 / 3.0;
    let r = SpeedRange {
        from: 0.0,
        to: 1.0,
        step: third,
    };
    assert!(r.at(2).to_bits() == (2.0 * third).to_bits());
}
