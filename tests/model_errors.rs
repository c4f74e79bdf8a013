//! Every validation error names the file, the line and column, and the offending item.

use modaltol::model::{Model, ModelError};

const BASE: &str = r#"gravity = [0, -9.81, 0]

[parameters]
m = 3.0
L = { value = 1.0, tolerance = "3%" }

[[bodies]]
name = "shaft"
mass = 0
cm = [0, 0, 0]

[[bodies]]
name = "rod"
mass = "m"
inertia = ["m*L^2/12", 0, "m*L^2/12"]
cm = [0, "-L/2", 0]

[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "shaft"
at = [0, 0, 0]
axis = [0, 1, 0]
drive = "speed"

[[joints]]
name = "hinge"
type = "revolute"
parent = "shaft"
child = "rod"
at = [0, 0, 0]
axis = [0, 0, 1]
damping = 3
"#;

/// Applies `from → to` to the base model and returns the error.
fn err(from: &str, to: &str) -> ModelError {
    assert!(
        BASE.contains(from),
        "test setup: '{from}' not in the base model"
    );
    let text = BASE.replacen(from, to, 1);
    Model::from_str(&text, "bad.toml").expect_err("the model should be rejected")
}

/// Line (1-based) of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).unwrap()].matches('\n').count() + 1
}

fn check(e: &ModelError, line: usize, column: Option<usize>, msg: &str) {
    assert_eq!(e.file, "bad.toml");
    assert_eq!(e.line, Some(line), "{e}");
    if let Some(c) = column {
        assert_eq!(e.column, Some(c), "{e}");
    }
    assert!(
        e.message.contains(msg),
        "message '{}' lacks '{msg}'",
        e.message
    );
    let shown = e.to_string();
    assert!(shown.starts_with(&format!("bad.toml:{line}:")), "{shown}");
}

#[test]
fn base_model_is_valid() {
    let m = Model::from_str(BASE, "ok.toml").unwrap();
    assert_eq!(m.dof(), 1);
}

#[test]
fn unknown_body_reference() {
    let e = err("child = \"rod\"", "child = \"rdo\"");
    check(
        &e,
        line_of(BASE, "child = \"rod\""),
        Some(9),
        "unknown body 'rdo'",
    );
}

#[test]
fn duplicate_names() {
    let e = err("name = \"hinge\"", "name = \"spin\"");
    check(
        &e,
        line_of(BASE, "name = \"hinge\""),
        Some(8),
        "duplicate joint name 'spin'",
    );
    let e = err("name = \"rod\"", "name = \"shaft\"");
    check(
        &e,
        line_of(BASE, "name = \"rod\""),
        Some(8),
        "duplicate body name 'shaft'",
    );
}

#[test]
fn missing_field() {
    let e = err("cm = [0, \"-L/2\", 0]\n", "");
    assert!(e.message.contains("missing field `cm`"), "{e}");
    assert!(e.line.is_some());
}

#[test]
fn unknown_field_is_a_typo_not_ignored() {
    let e = err("damping = 3", "dampign = 3");
    check(
        &e,
        line_of(BASE, "damping = 3"),
        Some(1),
        "unknown field `dampign`",
    );
}

#[test]
fn bad_expression_points_into_the_string() {
    let e = err("cm = [0, \"-L/2\", 0]", "cm = [0, \"-L/*2\", 0]");
    // The '*' after '/' is at column 14 of `cm = [0, "-L/*2", 0]`.
    check(
        &e,
        line_of(BASE, "cm = [0, \"-L/2\""),
        Some(14),
        "bad expression",
    );
    assert!(e.message.contains("body 'rod' cm[1]"), "{e}");
}

#[test]
fn unknown_parameter() {
    let e = err("mass = \"m\"", "mass = \"mass_rod\"");
    check(
        &e,
        line_of(BASE, "mass = \"m\""),
        Some(9),
        "unknown parameter 'mass_rod'",
    );
}

#[test]
fn body_not_connected_to_ground() {
    let e = err(
        "[[joints]]\nname = \"hinge\"",
        "[[bodies]]\nname = \"loose\"\nmass = 1\ncm = [0, 0, 0]\n\n[[joints]]\nname = \"hinge\"",
    );
    check(
        &e,
        line_of(BASE, "name = \"hinge\""),
        None,
        "body 'loose' is not connected to ground",
    );
}

#[test]
fn cycle_in_the_joint_tree() {
    // spin: shaft's parent becomes rod, hinge: rod's parent is shaft → a cycle without ground.
    let e = err("parent = \"ground\"", "parent = \"rod\"");
    assert!(e.message.contains("cycle"), "{e}");
    assert!(
        e.message.contains("spin") && e.message.contains("hinge"),
        "{e}"
    );
    assert!(e.line.is_some() && e.column.is_some());
}

#[test]
fn zero_axis() {
    let e = err("axis = [0, 0, 1]", "axis = [0, 0, \"L - 1\"]");
    check(
        &e,
        line_of(BASE, "axis = [0, 0, 1]"),
        Some(8),
        "axis is zero",
    );
}

#[test]
fn more_constraints_than_coordinates() {
    let extra = "\n[[constraints]]\nname = \"c1\"\ntype = \"distance\"\nbody1 = \"ground\"\npoint1 = [0, 0, 0]\nbody2 = \"rod\"\npoint2 = [0, -1, 0]\n\n[[constraints]]\nname = \"c2\"\ntype = \"distance\"\nbody1 = \"ground\"\npoint1 = [1, 0, 0]\nbody2 = \"rod\"\npoint2 = [0, -1, 0]\n";
    let text = format!("{BASE}{extra}");
    let e = Model::from_str(&text, "bad.toml").unwrap_err();
    assert!(e.message.contains("no degree of freedom"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "name = \"c2\"") - 1));
}

#[test]
fn non_finite_values() {
    let e = err("damping = 3", "damping = nan");
    check(&e, line_of(BASE, "damping = 3"), Some(11), "not finite");
    let e = err("m = 3.0", "m = inf");
    check(&e, line_of(BASE, "m = 3.0"), Some(5), "not finite");
    let e = err("mass = \"m\"", "mass = \"exp(1000)\"");
    check(&e, line_of(BASE, "mass = \"m\""), Some(8), "not finite");
}

#[test]
fn division_by_zero_in_an_expression() {
    let e = err("mass = \"m\"", "mass = \"m / (L - 1)\"");
    check(
        &e,
        line_of(BASE, "mass = \"m\""),
        Some(8),
        "division by zero",
    );
}

#[test]
fn negative_mass() {
    let e = err("mass = \"m\"", "mass = \"-m\"");
    check(&e, line_of(BASE, "mass = \"m\""), Some(8), "negative mass");
}

#[test]
fn inertia_not_positive_semidefinite() {
    let e = err(
        "inertia = [\"m*L^2/12\", 0, \"m*L^2/12\"]",
        "inertia = [[1, 2, 0], [2, 1, 0], [0, 0, 1]]",
    );
    check(
        &e,
        line_of(BASE, "inertia = "),
        Some(11),
        "not positive semi-definite",
    );
    let e = err(
        "inertia = [\"m*L^2/12\", 0, \"m*L^2/12\"]",
        "inertia = [[1, 2, 0], [0, 1, 0], [0, 0, 1]]",
    );
    check(&e, line_of(BASE, "inertia = "), Some(11), "not symmetric");
}

#[test]
fn syntax_errors_and_wrong_types() {
    let e = err("m = 3.0", "m = 3.0.0");
    assert_eq!(e.line, Some(line_of(BASE, "m = 3.0")));
    let e = err("axis = [0, 0, 1]", "axis = [0, 0]");
    check(
        &e,
        line_of(BASE, "axis = [0, 0, 1]"),
        Some(8),
        "expected 3 components",
    );
    let e = err(
        "type = \"revolute\"\nparent = \"shaft\"",
        "type = \"ball\"\nparent = \"shaft\"",
    );
    check(
        &e,
        line_of(BASE, "type = \"revolute\"\nparent = \"shaft\""),
        Some(8),
        "unknown type 'ball'",
    );
    let e = err("mass = 0", "mass = true");
    assert!(e.message.contains("a number or an expression"), "{e}");
}

#[test]
fn non_utf8_bytes() {
    let mut bytes = BASE.as_bytes().to_vec();
    let at = BASE.find("shaft").unwrap();
    bytes[at] = 0xff;
    let e = Model::from_bytes(&bytes, "bad.toml").unwrap_err();
    check(&e, line_of(BASE, "shaft"), Some(9), "not valid UTF-8");
}

#[test]
fn force_elements_take_the_fields_their_type_declares() {
    let with = |force: &str| {
        let text = format!("{BASE}\n[[forces]]\nname = \"f\"\n{force}");
        let e = Model::from_str(&text, "bad.toml").expect_err("the model should be rejected");
        (text, e)
    };
    let (text, e) = with("type = \"torsion_bar\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\n");
    check(
        &e,
        line_of(&text, "torsion_bar"),
        None,
        "unknown type 'torsion_bar' (expected spring_damper, rotational_spring_damper, bushing, spherical_spring_damper or bearing)",
    );
    let (text, e) = with(
        "type = \"bushing\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\npoint1 = [0, 0, 0]\nstiffness = [1, 2, 3, 4, 5]\n",
    );
    check(
        &e,
        line_of(&text, "stiffness = [1"),
        None,
        "expected 6 value(s), one per component, got 5",
    );
    let (text, e) =
        with("type = \"rotational_spring_damper\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\n");
    check(
        &e,
        line_of(&text, "[[forces]]"),
        None,
        "a rotational_spring_damper needs 'axis'",
    );
    let (text, e) = with(
        "type = \"rotational_spring_damper\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\naxis = [0, 0, 1]\npoint1 = [0, 0, 0]\n",
    );
    check(
        &e,
        line_of(&text, "point1 = [0, 0, 0]\n"),
        None,
        "a rotational_spring_damper has no 'point1'",
    );
    let (text, e) = with(
        "type = \"spherical_spring_damper\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\naxis = [0.5, 1, 0]\n",
    );
    check(
        &e,
        line_of(&text, "axis = [0.5, 1, 0]\n"),
        None,
        "a spherical_spring_damper has no 'axis'",
    );
    let (text, e) = with(
        "type = \"spherical_spring_damper\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\ndamping = [1, 2]\n",
    );
    check(
        &e,
        line_of(&text, "damping = [1, 2]"),
        None,
        "expected 3 value(s), one per component, got 2",
    );
    let (text, e) = with(
        "type = \"spring_damper\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\npoint1 = [0, 0, 0]\npoint2 = [0, 0, 0]\nstiffness = 3\n",
    );
    check(
        &e,
        line_of(&text, "[[forces]]"),
        None,
        "its two points coincide in the reference configuration",
    );
    // Matrices: square over the components, rows of the right length, not mixed with values,
    // and only where a matrix means something.
    let bearing = "type = \"bearing\"\nbody1 = \"ground\"\nbody2 = \"rod\"\npoint1 = [0, 0, 0]\naxis = [0, 1, 0]\n";
    let (text, e) = with(&format!("{bearing}stiffness = [[1, 2, 0], [3, 4, 0]]\n"));
    check(
        &e,
        line_of(&text, "stiffness = [["),
        None,
        "force 'f' stiffness: a matrix over the 3 components needs 3 rows of 3, got 2 rows",
    );
    let (text, e) = with(&format!(
        "{bearing}damping = [[1, 2, 0], [3, 4], [0, 0, 1]]\n"
    ));
    check(
        &e,
        line_of(&text, "damping = [["),
        None,
        "force 'f' damping: row 2 of the matrix has 2 entries, not 3 (one per component)",
    );
    let (text, e) = with(&format!("{bearing}stiffness = [1, [2, 3]]\n"));
    check(
        &e,
        line_of(&text, "stiffness = [1"),
        None,
        "a list of values or a matrix (a list of rows), not a mix of the two",
    );
    let (text, e) = with(&format!("{bearing}axis2 = [0, 2, 0]\n"));
    check(
        &e,
        line_of(&text, "axis2"),
        None,
        "force 'f': its axis2 [0.0, 2.0, 0.0] is zero or parallel to its axis [0.0, 1.0, 0.0]",
    );
    let (text, e) = with(
        "type = \"bushing\"\nbody1 = \"shaft\"\nbody2 = \"rod\"\npoint1 = [0, 0, 0]\naxis2 = [1, 0, 0]\n",
    );
    check(
        &e,
        line_of(&text, "axis2"),
        None,
        "force 'f': a bushing has no axis, so no 'axis2'",
    );
    let (text, e) = with(&format!(
        "{bearing}stiffness = [[1, 2, 0], [3, 4, 0], [0, 0, \"m/0\"]]\n"
    ));
    check(
        &e,
        line_of(&text, "stiffness = [["),
        None,
        "stiffness[2][2]",
    );
    let hinge = BASE.replacen("damping = 3", "damping = [[3]]", 1);
    let e = Model::from_str(&hinge, "bad.toml").expect_err("a matrix on a joint");
    check(
        &e,
        line_of(&hinge, "damping = [[3]]"),
        None,
        "a matrix is taken by a force element's stiffness and damping only",
    );
}

#[test]
fn a_coordinate_named_twice_as_independent_is_refused_for_every_example() {
    for name in [
        "rotating_pendulum.toml",
        "governor.toml",
        "spinning_universal_pendulum.toml",
        "spinning_spatial_fourbar.toml",
        "rotor_on_rubber_mounts.toml",
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples")
            .join(name);
        let m = Model::from_file(&path).unwrap();
        let free: Vec<String> = m
            .free()
            .iter()
            .map(|&i| m.coordinates[i].name.clone())
            .collect();
        // Every free coordinate repeated in place of the next one (or beside itself where
        // there is only one degree of freedom): as many names as degrees of freedom, or one
        // more, and never accepted.
        for (k, c) in free.iter().enumerate() {
            let mut names: Vec<String> = free.iter().take(m.dof().max(2)).cloned().collect();
            names.retain(|n| n != c);
            names.insert(0, c.clone());
            names.insert(1, c.clone());
            names.truncate(m.dof().max(2));
            let e = m.independent_coordinates(&names).unwrap_err();
            assert!(
                e.contains(&format!("'{c}' is named twice")),
                "{name}, coordinate {k} ({names:?}): {e}"
            );
        }
    }
}

#[test]
fn tables_are_checked_where_they_are_written() {
    let with = |table: &str| {
        let text = format!("{BASE}\n[[tables]]\n{table}");
        let e = Model::from_str(&text, "bad.toml").expect_err("the model should be rejected");
        (text, e)
    };
    let (text, e) = with("name = \"kxx\"\nx = [0, 200, 100]\ny = [1, 2, 3]\n");
    check(
        &e,
        line_of(&text, "x = [0, 200"),
        None,
        "table 'kxx': x must increase strictly, but x[2] = 100 follows x[1] = 200",
    );
    let (text, e) = with("name = \"kxx\"\nx = [0, 100]\ny = [1, 2, 3]\n");
    check(
        &e,
        line_of(&text, "y = [1, 2, 3]"),
        None,
        "x has 2 values and y 3",
    );
    let (text, e) = with("name = \"m\"\nx = [0, 100]\ny = [1, 2]\n");
    check(
        &e,
        line_of(&text, "name = \"m\""),
        None,
        "table name 'm' is already taken by a parameter",
    );
    let (text, e) = with("name = \"sqrt\"\nx = [0, 100]\ny = [1, 2]\n");
    check(
        &e,
        line_of(&text, "name = \"sqrt\""),
        None,
        "table name 'sqrt' is already taken by a built-in function or reserved name",
    );
    // A call with two arguments, and of a table that is not there.
    let table = "[[tables]]\nname = \"c\"\nx = [0, 100]\ny = [1, 2]\n";
    let text = format!(
        "{}\n{table}",
        BASE.replacen("damping = 3", "damping = \"c(speed, 2)\"", 1)
    );
    let e = Model::from_str(&text, "bad.toml").unwrap_err();
    check(
        &e,
        line_of(&text, "damping = \"c("),
        None,
        "table 'c' takes one argument",
    );
    let text = BASE.replacen("damping = 3", "damping = \"c(speed)\"", 1);
    let e = Model::from_str(&text, "bad.toml").unwrap_err();
    check(
        &e,
        line_of(&text, "damping = \"c("),
        None,
        "unknown function 'c' (known: sqrt sin cos tan asin acos atan atan2 exp ln abs, and the model's [[tables]])",
    );
}
