//! Claims about the engine, each checked against an independent route: closed forms derived by
//! hand for the rotating pendulum and the governor, finite differences of the nonlinear reduced
//! equations, a second choice of independent coordinates, and time-domain integration.

mod common;

use approx::assert_relative_eq;
use common::pendulum::{G, pendulum};
use common::{at, example, example_text};
use modaltol::compiled::{Compiled, Route};
use modaltol::equations::{Direct, Equations};
use modaltol::mechanics::System;
use modaltol::mechanics::dynamics::{Lifted, constraints_at, evaluate};
use modaltol::modal::ModeClass;
use modaltol::model::Model;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use nalgebra::DMatrix;
use num_dual::{Dual2, Dual64};
use std::f64::consts::{FRAC_PI_2, PI};

#[test]
fn pendulum_damped_frequency_matches_closed_form_on_both_branches() {
    let model = example("rotating_pendulum.toml");
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    let (i, c) = (1.0, 3.0);
    let mut overdamped = Vec::new();
    for s in 0..=600 {
        let w = s as f64 * 0.01;
        let p = sweep.step(w).unwrap();
        let known = pendulum(1.0, w);
        let (theta, k) = (known.theta, known.stiffness);
        assert!(
            (p.equilibrium.q[1] - theta).abs() < 1e-10,
            "Ω = {w}: θ = {} vs {theta}",
            p.equilibrium.q[1]
        );
        let disc = 4.0 * i * k - c * c;
        let wd = disc.max(0.0).sqrt() / (2.0 * i);
        let mode = &p.modes[0];
        assert!(
            (mode.damped_frequency - wd).abs() <= 1e-9 * wd.max(1e-3),
            "Ω = {w}: ω_d = {} vs {wd}",
            mode.damped_frequency
        );
        assert_relative_eq!(mode.natural_frequency, (k / i).sqrt(), max_relative = 1e-9);
        assert_ne!(
            mode.class,
            ModeClass::Unstable,
            "Ω = {w}: the stable branch must be followed"
        );
        assert_eq!(mode.class == ModeClass::Overdamped, disc < 0.0, "Ω = {w}");
        if mode.class == ModeClass::Overdamped {
            overdamped.push(w);
        }
    }
    // The paper's band 3.530 < Ω < 3.984 on this 0.01 grid.
    assert_relative_eq!(overdamped[0], 3.53, epsilon = 1e-12);
    assert_relative_eq!(*overdamped.last().unwrap(), 3.98, epsilon = 1e-12);
    assert_eq!(overdamped.len(), 46);
}

#[test]
fn pendulum_hanging_position_loses_stability_at_sqrt_3g_over_2l() {
    let model = example("rotating_pendulum.toml");
    let hanging = Options {
        no_branch_switch: true,
        ..Default::default()
    };
    let p = model.model().nominal();
    let unstable = |w: f64| {
        let pt = point(&model, &p, w, &[0.0, 0.0], &hanging).unwrap();
        assert!(pt.equilibrium.q[1].abs() < 1e-12);
        pt.modes[0].class == ModeClass::Unstable
    };
    let (mut lo, mut hi) = (3.0, 4.5);
    assert!(!unstable(lo) && unstable(hi));
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) { hi = mid } else { lo = mid }
    }
    let critical = (3.0 * G / 2.0).sqrt();
    assert!(
        (lo - critical).abs() < 1e-6,
        "stability lost at {lo}, expected {critical}"
    );
    assert_relative_eq!(critical, 3.835, epsilon = 1e-3);
    // Past it, the sweep swings out and says so.
    let mut sweep = Sweep::new(&model, p.clone(), Options::default());
    sweep.step(3.83).unwrap();
    let out = sweep.step(3.84).unwrap();
    assert!(out.equilibrium.q[1] > 0.05 && out.stable());
    assert_eq!(out.branch.as_str(), "switched");
    assert!(
        (out.branch.to_string()).contains("static divergence"),
        "{}",
        out.branch
    );
}

/// Governor by hand: arm angle φ from the downward spindle axis, the planar effective potential
/// V(φ) = V_gravity + V_spring − ½ Ω² J_y(φ) is stationary at the steady state.
fn governor_collar_height(w: f64) -> f64 {
    let (mb, k, a, arm, hy, link, l0) = (1.0, 1000.0, 0.08, 0.16, 0.2, 0.10922, 0.15);
    let g = 9.8;
    let collar = |phi: f64| hy - a * phi.cos() - (link * link - (a * phi.sin()).powi(2)).sqrt();
    let v = |phi: f64| {
        let h = collar(phi);
        let ball_y = hy - arm * phi.cos();
        let ball_x = arm * phi.sin();
        let gravity = 2.0 * mb * g * ball_y + 1.0 * g * h;
        let spring = 0.5 * k * ((hy - h) - l0).powi(2);
        let spin = 0.5 * w * w * 2.0 * mb * ball_x * ball_x; // constant inertia terms dropped
        gravity + spring - spin
    };
    let dv = |phi: f64| (v(phi + 1e-6) - v(phi - 1e-6)) / 2e-6;
    // The stable equilibrium: the minimum of V between hanging nearly straight and 85°.
    let (mut lo, mut hi) = (0.05, 85f64.to_radians());
    assert!(dv(lo) < 0.0 && dv(hi) > 0.0, "bracket at Ω = {w}");
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if dv(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    collar(0.5 * (lo + hi))
}

#[test]
fn governor_collar_height_matches_planar_energy_balance() {
    let model = example("governor.toml");
    let mut sweep = Sweep::new(&model, model.model().nominal(), Options::default());
    let slide = model.model().coordinate("slide").unwrap();
    for s in 0..=24 {
        let w = 0.5 * s as f64;
        let p = sweep.step(w).unwrap();
        let h = 0.05 + p.equilibrium.q[slide];
        let expected = governor_collar_height(w);
        assert!(
            (h - expected).abs() < 1e-7,
            "Ω = {w}: collar at {h} m, energy balance {expected} m"
        );
        assert!(
            p.equilibrium.constraint_violation <= 1e-12,
            "Ω = {w}: |Φ| = {}",
            p.equilibrium.constraint_violation
        );
    }
    // Haug's operating point: Ω = 11.0174 rad/s holds the arms at 45° (spring at free length).
    let p = at(&model, 11.0174, &Options::default());
    assert!(p.equilibrium.q[model.model().coordinate("arm1").unwrap()].abs() < 1e-4);
}

#[test]
fn governor_eigenvalues_independent_of_coordinate_choice() {
    let model = example("governor.toml");
    for w in [0.5, 1.595, 4.0, 11.0174] {
        let mut roots = Vec::new();
        for name in ["slide", "arm1", "arm2"] {
            let opt = Options {
                independent: Some(vec![model.model().coordinate(name).unwrap()]),
                ..Default::default()
            };
            let p = at(&model, w, &opt);
            assert_eq!(
                p.linear.independent,
                vec![model.model().coordinate(name).unwrap()]
            );
            roots.push((p.modes[0].root.lambda, p.modes[0].partner.lambda));
        }
        for r in &roots[1..] {
            for (a, b) in [(r.0, roots[0].0), (r.1, roots[0].1)] {
                assert!((a - b).norm() <= 1e-10 * b.norm(), "Ω = {w}: {a} vs {b}");
            }
        }
    }
}

/// The nonlinear reduced equations f(z, ż, z̈) = R(q)ᵀ r_R(q, q̇, q̈) on the constraint manifold,
/// built without the library's linearisation: dependent coordinates by Newton on Φ, their time
/// derivatives exact through Dual2 arithmetic, R from Φ_q at the perturbed state. No λ anywhere.
struct Reduced<'a> {
    model: &'a Model,
    sys: System<f64>,
    lifted: Lifted<f64>,
    q: Vec<f64>,
    qd_drive: Vec<f64>,
    free: Vec<usize>,
    ind: Vec<usize>,
    dep: Vec<usize>,
}

impl Reduced<'_> {
    fn phi_q(&self, q: &[f64], cols: &[usize]) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(self.sys.m, cols.len());
        for (j, &c) in cols.iter().enumerate() {
            let mut qq: Vec<Dual64> = q.iter().map(|&v| Dual64::from_re(v)).collect();
            qq[c] = Dual64::new(q[c], 1.0);
            let phi = constraints_at(&self.sys.map(Dual64::from_re), &qq);
            for k in 0..self.sys.m {
                out[(k, j)] = phi[k].eps;
            }
        }
        out
    }

    fn f(&self, z: &[f64], zd: &[f64], zdd: &[f64]) -> Vec<f64> {
        let n = self.q.len();
        let mut qt: Vec<Dual2<f64>> = (0..n)
            .map(|i| Dual2::new(self.q[i], self.qd_drive[i], 0.0))
            .collect();
        for (k, &i) in self.ind.iter().enumerate() {
            qt[i] = Dual2::new(self.q[i] + z[k], zd[k], zdd[k]);
        }
        let sys2 = self.sys.map(Dual2::from_re);
        for _ in 0..if self.dep.is_empty() { 0 } else { 60 } {
            let re: Vec<f64> = qt.iter().map(|x| x.re).collect();
            let pu = self.phi_q(&re, &self.dep);
            let phi = constraints_at(&sys2, &qt);
            let lu = pu.lu();
            let rhs =
                |f: fn(&Dual2<f64>) -> f64| DMatrix::from_iterator(phi.len(), 1, phi.iter().map(f));
            let d0 = lu.solve(&rhs(|x| x.re)).unwrap();
            let d1 = lu.solve(&rhs(|x| x.v1)).unwrap();
            let d2 = lu.solve(&rhs(|x| x.v2)).unwrap();
            for (k, &i) in self.dep.iter().enumerate() {
                qt[i] -= Dual2::new(d0[k], d1[k], d2[k]);
            }
        }
        let q: Vec<f64> = qt.iter().map(|x| x.re).collect();
        let qd: Vec<f64> = qt.iter().map(|x| x.v1).collect();
        let qdd: Vec<f64> = qt.iter().map(|x| x.v2).collect();
        let r = evaluate(&self.lifted, &q, &qd, &qdd).r;
        // R = [−Φ_u⁻¹ Φ_v; I] at the perturbed configuration.
        let nd = self.ind.len();
        let mut basis = DMatrix::zeros(self.free.len(), nd);
        let x = if self.dep.is_empty() {
            DMatrix::zeros(0, nd)
        } else {
            self.phi_q(&q, &self.dep)
                .lu()
                .solve(&self.phi_q(&q, &self.ind))
                .unwrap()
        };
        for (row, &f) in self.free.iter().enumerate() {
            if let Some(k) = self.ind.iter().position(|&i| i == f) {
                basis[(row, k)] = 1.0;
            } else {
                let k = self.dep.iter().position(|&i| i == f).unwrap();
                for c in 0..nd {
                    basis[(row, c)] = -x[(k, c)];
                }
            }
        }
        let rr = DMatrix::from_iterator(self.free.len(), 1, self.free.iter().map(|&i| r[i]));
        (basis.transpose() * rr).iter().copied().collect()
    }
}

#[test]
fn linearisation_matches_finite_differences_of_reduced_equations() {
    for (file, speeds) in [
        ("rotating_pendulum.toml", vec![1.0, 3.0, 5.0]),
        ("governor.toml", vec![0.8, 1.595, 6.0, 11.0174]),
        ("spinning_universal_pendulum.toml", vec![0.0, 2.5, 6.0]),
    ] {
        let model = example(file);
        for w in speeds {
            let pt = at(&model, w, &Options::default());
            let sys = System::new(model.model(), &model.model().nominal(), w).unwrap();
            let free = model.model().free();
            let ind = pt.linear.independent.clone();
            let red = Reduced {
                model: model.model(),
                lifted: Lifted::new(sys.clone()),
                qd_drive: sys.steady_speeds(),
                sys,
                q: pt.equilibrium.q.clone(),
                dep: free.iter().copied().filter(|i| !ind.contains(i)).collect(),
                free,
                ind,
            };
            let _ = red.model;
            let nd = red.ind.len();
            let zero = vec![0.0; nd];
            let h = 1e-5;
            for (which, lib) in [(0, &pt.linear.k), (1, &pt.linear.c), (2, &pt.linear.m)] {
                let scale = lib.amax().max(1e-300);
                for j in 0..nd {
                    let mut plus = [zero.clone(), zero.clone(), zero.clone()];
                    let mut minus = plus.clone();
                    plus[which][j] = h;
                    minus[which][j] = -h;
                    let fp = red.f(&plus[0], &plus[1], &plus[2]);
                    let fm = red.f(&minus[0], &minus[1], &minus[2]);
                    for i in 0..nd {
                        let fd = (fp[i] - fm[i]) / (2.0 * h);
                        assert!(
                            (fd - lib[(i, j)]).abs() <= 1e-6 * scale,
                            "{file} Ω = {w}: {}[{i},{j}] = {} but finite differences give {fd}",
                            ["K̂", "Ĉ", "M̂"][which],
                            lib[(i, j)]
                        );
                    }
                }
            }
        }
    }
}

/// Integrates the full nonlinear pendulum (RK4) from a small perturbation and measures ω_d
/// (zero crossings) and ζ (decay of successive extrema).
fn pendulum_time_response(model: &Compiled, w: f64, theta0: f64) -> (f64, f64) {
    let sys = System::new(model.model(), &model.model().nominal(), w).unwrap();
    let lifted = Lifted::new(sys);
    let accel = |t: f64, th: f64, thd: f64| {
        let q = [w * t, th];
        let qd = [w, thd];
        let r0 = evaluate(&lifted, &q, &qd, &[0.0, 0.0]).r[1];
        let m = evaluate(&lifted, &q, &qd, &[0.0, 1.0]).r[1] - r0;
        -r0 / m
    };
    let dt = 1e-3;
    let (mut t, mut x, mut v) = (0.0, theta0 + 1e-5, 0.0);
    let mut samples = vec![(t, x - theta0)];
    while t < 12.0 {
        let k1 = (v, accel(t, x, v));
        let k2 = (
            v + 0.5 * dt * k1.1,
            accel(t + 0.5 * dt, x + 0.5 * dt * k1.0, v + 0.5 * dt * k1.1),
        );
        let k3 = (
            v + 0.5 * dt * k2.1,
            accel(t + 0.5 * dt, x + 0.5 * dt * k2.0, v + 0.5 * dt * k2.1),
        );
        let k4 = (v + dt * k3.1, accel(t + dt, x + dt * k3.0, v + dt * k3.1));
        x += dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
        v += dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        t += dt;
        samples.push((t, x - theta0));
    }
    let mut crossings = Vec::new();
    let mut extrema = Vec::new();
    for k in 1..samples.len() - 1 {
        let (t0, a) = samples[k - 1];
        let (t1, b) = samples[k];
        if a * b < 0.0 {
            crossings.push(t0 + (t1 - t0) * a / (a - b));
        }
        let c = samples[k + 1].1;
        if (b - a) * (c - b) < 0.0 {
            // Parabola through three samples: peak value.
            let denom = a - 2.0 * b + c;
            let s = 0.5 * (a - c) / denom;
            extrema.push(b - 0.25 * (a - c) * s);
        }
    }
    assert!(
        crossings.len() >= 4 && extrema.len() >= 4,
        "too few oscillations"
    );
    let half = (crossings[3] - crossings[0]) / 3.0;
    let wd = std::f64::consts::PI / half;
    let ratio = (extrema[3] / extrema[1]).abs().sqrt(); // per half period
    let sigma = -ratio.ln() / half;
    (wd, sigma / (sigma * sigma + wd * wd).sqrt())
}

#[test]
fn time_integration_reproduces_damped_frequency_and_damping_ratio() {
    let model = example("rotating_pendulum.toml");
    for w in [1.0, 2.0, 5.0] {
        let pt = at(&model, w, &Options::default());
        let (wd, zeta) = pendulum_time_response(&model, w, pt.equilibrium.q[1]);
        let mode = &pt.modes[0];
        assert_relative_eq!(wd, mode.damped_frequency, max_relative = 0.01);
        assert_relative_eq!(zeta, mode.damping_ratio, max_relative = 0.01);
    }
}

#[test]
fn gyroscopic_example_has_skew_coupling_and_valid_left_vectors() {
    let model = example("spinning_universal_pendulum.toml");
    let slow = at(&model, 0.0, &Options::default());
    let fast = at(&model, 4.0, &Options::default());
    let skew = |c: &DMatrix<f64>| (c - c.transpose()).amax();
    assert!(
        skew(&slow.linear.c) < 1e-12,
        "no gyroscopic coupling at rest"
    );
    assert!(
        skew(&fast.linear.c) > 0.1,
        "Coriolis coupling at speed: {}",
        fast.linear.c
    );
    let (m, c, k) = (&fast.linear.m, &fast.linear.c, &fast.linear.k);
    assert!((k - k.transpose()).amax() > 1e-3 || skew(c) > 0.0);
    for mode in &fast.modes {
        for r in [&mode.root, &mode.partner] {
            let l = r.lambda;
            let p =
                m.map(|v| l * l * v) + c.map(|v| l * v) + k.map(|v| nalgebra::Complex::new(v, 0.0));
            assert!((&p * &r.right).norm() < 1e-9 * p.norm());
            let res = (r.left.transpose() * &p).norm();
            assert!(
                res < 1e-9 * p.norm(),
                "left residual {res} for λ = {l}; P = {p}, y = {}",
                r.left
            );
        }
    }
    // Two distinct underdamped whirl modes.
    assert_eq!(fast.modes.len(), 2);
    assert!(fast.modes.iter().all(|m| m.class == ModeClass::Underdamped));
    assert!((fast.modes[0].damped_frequency - fast.modes[1].damped_frequency).abs() > 0.1);
}

#[test]
fn drive_torque_balances_joint_damping_on_the_drive() {
    let text = example_text("rotating_pendulum.toml");
    let text = text.replace("drive = \"speed\"", "drive = \"speed\"\ndamping = 0.7");
    let model = Compiled::from_str(&text, "damped_spin.toml").unwrap();
    let p = at(&model, 2.5, &Options::default());
    assert_relative_eq!(
        p.equilibrium.drive_force[0],
        0.7 * 2.5,
        max_relative = 1e-12
    );
}

#[test]
fn gravity_off_the_spin_axis_has_no_steady_state() {
    let text = example_text("rotating_pendulum.toml");
    let text = text.replace("gravity = [0, -9.80665, 0]", "gravity = [-3, -9, 0]");
    let model = Compiled::from_str(&text, "tilted.toml").unwrap();
    let p = model.model().nominal();
    // Wherever the spin angle starts, including where the residual is stationary in it
    // (cos q_D at 0 and π) and where the tilt lies across the swing plane (π/2).
    // Both routes (recorded program, direct evaluation).
    for route in [Route::Recorded, Route::Direct] {
        let model = model.clone().with_route(route);
        for spin in [0.0, FRAC_PI_2, 1.0, PI, -2.2] {
            let err = point(&model, &p, 2.0, &[spin, 0.5], &Options::default())
                .expect_err("no steady state");
            assert!(err.to_string().contains("no steady state"), "{spin}: {err}");
        }
    }
    // A sweep reports it per speed and goes on.
    let mut sweep = Sweep::new(&model, p, Options::default());
    assert!(sweep.step(1.0).is_err() && sweep.step(2.0).is_err());
}

/// Where the model's structure proves that `F` cannot depend on a driven coordinate (a spin on
/// the ground turning its part of the mechanism alone, gravity along its axis), the
/// steady-state check is skipped: `F` evaluated directly is indeed the same at any value of
/// that coordinate, at states away from equilibrium too.
#[test]
fn a_spin_proved_symmetric_leaves_the_equations_unchanged() {
    let mut proved = Vec::new();
    for name in common::EXAMPLES {
        let model = example(name);
        let p = model.model().nominal();
        let speed = 1.3;
        let direct = Direct::new(
            System::new(model.model(), &p, speed).unwrap(),
            model.model().free(),
        );
        let q0 = initial_guess(model.model(), &p, speed).unwrap();
        let lambda: Vec<f64> = (0..model.model().n_constraints())
            .map(|k| 1.0 - 0.3 * k as f64)
            .collect();
        for c in model.model().steady_by_symmetry(&p, speed) {
            proved.push(name);
            for state in 0..4 {
                let q: Vec<f64> = (q0.iter().enumerate())
                    .map(|(i, v)| v + 0.1 * ((3 * i + 7 * state) % 5) as f64 - 0.2)
                    .collect();
                let f0 = direct.residual(&q, &lambda);
                let scale = f0.iter().fold(1.0f64, |s, v| s.max(v.abs()));
                for turn in [0.3, 1.0, 2.5, -2.0, 100.0] {
                    let mut turned = q.clone();
                    turned[c] += turn;
                    let f = direct.residual(&turned, &lambda);
                    let change = f
                        .iter()
                        .zip(&f0)
                        .fold(0.0f64, |s, (a, b)| s.max((a - b).abs()));
                    assert!(change <= 1e-12 * scale, "{name}: {change} of {scale}");
                }
            }
        }
    }
    // Not vacuous: the governors and the pendulums are proved; the rotor, whose spin rides on
    // its rubber mounts, is not.
    for name in [
        "governor.toml",
        "multi_arm_governor.toml",
        "rotating_pendulum.toml",
        "spinning_universal_pendulum.toml",
    ] {
        assert!(proved.contains(&name), "{name} not proved symmetric");
    }
    assert!(!proved.contains(&"rotor_on_rubber_mounts.toml"));
}

/// A spring from the ground to the spinning rod breaks the symmetry: it is not proved, and
/// the check by evaluation finds the dependence. A spring between two bodies that spin
/// together keeps it.
#[test]
fn a_spring_to_the_ground_is_checked_by_evaluation() {
    let spring = |body1: &str| {
        format!(
            "{}\n[[forces]]\nname = \"tie\"\ntype = \"spring_damper\"\nbody1 = \"{body1}\"\n\
             point1 = [0.4, -1.0, 0]\nbody2 = \"rod\"\npoint2 = [0, -1.0, 0]\nstiffness = 50\n",
            example_text("rotating_pendulum.toml")
        )
    };
    let tied = Compiled::from_str(&spring("ground"), "tied.toml").unwrap();
    let p = tied.model().nominal();
    assert!(tied.model().steady_by_symmetry(&p, 2.0).is_empty());
    for route in [Route::Recorded, Route::Direct] {
        let tied = tied.clone().with_route(route);
        let err =
            point(&tied, &p, 2.0, &[0.3, 0.5], &Options::default()).expect_err("no steady state");
        assert!(err.to_string().contains("no steady state"), "{err}");
    }
    let braced = Compiled::from_str(&spring("shaft"), "braced.toml").unwrap();
    assert_eq!(braced.model().steady_by_symmetry(&p, 2.0), vec![0]);
    point(&braced, &p, 2.0, &[0.3, 0.5], &Options::default()).unwrap();
}

/// The rotating pendulum's rod drawn across the spin axis (along x), with gravity `gravity`
/// and further tables `extra`: at θ = 0 the rod is perpendicular to the shaft.
fn rod_across(gravity: &str, extra: &str) -> Compiled {
    let text = example_text("rotating_pendulum.toml")
        .replace(
            "gravity = [0, -9.80665, 0]",
            &format!("gravity = {gravity}"),
        )
        .replace(
            "inertia = [\"m*L^2/12\", 0, \"m*L^2/12\"]",
            "inertia = [0, \"m*L^2/12\", \"m*L^2/12\"]",
        )
        .replace("cm = [0, \"-L/2\", 0]", "cm = [\"L/2\", 0, 0]")
        .replace("initial = \"pi/3\"", "initial = 0");
    Compiled::from_str(&format!("{text}\n{extra}"), "across.toml").unwrap()
}

/// Gravity g along x, across the spin axis y, on the rod across it: with the shaft turned by ψ
/// the centre of mass is at `(L/2)(cos θ cos ψ, sin θ, −cos θ sin ψ)`, so
/// `V = (mgL/2) cos θ cos ψ − ½ Ω² (mL²/3) cos² θ`. `∂V/∂θ = 0` at θ = 0 whatever ψ: the
/// equilibrium does not move as the shaft turns, but the stiffness
/// `K = Ω² mL²/3 − (mgL/2) cos ψ` does, so there is no steady state. The model is refused
/// wherever the shaft starts (also where `K` is stationary in ψ), on both routes, naming the
/// stiffness; at speed 0 nothing turns and it is accepted with `K = −(mgL/2) cos ψ`.
#[test]
fn gravity_across_the_spin_axis_that_moves_only_the_stiffness_has_no_steady_state() {
    let model = rod_across("[-9.80665, 0, 0]", "");
    let p = model.model().nominal();
    for route in [Route::Recorded, Route::Direct] {
        let model = model.clone().with_route(route);
        for spin in [0.0, FRAC_PI_2, 1.0, PI, -2.2] {
            let err = point(&model, &p, 3.0, &[spin, 0.0], &Options::default())
                .expect_err("no steady state");
            let e = err.to_string();
            assert!(
                e.contains("no steady state")
                    && e.contains("linearisation")
                    && e.contains("stiffness"),
                "{spin}: {e}"
            );
            let at_rest = point(&model, &p, 0.0, &[spin, 0.0], &Options::default()).unwrap();
            let k = -0.5 * 3.0 * 9.80665 * spin.cos();
            assert!(at_rest.equilibrium.q[1].abs() < 1e-12);
            assert_relative_eq!(at_rest.linear.k[(0, 0)], k, epsilon = 1e-10);
        }
    }
    // A sweep from rest reports it at the first turning speed, and at the next.
    let mut sweep = Sweep::new(&model, p, Options::default());
    assert!(sweep.step(0.0).is_ok());
    assert!(sweep.step(1.0).is_err() && sweep.step(2.0).is_err());
}

/// The same rod with gravity along the spin axis and a dead load along it too (which keeps
/// the motion steady, but leaves it to the check by evaluation: the symmetry proof does not
/// cover dead loads), and the shipped rotor (whose spin rides on its mounts, so it is checked
/// by evaluation): steady, and accepted at any spin angle, the linearisation included.
#[test]
fn steady_models_checked_by_evaluation_pass_the_linearisation_check() {
    let model = rod_across(
        "[0, -9.80665, 0]",
        "[[loads]]\nname = \"down\"\ntype = \"force\"\nbody = \"rod\"\npoint = [\"L\", 0, 0]\nforce = [0, -4, 0]\n",
    );
    let p = model.model().nominal();
    assert!(model.model().steady_by_symmetry(&p, 3.0).is_empty());
    let rotor = example("rotor_on_rubber_mounts.toml");
    let pr = rotor.model().nominal();
    assert!(rotor.model().steady_by_symmetry(&pr, 100.0).is_empty());
    for route in [Route::Recorded, Route::Direct] {
        let model = model.clone().with_route(route);
        let rotor = rotor.clone().with_route(route);
        for spin in [0.0, FRAC_PI_2, 1.0, -2.2] {
            point(&model, &p, 3.0, &[spin, 0.3], &Options::default()).unwrap();
            let mut q0 = initial_guess(rotor.model(), &pr, 100.0).unwrap();
            for c in rotor.model().driven() {
                q0[c] = spin;
            }
            point(&rotor, &pr, 100.0, &q0, &Options::default()).unwrap();
        }
    }
}

/// A disk whose two inertias across the shaft differ, on the Friswell rotor spinning on its
/// nodes (the stationary frame): its inertia turns with the shaft, so the mass, gyroscopic
/// and stiffness matrices are periodic in the spin angle while the straight shaft stays an
/// equilibrium. Refused on both routes by the linearisation's check (no residual changes),
/// at any starting angle; at rest nothing turns and it is accepted. The axisymmetric rotor
/// passes at the same speeds.
#[test]
fn an_unbalanced_inertia_on_a_spinning_shaft_is_refused_as_periodic() {
    let text = example_text("friswell_5_9_1.toml");
    let across = "  \"disk1*(D1^2 + bore^2)/16 + disk1*width^2/12\",\n]";
    assert!(text.contains(across));
    let flat = text.replace(across, "  \"3*disk1*(D1^2 + bore^2)/16\",\n]");
    let flat = Compiled::from_str(&flat, "flat_disk.toml").unwrap();
    let round = example("friswell_5_9_1.toml");
    let p = flat.model().nominal();
    for route in [Route::Recorded, Route::Direct] {
        let (flat, round) = (
            flat.clone().with_route(route),
            round.clone().with_route(route),
        );
        for spin in [0.0, 1.0, -2.2] {
            for speed in [30.0, 400.0] {
                let mut q0 = initial_guess(flat.model(), &p, speed).unwrap();
                for c in flat.model().driven() {
                    q0[c] = spin;
                }
                let e = point(&flat, &p, speed, &q0, &Options::default())
                    .expect_err("periodic")
                    .to_string();
                assert!(
                    e.contains("no steady state") && e.contains("linearisation"),
                    "{route:?} {spin} {speed}: {e}"
                );
                point(&round, &p, speed, &q0, &Options::default()).unwrap();
            }
            let mut q0 = initial_guess(flat.model(), &p, 0.0).unwrap();
            for c in flat.model().driven() {
                q0[c] = spin;
            }
            point(&flat, &p, 0.0, &q0, &Options::default()).unwrap();
        }
    }
}

/// An undamped rotor's modes are `undamped` (both roots exactly imaginary, ζ = 0) at rest and
/// spinning, gyroscopic coupling and all. With dampers in its bearings the modes they reach
/// are `underdamped` (ζ of order 10⁻³ to 10⁻² for the bending modes, 10⁻⁶ for a stiff one
/// they barely move); the torsion and the axial modes, which no damper reaches, keep a ζ at
/// rounding level; no mode is unstable or overdamped.
#[test]
fn an_undamped_rotor_has_undamped_modes_and_dampers_make_them_underdamped() {
    let round = example("friswell_5_9_1.toml");
    let text = example_text("friswell_5_9_1.toml");
    let bearing = "stiffness = [\"k_thrust\", \"k_bearing\", \"k_bearing\", 0, 0, 0]\n";
    assert_eq!(text.matches(bearing).count(), 2);
    let damped = text.replace(
        bearing,
        &format!("{bearing}damping = [0, 200, 200, 0, 0, 0]\n"),
    );
    let damped = Compiled::from_str(&damped, "damped.toml").unwrap();
    let p = round.model().nominal();
    for speed in [0.0, 100.0, 400.0] {
        let q0 = initial_guess(round.model(), &p, speed).unwrap();
        let pt = point(&round, &p, speed, &q0, &Options::default()).unwrap();
        for m in &pt.modes {
            assert_eq!(m.class, ModeClass::Undamped, "{speed}: {m:?}");
            assert_eq!(m.class.as_str(), "undamped");
            assert_eq!(m.root.lambda.re, 0.0);
            assert_eq!(m.damping_ratio.to_bits(), 0f64.to_bits());
        }
        let pt = point(&damped, &p, speed, &q0, &Options::default()).unwrap();
        let reached = (pt.modes.iter()).filter(|m| m.damping_ratio > 1e-4);
        assert!(reached.clone().count() >= 6, "{speed}");
        assert!(reached.clone().all(|m| m.class == ModeClass::Underdamped));
        for m in &pt.modes {
            assert!(
                m.damping_ratio > 1e-8 || m.damping_ratio.abs() < 1e-20,
                "{speed}: ζ {} at {} rad/s",
                m.damping_ratio,
                m.damped_frequency
            );
            assert!(matches!(
                m.class,
                ModeClass::Underdamped | ModeClass::Undamped
            ));
        }
    }
}

#[test]
fn massless_coordinate_is_reported_as_singular_mass() {
    let text = example_text("rotating_pendulum.toml");
    let text = text
        .replace("mass = \"m\"", "mass = 0")
        .replace(
            "inertia = [\"m*L^2/12\", 0, \"m*L^2/12\"]",
            "inertia = [0, 0, 0]",
        )
        .replace("damping = \"c\"", "damping = \"c\"\nstiffness = 10");
    let model = Compiled::from_str(&text, "massless.toml").unwrap();
    let err = point(
        &model,
        &model.model().nominal(),
        1.0,
        &[0.0, 0.3],
        &Options::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("mass matrix"), "{err}");
}

#[test]
fn partial_velocities_are_exact_derivatives() {
    // ∂r/∂q̈ is the mass matrix: symmetric positive definite for the gyroscopic example.
    let model = example("spinning_universal_pendulum.toml");
    let p = at(&model, 3.0, &Options::default());
    let m = &p.linear.m_full;
    assert!((m - m.transpose()).amax() < 1e-12 * m.amax());
    assert!(m.clone().symmetric_eigenvalues().min() > 0.0);
}

#[test]
fn twelve_arm_governor_matches_the_two_arm_governor() {
    // 32 bodies, 12 closed loops, one degree of freedom: with 2/12 of the ball mass and inertia
    // on each of 12 evenly spaced arms, the symmetric collar mode is the two-arm governor's.
    let many = example("multi_arm_governor.toml");
    let two = example("governor.toml");
    assert_eq!(
        (
            many.model().bodies.len(),
            many.model().constraints.len(),
            many.model().dof()
        ),
        (32, 12, 1)
    );
    let mut s_many = Sweep::new(&many, many.model().nominal(), Options::default());
    let mut s_two = Sweep::new(&two, two.model().nominal(), Options::default());
    let slide = (
        many.model().coordinate("slide").unwrap(),
        two.model().coordinate("slide").unwrap(),
    );
    for i in 0..=10 {
        let w = 0.5 * i as f64;
        let (a, b) = (s_many.step(w).unwrap(), s_two.step(w).unwrap());
        assert!(
            (a.equilibrium.q[slide.0] - b.equilibrium.q[slide.1]).abs() < 1e-10,
            "Ω = {w}"
        );
        let (la, lb) = (a.modes[0].root.lambda, b.modes[0].root.lambda);
        assert!(
            (la - lb).norm() <= 1e-9 * lb.norm(),
            "Ω = {w}: {la} vs {lb}"
        );
        assert!(a.equilibrium.constraint_violation < 1e-12);
    }
}
