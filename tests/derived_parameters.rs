//! Parameters defined by expressions of others (`[parameters] h = "L/20"`).
//!
//! - The blade written with `h = "L/20"` is the blade with `(L/20)` written in every field, to
//!   the bit: its modes, and its tolerance analysis with a tolerance on `L` (which reaches every
//!   field made from it).
//! - Cycles, unknown names, the speed, tolerances, costs and `--set` on a derived parameter,
//!   and expansions beyond the limit are refused at their place.

mod common;

use common::example_text;
use modaltol::analyze::{AnalyzeOptions, analyze};
use modaltol::compiled::Compiled;
use modaltol::model::{Case, Model};

/// The blade with its segment length `h` derived from a toleranced blade length `L`.
fn derived_text() -> String {
    let text = example_text("rotating_blade.toml");
    let line = text
        .lines()
        .find(|l| l.starts_with("h = 0.05"))
        .expect("the blade's h line");
    text.replace(
        line,
        "L = { value = 1.0, tolerance = \"1%\" }\nh = \"L/20\"",
    )
}

/// `text` with the name `h` inside every quoted string replaced by `(L/20)`, and no `h`
/// parameter: the model written out by hand.
fn by_hand(text: &str) -> String {
    let text = text.replace("h = \"L/20\"", "");
    let mut out = String::new();
    for (k, part) in text.split('"').enumerate() {
        if k > 0 {
            out.push('"');
        }
        if k % 2 == 0 {
            out.push_str(part);
            continue;
        }
        // Inside a string: whole identifiers `h` only.
        let mut word = String::new();
        for c in part.chars().chain(std::iter::once('\0')) {
            if c.is_alphanumeric() || c == '_' {
                word.push(c);
                continue;
            }
            out.push_str(if word == "h" { "(L/20)" } else { &word });
            word.clear();
            if c != '\0' {
                out.push(c);
            }
        }
    }
    out
}

#[test]
fn a_derived_parameter_is_its_expression_written_in_place() {
    let derived = Compiled::from_str(&derived_text(), "derived.toml").unwrap();
    let hand_text = by_hand(&derived_text());
    assert!(hand_text.contains("mu*(L/20)^3/12") && !hand_text.contains("\"0.5*h\""));
    let hand = Compiled::from_str(&hand_text, "hand.toml").unwrap();
    let (d, h) = (derived.model(), hand.model());
    assert_eq!(d.derived.len(), 1);
    assert_eq!(d.derived[0].name, "h");
    assert!(d.derived[0].value.to_bits() == (1.0f64 / 20.0).to_bits());
    assert!(h.derived.is_empty());
    // The same fields, to the bit (`Model` serialises what it computes with).
    assert_eq!(
        serde_json::to_string(d).unwrap(),
        serde_json::to_string(h).unwrap()
    );
    // The tolerance analysis with L toleranced (with μ and EI): the same numbers, bit for bit,
    // and L reaches the outputs (its share is not zero).
    let case = Case::from_parameters(d);
    assert_eq!(case.tolerances.len(), 3);
    let opt = AnalyzeOptions {
        speeds: vec![0.0, 20.0, 40.0],
        cases: vec![case],
        quadrature: None,
        monte_carlo: None,
        ..Default::default()
    };
    let (a, b) = (
        analyze(&derived, &opt, &|_, _, _| {}),
        analyze(&hand, &opt, &|_, _, _| {}),
    );
    assert!(!a.rows.is_empty() && a.rows.len() == b.rows.len());
    let l = a
        .vars
        .iter()
        .position(|&v| d.parameters[v].name == "L")
        .expect("L is a variable");
    let mut l_matters = false;
    for (x, y) in a.rows.iter().zip(&b.rows) {
        assert!(x.mean.to_bits() == y.mean.to_bits() && x.std.to_bits() == y.std.to_bits());
        if let Some(s) = &x.shares() {
            l_matters |= s[l] > 0.1;
        }
    }
    assert!(
        l_matters,
        "a 1 % tolerance on L moves the blade's frequencies"
    );
}

fn refused(extra_parameters: &str, rest: &str) -> String {
    let text = example_text("rotating_pendulum.toml").replacen(
        "[parameters]\n",
        &format!("[parameters]\n{extra_parameters}\n"),
        1,
    ) + "\n"
        + rest;
    match Model::from_str(&text, "refused.toml") {
        Ok(_) => panic!("accepted:\n{extra_parameters}\n{rest}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_derived_parameters_are_refused_at_their_place() {
    for (params, rest, expect) in [
        ("a = \"b + 1\"\nb = \"2*a\"", "", "cycle (a → b → a)"),
        ("a = \"L + nope\"", "", "unknown parameter 'nope'"),
        ("a = \"L*speed\"", "", "cannot depend on the speed"),
        (
            "a = { value = \"L/2\", tolerance = \"1%\" }",
            "",
            "carries no tolerance",
        ),
        (
            "a = \"L/2\"",
            "[[analysis.cases]]\nname = \"bad\"\ntolerances = { a = \"1%\" }",
            "parameter 'a' is derived (= \"L/2\")",
        ),
        (
            "a = \"L/2\"",
            "[allocation]\ncost = { a = { b = 1.0 } }",
            "parameter 'a' is derived",
        ),
    ] {
        let e = refused(params, rest);
        assert!(e.contains(expect), "{params} / {rest}: {e}");
        assert!(e.contains("refused.toml:"), "located: {e}");
    }
    // A cycle is reported at its first member, naming its members only (not `u` and `v`,
    // which use it, nor `w`, which `v` uses), in the order each uses the next.
    let params = "u = \"a + 1\"\nv = \"u*w\"\nw = \"L/2\"\nb = \"2*a + L\"\na = \"sqrt(b)\"";
    let e = refused(params, "");
    let line = 1
        + example_text("rotating_pendulum.toml")
            .lines()
            .position(|l| l == "[parameters]")
            .unwrap()
        + params.lines().position(|l| l.starts_with("b = ")).unwrap()
        + 1;
    assert!(
        e.contains(
            "parameter 'b': derived parameters defined through each other in a cycle (b → a → b)"
        ) && e.contains(&format!("refused.toml:{line}:")),
        "{e}"
    );
    // The limit is 100 000 terms (numbers and parameters written), as documented: with
    // a_k = a_{k−1} + a_{k−1} and a0 = L + L, a_k has 2^(k+1) terms, so a15 + a14 + a9 + a8 +
    // a6 + a4 has 65 536 + 32 768 + 1 024 + 512 + 128 + 32 = 100 000 and is accepted, and one
    // more term is refused.
    let mut chain = String::from("a0 = \"L + L\"\n");
    for k in 1..16 {
        chain.push_str(&format!("a{k} = \"a{} + a{}\"\n", k - 1, k - 1));
    }
    let at_limit = format!("{chain}b = \"a15 + a14 + a9 + a8 + a6 + a4\"\n");
    let text = example_text("rotating_pendulum.toml").replacen(
        "[parameters]\n",
        &format!("[parameters]\n{at_limit}"),
        1,
    );
    let model = Model::from_str(&text, "limit.toml").unwrap_or_else(|e| panic!("{e}"));
    let b = model.derived.iter().find(|d| d.name == "b").unwrap();
    assert_eq!(b.value, 100_000.0);
    let over = format!("{chain}b = \"a15 + a14 + a9 + a8 + a6 + a4 + 1\"\n");
    let e = refused(&over, "");
    assert!(
        e.contains("parameter 'b': its expression expands to more than 100000 terms"),
        "{e}"
    );
    // A chain doubling at every link: 2^20 terms.
    let mut chain = String::from("a0 = \"L + L\"\n");
    for k in 1..20 {
        chain.push_str(&format!("a{k} = \"a{} + a{}\"\n", k - 1, k - 1));
    }
    assert!(refused(&chain, "").contains("more than 100000 terms"));
    // `--set` on a derived parameter names what it is made of.
    let text = derived_text();
    let e = match Compiled::from_bytes_with(text.as_bytes(), "b.toml", &[("h".into(), 0.1)]) {
        Ok(_) => panic!("--set h accepted"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("'h' is derived (= \"L/20\")"), "{e}");
    // A derived parameter may use one written after it.
    let ok = text.replace("h = \"L/20\"", "h = \"k/20\"\nk = \"L*1\"");
    assert!(Compiled::from_str(&ok, "ok.toml").is_ok());
}

/// `--wrt` (a sensitivity's variables) refuses a derived parameter: it is a function of the
/// parameters it is made of, so a derivative with respect to it alone is not defined. The
/// message says so and names them, on the command line too.
#[test]
fn a_derived_parameter_is_not_a_variable_to_differentiate_by() {
    let model = Model::from_str(&derived_text(), "d.toml").unwrap();
    let e = model
        .design_variables(Some(&["h".to_string()]))
        .expect_err("derived");
    assert!(
        e.contains("parameter 'h' is derived (= \"L/20\") from L")
            && e.contains("ask for it instead"),
        "{e}"
    );
    let e = model
        .design_variables(Some(&["nope".to_string()]))
        .unwrap_err();
    assert!(e.contains("unknown parameter 'nope'"), "{e}");
    let dir = std::env::temp_dir().join(format!("modaltol-wrt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("d.toml");
    std::fs::write(&file, derived_text()).unwrap();
    let run = common::run_with_deadline(
        &[
            "sensitivity",
            file.to_str().unwrap(),
            "--speed",
            "10",
            "--wrt",
            "h",
        ],
        std::time::Duration::from_secs(60),
    )
    .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_ne!(run.code, Some(0));
    assert!(
        run.stderr.contains("--wrt: parameter 'h' is derived"),
        "{}",
        run.stderr
    );
}
