//! A shard is merged only with the model, tolerance cases and settings it was computed from:
//! every field of every example, changed, makes `merge` refuse the shard naming what differs,
//! and nothing that leaves the numbers alone (where the file lies, its comments and layout)
//! does.

mod common;

use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::{Model, SpeedRange};
use modaltol::montecarlo::McOptions;
use modaltol::montecarlo::Split;
use modaltol::quadrature::QuadOptions;
use modaltol::shard::{RunSettings, ShardFile, read_all};
use std::path::{Path, PathBuf};
use toml_edit::{DocumentMut, Item, TableLike};

/// Every example, the rotating blade included.
fn examples() -> Vec<&'static str> {
    let mut all = common::EXAMPLES.to_vec();
    all.push("rotating_blade.toml");
    all
}

/// Shard 1 of 1 of a tiny run of `model` (one speed, two samples per case), written to `dir`.
fn shard_of(model: &Compiled, dir: &Path) -> PathBuf {
    let cases = model.model().tolerance_cases(&[]).unwrap();
    let speed = model.model().analysis.speed.unwrap();
    let range = SpeedRange {
        from: speed.from,
        to: speed.from,
        step: 1.0,
    };
    let mc = McOptions {
        samples: 2,
        seed: 5,
        sampling: model.model().analysis.sampling,
    };
    let opt = AnalyzeOptions {
        speeds: range.speeds().collect(),
        cases: cases.clone(),
        quadrature: None,
        monte_carlo: Some(mc),
        split: Split::Shard(0, 1),
        threads: Some(1),
        ..Default::default()
    };
    let a = analyze(model, &opt, &|_: &str, _: usize, _: usize| {});
    let run = RunSettings::new(&range, &mc, Some(QuadOptions::default()), 1);
    let file = ShardFile::of_analysis(model.model(), &cases, &a, &run, 0).unwrap();
    let path = dir.join("shard-1-of-1.json");
    std::fs::write(&path, file.to_json()).unwrap();
    path
}

/// An edit of one leaf of a model file.
#[derive(Clone, Copy)]
enum Edit {
    /// The `k`-th of [`changes`].
    Change(usize),
    /// The leaf removed, where it is a table's entry.
    Remove,
}

/// Applies `edit` to leaf number `target` (in document order) of a model file, keeping
/// everything else as written (the order of parameters is part of a model: it orders the
/// random streams of the Monte Carlo). Counts leaves in `seen`; returns the top-level key of
/// the leaf edited.
struct Walker {
    target: usize,
    seen: usize,
    edit: Edit,
    done: bool,
}

impl Walker {
    fn table(&mut self, t: &mut dyn TableLike, top: &str) -> Option<String> {
        let keys: Vec<String> = t.iter().map(|(k, _)| k.to_string()).collect();
        for k in keys {
            let top = if top.is_empty() { k.as_str() } else { top };
            let item = t.get_mut(&k).unwrap();
            let is_leaf = matches!(item, Item::Value(v) if !v.is_array() && !v.is_inline_table());
            if is_leaf && self.seen == self.target && matches!(self.edit, Edit::Remove) {
                self.seen += 1;
                t.remove(&k);
                self.done = true;
                return Some(top.to_string());
            }
            if let Some(top) = self.item(t.get_mut(&k).unwrap(), top) {
                return Some(top);
            }
        }
        None
    }

    fn item(&mut self, item: &mut Item, top: &str) -> Option<String> {
        match item {
            Item::Value(v) => self.value(v, top),
            Item::Table(t) => self.table(t, top),
            Item::ArrayOfTables(a) => a.iter_mut().find_map(|t| self.table(t, top)),
            Item::None => None,
        }
    }

    fn value(&mut self, v: &mut toml_edit::Value, top: &str) -> Option<String> {
        match v {
            toml_edit::Value::Array(a) => a.iter_mut().find_map(|x| self.value(x, top)),
            toml_edit::Value::InlineTable(t) => self.table(t, top),
            leaf => {
                let here = self.seen == self.target;
                self.seen += 1;
                if !here {
                    return None;
                }
                if let Edit::Change(k) = self.edit
                    && let Some(new) = changes(leaf).into_iter().nth(k)
                {
                    *leaf = new;
                    self.done = true;
                }
                Some(top.to_string())
            }
        }
    }
}

/// The model file `text` with `edit` applied to leaf number `target`: the edited text and
/// the leaf's top-level key; `None` past the last leaf, or where the edit does not apply.
fn edited(text: &str, target: usize, edit: Edit) -> Option<Result<(String, String), ()>> {
    let mut doc: DocumentMut = text.parse().unwrap();
    let mut w = Walker {
        target,
        seen: 0,
        edit,
        done: false,
    };
    let top = w.table(doc.as_table_mut(), "")?;
    Some(if w.done {
        Ok((doc.to_string(), top))
    } else {
        Err(())
    })
}

/// The changes tried at a leaf: another number, the expression scaled, the name altered, the
/// flag flipped.
fn changes(v: &toml_edit::Value) -> Vec<toml_edit::Value> {
    use toml_edit::Value as V;
    match v {
        V::Integer(i) => vec![V::from(i.value() + 1)],
        V::Float(x) => vec![V::from(x.value() * 1.01 + 0.01)],
        V::Boolean(b) => vec![V::from(!b.value())],
        V::String(s) => vec![
            V::from(format!("({})*1.01", s.value())),
            V::from(format!("{}_x", s.value())),
        ],
        _ => Vec::new(),
    }
}

/// The validated model as its `Debug` text, without where it was written (the file and the
/// sites of its fields): an account of the model independent of the fingerprint's, to tell a
/// change of the model from an edit that leaves it as it was.
fn meaning(m: &Model) -> String {
    let text = format!("{m:?}");
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    // `Site { file: "…", line: …, column: …, what: "…" }` and the model's `file: "…"`.
    while let Some(i) = rest
        .find("Site { ")
        .into_iter()
        .chain(rest.find("file: \""))
        .min()
    {
        out.push_str(&rest[..i]);
        let mut depth = 0;
        let mut quoted = false;
        let mut escaped = false;
        let mut end = rest.len();
        for (j, c) in rest[i..].char_indices() {
            match (quoted, escaped, c) {
                (true, true, _) => escaped = false,
                (true, false, '\\') => escaped = true,
                (true, false, '"') => {
                    quoted = false;
                    if depth == 0 {
                        end = i + j + 1;
                        break;
                    }
                }
                (false, _, '"') => quoted = true,
                (false, _, '{') => depth += 1,
                (false, _, '}') => {
                    depth -= 1;
                    if depth == 0 {
                        end = i + j + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// Keys of the file that hold no number and take part in none.
const NOT_NUMBERS: [&str; 1] = ["description"];

/// What the refusal must name for a change under the top-level key `key`.
fn section(key: &str) -> &'static str {
    match key {
        "name" => "model name",
        "parameters" => "parameters",
        "gravity" => "gravity",
        "bodies" => "bodies",
        "joints" => "joints",
        "forces" => "force elements",
        "constraints" => "constraints",
        "ports" => "ports",
        "independent" => "independent coordinates",
        "analysis" => "[analysis] table",
        _ => panic!("a top-level key the test does not know: {key}"),
    }
}

#[test]
fn a_shard_of_another_model_is_refused_for_every_kind_of_field() {
    let dir = tempfile::tempdir().unwrap();
    for name in examples() {
        let text = common::example_text(name);
        let original = Compiled::from_str(&text, name).unwrap();
        let shard = shard_of(&original, dir.path());
        // The same model elsewhere, its comments gone and its lines moved, merges.
        let elsewhere = dir.path().join(format!("moved-{name}"));
        let plain: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with('#'))
            .map(|l| format!("\n{l}\n"))
            .collect();
        std::fs::write(&elsewhere, plain).unwrap();
        let moved = Model::from_file(&elsewhere).unwrap();
        read_all(
            &moved,
            &moved.tolerance_cases(&[]).unwrap(),
            std::slice::from_ref(&shard),
        )
        .unwrap_or_else(|e| panic!("{name}: the same model, moved, is refused: {e}"));
        let mut tried = 0;
        for target in 0.. {
            let edits = [Edit::Change(0), Edit::Change(1), Edit::Remove];
            let mut past_the_end = true;
            for edit in edits {
                let Some(result) = edited(&text, target, edit) else {
                    continue;
                };
                past_the_end = false;
                let Ok((changed_text, top)) = result else {
                    continue;
                };
                if NOT_NUMBERS.contains(&top.as_str()) {
                    continue;
                }
                let Ok(changed) = Model::from_str(&changed_text, name) else {
                    continue; // not a model: nothing to merge
                };
                let Ok(cases) = changed.tolerance_cases(&[]) else {
                    continue;
                };
                if meaning(&changed) == meaning(original.model()) {
                    continue; // the same model (a default written out, or removed)
                }
                tried += 1;
                let e = read_all(&changed, &cases, std::slice::from_ref(&shard)).expect_err(&format!(
                    "{name}: leaf {target} of {top} changed, and the shard merges:\n{changed_text}"
                ));
                let msg = e.to_string();
                assert!(
                    msg.contains("shard-1-of-1.json") && msg.contains(section(&top)),
                    "{name}: leaf {target} of {top} changed: the refusal does not name the \
                     file and {}: {msg}",
                    section(&top)
                );
            }
            if past_the_end {
                break;
            }
        }
        assert!(tried > 10, "{name}: only {tried} changes were models");
    }
}

/// An edit of a shard file's settings.
type Forgery = fn(&mut ShardFile);

#[test]
fn a_shard_of_other_settings_is_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let model = common::example("rotating_pendulum.toml");
    let cases = model.model().tolerance_cases(&[]).unwrap();
    let shard = shard_of(&model, dir.path());
    let text = std::fs::read_to_string(&shard).unwrap();
    let file = ShardFile::parse(&text, "shard").unwrap();
    // A shard that claims other settings than it was computed with (its digest resealed, as
    // a careful forger would) is refused by its fingerprint, naming the setting.
    let edits: [(&str, Forgery); 6] = [
        ("speeds", |f| f.speed = "0:1:1".into()),
        ("samples", |f| f.samples = 3),
        ("seed", |f| f.seed += 1),
        ("sampling", |f| {
            f.sampling = match f.sampling {
                modaltol::model::Sampling::Sobol => modaltol::model::Sampling::Random,
                _ => modaltol::model::Sampling::Sobol,
            }
        }),
        ("quadrature", |f| f.quadrature = None),
        ("--quadrature-nodes", |f| f.quadrature_nodes = Some(150)),
    ];
    for (what, edit) in edits {
        let mut f = file.clone();
        edit(&mut f);
        f.digest.clear();
        std::fs::write(&shard, f.to_json()).unwrap();
        let e = read_all(model.model(), &cases, std::slice::from_ref(&shard)).expect_err(what);
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
    // Other tolerance cases than the shard's.
    std::fs::write(&shard, &text).unwrap();
    let fewer = model.model().tolerance_cases(&["L3".into()]).unwrap();
    let e = read_all(model.model(), &fewer, std::slice::from_ref(&shard)).unwrap_err();
    assert!(e.to_string().contains("tolerance cases"), "{e}");
    read_all(model.model(), &cases, &[shard]).unwrap();
}

#[test]
fn kept_values_that_do_not_fit_their_moments_are_refused() {
    // A shard whose kept values (for the merge's quantiles) were cut, padded or dropped, even
    // with its digest recomputed, is refused naming the case: the values must be exactly the
    // finite values its blocks count, one worst margin per sample per requirement.
    let dir = tempfile::tempdir().unwrap();
    let m = common::example("governor_specification.toml");
    let path = shard_of(&m, dir.path());
    let cases = m.model().tolerance_cases(&[]).unwrap();
    let good = std::fs::read_to_string(&path).unwrap();
    let file = ShardFile::parse(&good, "good").unwrap();
    assert_eq!(file.kept.len(), cases.len(), "a shard keeps its values");
    assert!(read_all(m.model(), &cases, std::slice::from_ref(&path)).is_ok());
    let tampered: Vec<(&str, ShardFile)> = vec![
        ("values", {
            let mut f = file.clone();
            f.kept[0].values[0] = String::new();
            f
        }),
        ("worst", {
            let mut f = file.clone();
            f.kept[0].worst.pop();
            f
        }),
        ("dropped", {
            let mut f = file.clone();
            f.kept.clear();
            f
        }),
    ];
    for (what, f) in tampered {
        let p = dir.path().join(format!("{what}.json"));
        std::fs::write(&p, f.to_json()).unwrap();
        let e = match read_all(m.model(), &cases, &[p]) {
            Ok(_) => panic!("{what}: a shard with bad kept values accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("kept"), "{what}: {e}");
    }
}

/// A model whose nominal design fails at every speed (the pendulum with a hinge damping of
/// 1e308: its matrices span more than double precision) still has its outputs, ω_d and ζ of
/// its one mode and |H|: its two shards are verified and merge into exactly the whole run
/// (found by the pipeline fuzzer: the Monte Carlo counted the outputs of the nominal points
/// that solved, none, while the shard file and the merge counted the model's).
#[test]
fn a_model_failing_at_every_speed_shards_and_merges_as_one_run() {
    let text = common::example_text("rotating_pendulum.toml")
        .replace("c = 3.0 ", "c = 1e308 ")
        .replace("samples = 3000", "samples = 16");
    assert!(text.contains("c = 1e308"));
    let model = Compiled::from_str(&text, "failing.toml").unwrap();
    let cases = model.model().tolerance_cases(&[]).unwrap();
    let range = SpeedRange {
        from: 0.0,
        to: 2.0,
        step: 1.0,
    };
    let mc = McOptions {
        samples: 16,
        seed: 1,
        sampling: model.model().analysis.sampling,
    };
    let opt = |split: Split| AnalyzeOptions {
        speeds: range.speeds().collect(),
        cases: cases.clone(),
        quadrature: None,
        monte_carlo: Some(mc),
        split,
        threads: Some(1),
        ..Default::default()
    };
    let run = RunSettings::new(&range, &mc, None, 2);
    let texts: Vec<(String, String)> = (0..2)
        .map(|k| {
            let a = analyze(&model, &opt(Split::Shard(k, 2)), &|_: &str, _, _| {});
            let file = ShardFile::of_analysis(model.model(), &cases, &a, &run, k).unwrap();
            (format!("shard {}", k + 1), file.to_json())
        })
        .collect();
    let texts_again = texts.clone();
    let gathered = modaltol::shard::verify(model.model(), &cases, texts)
        .unwrap_or_else(|e| panic!("the shards are refused: {e}"));
    // The merge reports the shards' Monte Carlo time, summed, each shard's own.
    let (first, second) = (
        ShardFile::parse(&texts_again[0].1, "1").unwrap(),
        ShardFile::parse(&texts_again[1].1, "2").unwrap(),
    );
    let each = [first.monte_carlo_seconds, second.monte_carlo_seconds];
    assert!(each.iter().all(|s| s.is_some_and(|s| s > 0.0)), "{each:?}");
    assert_eq!(
        gathered.monte_carlo_seconds,
        Some(each[0].unwrap() + each[1].unwrap())
    );
    let merged = analyze(
        &model,
        &opt(Split::Merged(gathered.states)),
        &|_: &str, _, _| {},
    );
    let whole = analyze(&model, &opt(Split::Whole), &|_: &str, _, _| {});
    assert_eq!(merged.outputs.len(), 3, "ω_d, ζ and |H|");
    assert_eq!(merged.rows.len(), whole.rows.len());
    for (m, w) in merged.rows.iter().zip(&whole.rows) {
        assert_eq!(format!("{m:?}"), format!("{w:?}"));
    }
}
