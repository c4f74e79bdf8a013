//! Independent references for the beam element of issue 56, written before the element: the
//! closed-form Timoshenko element matrices of one bending plane (stiffness, consistent
//! translational and rotary mass, gyroscopic; Przemieniecki 1968, Friswell et al. 2010 §5.4,
//! Nelson 1980), assembled into beams and checked here against exact frequencies and the
//! published Friswell Example 5.9.1 rotor (ROSS's `rotor_example1`). Once the element exists,
//! its linearisation is compared with these assemblies matrix by matrix and root by root.

mod common;

use common::timoshenko::{self, Plane, whirl};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// A uniform circular section and material: Young's and shear moduli (Pa), density (kg/m³),
/// outer diameter (m), shear coefficient.
#[derive(Clone, Copy)]
struct Section {
    e: f64,
    g: f64,
    rho: f64,
    d: f64,
    kappa: f64,
}

impl Section {
    fn area(&self) -> f64 {
        PI * self.d * self.d / 4.0
    }
    fn inertia(&self) -> f64 {
        PI * self.d.powi(4) / 64.0
    }
}

/// One element's stiffness, consistent mass (translational plus rotary, the rotary part only
/// where `rotary`) and gyroscopic matrix (`I_p = 2I`), dofs `(v₁, θ₁, v₂, θ₂)`.
fn element(s: Section, l: f64, rotary: bool) -> [DMatrix<f64>; 3] {
    let plane = Plane {
        ei: s.e * s.inertia(),
        ga: s.kappa * s.g * s.area(),
        rho_a: s.rho * s.area(),
        rho_i: s.rho * s.inertia(),
    };
    timoshenko::plane(plane, l, rotary)
}

/// A uniform beam of `n` elements of length `l` over `2(n + 1)` dofs: `[K, M, G]`.
fn assemble(s: Section, n: usize, l: f64, rotary: bool) -> [DMatrix<f64>; 3] {
    let size = 2 * (n + 1);
    let mut out = [0, 1, 2].map(|_| DMatrix::zeros(size, size));
    let parts = element(s, l, rotary);
    for e in 0..n {
        for (whole, part) in out.iter_mut().zip(&parts) {
            let mut block = whole.view_mut((2 * e, 2 * e), (4, 4));
            block += part;
        }
    }
    out
}

/// The matrices without the dofs `fixed`.
fn restrain(mats: [DMatrix<f64>; 3], fixed: &[usize]) -> [DMatrix<f64>; 3] {
    let keep: Vec<usize> = (0..mats[0].nrows())
        .filter(|i| !fixed.contains(i))
        .collect();
    mats.map(|a| DMatrix::from_fn(keep.len(), keep.len(), |i, j| a[(keep[i], keep[j])]))
}

/// `|a − b| ≤ tol·|b|`.
fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs()
}

#[test]
fn euler_bernoulli_cantilever_matches_its_exact_frequencies() {
    // Clamped–free, ω = (βL)² √(EI/(ρAL⁴)) with βL = 1.875104069, 4.694091133, 7.854757438.
    let s = Section {
        e: 2.0e11,
        g: 8.0e10,
        rho: 7800.0,
        d: 0.02,
        kappa: f64::INFINITY,
    };
    let length: f64 = 1.0;
    let scale = (s.e * s.inertia() / (s.rho * s.area() * length.powi(4))).sqrt();
    let exact = [1.875_104_068_7, 4.694_091_132_97, 7.854_757_438_24].map(|b| b * b * scale);
    let errors = |n: usize| {
        let mats = restrain(assemble(s, n, length / n as f64, false), &[0, 1]);
        let w = whirl(&mats, 0.0);
        exact.map(|x| {
            let k = exact.iter().position(|&y| y == x).unwrap();
            // Consistent mass: the frequencies converge from above.
            assert!(
                w[k] >= x * (1.0 - 1e-12),
                "{n} elements, mode {k}: {} < {x}",
                w[k]
            );
            (w[k] - x) / x
        })
    };
    converges_at_order(errors(10), errors(20), 4, 2e-5);
}

/// Relative errors `coarse` and `fine` (twice the elements): each of `fine` below `tol` and,
/// where above rounding, about `2^order` times smaller than `coarse` (between 0.75 and 1.25
/// of it).
fn converges_at_order<const N: usize>(coarse: [f64; N], fine: [f64; N], order: i32, tol: f64) {
    let expected = 2f64.powi(order);
    for (k, (c, f)) in coarse.iter().zip(&fine).enumerate() {
        assert!(f.abs() <= tol, "mode {k}: error {f}");
        if f.abs() > 1e-9 {
            let ratio = c / f;
            assert!(
                (0.75 * expected..=1.25 * expected).contains(&ratio),
                "mode {k}: {c} → {f}"
            );
        }
    }
}

#[test]
fn timoshenko_pinned_beam_converges_to_its_frequency_equation() {
    // Simply supported with shear and rotary inertia, half-wave k = nπ/L:
    // (κGAk² − ρAω²)(EIk² + κGA − ρIω²) − (κGAk)² = 0, the lower root (Timoshenko 1921).
    let nu: f64 = 0.3;
    let s = Section {
        e: 2.0e11,
        g: 2.0e11 / (2.0 * (1.0 + nu)),
        rho: 7800.0,
        d: 0.2,
        kappa: 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu),
    };
    let length: f64 = 1.0;
    let (a, i) = (s.area(), s.inertia());
    let exact: [f64; 3] = std::array::from_fn(|m| {
        let half_waves = m + 1;
        let k = half_waves as f64 * PI / length;
        // The quadratic in ω²: (ρA)(ρI) x² − [ρA(EIk² + κGA) + ρI κGAk²] x + κGAk²·EIk² = 0.
        let ga = s.kappa * s.g * a;
        let qa = s.rho * a * s.rho * i;
        let qb = -(s.rho * a * (s.e * i * k * k + ga) + s.rho * i * ga * k * k);
        let qc = ga * k * k * s.e * i * k * k;
        let x = (-qb - (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
        let exact = x.sqrt();
        // Shear and rotary inertia matter here: Euler–Bernoulli is off by more than 1 %.
        let bernoulli = k * k * (s.e * i / (s.rho * a)).sqrt();
        assert!(bernoulli > 1.01 * exact, "n = {half_waves}");
        exact
    });
    let errors = |n: usize| {
        let mats = restrain(assemble(s, n, length / n as f64, true), &[0, 2 * n]);
        let w = whirl(&mats, 0.0);
        std::array::from_fn::<f64, 3, _>(|m| (w[m] - exact[m]) / exact[m])
    };
    // The interdependent (shear-aware) element converges at second order here (its `φ` grows
    // as `1/h²`): measured 2.7e-4, 6.7e-5, 1.7e-5, 4.2e-6, 1.0e-6 from 10 to 160 elements on
    // the first half-wave, ratios 4.0, to the exact root.
    converges_at_order(errors(20), errors(40), 2, 1e-3);
}

#[test]
fn friswell_example_5_9_1_rotor_matches_ross() {
    // Friswell, Penny, Garvey & Lees (2010), Example 5.9.1, as ROSS builds it
    // (`ross/tests/test_examples.py::rotor_example1`): a 1.5 m steel shaft of 50 mm in six
    // Timoshenko elements (Cowper's shear coefficient), disks of 70 mm width on nodes 2
    // (Ø 280 mm) and 4 (Ø 350 mm), isotropic bearings of 1 MN/m at the ends. ROSS asserts the
    // lateral frequencies below (rad/s, relative tolerance 1e-3); its 650.41 is a torsional
    // mode, not in this one-plane model.
    let (e, g) = (211.0e9, 81.2e9);
    let nu = e / (2.0 * g) - 1.0;
    let s = Section {
        e,
        g,
        rho: 7810.0,
        d: 0.05,
        kappa: 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu),
    };
    let n = 6;
    let [mut k, mut m, mut gy] = assemble(s, n, 0.25, true);
    for (node, outer) in [(2, 0.28), (4, 0.35)] {
        let (width, inner): (f64, f64) = (0.07, 0.05);
        let mass = s.rho * PI * width * (outer * outer - inner * inner) / 4.0;
        let polar = mass * (outer * outer + inner * inner) / 8.0;
        let diametral = polar / 2.0 + mass * width * width / 12.0;
        m[(2 * node, 2 * node)] += mass;
        m[(2 * node + 1, 2 * node + 1)] += diametral;
        gy[(2 * node + 1, 2 * node + 1)] += polar;
    }
    for node in [0, n] {
        k[(2 * node, 2 * node)] += 1.0e6;
    }
    let mats = [k, m, gy];
    let at_rest = whirl(&mats, 0.0);
    for (w, ross) in at_rest.iter().zip([86.66, 274.31, 716.78]) {
        assert!(close(*w, ross, 1e-3), "0 rpm: {w} vs {ross}");
    }
    let spin = 4000.0 * PI / 30.0;
    let forward = whirl(&mats, spin);
    let backward = whirl(&mats, -spin);
    for (w, ross) in backward.iter().zip([85.39, 251.78, 600.18]) {
        assert!(close(*w, ross, 1e-3), "4000 rpm backward: {w} vs {ross}");
    }
    for (w, ross) in forward.iter().zip([87.80, 294.71]) {
        assert!(close(*w, ross, 1e-3), "4000 rpm forward: {w} vs {ross}");
    }
    // The gyroscopic split: forward whirl stiffens, backward softens, mode by mode.
    for ((f, b), r) in forward.iter().zip(&backward).zip(&at_rest).take(3) {
        assert!(f > r && b < r, "{f} {b} {r}");
    }
    // A residual check of one root: the dynamic stiffness is singular there.
    let w = forward[0];
    let dynamic = &mats[0] - &mats[1] * (w * w) + &mats[2] * (spin * w);
    let smallest = dynamic.clone().symmetric_eigenvalues().abs().min();
    let largest = DVector::from(dynamic.symmetric_eigenvalues()).abs().max();
    assert!(smallest <= 1e-9 * largest, "{smallest} vs {largest}");
}
