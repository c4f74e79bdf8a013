//! Property-based fuzzing (proptest) of expression parsing and evaluation and of model
//! validation, run in CI: arbitrary text and random byte mutations of the valid examples never
//! make the library panic, and evaluation never returns a silent NaN.
//!
//! Inputs that once broke something are kept in `tests/fuzz_corpus/` and replayed by
//! `fuzz_corpus_replays`. Longer runs: `PROPTEST_CASES=100000 cargo test --release --test fuzz`.

mod common;

use modaltol::compiled::Compiled;
use modaltol::model::Expr;
use modaltol::sweep::{Options, initial_guess, point};
use proptest::prelude::*;

fn lookup(s: &str) -> Option<usize> {
    ["a", "b", "L"].iter().position(|n| *n == s)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000),
        // Failing seeds are kept beside the corpus (replayed by proptest on the next run).
        failure_persistence: Some(Box::new(proptest::test_runner::FileFailurePersistence::Direct("tests/fuzz_corpus/proptest-regressions.txt"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn expressions_parse_or_fail_cleanly(s in "[-+*/^()a-zL0-9., eEpisqrtcoanlbx_]{0,60}") {
        if let Ok(e) = Expr::parse(&s, &lookup)
            && let Ok(v) = e.eval::<f64>(&[1.5, -2.0, 0.25], 3.0)
        {
            prop_assert!(v.is_finite(), "{s} → {v}");
        }
    }

    #[test]
    fn arbitrary_text_never_panics_the_validator(s in "\\PC{0,400}") {
        let _ = Compiled::from_str(&s, "fuzz.toml");
    }

    #[test]
    fn mutated_examples_validate_or_fail_cleanly(
        which in 0usize..5,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
    ) {
        let name = ["rotating_pendulum.toml", "governor.toml", "spinning_universal_pendulum.toml", "spinning_spatial_fourbar.toml", "rotor_on_rubber_mounts.toml"][which];
        let mut bytes = common::example_text(name).into_bytes();
        for (at, byte) in &edits {
            let i = at.index(bytes.len());
            bytes[i] = *byte;
        }
        if let Ok(model) = Compiled::from_bytes(&bytes, "mutant.toml") {
            // A mutant that validates must also solve or fail cleanly at a speed.
            let p = model.model().nominal();
            if let Ok(q0) = initial_guess(model.model(), &p, 1.0)
                && let Ok(pt) = point(&model, &p, 1.0, &q0, &Options::default())
            {
                for m in &pt.modes {
                    prop_assert!(m.damped_frequency.is_finite() && m.natural_frequency.is_finite());
                }
            }
        }
    }
}

#[test]
fn fuzz_corpus_replays() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_corpus");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let path = f.unwrap().path();
        if path.is_dir() {
            continue; // the pipeline corpus, replayed by tests/fuzz_pipeline.rs
        }
        let bytes = std::fs::read(path).unwrap();
        if let Ok(model) = Compiled::from_bytes(&bytes, "corpus.toml") {
            let p = model.model().nominal();
            if let Ok(q0) = initial_guess(model.model(), &p, 1.0) {
                let _ = point(&model, &p, 1.0, &q0, &Options::default());
            }
        }
        n += 1;
    }
    assert!(n >= 1, "the corpus is empty");
}
