//! Cost of a flexible rotor's size: Friswell et al. (2010) Example 5.9.1 (the shaft of
//! `examples/friswell_5_9_1.toml`: 1.5 m, Ø 50 mm, disks at 0.5 and 1 m, bearings of 1 MN/m
//! at the ends, spinning nodes) meshed into n Timoshenko elements (n a multiple of 6, so the
//! disks sit on nodes), each n in a fresh process: one cold modal point at 4000 rpm (the model
//! read and its program recorded), one swept point (the mean over a 20-speed sweep from 0 to
//! 4000 rpm after its first point: what a Campbell diagram costs a speed), and the process's
//! peak resident memory. Then the growth exponents fitted on the log–log points. Times are the
//! best of 3 runs.
//!
//! `cargo run --release --example scale_shaft -- [n …]` (default: 6 12 24 48 96);
//! `… -- model n` prints the model file.
use modaltol::compiled::Compiled;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{exponent, peak_mb};

/// The Friswell rotor in `n` elements (`n` a multiple of 6).
fn rotor(n: usize) -> String {
    assert!(
        n.is_multiple_of(6) && n > 0,
        "n must be a positive multiple of 6"
    );
    let third = n / 3;
    let disk = |name: &str, outer: f64, node: usize, x: f64| {
        format!(
            "[[bodies]]\nname = \"{name}\"\nmass = \"rho*pi*width*({outer}^2 - bore^2)/4\"\n\
             inertia = [\"rho*pi*width*({outer}^2 - bore^2)/4*({outer}^2 + bore^2)/8\", \
             \"rho*pi*width*({outer}^2 - bore^2)/4*(({outer}^2 + bore^2)/16 + width^2/12)\", \
             \"rho*pi*width*({outer}^2 - bore^2)/4*(({outer}^2 + bore^2)/16 + width^2/12)\"]\n\
             cm = [{x}, 0, 0]\n\
             [[joints]]\nname = \"{name}_on_shaft\"\ntype = \"fixed\"\nparent = \"shaft_{node}\"\n\
             child = \"{name}\"\nat = [{x}, 0, 0]\n"
        )
    };
    let bearing = |node: usize, x: f64| {
        format!(
            "[[forces]]\nname = \"bearing{node}\"\ntype = \"bushing\"\nbody1 = \"ground\"\n\
             body2 = \"shaft_{node}\"\npoint1 = [{x}, 0, 0]\nstiffness = [1e9, 1e6, 1e6, 0, 0, 0]\n"
        )
    };
    format!(
        "name = \"friswell_{n}\"\ngravity = [0, 0, 0]\n\
         [parameters]\nd = 0.05\nE = 211e9\nG = 81.2e9\nrho = 7810\nwidth = 0.07\nbore = 0.05\n\
         [[shafts]]\nname = \"shaft\"\nstart = [0, 0, 0]\naxis = [1, 0, 0]\nspin = \"speed\"\n\
         coupling = 1\nE = \"E\"\nG = \"G\"\ndensity = \"rho\"\n\
         stations = [{{ length = 1.5, elements = {n}, outer_diameter = \"d\" }}]\n{}{}{}{}",
        disk("disk1", 0.28, third, 0.5),
        disk("disk2", 0.35, 2 * third, 1.0),
        bearing(0, 0.0),
        bearing(n, 1.5),
    )
}

/// One n in this process: `[cold, swept]` (s) and the peak memory (MB).
fn measure(n: usize) -> [f64; 3] {
    let text = rotor(n);
    let best = |f: &mut dyn FnMut() -> f64| (0..3).map(|_| f()).fold(f64::INFINITY, f64::min);
    let top = 4000.0 * std::f64::consts::PI / 30.0;
    let cold = best(&mut || {
        let t = Instant::now();
        let model = Compiled::from_str(&text, "rotor.toml").unwrap();
        let p = model.model().nominal();
        let q0 = initial_guess(model.model(), &p, top).unwrap();
        point(&model, &p, top, &q0, &Options::single()).unwrap();
        t.elapsed().as_secs_f64()
    });
    let model = Compiled::from_str(&text, "rotor.toml").unwrap();
    let p = model.model().nominal();
    let swept = best(&mut || {
        let mut sweep = Sweep::new(&model, p.clone(), Options::default());
        sweep.step(0.0).unwrap();
        let t = Instant::now();
        for k in 1..20 {
            sweep.step(top * k as f64 / 19.0).unwrap();
        }
        t.elapsed().as_secs_f64() / 19.0
    });
    [cold, swept, peak_mb()]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("model") {
        print!("{}", rotor(args[1].parse().unwrap()));
        return;
    }
    if args.first().map(String::as_str) == Some("one") {
        let [cold, swept, peak] = measure(args[1].parse().unwrap());
        println!("{cold} {swept} {peak}");
        return;
    }
    let ns: Vec<usize> = if args.is_empty() {
        vec![6, 12, 24, 48, 96]
    } else {
        args.iter().map(|a| a.parse().unwrap()).collect()
    };
    let exe = std::env::current_exe().unwrap();
    println!("| n | free coordinates | cold point | swept point | peak memory |");
    println!("|---|---|---|---|---|");
    let mut rows = Vec::new();
    for &n in &ns {
        let out = std::process::Command::new(&exe)
            .args(["one", &n.to_string()])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        let v: Vec<f64> = text
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if v.len() != 3 {
            println!(
                "| {n} | failed: {} |",
                String::from_utf8_lossy(&out.stderr).trim()
            );
            continue;
        }
        println!(
            "| {n} | {} | {:.1} ms | {:.2} ms | {:.0} MB |",
            6 * (n + 1),
            1e3 * v[0],
            1e3 * v[1],
            v[2]
        );
        rows.push((n as f64, v[0], v[1]));
    }
    if rows.len() >= 2 {
        let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
        let cold: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let swept: Vec<f64> = rows.iter().map(|r| r.2).collect();
        println!(
            "growth: cold point n^{:.1}, swept point n^{:.1}",
            exponent(&x, &cold),
            exponent(&x, &swept)
        );
    }
}
