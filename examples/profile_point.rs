//! Profiling driver (not shipped as a feature): repeats one governor modal point.
//! `cargo run --release --example profile_point`.
use modaltol::model::Model;
use modaltol::sweep::{Options, initial_guess, point};

fn main() {
    let model = Model::from_file(std::path::Path::new("examples/governor.toml")).unwrap();
    let p = model.nominal();
    let q0 = initial_guess(&model, &p, 1.595).unwrap();
    let q = point(&model, &p, 1.595, &q0, &Options::default())
        .unwrap()
        .equilibrium
        .q;
    let mut n = 0;
    for _ in 0..3000 {
        n += point(&model, &p, 1.595, &q, &Options::default())
            .unwrap()
            .equilibrium
            .iterations;
    }
    println!("{n}");
}
