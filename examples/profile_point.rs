//! Profiling driver (not shipped as a feature): repeats one governor modal point.
//! `cargo run --release --example profile_point`.
use modaltol::model::Model;
use modaltol::sweep::{Options, initial_guess, point};

fn main() {
    let model = Model::from_file(std::path::Path::new(
        &std::env::args()
            .nth(1)
            .unwrap_or("examples/governor.toml".into()),
    ))
    .unwrap();
    let speed: f64 = std::env::args()
        .nth(2)
        .map_or(1.595, |s| s.parse().unwrap());
    let p = model.nominal();
    let q0 = initial_guess(&model, &p, speed).unwrap();
    let q = point(&model, &p, speed, &q0, &Options::default())
        .unwrap()
        .equilibrium
        .q;
    let mut n = 0;
    for _ in 0..3000 {
        n += point(&model, &p, speed, &q, &Options::default())
            .unwrap()
            .equilibrium
            .iterations;
    }
    println!("{n}");
}
