//! A rotating cantilever blade as N rigid segments with joint springs (Hencky's bar chain:
//! springs `EI/h` between segments, `2EI/h` at the clamp), against the Euler–Bernoulli
//! cantilever: the first flapwise frequency at rest tends to `(1.8751)² √(EI/(μL⁴))`, and its
//! centrifugal stiffening `dω₁²/dΩ²` at low speed to Southwell's coefficient `S = 1.193`
//! (zero hub radius), as N grows. The shipped example is the N = 20 chain.

// The coupled families of the shared generators are not used here.
#[allow(dead_code)]
#[path = "../examples/common/chain.rs"]
mod chain;
mod common;

use common::solve;
use modaltol::compiled::Compiled;
use modaltol::modal::{C64, ModeClass, similarity};

/// Uniform blade: length 1 m, μ = 2 kg/m, EI = 50 N·m², spinning about z, flapping along z.
pub fn blade(n: usize) -> String {
    let (length, mu, ei) = (1.0f64, 2.0f64, 50.0f64);
    let h = length / n as f64;
    let mut s = format!(
        "name = \"blade {n}\"\ngravity = [0, 0, 0]\n[parameters]\nmu = {mu}\nEI = {ei}\nh = {h}\n\
         [[bodies]]\nname = \"hub\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\ncm = [0, 0, 0]\n\
         [[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\nchild = \"hub\"\n\
         at = [0, 0, 0]\naxis = [0, 0, 1]\ndrive = \"speed\"\n"
    );
    for i in 0..n {
        let x0 = i as f64 * h;
        let parent = if i == 0 {
            "hub".to_string()
        } else {
            format!("s{}", i - 1)
        };
        let k = if i == 0 { "2*EI/h" } else { "EI/h" };
        s += &format!(
            "[[bodies]]\nname = \"s{i}\"\nmass = \"mu*h\"\ninertia = [0, \"mu*h^3/12\", \"mu*h^3/12\"]\n\
             cm = [{}, 0, 0]\n[[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\nparent = \"{parent}\"\n\
             child = \"s{i}\"\nat = [{x0}, 0, 0]\naxis = [0, -1, 0]\nstiffness = \"{k}\"\n",
            x0 + h / 2.0
        );
    }
    s
}

/// The lowest damped frequency at `speed` (rad/s).
fn first(model: &Compiled, speed: f64) -> f64 {
    solve(model, speed, false)
        .modes
        .iter()
        .map(|m| m.damped_frequency)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_segment_chain_converges_to_the_rotating_euler_bernoulli_cantilever() {
    let w10 = 1.875_104_068_711_961f64.powi(2) * (50.0f64 / 2.0).sqrt();
    let southwell = 1.193;
    let mut results = Vec::new();
    for n in [5, 10, 20, 40] {
        let model = Compiled::from_str(&blade(n), "blade.toml").unwrap_or_else(|e| panic!("{e}"));
        let w0 = first(&model, 0.0);
        // dω₁²/dΩ² at Ω → 0 is the Rayleigh quotient of the centrifugal stiffness in the mode
        // at rest: Southwell's coefficient (a small speed keeps the Ω⁴ term below 1e-5).
        let omega = 0.05 * w10;
        let s = (first(&model, omega).powi(2) - w0 * w0) / (omega * omega);
        eprintln!("N = {n}: ω₁₀ = {w0:.6} rad/s (continuum {w10:.6}), S = {s:.5}");
        results.push((w0, s));
    }
    let error = |(w, s): (f64, f64)| ((w / w10 - 1.0).abs(), (s / southwell - 1.0).abs());
    // Second order in h for the frequency: each halving of h divides the error by about 4.
    for pair in results.windows(2) {
        let (a, b) = (error(pair[0]), error(pair[1]));
        assert!(b.0 < a.0 / 3.5, "ω₁₀ errors {a:?} → {b:?}");
        assert!(b.1 < a.1, "S errors {a:?} → {b:?}");
    }
    let (w40, s40) = results[3];
    let (w20, s20) = results[2];
    assert!(
        error(results[3]).0 < 5e-4 && error(results[3]).1 < 1e-3,
        "{:?}",
        error(results[3])
    );
    // Richardson's extrapolation of the last two removes the h² term: the continuum's
    // frequency to 1e-5 and its Southwell coefficient to the three digits it is known to.
    let (w, s) = ((4.0 * w40 - w20) / 3.0, (4.0 * s40 - s20) / 3.0);
    assert!(
        (w / w10 - 1.0).abs() < 1e-5,
        "extrapolated ω₁₀ {w} vs {w10}"
    );
    assert!((s / southwell - 1.0).abs() < 1e-3, "extrapolated S {s}");
}

/// To 1e-8: the chain's frequencies spread over three decades (17.6 to 13 700 rad/s), and the
/// damped eigensolve of the 40×40 state matrix resolves the lowest roots to about 1e-9 of their
/// size (the undamped roots come out with real parts of ±4e-9 rad/s, not zero), so two writings
/// of the same numbers agree to that, not to 1e-10.
#[test]
fn the_shipped_blade_is_the_twenty_segment_chain() {
    let shipped = common::example("rotating_blade.toml");
    let generated = Compiled::from_str(&blade(20), "blade.toml").unwrap();
    for w in [0.0, 10.0, 25.0] {
        common::same_roots(
            &common::roots(&solve(&shipped, w, false)),
            &common::roots(&solve(&generated, w, false)),
            1e-8,
        );
    }
}

#[test]
fn a_three_hundred_twenty_segment_blade_solves_on_southwells_line() {
    // The benchmark's chain (examples/common/chain.rs). A stiff spectrum (the highest modes 1e5 times the lowest): the point completes, every
    // mode shape finite (checked by the modal solve itself), and the first frequency lies on
    // Southwell's line ω₁² ≈ ω₁₀² + S Ω² (the Ω⁴ term and the chain's discretisation are below
    // 1e-4 here).
    let model =
        Compiled::from_str(&chain::chain(320), "chain.toml").unwrap_or_else(|e| panic!("{e}"));
    let w10 = 1.875_104_068_711_961f64.powi(2) * (50.0f64 / 2.0).sqrt();
    let omega = 5.0;
    let w1 = first(&model, omega);
    let expected = w10 * w10 + 1.193 * omega * omega;
    assert!(
        (w1 * w1 / expected - 1.0).abs() < 2e-4,
        "ω₁² = {}, ω₁₀² + S Ω² = {expected}",
        w1 * w1
    );
}

#[test]
fn a_thousand_segment_blade_converges_without_rounding_noise() {
    // The benchmark's chain with a thousand segments: M̂ in joint coordinates has condition
    // 3.9e12 (∝ n⁴). The lowest frequency at rest approaches the continuum's from below as h²,
    // so its error at N = 1000 is (40/1000)² of the error at N = 40 (to the h⁴ term, below
    // 1 % of it). Rounding of order ε cond(M̂) (what the eigensolve reduced by M̂'s Cholesky
    // factor committed: the first frequency came out 1e-4 off, above the continuum at
    // N = 800) would be 200 times that error.
    let w10 = 1.875_104_068_711_961f64.powi(2) * (50.0f64 / 2.0).sqrt();
    let error = |n: usize| {
        let model =
            Compiled::from_str(&chain::chain(n), "chain.toml").unwrap_or_else(|e| panic!("{e}"));
        1.0 - first(&model, 0.0) / w10
    };
    let (e40, e1000) = (error(40), error(1000));
    let predicted = e40 * (40.0f64 / 1000.0).powi(2);
    assert!(
        e1000 > 0.0 && (e1000 / predicted - 1.0).abs() < 0.02,
        "error {e1000:e} at N = 1000, {predicted:e} predicted from N = 40 ({e40:e})"
    );
}

#[test]
fn a_long_chain_with_joint_damping_has_the_undamped_chains_frequencies() {
    // Joint dampers proportional to the springs (c = α k) make Ĉ = α K̂ at rest (no gravity,
    // no speed: K̂ is the springs alone), so each damped pair is λ = −αμ/2 ± i√(μ − (αμ/2)²)
    // with μ = ω² of the undamped chain, solved by the symmetric route. The damped chain goes
    // through the first-order form, which divided by M̂ (condition 1e9 at 160 segments): there
    // its vectors overflowed and the point failed, and at 480 segments the first frequency
    // was 4e-5 off with a positive real part.
    let n = 160;
    let alpha = 1e-4;
    let undamped = chain::chain(n);
    let damped = chain::with_joint_dampers(&undamped, alpha);
    assert_eq!(damped.matches("damping").count(), n);
    let load =
        |text: &str| Compiled::from_str(text, "chain.toml").unwrap_or_else(|e| panic!("{e}"));
    let reference = solve(&load(&undamped), 0.0, false);
    let point = solve(&load(&damped), 0.0, false);
    for (k, (u, d)) in reference.modes.iter().zip(&point.modes).take(6).enumerate() {
        let mu = u.natural_frequency.powi(2);
        let expected = C64::new(-alpha * mu / 2.0, (mu - (alpha * mu / 2.0).powi(2)).sqrt());
        let got = d.root.lambda;
        assert!(
            (got - expected).norm() < 1e-9 * expected.norm()
                && (got.re / expected.re - 1.0).abs() < 1e-6,
            "mode {}: λ = {got} vs {expected}",
            k + 1
        );
        assert_eq!(d.class, ModeClass::Underdamped);
    }
}

#[test]
fn an_overdamped_long_chain_pairs_each_modes_two_real_roots() {
    // Joint dampers c = α k at rest make Ĉ = α K̂: each mode of the undamped chain (μ = ω²,
    // shape φ) becomes the roots of λ² + αμλ + μ, both with the shape φ, overdamped where
    // αω > 2. With α set so that two thirds of the modes are overdamped, the damped solve has
    // some 160 real roots to pair by their vectors; a wrong pair joins two modes' shapes,
    // which are far from parallel. (Pairing compared every pair anew for each pair taken: a
    // 480-segment chain at 5 rad/s spent 74 of its 76 s there; 2.3 s in all now.)
    let n = 120;
    let undamped = chain::chain(n);
    let load =
        |text: &str| Compiled::from_str(text, "chain.toml").unwrap_or_else(|e| panic!("{e}"));
    let by_frequency = |mut modes: Vec<modaltol::modal::Mode>| {
        modes.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
        modes
    };
    let reference = by_frequency(solve(&load(&undamped), 0.0, false).modes);
    let alpha = 2.0 / reference[n / 3].natural_frequency;
    let damped = chain::with_joint_dampers(&undamped, alpha);
    let modes = by_frequency(solve(&load(&damped), 0.0, false).modes);
    assert_eq!(modes.len(), n);
    let overdamped = modes
        .iter()
        .filter(|m| m.class == ModeClass::Overdamped)
        .count();
    assert!(overdamped > n / 2, "{overdamped} overdamped modes of {n}");
    for (k, (u, d)) in reference.iter().zip(&modes).enumerate() {
        // Both roots have the undamped shape (measured: to 1e-13 of each other, and to 7e-5
        // of the reference in the top modes, whose shapes M̂'s condition blurs; two modes'
        // shapes are nearly orthogonal).
        let pair = 1.0 - similarity(&d.root.right, &d.partner.right);
        let shape = 1.0 - similarity(&d.root.right, &u.root.right);
        assert!(
            pair < 1e-9 && shape < 1e-3,
            "mode {}: 1 − similarity {pair:.1e} of its roots' shapes, {shape:.1e} to φ",
            k + 1
        );
        // Product μ and sum −αμ: to 6e-5 at worst (the fast roots −αμ of the top modes, five
        // decades from the slow ones near −1/α, in an unscaled first-order form).
        let mu = u.natural_frequency.powi(2);
        let (l1, l2) = (d.root.lambda, d.partner.lambda);
        let product = ((l1 * l2).re / mu - 1.0).abs();
        let sum = ((l1 + l2).re / (-alpha * mu) - 1.0).abs();
        assert!(
            product < 1e-3 && sum < 1e-3,
            "mode {}: roots {l1}, {l2}: product off by {product:.1e}, sum by {sum:.1e}",
            k + 1
        );
    }
}

/// The three parameters of a 40-segment blade share one `Dual4` pass of its program, whose
/// tangent rows are shared between operations alive at different times (the loop of big
/// programs, lane by lane for so wide a scalar): each parameter's derivatives are bit for bit
/// those of a `Dual64` pass of its own.
#[test]
fn a_big_program_shares_its_sensitivity_pass_to_the_bit() {
    use modaltol::sensitivity::DesignPoint;
    let model = Compiled::from_str(&blade(40), "blade40.toml").unwrap();
    let p = model.model().nominal();
    let pt = solve(&model, 5.0, false);
    let wrt = [0, 1, 2];
    let together = DesignPoint::new(&model, &p, &pt)
        .dual_linearizations(&wrt)
        .unwrap();
    for (shared, &b) in together.iter().zip(&wrt) {
        let alone = DesignPoint::new(&model, &p, &pt)
            .dual_linearizations(&[b])
            .unwrap()
            .remove(0);
        assert!(
            format!("{:?} {:?}", shared.linear, shared.d_equilibrium)
                == format!("{:?} {:?}", alone.linear, alone.d_equilibrium),
            "parameter {b}"
        );
    }
}

/// Issue 38's benchmark family (`examples/scale_chain.rs -- tolerances`): the chain whose first
/// k segments carry their own `mu` and `EI` is, at the nominal values, the same mechanism as
/// the chain with shared ones (the same modes at every speed), and it has 2k toleranced
/// variables, one per segment parameter, each with its own tolerance.
#[test]
fn the_toleranced_chain_is_the_chain_with_a_variable_per_segment_parameter() {
    let n = 6;
    let shared = Compiled::from_str(&chain::chain(n), "chain.toml").unwrap();
    for k in [1, 3, 6] {
        let own = Compiled::from_str(&chain::chain_toleranced(n, k), "chain.toml")
            .unwrap_or_else(|e| panic!("k = {k}: {e}"));
        let m = own.model();
        let toleranced = m.toleranced();
        assert_eq!(toleranced.len(), 2 * k, "k = {k}");
        let names: Vec<&str> = toleranced
            .iter()
            .map(|&i| m.parameters[i].name.as_str())
            .collect();
        for i in 0..k {
            assert!(names.contains(&format!("mu_{i}").as_str()), "{names:?}");
            assert!(names.contains(&format!("EI_{i}").as_str()), "{names:?}");
        }
        for w in [0.0, 20.0, 60.0] {
            common::same_roots(
                &common::roots(&solve(&shared, w, false)),
                &common::roots(&solve(&own, w, false)),
                1e-12,
            );
        }
        // Each own parameter reaches the mechanism: changing the first segment's `EI` or the
        // last own segment's `mu` moves the modes.
        let base = common::roots(&solve(&own, 20.0, false));
        let last = k - 1;
        for (from, to) in [
            (
                "EI_0 = { value = 50.0,".to_string(),
                "EI_0 = { value = 60.0,".to_string(),
            ),
            (
                format!("mu_{last} = {{ value = 2.0,"),
                format!("mu_{last} = {{ value = 2.5,"),
            ),
        ] {
            let text = chain::chain_toleranced(n, k).replace(&from, &to);
            assert_ne!(text, chain::chain_toleranced(n, k), "{from}");
            let changed = Compiled::from_str(&text, "chain.toml").unwrap();
            let moved = common::roots(&solve(&changed, 20.0, false));
            assert!(
                base.iter().zip(&moved).any(|(x, y)| (x - y).norm() > 1e-6),
                "k = {k}: {to}"
            );
        }
    }
}
