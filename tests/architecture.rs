//! The crate's data flows one way: each module imports only modules of the layers below its
//! own, in the order `src/lib.rs` states (a folder module with its submodules counts as one).
//! This test reads every `crate::` path in `src/` and fails on an import that goes up or
//! sideways within a layer where the layer is not marked as one whose members may use each
//! other.

use std::collections::BTreeMap;
use std::path::Path;

/// The layers, lowest first (the order of `src/lib.rs`'s documentation). Modules in one layer
/// may import each other only where the layer says so (`true`).
const LAYERS: &[(&[&str], bool)] = &[
    (
        &[
            "real", "linalg", "schur", "threads", "cancel", "files", "dual4", "rigid", "settings",
        ],
        true,
    ),
    (&["joints", "cuts", "forces"], true),
    (&["model"], false),
    (&["mechanics"], false),
    (&["linearize"], false),
    (&["route"], false),
    (&["equilibrium"], false),
    (&["tape", "program"], true),
    (&["compiled"], false),
    (&["pair", "modal", "output", "frf"], true),
    (&["sweep"], false),
    (&["sensitivity", "hessian", "study"], true),
    (&["tolerance"], false),
    (&["sampling"], false),
    (&["propagate"], false),
    (&["taylor", "quadrature", "montecarlo"], false),
    (&["analyze", "shard"], true),
    (&["plots", "report", "results"], true),
];

fn layer_of(module: &str) -> Option<(usize, bool)> {
    LAYERS
        .iter()
        .enumerate()
        .find(|(_, (names, _))| names.contains(&module))
        .map(|(i, (_, within))| (i, *within))
}

/// Every top-level module each source file of the crate imports through a `crate::` path.
fn imports(src: &Path) -> BTreeMap<String, Vec<(String, String)>> {
    let mut out: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(src).unwrap();
            let module = rel
                .components()
                .next()
                .unwrap()
                .as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string();
            if module == "lib" || module == "main" {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            for line in text.lines() {
                let code = line.split("//").next().unwrap();
                for (i, _) in code.match_indices("crate::") {
                    let rest = &code[i + "crate::".len()..];
                    let target: String = rest
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if !target.is_empty() && target != module {
                        out.entry(module.clone())
                            .or_default()
                            .push((target, rel.display().to_string()));
                    }
                }
                // `use crate::{a, b}` groups.
                if let Some(group) = code.trim().strip_prefix("use crate::{") {
                    for name in group.split([',', '}', ' ']).filter(|s| !s.is_empty()) {
                        let target = name.split("::").next().unwrap().to_string();
                        if target != module {
                            out.entry(module.clone())
                                .or_default()
                                .push((target, rel.display().to_string()));
                        }
                    }
                }
            }
        }
    }
    out
}

#[test]
fn every_module_imports_only_modules_below_it_in_the_stated_order() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut wrong = Vec::new();
    for (module, targets) in imports(&src) {
        let Some((from, _)) = layer_of(&module) else {
            wrong.push(format!("{module}: not in any layer of the stated order"));
            continue;
        };
        for (target, file) in targets {
            let Some((to, within)) = layer_of(&target) else {
                continue;
            };
            if to > from || (to == from && !within) {
                wrong.push(format!(
                    "{file}: {module} imports {target}, which sits above it"
                ));
            }
        }
    }
    wrong.sort();
    wrong.dedup();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn every_module_of_the_crate_is_in_the_stated_order() {
    let lib =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let declared: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    assert!(declared.len() > 30, "{declared:?}");
    for m in declared {
        assert!(layer_of(m).is_some(), "{m} is in no layer");
    }
}
