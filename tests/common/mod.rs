//! Helpers shared by the integration tests: the shipped examples and one solved point.
#![allow(dead_code)] // each test target uses its own subset

use modaltol::compiled::{Compiled, Route};
use modaltol::modal::C64;
use modaltol::sweep::{Options, Point, initial_guess, point};
use std::path::{Path, PathBuf};

pub mod pendulum;
pub mod timoshenko;

/// The shipped example models but the rotating blade (a chain of many segments).
pub const EXAMPLES: [&str; 8] = [
    "rotating_pendulum.toml",
    "conical_pendulum.toml",
    "governor.toml",
    "spinning_universal_pendulum.toml",
    "multi_arm_governor.toml",
    "multi_arm_governor_13_variables.toml",
    "spinning_spatial_fourbar.toml",
    "rotor_on_rubber_mounts.toml",
];

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
pub fn example(name: &str) -> Compiled {
    Compiled::from_file(&example_path(name)).unwrap()
}

/// The point at `speed` with nominal parameters, solved from the model's initial guess.
pub fn at(model: &Compiled, speed: f64, opt: &Options) -> Point {
    let p = model.model().nominal();
    let q0 = initial_guess(model.model(), &p, speed).unwrap();
    point(model, &p, speed, &q0, opt).unwrap()
}

/// What a run of the binary gave.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs the `modaltol` binary with `args`; kills it and returns `Err` if it is still running
/// after `limit` (a hang).
pub fn run_with_deadline(args: &[&str], limit: std::time::Duration) -> Result<Run, String> {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_modaltol"));
    cmd.args(args);
    command_with_deadline(cmd, limit)
}

/// Runs `cmd` (the binary, or a shell that sets limits and runs it); kills it and returns
/// `Err` if it is still running after `limit` (a hang).
pub fn command_with_deadline(
    mut cmd: std::process::Command,
    limit: std::time::Duration,
) -> Result<Run, String> {
    use std::io::Read;
    use std::process::Stdio;
    let args = format!("{cmd:?}");
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let ro = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let re = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let t = std::time::Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return Ok(Run {
                code: s.code(),
                stdout: ro.join().unwrap(),
                stderr: re.join().unwrap(),
            });
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("{args} hung (killed after {limit:?})"));
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// The point at `speed` with nominal parameters from the model's initial guess, on the recorded
/// route (which must record) or the direct one.
pub fn solve(model: &Compiled, speed: f64, direct: bool) -> Point {
    // The direct route on a copy; the recorded one on the model itself, so that its program,
    // recorded at the first speed asked, is replayed at the later ones.
    let reference;
    let model = if direct {
        reference = model.clone().with_route(Route::Direct);
        &reference
    } else {
        model
    };
    let p = model.model().nominal();
    let q0 = initial_guess(model.model(), &p, speed).unwrap();
    if !direct {
        assert!(
            model.program().is_some(),
            "{}: the equations record as a program",
            model.model().name
        );
    }
    point(model, &p, speed, &q0, &Options::default())
        .unwrap_or_else(|e| panic!("{}: {e}", model.model().name))
}

/// Every root of every mode.
pub fn roots(pt: &Point) -> Vec<C64> {
    pt.modes
        .iter()
        .flat_map(|m| [m.root.lambda, m.partner.lambda])
        .collect()
}

/// The two lists hold the same roots (matched greedily, nearest first) to `tol` relative.
pub fn same_roots(a: &[C64], b: &[C64], tol: f64) {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    let mut used = vec![false; b.len()];
    for x in a {
        let (k, d) = b
            .iter()
            .enumerate()
            .filter(|(k, _)| !used[*k])
            .map(|(k, y)| (k, (x - y).norm()))
            .min_by(|u, v| u.1.total_cmp(&v.1))
            .unwrap();
        used[k] = true;
        assert!(
            d <= tol * x.norm().max(1.0),
            "root {x} unmatched (nearest at {d:e}): {a:?} vs {b:?}"
        );
    }
}

/// A shaft spinning about y (gravity along −y) carrying an arm on a hinge about an inclined
/// axis: `inertia` is the arm's inertia entry (with any body-frame keys), `hinge` the hinge's
/// spring fields, `rest` any further tables (bodies, joints, force elements).
pub fn spinning_arm(inertia: &str, hinge: &str, rest: &str) -> String {
    format!(
        r#"
name = "arm"
gravity = [0, -9.80665, 0]
[[bodies]]
name = "shaft"
mass = 1
inertia = [0.01, 0.01, 0.01]
cm = [0, 0.1, 0]
[[bodies]]
name = "arm"
mass = 0.7
{inertia}
cm = [0.3, -0.2, 0.05]
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
child = "arm"
at = [0.1, 0.2, 0]
axis = [0.2, 0.3, 1]
{hinge}
{rest}
"#
    )
}

/// The flapwise frequencies of a blade spinning about z at `speed`, ascending: the modes whose
/// translations (coordinates `….x`, `….y`, `….z`) are out of the plane of rotation, along z
/// (their rotations may carry some twist, which the torsional inertia couples to flapping on a
/// spinning hub).
pub fn flapwise(m: &Compiled, speed: f64, direct: bool) -> Vec<f64> {
    let pt = solve(m, speed, direct);
    let names: Vec<&str> = (pt.linear.independent.iter())
        .map(|&i| m.model().coordinates[i].name.as_str())
        .collect();
    let mut out: Vec<f64> = (pt.modes.iter())
        .filter(|mode| {
            let x = &mode.root.right;
            let moves = |axis: &str| -> f64 {
                (x.iter().zip(&names))
                    .filter(|(_, n)| n.ends_with(axis))
                    .map(|(v, _)| v.norm_sqr())
                    .sum()
            };
            let z = moves(".z");
            z > 0.99 * (z + moves(".x") + moves(".y"))
        })
        .map(|mode| mode.natural_frequency)
        .collect();
    out.sort_by(f64::total_cmp);
    out
}

/// Nodes and weights of `∫ f(z) φ(z) dz` (`φ` the standard normal density) over `[−h, h]`:
/// 5-point Gauss–Legendre on `panels` panels, for smooth integrands (the exact statistics
/// the methods are checked against).
pub fn normal_rule(panels: usize, h: f64) -> Vec<(f64, f64)> {
    const X: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683_1,
        0.0,
        0.538_469_310_105_683_1,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.236_926_885_056_189_1,
        0.478_628_670_499_366_5,
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
    ];
    let step = 2.0 * h / panels as f64;
    let phi = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    (0..panels)
        .flat_map(|k| {
            X.iter().zip(&W).map(move |(x, w)| {
                let z = -h + step * (k as f64 + 0.5 * (1.0 + x));
                (z, 0.5 * step * w * phi(z))
            })
        })
        .collect()
}
