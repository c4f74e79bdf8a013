//! Helpers shared by the integration tests: the shipped examples and one solved point.
#![allow(dead_code)] // each test target uses its own subset

use modaltol::model::Model;
use modaltol::sweep::{Options, Point, initial_guess, point};
use std::path::{Path, PathBuf};

/// Path of a shipped example model.
pub fn example_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

/// Text of a shipped example model (for variants made by editing it).
pub fn example_text(name: &str) -> String {
    std::fs::read_to_string(example_path(name)).unwrap()
}

/// A shipped example model, validated.
pub fn example(name: &str) -> Model {
    Model::from_file(&example_path(name)).unwrap()
}

/// The point at `speed` with nominal parameters, solved from the model's initial guess.
pub fn at(model: &Model, speed: f64, opt: &Options) -> Point {
    let p = model.nominal();
    let q0 = initial_guess(model, &p, speed).unwrap();
    point(model, &p, speed, &q0, opt).unwrap()
}
