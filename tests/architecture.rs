//! The crate's data flows one way: each module imports only modules of the layers below its
//! own, in the order `src/lib.rs` states (a folder module with its submodules counts as one).
//! This test reads every `crate::` path in `src/` and fails on an import that goes up or
//! sideways within a layer where the layer is not marked as one whose members may use each
//! other.

use std::path::Path;

/// The layers, lowest first (the order of `src/lib.rs`'s documentation). Modules in one layer
/// may import each other only where the layer says so (`true`).
const LAYERS: &[(&[&str], bool)] = &[
    (
        &[
            "real", "linalg", "schur", "threads", "cancel", "files", "dual4", "jet", "implicit",
            "rigid", "settings", "kinds",
        ],
        true,
    ),
    (&["joints", "cuts", "forces", "beams", "requirements"], true),
    (&["model"], false),
    (&["mechanics"], false),
    (&["linearize"], false),
    (&["equations"], false),
    (&["equilibrium"], false),
    (&["tape", "program"], true),
    (&["compiled"], false),
    (&["pair", "modal", "output", "frf"], true),
    (&["sweep"], false),
    (&["whirl"], false),
    (&["scene"], false),
    (&["sensitivity", "hessian", "nominal_sweep"], true),
    (&["tolerance", "margins"], false),
    (&["peaks"], false),
    (&["sampling"], false),
    (&["table"], false),
    (&["propagate"], false),
    (&["taylor", "quadrature", "montecarlo", "sobol"], false),
    (&["analyze", "allocate", "request", "shard"], true),
    (&["plots", "drawing", "report", "results"], true),
];

fn layer_of(module: &str) -> Option<(usize, bool)> {
    LAYERS
        .iter()
        .enumerate()
        .find(|(_, (names, _))| names.contains(&module))
        .map(|(i, (_, within))| (i, *within))
}

/// The text of a source file without its comments (line and block) and with string and
/// character literals emptied, so that only code is searched for paths.
fn code_only(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
                out.push(' ');
            }
            // A character literal (`'x'`, `'\''`), not a lifetime: emptied, so that `'"'`
            // opens no string.
            '\'' if chars.peek() == Some(&'\\') => {
                chars.next();
                chars.next();
                for c in chars.by_ref() {
                    if c == '\'' {
                        break;
                    }
                }
                out.push_str("' '");
            }
            '\'' if chars.clone().nth(1) == Some('\'') => {
                chars.next();
                chars.next();
                out.push_str("' '");
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if c == '"' && !escaped {
                        break;
                    }
                    escaped = c == '\\' && !escaped;
                }
                out.push_str("\"\"");
            }
            _ => out.push(c),
        }
    }
    out
}

/// The first path segment of every item of a `{…}` group (nested groups included once).
fn group_heads(group: &str) -> Vec<String> {
    let mut heads = Vec::new();
    let mut depth = 0;
    let mut item = String::new();
    for c in group.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                heads.push(std::mem::take(&mut item));
                continue;
            }
            _ => {}
        }
        if depth == 0 || item.is_empty() {
            item.push(c);
        }
    }
    heads.push(item);
    heads
        .iter()
        .filter_map(|i| {
            let head: String = i
                .trim()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            (!head.is_empty()).then_some(head)
        })
        .collect()
}

/// The top-level modules a piece of code names through `crate::` paths, `crate::{…}` groups
/// (over any number of lines) included.
fn targets(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1;
            let end = group
                .char_indices()
                .find(|&(_, c)| {
                    depth += match c {
                        '{' => 1,
                        '}' => -1,
                        _ => 0,
                    };
                    depth == 0
                })
                .map_or(group.len(), |(k, _)| k);
            out.extend(group_heads(&group[..end]));
        } else {
            let head: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !head.is_empty() {
                out.push(head);
            }
        }
    }
    out
}

/// Every top-level module each source file of the crate imports through a `crate::` path:
/// `(importing module, imported module, file)`.
fn imports(src: &Path) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
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
            // The library's roots, and the command line (a crate of its own, over the library).
            if module == "lib" || module == "main" || module == "cli" {
                continue;
            }
            let code = code_only(&std::fs::read_to_string(&path).unwrap());
            for target in targets(&code) {
                if target != module && target != "self" {
                    out.push((module.clone(), target, rel.display().to_string()));
                }
            }
        }
    }
    out
}

#[test]
fn the_import_reader_finds_paths_in_every_form_and_none_in_comments() {
    let code = code_only(
        "use crate::a::X;\npub use crate::{b, c::{D, E}};\nuse crate::{\n    d::F,\n    e,\n};\n\
         fn f<'a>() { crate::g::h(); let s = \"crate::no\"; let q = '\"'; crate::i::j(); }\n\
         // crate::no\n/* crate::no */",
    );
    assert_eq!(targets(&code), ["a", "b", "c", "d", "e", "g", "i"]);
}

#[test]
fn every_module_imports_only_modules_below_it_in_the_stated_order() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut wrong = Vec::new();
    let found = imports(&src);
    assert!(found.len() > 100, "{} imports found", found.len());
    for (module, target, file) in found {
        let Some((from, _)) = layer_of(&module) else {
            wrong.push(format!("{module}: not in any layer of the stated order"));
            continue;
        };
        let Some((to, within)) = layer_of(&target) else {
            wrong.push(format!(
                "{file}: crate::{target} is no module of the stated order"
            ));
            continue;
        };
        if to > from || (to == from && !within) {
            wrong.push(format!(
                "{file}: {module} imports {target}, which sits above it"
            ));
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
