//! Profiling driver: repeats one modal point (or, with a third argument `sens`, the
//! sensitivities at that point) for `perf record`.
//! `cargo run --release --example profile_point -- examples/governor.toml 1.595 [sens]`.
use modaltol::compiled::Compiled;
use modaltol::sensitivity::{DesignPoint, TransferAt};
use modaltol::sweep::{Options, initial_guess, point};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let file = args.get(1).map_or("examples/governor.toml", |s| s.as_str());
    let speed: f64 = args.get(2).map_or(1.595, |s| s.parse().unwrap());
    let sens = args.get(3).is_some_and(|s| s == "sens");
    let model = Compiled::from_file(std::path::Path::new(file)).unwrap();
    let p = model.model().nominal();
    let q0 = initial_guess(model.model(), &p, speed).unwrap();
    let pt = point(&model, &p, speed, &q0, &Options::default()).unwrap();
    let tf = model
        .model()
        .analysis
        .transfer
        .map(|t| TransferAt::at_speed(&t, speed));
    let wrt = model.model().toleranced();
    let mut n = 0;
    for _ in 0..3000 {
        if sens {
            n += DesignPoint::new(&model, &p, &pt)
                .with_transfer(tf)
                .analytic(&wrt)
                .unwrap()
                .variables
                .len();
        } else {
            n += point(&model, &p, speed, &pt.equilibrium.q, &Options::default())
                .unwrap()
                .equilibrium
                .iterations;
        }
    }
    println!("{n}");
}
