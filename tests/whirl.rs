//! Whirl directions (issue 57, item 3) against the book and closed forms:
//!
//! * Friswell et al. (2010) Example 5.9.1 at 4000 rpm: each pair's lower root whirls backward
//!   and its upper one forward (the book's Fig. 5.13 and Table 5.5; ROSS labels the same);
//! * a rigid disk on isotropic bearings spinning about its axis: the tilt pair splits into
//!   `Id ω² ∓ Ip Ω ω − k_r = 0` (forward the upper root), and the bounce pair, which the spin
//!   does not split, is one forward and one backward circle at the same `√(k/m)`; the axial
//!   and torsional modes and every mode at rest have no whirl;
//! * the same disk written in rotating coordinates (its translations riding on the drive)
//!   is not labelled.

mod common;

use common::solve;
use modaltol::compiled::Compiled;
use modaltol::whirl::{Whirl, of_point};

fn labels(m: &Compiled, w: f64) -> Vec<(f64, Option<Whirl>)> {
    let pt = solve(m, w, false);
    let whirl = of_point(m.model(), &m.model().nominal(), &pt).unwrap();
    pt.modes
        .iter()
        .map(|m| m.damped_frequency)
        .zip(whirl)
        .collect()
}

/// The label of the mode at `omega` (within 0.05 %).
fn at(labels: &[(f64, Option<Whirl>)], omega: f64) -> Vec<Option<Whirl>> {
    let found: Vec<_> = (labels.iter())
        .filter(|(w, _)| (w - omega).abs() <= 5e-4 * omega)
        .map(|x| x.1)
        .collect();
    assert!(!found.is_empty(), "no mode at {omega}: {labels:?}");
    found
}

#[test]
fn friswell_5_9_1_whirls_as_the_book_says() {
    let m = common::example("friswell_5_9_1.toml");
    let l = labels(&m, 4000.0 * std::f64::consts::PI / 30.0);
    use Whirl::{Backward, Forward};
    for (omega, whirl) in [
        (85.39, Backward),
        (87.80, Forward),
        (251.78, Backward),
        (294.71, Forward),
        (600.18, Backward),
        (827.08, Forward),
    ] {
        assert_eq!(at(&l, omega), [Some(whirl)], "{omega} rad/s: {l:?}");
    }
    // At rest nothing spins: no whirl.
    assert!(labels(&m, 0.0).iter().all(|x| x.1.is_none()));
}

/// A rigid disk (mass m, inertia [Id, Id, Ip] about its centre) spinning about z on a frame
/// held at its centre by isotropic bearings: stationary coordinates (a free joint to the frame,
/// the spin a driven revolute) or rotating ones (the spin first, then the slides).
fn disk(rotating: bool) -> Compiled {
    let holder = if rotating {
        r#"
[[joints]]
name = "spin"
type = "revolute"
parent = "ground"
child = "frame"
at = [0, 0, 0]
axis = [0, 0, 1]
drive = "speed"
[[joints]]
name = "float"
type = "free"
parent = "frame"
child = "disk"
at = [0, 0, 0]
[[forces]]
name = "bearing"
type = "bushing"
body1 = "frame"
body2 = "disk"
point1 = [0, 0, 0]
stiffness = ["k", "k", "kz", "kr", "kr", "kt"]
"#
    } else {
        r#"
[[joints]]
name = "float"
type = "free"
parent = "ground"
child = "frame"
at = [0, 0, 0]
[[joints]]
name = "spin"
type = "revolute"
parent = "frame"
child = "disk"
at = [0, 0, 0]
axis = [0, 0, 1]
drive = "speed"
[[forces]]
name = "bearing"
type = "bushing"
body1 = "ground"
body2 = "frame"
point1 = [0, 0, 0]
stiffness = ["k", "k", "kz", "kr", "kr", "kt"]
"#
    };
    Compiled::from_str(
        &format!(
            r#"
name = "disk"
[parameters]
m = 10.0
Id = 0.05
Ip = 0.09
k = 1e6
kz = 4e6
kr = 2e4
kt = 3e3
[[bodies]]
name = "frame"
mass = 0
cm = [0, 0, 0]
[[bodies]]
name = "disk"
mass = "m"
inertia = ["Id", "Id", "Ip"]
cm = [0, 0, 0]
{holder}
"#
        ),
        "disk.toml",
    )
    .unwrap()
}

#[test]
fn a_spinning_disk_whirls_as_its_closed_form() {
    let (m, id, ip, k, kz, kr, kt): (f64, f64, f64, f64, f64, f64, f64) =
        (10.0, 0.05, 0.09, 1e6, 4e6, 2e4, 3e3);
    let d = disk(false);
    for spin in [50.0, 400.0, -400.0] {
        let l = labels(&d, spin);
        let g = ip * spin.abs();
        let root = (g * g + 4.0 * id * kr).sqrt();
        let (forward, backward) = ((g + root) / (2.0 * id), (-g + root) / (2.0 * id));
        // The spin's sense does not matter: the forward root is the one turning with it.
        assert_eq!(at(&l, forward), [Some(Whirl::Forward)], "Ω = {spin}: {l:?}");
        assert_eq!(
            at(&l, backward),
            [Some(Whirl::Backward)],
            "Ω = {spin}: {l:?}"
        );
        let mut bounce = at(&l, (k / m).sqrt());
        bounce.sort_by_key(|w| w.map(Whirl::as_str));
        assert_eq!(
            bounce,
            [Some(Whirl::Backward), Some(Whirl::Forward)],
            "Ω = {spin}"
        );
        assert_eq!(at(&l, (kz / m).sqrt()), [None]);
        assert_eq!(at(&l, (kt / ip).sqrt()), [None]);
    }
    assert!(labels(&d, 0.0).iter().all(|x| x.1.is_none()));
    // In rotating coordinates the orbits are the rotating frame's: no label.
    assert!(labels(&disk(true), 400.0).iter().all(|x| x.1.is_none()));
}

/// The sweep CSV's `whirl` column and the modal JSON's `whirl` say it for the Friswell rotor.
#[test]
fn the_outputs_carry_the_whirl() {
    let exe = env!("CARGO_BIN_EXE_modaltol");
    let file = common::example_path("friswell_5_9_1.toml");
    let out = std::process::Command::new(exe)
        .args([
            "sweep",
            file.to_str().unwrap(),
            "--speed",
            "0:418.879:418.879",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut r = csv::Reader::from_reader(out.stdout.as_slice());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let mut seen = Vec::new();
    for row in r.records() {
        let row = row.unwrap();
        let (speed, w): (f64, f64) = (
            row[col("speed")].parse().unwrap(),
            row[col("damped_frequency")].parse().unwrap(),
        );
        let whirl = row[col("whirl")].to_string();
        if speed == 0.0 {
            assert_eq!(whirl, "", "at rest");
        } else if (w - 87.80).abs() < 0.05 || (w - 85.39).abs() < 0.05 {
            seen.push(whirl);
        }
    }
    seen.sort();
    assert_eq!(seen, ["backward", "forward"]);
    let out = std::process::Command::new(exe)
        .args([
            "modal",
            file.to_str().unwrap(),
            "--speed",
            "418.879",
            "--format",
            "json",
        ])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mode = (v["modes"].as_array().unwrap().iter())
        .find(|m| (m["damped_frequency"].as_f64().unwrap() - 294.71).abs() < 0.05)
        .unwrap();
    assert_eq!(mode["whirl"], "forward");
}
